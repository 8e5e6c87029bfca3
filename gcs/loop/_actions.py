"""The operator's phase actions, run off the loop: arm, take off, lift, land, resume, abort.

Actions that wait for acknowledgements run on a worker thread, so the 4 Hz loop
never waits on a vehicle; one runs at a time (a second is refused with a
PhaseError), and an abort never waits for one. In lockstep with the simulator
they act only at ticks (:class:`~gcs.loop.StepGate`).
"""

from __future__ import annotations

import functools
import threading
import time
from collections.abc import Callable, Mapping, Sequence
from concurrent.futures import ThreadPoolExecutor

from gcs.config import Team
from gcs.link import AutopilotProfile
from gcs.loop._clock import Clock
from gcs.loop._events import EventLog
from gcs.loop._fleet import FleetTable
from gcs.loop._operator import OperatorCommand
from gcs.loop._phase_machine import PhaseMachine
from gcs.loop._phases import Action, Phase, PhaseError
from gcs.loop._prearm import Prearm, PrearmError
from gcs.loop._reached import AltitudeReached
from gcs.loop._stepgate import StepGate
from gcs.loop._vehicle_modes import VehicleModes

__all__ = ["ActionRunner"]


class ActionRunner:
    """Starts and runs the phase actions of one team (see the module's docstring)."""

    def __init__(self, team: Team, profiles: Mapping[int, AutopilotProfile], *,
                 fleet_table: FleetTable, clock: Clock, operator: OperatorCommand,
                 gate: StepGate, prearm: Prearm, phases: PhaseMachine, events: EventLog,
                 modes: VehicleModes) -> None:
        self._team = team
        self._ids = team.formation.ids
        self._profiles = profiles
        self._fleet_table = fleet_table
        self._clock = clock
        self._operator = operator
        self._gate = gate
        self._prearm = prearm
        self._phases = phases
        self._events = events
        self._modes = modes
        # An action and its step per vehicle, twice: the loop may start a landing while an
        # action is stuck. Fewer and a vehicle's step would queue behind the others (in
        # lockstep, holding every tick's window until the gate's cap).
        self._pool = ThreadPoolExecutor(max_workers=2 * (len(self._ids) + 1),
                                        thread_name_prefix="gcs-action")
        self._busy = threading.Lock()
        self.handing_over = False
        """Taking off: the vehicles are switching to their streaming mode (the loop
        streams setpoints meanwhile)."""

    @property
    def running(self) -> bool:
        """Whether an action is still running."""
        return self._busy.locked()

    def request(self, action: Action) -> None:
        """Start ``action``; returns at once. PhaseError if the phase does not allow it."""
        if action is Action.ABORT:
            self.abort()
            return
        target = self._phases.target(action)
        if action in (Action.LIFT, Action.SET_DOWN):
            # target altitude first: a tick between the two would find the old one
            # reached and end the phase at once
            now = self._clock.now()
            base = self._team.taut_altitude(self._operator.snapshot(now).demand.scale)
            flight = self._team.config.flight
            height = base + (flight.lift_height if action is Action.LIFT
                             else -flight.takeoff_slack)
            below, above = flight.pickup_band
            self._operator.set_altitude(height, now=self._clock.now(), rate=flight.lift_rate,
                                        slow=(base - below, base + above, flight.pickup_rate))
            self._phases.set(target)
            return
        if not self._busy.acquire(blocking=False):
            raise PhaseError(f"cannot {action.text}: another action is still running")
        self._gate.submit(self._pool, self._run, action, target)

    def abort(self) -> None:
        """Freeze the motion and start the hold, unless already aborting or landing: the
        sticks are centred either way; a refused abort (PhaseError) changes nothing."""
        now = self._clock.now()
        started = self._phases.start_abort(now)
        self._operator.release(now=now, source="abort")
        if started is not None:
            self._phases.announce(started)

    def try_start(self, action: Action, target: Phase, *, say: str = "") -> bool:
        """Start ``action`` unless another one runs (then False); ``say``: its event."""
        if not self._busy.acquire(blocking=False):
            return False
        if say:
            self._events.add("info", say)
        self._gate.submit(self._pool, self._run, action, target)
        return True

    def land(self) -> None:
        """The abort's hold is over: land, directly if an action is stuck."""
        if not self.try_start(Action.LAND, Phase.LANDING):
            self._gate.submit(self._pool, functools.partial(
                self.for_all, "land", lambda p: p.land(), quiet=True))

    def for_all(self, what: str, fn: Callable[[AutopilotProfile], None], *,
                quiet: bool = False, only: Sequence[int] | None = None) -> None:
        """Run ``fn`` on every vehicle (or those with ids ``only``) in parallel; raise one
        error naming every failure."""
        ids = self._ids if only is None else tuple(only)
        outcomes = self._gate.map(self._pool, fn, [self._profiles[vid] for vid in ids])
        failures = [f"vehicle {vid}: {exc}" for vid, exc in zip(ids, outcomes, strict=True)
                    if exc is not None]
        if failures and not quiet:
            raise RuntimeError(f"{what}: " + "; ".join(failures))

    def close(self) -> None:
        """Stop the worker threads (an action under way is abandoned)."""
        self._pool.shutdown(wait=False, cancel_futures=True)

    def _run(self, action: Action, target: Phase) -> None:
        try:
            if action is Action.ARM:
                self._prearm.check(lambda: self._fleet_table.read(self._clock.now()),
                                   scale=self._operator.snapshot(self._clock.now()).demand.scale)
                self.for_all("arm", lambda p: p.arm())
                self._phases.set(target)
            elif action is Action.DISARM:
                self.for_all("disarm", lambda p: p.disarm())
                self._phases.set(target)
            elif action is Action.TAKEOFF:
                self._takeoff()
            elif action is Action.LAND:
                self._phases.set(target)
                self.for_all("land", lambda p: p.land())
            elif action is Action.RESUME:
                self._resume()
        except Exception as exc:  # report, never kill the worker
            self._events.add("error", f"{action.text} failed: {exc}")
            if action is Action.ARM and not isinstance(exc, PrearmError):  # none armed
                self.for_all("disarm", lambda p: p.disarm(), quiet=True)
                self._phases.set(Phase.READY)
        finally:
            self._busy.release()

    def _resume(self) -> None:
        """Switch back to the streaming mode the vehicles that left it while still flying.

        A vehicle coming down on its own (landing, disarmed) is not resumed: that
        one lands the team (gcs.loop._safety).
        """
        fleet = self._fleet_table.read(self._clock.now())
        out = self._modes.out_flying(self._ids, fleet.modes, self._modes.coming_down(fleet))
        if not out:
            self._events.add("info", "resume: every flying vehicle is in its streaming mode "
                                     "already")
            return
        z = -self._operator.snapshot(self._clock.now()).altitude
        self.for_all("resume", lambda p: p.start_offboard(z_ned=z), only=out)
        for vid in out:
            self._events.add("info", f"resume: vehicle {vid} back in "
                                     f"{self._profiles[vid].streaming_mode}")

    def _takeoff(self) -> None:
        cfg = self._team.config.flight
        self._phases.set(Phase.TAKING_OFF)
        scale = self._operator.snapshot(self._clock.now()).demand.scale
        h0 = self._team.taut_altitude(scale) - cfg.takeoff_slack
        self.for_all("take off", lambda p: p.takeoff(altitude_m=h0))
        deadline = time.monotonic() + cfg.takeoff_timeout
        reached = AltitudeReached()
        while True:
            fleet = self._fleet_table.read(self._clock.now())
            if reached.update(-fleet.p_ned[:, 2], h0, cfg.altitude_tolerance):
                break
            if self._phases.phase is not Phase.TAKING_OFF:
                return  # aborted meanwhile
            if time.monotonic() > deadline:
                low = [vid for vid, m in zip(self._ids, reached.missing(), strict=True) if m]
                raise RuntimeError(f"vehicles {low} did not reach {h0:.2f} m in "
                                   f"{cfg.takeoff_timeout:g} s")
            for vid in self._ids:
                self._profiles[vid].keep_climbing()
            if not self._gate.pause():
                time.sleep(0.02)
        self._operator.reset_altitude(h0, now=self._clock.now())
        # The loop streams from here on: a vehicle confirmed in offboard must not wait
        # for the slowest one's confirmation without setpoints (on a loaded machine its
        # 0.5 s timeout would send it to hold).
        self.handing_over = True
        try:
            self.for_all("offboard", lambda p: p.start_offboard(z_ned=-h0))
        finally:
            self.handing_over = False
        if self._phases.phase is Phase.TAKING_OFF:
            self._phases.set(Phase.HOVER)
