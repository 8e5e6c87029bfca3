"""``gcs --help`` and ``python -m gcs --help`` list the seven commands the README names."""

from __future__ import annotations

import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

import pytest

from gcs.cli import main
from tests.support.commands import run_gcs
from tests.support.paths import ROOT

COMMANDS = {"analyze", "sim", "run", "demo", "fly", "replay", "report", "key", "certs"}


def listed(help_text: str) -> set[str]:
    """The commands argparse lists under ``COMMAND``: the first word of each line
    indented by exactly four spaces (a wrapped description is indented further)."""
    lines = help_text.splitlines()
    names = set()
    for line in lines[lines.index("  COMMAND") + 1:]:
        if not line.startswith("    "):
            break
        if line[4] != " ":
            names.add(line.split()[0])
    return names


def gcs_script(*args: str) -> subprocess.CompletedProcess[str]:
    """The ``gcs`` console script that pip installed beside this interpreter."""
    script = Path(sys.executable).with_name("gcs")
    assert script.is_file(), f"{script}: not installed (pip install -e .)"
    return subprocess.run([str(script), *args], capture_output=True, text=True, timeout=60,
                          check=False)


@pytest.mark.parametrize("run", [gcs_script, run_gcs], ids=["gcs", "python -m gcs"])
def test_help_lists_every_command(
        run: Callable[..., subprocess.CompletedProcess[str]]) -> None:
    out = run("--help")
    assert out.returncode == 0, out.stderr
    assert listed(out.stdout) == COMMANDS, out.stdout


def test_the_readme_table_names_the_same_commands() -> None:
    readme = ROOT / "README.md"
    rows = [line for line in readme.read_text().splitlines() if line.startswith("| `gcs ")]
    assert {row.split()[2] for row in rows} == COMMANDS


@pytest.mark.parametrize("command", sorted(COMMANDS))
def test_each_command_has_its_own_help(command: str,
                                       capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as info:
        main([command, "--help"])
    assert info.value.code == 0
    assert capsys.readouterr().out.startswith(f"usage: gcs {command} ")


@pytest.mark.parametrize("command", ["run", "demo"])
def test_the_gamepad_help_names_both_default_mappings(command: str,
                                                      capsys: pytest.CaptureFixture[str]) -> None:
    """As web._launch.default_gamepad reads them: the directory's own, else the shipped one."""
    with pytest.raises(SystemExit):
        main([command, "--help"])
    text = " ".join(capsys.readouterr().out.split())
    assert "configs/gamepad.yaml in the current directory, else the shipped one" in text, text



def test_a_simulator_that_cannot_start_is_one_line(monkeypatch: pytest.MonkeyPatch,
                                                   capsys: pytest.CaptureFixture[str]) -> None:
    """A simulator that dies before it is ready was a SimStartError traceback from
    ``gcs fly``, ``gcs demo``: now one line and exit 1. Here a real simulator process
    refuses an option, inside the command's own flight function."""
    import gcs.app
    from gcs.app import SimProcess, free_tcp_port
    from gcs.cli import main

    def fly(team: object, *args: object, **kwargs: object) -> None:
        SimProcess("configs/bebop_square.yaml", endpoint=f"tcp/127.0.0.1:{free_tcp_port()}",
                   extra=("--no-such-option",))

    monkeypatch.setattr(gcs.app, "fly", fly)
    code = main(["fly", "--config", "configs/bebop_square.yaml", "--scenario",
                 "configs/scenarios/short_flight.yaml"])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 1
    assert len(err) == 1 and err[0].startswith("gcs fly: error: the simulator exited before "
                                               "it was ready: "), err
    assert "--no-such-option" in err[0]
