"""The GCS process, assembled: links, clock, operator, recorder and the 4 Hz loop.

``gcs run``, ``gcs demo`` and ``gcs fly`` all build one :class:`GcsApp` from a
team config; they differ only in where the vehicles are and which clock runs.
With ``sim_clock`` the loop follows the simulator's clock (and, with
``lockstep``, acknowledges every tick so the simulator never runs ahead of the
guidance: a headless flight is then deterministic and as fast as the machine).
Joining a simulator started elsewhere, the GCS reads from its clock whether it
is in lockstep (:mod:`gcs.app._simjoin`); a lockstep simulator follows one GCS,
its partner, and one that names another stops this GCS's clock.
"""

from __future__ import annotations

import dataclasses
import functools
import gc
import secrets
import sys
import threading
import time
from collections.abc import Callable, Iterable
from pathlib import Path

import zenoh

from gcs.analysis import analyze, safe_guidance
from gcs.app._simjoin import ClockProbe
from gcs.common import join_thread
from gcs.config import Team, seal_key
from gcs.flightlog import TlogRecorder
from gcs.link import Link, LinkManager, Presence, PresenceEvent
from gcs.loop import (
    HOLD_CAP_S,
    Clock,
    ExternalClock,
    OperatorCommand,
    Runtime,
    RuntimeSnapshot,
    StepGate,
    WallClock,
)
from gcs.transport import Arrivals, FrameDirection, ZenohSettings, bounded_payload, open_session
from gcs.wire import (
    CLOCK_MAX_BYTES,
    SEAL_OVERHEAD,
    TRUTH_MAX_BYTES,
    ClockGuard,
    ClockSample,
    ClockVerdict,
    MavlinkEncoder,
    MavMessage,
    Sealer,
    SealError,
    SimTruth,
    Unsealer,
    decode_clock,
    encode_ack,
    keys,
    mavlink,
)

__all__ = ["LOOP_GIL_SWITCH_S", "GcsApp"]


SIM_CLOCK_TIMEOUT_S = HOLD_CAP_S + 5.0
"""Wall time without the simulator clock advancing after which the loop stops, s: longer
than a lockstep window may hold the sim (``HOLD_CAP_S``), so a phase action that keeps a
window open to its cap (commands to a dead vehicle, retried in wall time) does not read
as a dead simulator."""

CLOCK_NOTE_PERIOD_S = 5.0
"""At most one event about refused clock samples per this much wall time, s."""

ECHO_WAIT = 1.0
"""Longest wall time a lockstep ack waits for a vehicle's setpoint echoes, s. Long, so that
a loaded or briefly frozen machine (a VM's hypervisor stalls it in bursts:
docs/performance.md, "The machine") still acks only once the sim has the setpoints; only
vehicles heard from since the last ack are waited for, so a dead or cut-off vehicle costs
nothing (:class:`_EchoCounter`)."""


class _EchoCounter:
    """Counts setpoints sent to and echoed by each vehicle (lockstep ordering)."""

    def __init__(self, links: Iterable[Link]) -> None:
        self._cond = threading.Condition()
        self._sent: dict[int, int] = {}
        self._echoed: dict[int, int] = {}
        self._heard: set[int] = set()  # vehicles that sent anything since the last wait
        for link in links:
            sysid = link.sysid
            self._sent[sysid] = self._echoed[sysid] = 0
            link.add_frame_listener(functools.partial(self._on_frame, sysid))
            link.add_message_listener(functools.partial(self._on_message, sysid))

    def _on_frame(self, sysid: int, direction: FrameDirection, frame: bytes) -> None:
        if direction is FrameDirection.OUT and _msgid(frame) == _SETPOINT_ID:
            with self._cond:
                self._sent[sysid] += 1

    def _on_message(self, sysid: int, msg: MavMessage) -> None:
        with self._cond:
            self._heard.add(sysid)
            if msg.get_type() == "POSITION_TARGET_LOCAL_NED":
                self._echoed[sysid] += 1
                self._cond.notify_all()

    def wait(self, timeout: float) -> bool:
        """Block until every vehicle heard from since the last wait has echoed every setpoint
        sent to it (True), or ``timeout`` passed.

        A lockstep vehicle sends telemetry every sim period, so one not heard from
        is dead or cut off: it is not waited for. Echoes still missing when this
        returns are written off, so a vehicle that comes back, or that refused a
        setpoint (no echo), is counted afresh from then on.
        """
        with self._cond:
            waited = [s for s in self._sent if s in self._heard]
            done = self._cond.wait_for(
                lambda: all(self._echoed[s] >= self._sent[s] for s in waited), timeout)
            for s in self._sent:
                self._echoed[s] = max(self._echoed[s], self._sent[s])
            self._heard.clear()
            return done


_SETPOINT_ID = mavlink.MAVLINK_MSG_ID_SET_POSITION_TARGET_LOCAL_NED


def _msgid(frame: bytes) -> int:
    """Message id from a MAVLink 2 frame header (-1 for anything else)."""
    if len(frame) < 10 or frame[0] != 0xFD:
        return -1
    return frame[7] | frame[8] << 8 | frame[9] << 16


LOOP_GIL_SWITCH_S = 1e-4
"""Longest another thread keeps the GIL once the loop wants it, s (Python's default: 5 ms).

Receive threads decode every vehicle's telemetry; with a hundred vehicles the
default lets them hold the loop back, and its tick jitter with it (figures:
docs/performance.md, bench/gcs_tick.py). The sim host sets the same for its receive
threads."""


class GcsApp:
    """Everything one GCS process runs for one team.

    Args:
        team: the loaded team.
        zenoh_settings: how to join zenoh (default: the team's ``gcs.zenoh``).
        sim_clock: follow the simulator's clock instead of the wall clock.
        lockstep: acknowledge each tick on the sim clock (with ``sim_clock``); None: if
            the simulator's clock says it is in lockstep, as a GCS joining a simulator
            started elsewhere does (refused at once, a ConfigError on ``--connect``, where
            that cannot be sound: :class:`gcs.app._simjoin.ClockProbe`).
        record: .tlog file to record to, or None.
        override_analysis: fly although ``gcs analyze`` refuses the team (a warning event
            names every violation).
    """

    def __init__(self, team: Team, *, zenoh_settings: ZenohSettings | None = None,
                 sim_clock: bool = False, lockstep: bool | None = False,
                 record: str | Path | None = None, override_analysis: bool = False) -> None:
        cfg = team.config
        self.team = team
        self.fleet = cfg.gcs.fleet
        # relative TLS paths are the team file's, wherever the GCS is started from
        settings = (zenoh_settings or cfg.gcs.zenoh).resolved(Path(team.source).parent)
        self.session: zenoh.Session = open_session(settings)
        self._subs: list[zenoh.Subscriber] = []
        self._closed = False
        self.truth: SimTruth | None = None
        self._truth_arrivals = Arrivals()
        self.truth_errors = 0
        """Truth samples refused: malformed or longer than ``TRUTH_MAX_BYTES``."""
        self.clock_errors = 0
        """Clock samples refused as malformed or longer than ``CLOCK_MAX_BYTES``."""
        self.clock_refused = 0
        """Clock samples refused by the guard: backwards, too far ahead (:class:`ClockGuard`)."""
        self._clock_guard = ClockGuard()
        key = seal_key(cfg.gcs, Path(team.source).parent)
        self._open_clock = Unsealer(key, keys.clock(self.fleet))
        self._open_truth = Unsealer(key, keys.sim(self.fleet, "truth"))
        self._seal_ack = Sealer(key, keys.clock_ack(self.fleet))
        self._clock_noted: float | None = None  # wall time of the last event about them
        self.clock: Clock
        self._ack: zenoh.Publisher | None = None
        self._last_ack: bytes | None = None
        self._probe: ClockProbe | None = None  # joining: the first clock samples
        self._partner = secrets.randbits(32) or 1  # lockstep: this GCS's id in its acks
        self._partnered = True  # lockstep: the simulator names no other partner
        if sim_clock:
            ext = ExternalClock(timeout=SIM_CLOCK_TIMEOUT_S)
            self.clock = ext
            if lockstep is None:
                self._probe = ClockProbe(", ".join(settings.connect) or "the zenoh fabric")
            self._subs.append(self.session.declare_subscriber(keys.clock(self.fleet),
                                                              self._on_clock))
            if self._probe is not None:
                try:
                    lockstep = self._probe.judge()
                except BaseException:
                    self.session.close()
                    raise
                self._probe = None
            if lockstep:
                self._ack = self.session.declare_publisher(
                    keys.clock_ack(self.fleet), congestion_control=zenoh.CongestionControl.BLOCK,
                    priority=zenoh.Priority.REAL_TIME, express=True)
        else:
            self.clock = WallClock()
        self._subs.append(self.session.declare_subscriber(keys.sim(self.fleet, "truth"),
                                                          self._on_truth))
        self.runtime: Runtime | None = None
        self._early_notes: list[tuple[str, str]] = []  # link notes before the runtime exists
        self._notes_lock = threading.Lock()
        self.links = LinkManager(cfg.vehicle_links(),
                                 settings=dataclasses.replace(cfg.gcs, zenoh=settings),
                                 base_dir=Path(team.source).parent, session=self.session,
                                 clock=self.clock.now, on_presence=self._on_presence,
                                 on_note=self._note)
        analysis = analyze(team)
        self.operator = OperatorCommand(cfg.operator, safe_guidance(team, analysis),
                                        now=self.clock.now())
        self.recorder: TlogRecorder | None = None
        if record is not None:
            encoder = MavlinkEncoder(system_id=cfg.gcs.system_id,
                                     component_id=cfg.gcs.component_id)
            self.recorder = TlogRecorder(record, encoder=encoder,
                                         epoch=time.time() - self.clock.now())
        self.gate = StepGate(enabled=self._ack is not None)
        """In lockstep, phase actions and a scenario act only at ticks (gcs.loop._stepgate)."""
        if self.gate.enabled:
            for link in self.links.links.values():
                link.set_pause(self.gate.pause)
        runtime = Runtime(team, self.links.profiles, self.clock, self.operator,
                          recorder=self.recorder, analysis=analysis,
                          truth_source=lambda: self.truth,
                          setpoints_per_tick=1 if lockstep else None, gate=self.gate)
        if override_analysis and not analysis.ok:
            runtime.analysis_override = True
            self._early_notes += [("warning", f"flying a team the analysis refuses "
                                              f"(overridden): {v.term}: {v.message}")
                                  for v in analysis.violations]
        with self._notes_lock:  # the notes that came first are shown first
            for level, text in self._early_notes:
                runtime.note(level, text)
            self._early_notes.clear()
            self.runtime = runtime
        if self._ack is not None:
            self._echo = _EchoCounter(self.links.links.values())
            self.runtime.add_listener(lambda snap: self._send_ack(snap.fleet.t))
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None

    @property
    def loop(self) -> Runtime:
        """:attr:`runtime`, which is None only while ``__init__`` builds the links."""
        assert self.runtime is not None, "the runtime is built in __init__"
        return self.runtime

    def _on_presence(self, event: PresenceEvent) -> None:
        self._note("info" if event.presence is Presence.APPEARED else "warning", event.text)

    def _note(self, level: str, text: str) -> None:
        """An event from the links (any thread); kept until the runtime exists to show it."""
        with self._notes_lock:
            if self.runtime is None:
                self._early_notes.append((level, text))
                return
        self.runtime.note(level, text)

    @property
    def lockstep(self) -> bool:
        """Whether this GCS acknowledges every tick of the simulator's clock."""
        return self._ack is not None

    def _on_clock(self, sample: zenoh.Sample) -> None:
        if getattr(self, "runtime", None) is None:
            probe = self._probe
            if probe is not None:  # joining: what kind of simulator is it?
                clock = self._read_clock(sample)
                if clock is not None:
                    probe.add(clock)
            return  # still being built (no links yet): the sim repeats its clock anyway
        clock = self._read_clock(sample)
        if clock is None or not self._partnered:
            return
        if self._ack is not None and clock.partner not in (None, self._partner):
            self._not_the_partner(clock.partner)
            return
        t = clock.t
        assert isinstance(self.clock, ExternalClock)
        last = self._clock_guard.last
        verdict = self._clock_guard.check(t)
        if not verdict.accepted:
            # Anyone can publish on the clock key: a forged sample must not throw the
            # clock years ahead (a follower's clock never comes back).
            self.clock_refused += 1
            self._note_refused_clock(t, last, verdict.value)
            return
        if verdict is ClockVerdict.REANCHORED:
            self._note("warning", f"the simulator clock leapt from t = {last:.3f} s to "
                                  f"{t:.3f} s: following it")
        if self._ack is not None and clock.truth is not None:
            # Lockstep: the tick at t reads every payload and truth sample sent before t, on
            # every run (the clock can overtake them: another priority, another thread).
            self.links.wait_received(clock.sent, ECHO_WAIT)
            self._truth_arrivals.wait({"truth": clock.truth}, ECHO_WAIT)
        if self._ack is not None and t <= self.clock.now() and self._last_ack is not None:
            # A repeated sample: the sim is waiting; our ack may have been lost (sealed
            # anew: the same sealed bytes again would be a replay).
            self._ack.put(self._seal_ack.seal(self._last_ack))
        self.clock.advance(t)

    def _read_clock(self, sample: zenoh.Sample) -> ClockSample | None:
        """The clock sample in ``sample``, or None (counted) if refused or malformed."""
        data = bounded_payload(sample, CLOCK_MAX_BYTES + SEAL_OVERHEAD)
        try:
            if data is None:
                raise ValueError(f"{len(sample.payload)} bytes")
            data = self._open_clock.open(data)
        except SealError as exc:
            # Anyone can publish on the clock key: without the team key's seal a sample
            # is a stranger's, and never moves the clock.
            self.clock_refused += 1
            self._note_refused_clock(None, self._clock_guard.last, str(exc))
            return None
        except ValueError:
            self.clock_errors += 1
            return None
        try:
            return decode_clock(data)
        except ValueError:
            self.clock_errors += 1
            return None

    def _not_the_partner(self, partner: int) -> None:
        """The lockstep simulator follows another GCS's acks: stop, naming why (flying on,
        this GCS would command the vehicles beside the one the simulator follows)."""
        self._partnered = False
        why = (f"the simulator is in lockstep with another GCS (partner {partner:08x}, this "
               f"one {self._partner:08x}), and a lockstep simulator follows one GCS: give "
               f"each flight a simulator of its own")
        self._note("error", why)
        assert isinstance(self.clock, ExternalClock)
        self.clock.close(why)

    def _note_refused_clock(self, t: float | None, last: float | None, why: str) -> None:
        """An event for the first refused clock sample, then at most one per period."""
        now = time.monotonic()
        if self._clock_noted is not None and now - self._clock_noted < CLOCK_NOTE_PERIOD_S:
            return
        self._clock_noted = now
        following = "nothing yet" if last is None else f"t = {last:.3f} s"
        sample = "" if t is None else f" t = {t:g} s"
        self._note("warning", f"refused simulator clock sample{sample} ({why}; following "
                              f"{following}; {self.clock_refused} refused so far)")

    def _send_ack(self, t: float) -> None:
        """Let the sim run the next period, once it has taken this tick's setpoints.

        Zenoh delivers different keys on different callback threads, so an ack
        could overtake the setpoints it follows; the vehicles' echoes of the
        setpoints (POSITION_TARGET_LOCAL_NED) prove they arrived. A missing echo costs
        at most ``ECHO_WAIT`` of wall time, never a stall.
        """
        assert self._ack is not None
        self._echo.wait(ECHO_WAIT)
        self._last_ack = encode_ack(t, self._partner)
        if self._partnered:
            self._ack.put(self._seal_ack.seal(self._last_ack))

    def _on_truth(self, sample: zenoh.Sample) -> None:
        data = bounded_payload(sample, TRUTH_MAX_BYTES + SEAL_OVERHEAD)
        try:
            if data is None:
                raise ValueError(f"{len(sample.payload)} bytes")
            self.truth = SimTruth.from_bytes(self._open_truth.open(data))
        except ValueError:
            self.truth_errors += 1  # dropped; the next sample replaces it
        self._truth_arrivals.arrived("truth")

    def add_listener(self,
                     callback: Callable[[RuntimeSnapshot, SimTruth | None], None]) -> None:
        """Call ``callback(snapshot, snapshot.truth)`` after every tick (loop thread: be quick)."""
        self.loop.add_listener(lambda snap: callback(snap, snap.truth))

    @property
    def snapshot(self) -> RuntimeSnapshot | None:
        return self.loop.snapshot

    def start(self) -> None:
        """Run the loop on its own thread (and let it take the GIL back quickly).

        Everything built so far (numpy, scipy, numba, zenoh, the links) is moved
        out of the garbage collector's sight first (``gc.freeze``): a full
        collection then walks only what the flight allocates, not the hundreds
        of thousands of start-up objects, and pauses every thread for less.
        """
        gc.collect()
        gc.freeze()
        sys.setswitchinterval(min(sys.getswitchinterval(), LOOP_GIL_SWITCH_S))
        self._thread = threading.Thread(target=self.loop.run, args=(self._stop,),
                                        daemon=True, name="gcs-loop")
        self._thread.start()

    def close(self) -> None:
        """Stop the loop, close links, the recorder and zenoh; idempotent."""
        if self._closed:
            return
        self._closed = True
        self._stop.set()
        if isinstance(self.clock, ExternalClock):
            self.clock.close()
        join_thread(self._thread, 3.0, what="the GCS loop")
        self.loop.close()
        self.links.close()
        if self.recorder is not None:
            self.recorder.close()
        for sub in self._subs:
            sub.undeclare()
        self.session.close()

    def __enter__(self) -> GcsApp:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
