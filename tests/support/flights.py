"""A team flown against the real simulator, in lockstep, for tests in several folders:
in formation with the payload lifted, a vehicle broken through the simulator's control
key, sim time waited for, a ready team whose vehicle 3 banks beyond the team file."""

from __future__ import annotations

import contextlib
from collections.abc import Iterator

from gcs.app import GcsApp, SimProcess, free_tcp_port
from gcs.app._fly import CONTROL_ANSWER_S
from gcs.app._scenario import Scenario, Step, play
from gcs.config import Team, load_team
from gcs.loop import ClockStoppedError, Phase
from gcs.testing import SimTeam, team_key
from gcs.transport import ZenohSettings
from gcs.wire import Sealer, keys
from tests.support.paths import ROOT, SQUARE

SQUARE_FILE = ROOT / SQUARE
"""The paper's team, wherever the test runs from."""


@contextlib.contextmanager
def in_formation(team: Team | None = None, *, speed: str = "max") -> Iterator[GcsApp]:
    """``team`` (default the paper's square) in formation flight with the payload lifted, in
    lockstep with the real sim (``speed``: its pace; a page watched in a browser wants a
    pace a viewer sees)."""
    team = team or load_team(SQUARE)
    endpoint = f"tcp/127.0.0.1:{free_tcp_port()}"
    with SimProcess(team.source, endpoint=endpoint, speed=speed, lockstep=True), \
            GcsApp(team, zenoh_settings=ZenohSettings(connect=(endpoint,)), sim_clock=True,
                   lockstep=True) as app:
        app.start()
        runtime = app.runtime
        assert runtime is not None
        play(Scenario(name="up", steps=(Step(action="arm"), Step(action="takeoff"),
                                          Step(action="lift"))), runtime, app.clock)
        assert runtime.phase is Phase.FORMATION
        yield app


def break_vehicle(app: GcsApp, action: str, sysid: int) -> None:
    """Break vehicle ``sysid`` through the simulator's control queryable, which answers once
    the fault is queued: it then acts at the sim time the test reads next (a put could reach
    the simulator ticks later on a busy machine, and the test would time the wrong moment)."""
    topic = keys.sim(app.fleet, "control")
    sealed = Sealer(team_key(), topic).seal(
        f'{{"action": "{action}", "sysid": {sysid}}}'.encode())
    answers = [reply.ok.payload.to_bytes().decode()
               for reply in app.session.get(topic, payload=sealed, timeout=CONTROL_ANSWER_S)
               if reply.ok is not None]
    assert answers == ["queued"], f"{action} {sysid}: the simulator answered {answers}"


def sim_sleep(app: GcsApp, seconds: float) -> None:
    """Wait ``seconds`` of sim time; if the sim clock stops, fail with the loop's latest
    events (what the GCS was doing is the clue to why the lockstep stood still)."""
    try:
        app.clock.sleep_until(app.clock.now() + seconds)
    except ClockStoppedError as exc:
        latest = app.runtime.events()[-15:] if app.runtime is not None else []
        events = "\n".join(f"  {e.level}: {e.text}" for e in latest)
        raise AssertionError(f"{exc}; the GCS's latest events:\n{events}") from exc


RAISED = 30.0
"""Vehicle 3's bank limit, raised over the square's 20 degrees before the arm, degrees."""
TOO_STEEP = (f"vehicle 3: its tilt limit MPC_TILTMAX_AIR is {RAISED:g} degrees, above the "
             f"config's bank limit of 20 degrees (limits.bank_deg)")
"""What the checks before arming say of vehicle 3 once :func:`ready_with_vehicle_3_raised`."""


def ready_with_vehicle_3_raised(team: SimTeam) -> None:
    """Wait until ready, then raise vehicle 3's bank limit on the simulator (PARAM_SET, as
    another ground station would; the GCS hears the simulator's PARAM_VALUE)."""
    team.wait_for("ready")
    team.wait(1.5)
    assert prearm(team) == ()  # the shipped simulator and team file agree: nothing fails
    assert team.app.loop.profiles[3].set_tilt_limit_deg(RAISED) == RAISED
    team.wait(1.5)  # the ready checks run about once a second


def prearm(team: SimTeam) -> tuple[str, ...]:
    """The checks before arming that fail, as of the last tick."""
    snap = team.app.loop.snapshot
    assert snap is not None
    return snap.prearm
