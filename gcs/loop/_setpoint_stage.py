"""The loop's setpoint stage: each vehicle's altitude target, and the stream to the team.

The guidance's accelerations go to the link layer's
:class:`~gcs.link.SetpointStream` with each vehicle's altitude target: the
operator's altitude under the geofence's ceiling, trimmed by load sharing.
Between ticks the stream re-sends the latest setpoints
(``guidance.setpoint_rate_hz``) on a wall-clock deadline of its own, so a late
tick (a busy machine, a slow page, a garbage collection) never leaves a vehicle
half a second without a setpoint, which sends it into hold. A setpoint re-sent
more than :data:`HELD_SETPOINT_S` after its tick is replaced by velocity damping
(the tick's shape-keeping terms are out of date by then). In lockstep with the
simulator the sim cannot outrun the loop, and re-sends would arrive at sim
times that vary from run to run, so there each tick sends once.
"""

from __future__ import annotations

import threading
from collections.abc import Callable

import numpy as np

from gcs.config import Team
from gcs.link import SetpointStream
from gcs.loop._clock import Clock
from gcs.loop._events import EventLog
from gcs.loop._fleet import FleetTable
from gcs.loop._guidance_stage import GuidanceStage
from gcs.loop._operator import OperatorCommand, OperatorSnapshot
from gcs.loop._phases import Phase

__all__ = ["HELD_SETPOINT_S", "SetpointStage"]

HELD_SETPOINT_S = 1.0
"""Longest a tick's acceleration setpoint is re-sent, s of the loop's clock; past it, a late
loop's re-sends damp velocity only."""


class SetpointStage:
    """Sends each tick's setpoints and re-sends them between ticks.

    Args:
        phase: the phase now (re-sends stop as soon as it stops streaming).
        handing_over: whether a take-off is switching the vehicles to their streaming
            mode (the loop streams meanwhile).
        trims: each vehicle's load-sharing altitude trim now (None: off).
    """

    def __init__(self, team: Team, stream: SetpointStream, *, clock: Clock,
                 operator: OperatorCommand, fleet_table: FleetTable, guidance: GuidanceStage,
                 events: EventLog, phase: Callable[[], Phase], handing_over: Callable[[], bool],
                 trims: Callable[[], np.ndarray | None]) -> None:
        self._team = team
        self.stream = stream
        self._clock = clock
        self._operator = operator
        self._fleet_table = fleet_table
        self._guidance = guidance
        self._events = events
        self._phase = phase
        self._handing_over = handing_over
        self._trims = trims
        self._streamed: np.ndarray | None = None  # (n, 2) the last tick's setpoints, if any
        self._streamed_at = 0.0  # the loop's time of that tick

    def streams(self, phase: Phase) -> bool:
        """Whether the loop sends setpoints in ``phase`` (and during the offboard handover)."""
        return phase.streaming or (phase is Phase.TAKING_OFF and self._handing_over())

    def altitude(self, op: OperatorSnapshot) -> float:
        """The team's altitude target: the operator's, never above the geofence's ceiling."""
        return min(op.altitude, self._team.config.safety.geofence_altitude)

    def hold_back(self) -> None:
        """A tick is computing its setpoints: re-send nothing of the last one meanwhile."""
        self._streamed = None

    def send(self, now: float, accel: np.ndarray, op: OperatorSnapshot) -> None:
        """This tick's setpoints: ``accel`` (n, 2) and the operator's altitude."""
        self.stream.send(accel, self._altitudes(-self.altitude(op)))
        self._streamed, self._streamed_at = accel, now

    def stop(self) -> None:
        """No setpoints this tick: the next stream starts afresh (no gap to measure)."""
        self.stream.stop()

    def refresh(self) -> tuple[np.ndarray, np.ndarray] | None:
        """What a re-send sends now (None: the last tick streamed none, or the phase
        stopped streaming since): the last tick's accelerations, or velocity damping on
        the latest telemetry once they are :data:`HELD_SETPOINT_S` old, with the altitude
        target's ramp moved on."""
        accel = self._streamed
        if accel is None or not self.streams(self._phase()):
            return None
        now = self._clock.now()
        if now - self._streamed_at > HELD_SETPOINT_S:
            accel = self._guidance.damping(self._fleet_table.read(now))
        return accel, self._altitudes(-self.altitude(self._operator.snapshot(now)))

    def resend_until(self, stop: threading.Event, *, per_tick: int,
                     period: float) -> Callable[[], None]:
        """Start re-sending ``per_tick - 1`` times between ticks of ``period`` s (none for
        1), until ``stop`` is set or the returned call ends it."""
        if per_tick <= 1:
            return lambda: None
        done = threading.Event()
        keeper = threading.Thread(target=self.stream.resend_while, args=(self.refresh,),
                                  kwargs={"slot": period / per_tick, "done": done,
                                          "stop": stop, "on_error": self._on_resend},
                                  daemon=True, name="gcs-setpoints")
        keeper.start()

        def end() -> None:
            done.set()
            keeper.join(timeout=1.0)
        return end

    def _altitudes(self, z_ned: float) -> np.ndarray:
        """Each vehicle's altitude target, z NED: trimmed by load sharing, never above the
        geofence's ceiling."""
        vertical = np.full(len(self._team.formation.ids), z_ned)
        trims = self._trims()
        if trims is not None:
            ceiling = -self._team.config.safety.geofence_altitude
            vertical = np.maximum(vertical + trims, min(z_ned, ceiling))
        return vertical

    def _on_resend(self, exc: Exception | None) -> None:
        if exc is None:
            self._events.unlatch(("resend", 0))
        else:
            self._events.warn_once(("resend", 0), f"setpoint re-send failed: "
                                                  f"{type(exc).__name__}: {exc}")
