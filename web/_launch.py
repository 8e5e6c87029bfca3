"""``gcs demo`` and ``gcs run``: a GCS with its page (and gamepad), until Ctrl-C.

* demo: starts the simulated team (``python -m sim`` at 1x on a free loopback
  port), a GCS on the wall clock (as with real vehicles) joined to it over
  embedded zenoh (peer mode, no router) and the page, in one command.
* run: the GCS on the wall clock for the vehicles its config's links reach (a
  ``gcs sim`` started by hand, or real autopilots), with its page.

Ctrl-C (or SIGTERM) stops the page, the gamepad, the GCS and the simulator,
in that order. The page binds 127.0.0.1 unless another host is asked for.
"""

from __future__ import annotations

import sys
import time
from collections.abc import Callable
from pathlib import Path

from gcs.app import GcsApp, SimProcess
from gcs.common import LOCAL_CONFIGS, default_config, stop_on_signals
from gcs.config import load_team, signing_line
from gcs.loop import Action, Gamepad, PhaseError, load_gamepad_config
from gcs.transport import ZenohSettings
from web._ui import WebUi

__all__ = ["DEFAULT_GAMEPAD", "default_gamepad", "run_demo", "run_gcs", "serve"]

DEFAULT_GAMEPAD = LOCAL_CONFIGS / "gamepad.yaml"
"""Gamepad mapping used when none is named (if the file exists), see :func:`default_gamepad`."""


def default_gamepad() -> Path:
    """configs/gamepad.yaml here, else the one beside the installed package.

    The same rule as the default team (``gcs.cli``): a project directory's own
    mapping wins, and ``gcs demo`` started from anywhere else still finds the
    shipped one (relative to the current directory alone, the pad would be silently
    off there).
    """
    return default_config(DEFAULT_GAMEPAD.name)


def _say(text: str) -> None:
    print(text, flush=True)


def _start_gamepad(app: GcsApp, mapping: Path | None,
                   may_steer: Callable[[], bool]) -> Gamepad | None:
    """The gamepad reader, or None (with a line saying why) when there is none to run.

    ``may_steer`` says when the pad may steer: while no browser holds control.
    """
    path = mapping if mapping is not None else default_gamepad()
    if mapping is None and not path.is_file():
        _say(f"gamepad: off ({path} not found)")
        return None
    config = load_gamepad_config(path)

    def request(action: Action) -> Callable[[], None]:
        def run() -> None:
            try:
                app.loop.request(action)
            except PhaseError as exc:
                _say(f"gamepad: {action.text} refused: {exc}")
        return run

    pad = Gamepad(config, app.operator, app.clock, on_abort=request(Action.ABORT),
                  on_resume=request(Action.RESUME), may_steer=may_steer,
                  on_fault=lambda text: app.loop.note("warning", text))
    try:
        pad.start()
    except RuntimeError as exc:
        _say(f"{exc}: gamepad off")
        return None
    _say(f"gamepad: mapping {path}; plug a pad in at any time (it steers while no browser "
         "holds control)")
    return pad


def serve(app: GcsApp, *, host: str, port: int, gamepad: Path | None, no_gamepad: bool,
          alive: Callable[[], bool] = lambda: True) -> int:
    """Run ``app`` with its page (and gamepad) until Ctrl-C or ``alive()`` turns False."""
    ui = WebUi(app, host=host, port=port)
    pad: Gamepad | None = None
    try:
        app.start()
        ui.start()
        if not no_gamepad:
            pad = _start_gamepad(app, gamepad,
                                 may_steer=lambda: not ui.browser_holds_control())
        _say(f"GCS page: {ui.url}  (Ctrl-C to stop)")
        while alive():
            time.sleep(0.5)
        _say("stopped: the simulator exited")
        return 1
    except KeyboardInterrupt:
        _say("stopping…")
        return 0
    finally:
        ui.close()
        if pad is not None:
            pad.close()


def run_demo(config: str, *, host: str, port: int, gamepad: Path | None,
             no_gamepad: bool, insecure: bool = False, override_analysis: bool = False) -> int:
    """Simulated team at real speed + GCS + page; blocks until stopped.

    The GCS runs on the wall clock, as ``gcs run`` does with real vehicles: its
    setpoints then keep their schedule even when the sim's clock samples queue
    up behind a busy machine's telemetry (on the sim clock they would not, and the
    vehicles would go into hold).
    """
    stop_on_signals()
    team = load_team(config)
    if insecure:
        team = team.without_signing()
    _say(signing_line(team.config.gcs, Path(team.source).parent))
    _say(f"starting the simulated team of {team.source}…")
    with SimProcess.on_free_port(team.source, speed="1", signing=team.config.gcs.signing,
                                 ready_timeout=180.0, progress=_say,
                                 fork_server=False) as sim:  # one simulator: no fork server
        _say(sim.ready_line)
        settings = ZenohSettings(mode="peer", connect=(sim.endpoint,))
        with GcsApp(team, zenoh_settings=settings, override_analysis=override_analysis) as app:
            code = serve(app, host=host, port=port, gamepad=gamepad, no_gamepad=no_gamepad,
                         alive=sim.alive)
        if code:
            print(" | ".join(sim.stderr_tail[-3:]), file=sys.stderr)
        return code


def run_gcs(config: str, *, host: str, port: int, record: Path | None,
            gamepad: Path | None, no_gamepad: bool, insecure: bool = False,
            override_analysis: bool = False) -> int:
    """GCS on the wall clock for the config's links + page; blocks until stopped."""
    stop_on_signals()
    team = load_team(config)
    if insecure:
        team = team.without_signing()
    _say(signing_line(team.config.gcs, Path(team.source).parent))
    with GcsApp(team, record=record, override_analysis=override_analysis) as app:
        if record is not None:
            _say(f"recording to {record}")
        return serve(app, host=host, port=port, gamepad=gamepad, no_gamepad=no_gamepad)
