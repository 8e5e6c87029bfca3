"""The ``gcs`` command line as the tests run it: in a subprocess, in this process, or
outside this checkout."""

from __future__ import annotations

import contextlib
import io
import os
import signal
import subprocess
import sys
from pathlib import Path


def run_gcs(*args: str, timeout: float = 300) -> subprocess.CompletedProcess[str]:
    """``python -m gcs ARGS`` in a subprocess, output captured, never raising on exit status."""
    return subprocess.run([sys.executable, "-m", "gcs", *args], capture_output=True, text=True,
                          timeout=timeout, check=False)


def gcs_here(*args: str) -> subprocess.CompletedProcess[str]:
    """``gcs ARGS`` run by the command line's own ``main`` in this process, its output and
    exit status captured as :func:`run_gcs` gives them.

    For tests of what a command computes and says (an analysis, a report, a refusal): a
    subprocess spent about a second of CPU starting Python and loading the kernels before
    it did anything, some sixty times a suite. Where the process is the subject (its exit,
    signals, what reaches a terminal), :func:`run_gcs`.
    """
    from gcs.cli import main

    out, err = io.StringIO(), io.StringIO()
    handlers = {sig: signal.getsignal(sig) for sig in (signal.SIGINT, signal.SIGTERM)}
    try:
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            try:
                code = main(list(args))
            except SystemExit as exc:  # argparse's usage errors
                code = exc.code if isinstance(exc.code, int) else int(exc.code is not None)
    finally:
        for sig, handler in handlers.items():  # main() makes them raise KeyboardInterrupt
            if handler is not None:  # None: set outside Python, left as main() made it
                signal.signal(sig, handler)
    return subprocess.CompletedProcess(["gcs", *args], code, out.getvalue(), err.getvalue())


def run_outside(cmd: list[str], cwd: Path,
                timeout: float = 180) -> subprocess.CompletedProcess[str]:
    """``cmd`` in ``cwd`` without this checkout's PYTHONPATH or venv, output captured."""
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "VIRTUAL_ENV")}
    return subprocess.run(cmd, cwd=cwd, env=env, capture_output=True, text=True,
                          timeout=timeout, check=False)
