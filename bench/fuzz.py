"""Fuzzing every entry point that takes bytes from the network: counts per entry point.

Why: anyone on the zenoh fabric, or on a vehicle's UDP port, can send anything,
and an entry point that trusts its bytes can be made to kill the simulator, throw
the GCS clock years ahead or print tracebacks (``docs/security.md``). The suite
fuzzes each entry point with ~10^4 generated inputs (``tests/fuzz/``,
hypothesis); this bench runs many more, from its own fast generators (random
bytes, mutated real samples and frames, hostile JSON, frames with good
checksums and random payloads), and checks the same properties for every input:

- no exception escapes, except the documented ``ValueError`` refusals of the
  parsers (control messages, clock samples, truth samples);
- no input takes longer than ``--max-input-s`` of CPU time (no hang; the first
  input of each entry point, which loads compiled kernels, is not timed);
- nothing is written to stderr (file descriptor 2, while the entry points run);
- every refusal is counted: a decoder that gives no message for non-empty
  bytes moved one of its counters, a refused telemetry message is counted by
  its store, a refused parse is a ValueError.

Entry points: ``sim_control`` (:func:`sim.parse_control`), ``clock``
(:func:`gcs.wire.decode_clock` and a :class:`gcs.wire.ClockGuard`),
``sim_truth`` (:meth:`gcs.wire.SimTruth.from_bytes`), ``gcs_frames``
(:class:`gcs.wire.FrameDecoder`, datagram, stream and signed),
``vehicle_endpoint`` (:meth:`vehicles.endpoint.VehicleEndpoint.receive` and
``update`` on a real autopilot) and ``telemetry``
(:meth:`gcs.wire.TelemetryStore.update` on frames of every message type of the
dialect with random payloads). Prints one line per entry point, then one JSON
object on the last line::

    {"count": 1000000, "seed": 0, "entry_points": {"sim_control": {"inputs": ...,
     "accepted": ..., "refused": ..., "violations": 0, "max_input_ms": ...,
     "seconds": ...}, ...}, "violations": 0, "stderr_bytes": 0}

and exits with status 1 if any property was violated (the first few are
printed on stdout).

    python bench/fuzz.py [--count 1000000] [--seed 0] [--only NAME ...] [--max-input-s 1]
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import math
import os
import random
import struct
import sys
import tempfile
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field

from gcs.testing import field_layout, raw_frame

__all__ = ["ENTRY_POINTS", "main"]

_CLOCK_SPECIALS = (math.nan, math.inf, -math.inf, -0.0, 0.0, 5e-324, 1.7976931348623157e308,
                   1e9, -1.0, 1e-9, 2.0**53)


@dataclass
class Tally:
    """What one entry point made of its inputs."""

    inputs: int = 0
    accepted: int = 0
    refused: int = 0
    violations: int = 0
    max_input_s: float = 0.0
    seconds: float = 0.0
    first_violations: list[str] = field(default_factory=list)

    def to_json(self) -> dict[str, object]:
        return {"inputs": self.inputs, "accepted": self.accepted, "refused": self.refused,
                "violations": self.violations, "max_input_ms": round(self.max_input_s * 1e3, 3),
                "seconds": round(self.seconds, 2)}


class PropertyError(AssertionError):
    """An input broke one of the properties."""


# -- generators ---------------------------------------------------------------------------------

def random_bytes(rng: random.Random, max_len: int) -> bytes:
    return rng.randbytes(rng.randrange(max_len + 1))


def mutate(rng: random.Random, data: bytes) -> bytes:
    """Flip, insert, delete, duplicate or truncate a few bytes of ``data``."""
    out = bytearray(data)
    for _ in range(rng.randrange(1, 5)):
        op = rng.randrange(5)
        if op == 0 and out:
            out[rng.randrange(len(out))] = rng.randrange(256)
        elif op == 1:
            out.insert(rng.randrange(len(out) + 1), rng.randrange(256))
        elif op == 2 and out:
            del out[rng.randrange(len(out))]
        elif op == 3 and out:
            a = rng.randrange(len(out))
            out[a:a] = out[a:a + rng.randrange(1, 16)]
        elif out:
            del out[rng.randrange(len(out)):]
    return bytes(out)


def json_value(rng: random.Random, depth: int = 0) -> object:
    """A random JSON value: nested containers, huge and special numbers, odd strings."""
    kind = rng.randrange(10 if depth < 4 else 7)
    if kind == 0:
        return None
    if kind == 1:
        return rng.random() < 0.5
    if kind == 2:
        return rng.choice((0, 1, -1, 255, 256, 2**31, -(2**63), 10**30, rng.randrange(-9, 300)))
    if kind == 3:
        return rng.choice((0.5, -1e300, 1e-300, math.inf, -math.inf, math.nan, rng.uniform(-1e6,
                                                                                        1e6)))
    if kind == 4:
        return rng.choice(("", "kill", "cut", "restore", "\x00", "\udcff"[:0] + "é", "a" * 50))
    if kind in (5, 6):
        return rng.choice(("kill", "cut", "restore", 1, 2, 3, 4))
    if kind in (7, 8):
        return [json_value(rng, depth + 1) for _ in range(rng.randrange(5))]
    keys = ("action", "sysid", "t", "ids", "vehicle_p_ned", "payload_p_ned", "payload_v_ned",
            "rope_tension", "x")
    return {rng.choice(keys): json_value(rng, depth + 1) for _ in range(rng.randrange(5))}


def hostile_json(rng: random.Random) -> bytes:
    """Deep nesting, huge numbers, non-UTF-8 and the like."""
    k = rng.randrange(1, 3000)
    return rng.choice((b'{"a":' * k, b"[" * k, b"[" * k + b"]" * k, b"1" * k, b"1e" + b"9" * k,
                       b'"' + b"\\u" * k, b"\xff\xfe" + b"[" * k, b"-" * k, b"NaN", b"Infinity",
                       b'{"action": "kill", "sysid": ' + b"9" * k + b"}"))


def json_bytes(rng: random.Random, value: object) -> bytes:
    try:
        return json.dumps(value).encode("utf-8", "surrogatepass")
    except (ValueError, RecursionError):
        return b"null"


def control_input(rng: random.Random) -> bytes:
    from sim import ControlAction, ControlCommand

    real = ControlCommand(rng.choice(list(ControlAction)), rng.randrange(-2, 260)).to_bytes()
    pick = rng.randrange(6)
    if pick == 0:
        return real
    if pick == 1:
        return mutate(rng, real)
    if pick == 2:
        doc = json.loads(real)
        doc[rng.choice(("action", "sysid", "extra"))] = json_value(rng)
        return json_bytes(rng, doc)
    if pick == 3:
        return json_bytes(rng, json_value(rng))
    if pick == 4:
        return hostile_json(rng)
    return random_bytes(rng, 1500)


def clock_input(rng: random.Random, t: float) -> bytes:
    from gcs.wire import encode_clock

    pick = rng.randrange(6)
    if pick == 0:  # the real clock, going on
        return struct.pack("<d", t)
    if pick == 1:  # (a sample a few seconds ahead is taken, and holds the real one back)
        return struct.pack("<d", rng.choice(_CLOCK_SPECIALS + (t - 1.0, t + 1e6)) if
                           rng.random() < 0.99 else t + 4.0)
    if pick == 2:
        return struct.pack("<d", t) + rng.randbytes(4 + 5 * rng.randrange(300))
    if pick == 3:
        sent = {rng.randrange(256): rng.randrange(2**32) for _ in range(rng.randrange(8))}
        return mutate(rng, encode_clock(t, rng.randrange(2**32), sent))
    if pick == 4:
        return rng.randbytes(rng.choice((0, 7, 8, 9, 12, 13, 17, 12 + 5 * 256, 12 + 5 * 255)))
    return random_bytes(rng, 64)


def truth_input(rng: random.Random) -> bytes:
    from gcs.wire import SimTruth

    n = rng.randrange(1, 6)
    real = SimTruth(t=rng.uniform(0, 100), ids=tuple(range(1, n + 1)),
                    vehicle_p_ned=tuple((rng.uniform(-5, 5), rng.uniform(-5, 5), -1.0)
                                        for _ in range(n)),
                    payload_p_ned=(0.0, 0.0, -0.5), payload_v_ned=(0.0, 0.1, 0.0),
                    rope_tension=tuple(rng.uniform(0, 3) for _ in range(n))).to_bytes()
    pick = rng.randrange(6)
    if pick == 0:
        return real
    if pick == 1:
        return mutate(rng, real)
    if pick == 2:
        doc = json.loads(real)
        field_name = rng.choice(list(doc))
        if isinstance(doc[field_name], list) and doc[field_name] and rng.random() < 0.5:
            doc[field_name][rng.randrange(len(doc[field_name]))] = json_value(rng)
        else:
            doc[field_name] = json_value(rng)
        return json_bytes(rng, doc)
    if pick == 3:
        return json_bytes(rng, json_value(rng))
    if pick == 4:
        return hostile_json(rng)
    return random_bytes(rng, 600)


_SPECIAL_FLOATS = (math.nan, math.inf, -math.inf, 3.4e38, -3.4e38, 1e-45, 0.0, 1.0, -1.0, 1e7)


def field_payload(rng: random.Random, msgid: int, target: int = 0) -> bytes:
    """A payload of the type's full length with random values, floats often special;
    ``target``: addressed to that system (component 1) where the type has the fields."""
    from gcs.wire import mavlink

    out = bytearray(rng.randbytes(mavlink.mavlink_map[msgid].unpacker.size))
    for name, offset, code, n in field_layout(msgid):
        if code in "fd" and rng.random() < 0.3:  # random bytes rarely make these
            for k in range(n):
                struct.pack_into("<" + code, out, offset + k * struct.calcsize(code),
                                 rng.choice(_SPECIAL_FLOATS))
        elif target and name == "target_system" and rng.random() < 0.8:
            out[offset] = rng.choice((target, target, 0))
        elif target and name == "target_component" and rng.random() < 0.8:
            out[offset] = rng.choice((1, 1, 0))
    if rng.random() < 0.3:  # MAVLink 2 trims trailing zeros
        out = bytearray(out.rstrip(b"\x00"))
    return bytes(out)

def frames_input(rng: random.Random, msgids: list[int], target: int = 0) -> bytes:
    """Bytes a MAVLink datagram could carry: frames with good checksums and random payloads,
    real frames mutated, noise, or a mix."""
    pick = rng.randrange(6)
    if pick == 5:
        return random_bytes(rng, 600)
    parts = []
    for _ in range(rng.randrange(1, 4)):
        msgid = rng.choice(msgids)
        f = raw_frame(msgid, field_payload(rng, msgid, target), seq=rng.randrange(256))
        if pick == 1:
            f = mutate(rng, f)
        elif pick == 2:
            f = f[:rng.randrange(len(f))]
        elif pick == 3:
            f = rng.randbytes(rng.randrange(8)) + f
        parts.append(f)
    if pick == 4:
        parts.append(rng.randbytes(rng.randrange(20)))
    return b"".join(parts)


# -- entry points -------------------------------------------------------------------------------

def _control(rng: random.Random, tally: Tally) -> Callable[[], None]:
    from sim import parse_control

    def one() -> None:
        data = control_input(rng)
        try:
            parse_control(data)
        except ValueError:
            tally.refused += 1
        else:
            tally.accepted += 1
    return one


def _clock(rng: random.Random, tally: Tally) -> Callable[[], None]:
    from gcs.wire import ClockGuard, decode_clock

    guard = ClockGuard()
    state = {"t": 0.0}

    def one() -> None:
        state["t"] += 1 / 128
        # the first sample is the sim's: a follower adopts its first sample, whatever it is
        data = clock_input(rng, state["t"]) if guard.last is not None else \
            struct.pack("<d", state["t"])
        try:
            sample = decode_clock(data)
        except ValueError:
            tally.refused += 1
            return
        before = guard.refused
        verdict = guard.check(sample.t)
        if verdict.accepted:
            tally.accepted += 1
            if not math.isfinite(guard.last or 0.0):
                raise PropertyError(f"the guard adopted {guard.last}")
        else:
            tally.refused += 1
            if guard.refused != before + 1:
                raise PropertyError("a refused clock sample was not counted")
    return one


def _truth(rng: random.Random, tally: Tally) -> Callable[[], None]:
    from gcs.wire import SimTruth

    def one() -> None:
        data = truth_input(rng)
        try:
            truth = SimTruth.from_bytes(data)
        except ValueError:
            tally.refused += 1
            return
        tally.accepted += 1
        if not all(math.isfinite(x) for x in (truth.t, *truth.payload_p_ned)):
            raise PropertyError(f"truth with values not finite: {truth}")
    return one


def _frames(rng: random.Random, tally: Tally) -> Callable[[], None]:
    from gcs.wire import FrameDecoder, SigningKey, mavlink

    key = SigningKey(bytes(range(1, 33)))
    decoders = [FrameDecoder(datagram=True), FrameDecoder(datagram=False),
                FrameDecoder(datagram=True, signing_key=key)]
    msgids = sorted(mavlink.mavlink_map)

    def one() -> None:
        decoder = rng.choice(decoders)
        data = frames_input(rng, msgids)
        before = decoder.stats()
        messages = decoder.feed(data)
        after = decoder.stats()
        if after.bytes_received != before.bytes_received + len(data):
            raise PropertyError("bytes fed not counted")
        moved = (after.frames - before.frames) + (after.garbage_bytes - before.garbage_bytes) \
            + (after.dropped - before.dropped)
        if after.frames - before.frames != len(messages):
            raise PropertyError("frames counted differ from messages returned")
        if decoder.datagram and data and not moved:
            raise PropertyError(f"{len(data)} bytes gave nothing and moved no counter")
        tally.accepted += len(messages)
        tally.refused += after.dropped - before.dropped
    return one


def _endpoint(rng: random.Random, tally: Tally) -> Callable[[], None]:
    import numpy as np

    from gcs.wire import mavlink
    from sim import (
        DEFAULT_AIRFRAME,
        DEFAULT_AUTOPILOT_CONFIG,
        DEFAULT_WORLD_CONFIG,
        build_team,
        load_world_config,
        paper_square,
    )
    from vehicles import load_airframe, load_autopilot_config
    from vehicles.endpoint import VehicleEndpoint

    world, autopilot = build_team(
        paper_square(), payload_mass=0.4, rng=np.random.default_rng(rng.randrange(2**32)),
        airframe=load_airframe(DEFAULT_AIRFRAME),
        world_config=load_world_config(DEFAULT_WORLD_CONFIG),
        autopilot_config=load_autopilot_config(DEFAULT_AUTOPILOT_CONFIG))
    sent: list[bytes] = []
    endpoint = VehicleEndpoint(autopilot, 0, sysid=1, measurements=world.measurements(),
                               send=sent.append)
    handled = [mavlink.MAVLINK_MSG_ID_COMMAND_LONG, mavlink.MAVLINK_MSG_ID_COMMAND_INT,
               mavlink.MAVLINK_MSG_ID_SET_POSITION_TARGET_LOCAL_NED,
               mavlink.MAVLINK_MSG_ID_TIMESYNC, mavlink.MAVLINK_MSG_ID_HEARTBEAT,
               mavlink.MAVLINK_MSG_ID_SET_ATTITUDE_TARGET]
    commands = [mavlink.MAV_CMD_COMPONENT_ARM_DISARM, mavlink.MAV_CMD_NAV_TAKEOFF,
                mavlink.MAV_CMD_NAV_LAND, mavlink.MAV_CMD_DO_SET_MODE,
                mavlink.MAV_CMD_SET_MESSAGE_INTERVAL]
    state = {"t": world.t}

    def one() -> None:
        data = frames_input(rng, handled, target=1)
        if rng.random() < 0.3:  # a command the endpoint knows, with random parameters
            payload = bytearray(field_payload(rng, mavlink.MAVLINK_MSG_ID_COMMAND_LONG)
                                .ljust(33, b"\x00"))
            struct.pack_into("<HBB", payload, 28, rng.choice(commands), 1, 1)
            data = raw_frame(mavlink.MAVLINK_MSG_ID_COMMAND_LONG, bytes(payload))
        before = endpoint.counters()
        endpoint.receive(data, state["t"])
        after = endpoint.counters()
        d0, d1 = before.decode, after.decode
        moved = (d1.frames - d0.frames) + (d1.garbage_bytes - d0.garbage_bytes) \
            + (d1.dropped - d0.dropped)
        if data and not moved:
            raise PropertyError(f"{len(data)} bytes gave nothing and moved no counter")
        tally.accepted += after.setpoints_accepted - before.setpoints_accepted \
            + after.commands - before.commands
        tally.refused += (d1.dropped - d0.dropped) + after.setpoints_refused \
            - before.setpoints_refused + after.not_for_us - before.not_for_us
        state["t"] += 1 / 128
        endpoint.update(state["t"])  # telemetry at the rates the fuzzed commands set
        sent.clear()
    return one


def _telemetry(rng: random.Random, tally: Tally) -> Callable[[], None]:
    from gcs.wire import TELEMETRY_MAX_ABS, FrameDecoder, TelemetryStore, mavlink

    decoder = FrameDecoder(datagram=True)
    store = TelemetryStore(1)
    telemetry = [mavlink.MAVLINK_MSG_ID_HEARTBEAT, mavlink.MAVLINK_MSG_ID_LOCAL_POSITION_NED,
                 mavlink.MAVLINK_MSG_ID_ATTITUDE, mavlink.MAVLINK_MSG_ID_ATTITUDE_QUATERNION,
                 mavlink.MAVLINK_MSG_ID_HIGHRES_IMU, mavlink.MAVLINK_MSG_ID_SYS_STATUS,
                 mavlink.MAVLINK_MSG_ID_STATUSTEXT]
    every = sorted(mavlink.mavlink_map)

    def one() -> None:
        msgid = rng.choice(telemetry) if rng.random() < 0.8 else rng.choice(every)
        data = raw_frame(msgid, field_payload(rng, msgid), sysid=1, compid=1)
        for msg in decoder.feed(data):
            refused = store.refused
            record = store.update(msg, 1.0)
            if record is None:
                if store.refused > refused:
                    tally.refused += 1
                elif msg.get_type() in ("ATTITUDE", "LOCAL_POSITION_NED", "HIGHRES_IMU",
                                        "ATTITUDE_QUATERNION"):
                    raise PropertyError(f"{msg.get_type()} neither stored nor counted")
                continue
            tally.accepted += 1
            values = [v for name in getattr(record, "__slots__", ())
                      for v in _floats(getattr(record, name))]
            if not all(-TELEMETRY_MAX_ABS * 4 <= v <= TELEMETRY_MAX_ABS * 4 or name_ok(v)
                       for v in values):
                raise PropertyError(f"record with values the loop cannot fly by: {record}")
    return one


def name_ok(value: float) -> bool:
    """Times and counters may be large; they are never NaN."""
    return math.isfinite(value)


def _floats(value: object) -> Iterator[float]:
    if isinstance(value, bool):
        return
    if isinstance(value, (int, float)):
        yield float(value)
    elif isinstance(value, tuple):
        for v in value:
            yield from _floats(v)


ENTRY_POINTS: dict[str, Callable[[random.Random, Tally], Callable[[], None]]] = {
    "sim_control": _control,
    "clock": _clock,
    "sim_truth": _truth,
    "gcs_frames": _frames,
    "vehicle_endpoint": _endpoint,
    "telemetry": _telemetry,
}
"""Name -> builder of a function that generates, feeds and checks one input."""


# -- running ------------------------------------------------------------------------------------

@contextlib.contextmanager
def stderr_captured() -> Iterator[Callable[[], bytes]]:
    """Redirect file descriptor 2 (and ``sys.stderr``) to a temporary file; yields a reader."""
    sys.stderr.flush()
    saved = os.dup(2)
    with tempfile.TemporaryFile() as tmp:
        os.dup2(tmp.fileno(), 2)
        old = sys.stderr
        sys.stderr = io.TextIOWrapper(os.fdopen(os.dup(2), "wb"), write_through=True)

        def read() -> bytes:
            sys.stderr.flush()
            tmp.seek(0)
            return tmp.read()
        try:
            yield read
        finally:
            sys.stderr.close()
            sys.stderr = old
            os.dup2(saved, 2)
            os.close(saved)


def fuzz(name: str, count: int, seed: int, max_input_s: float) -> Tally:
    """Run ``count`` inputs through entry point ``name``."""
    tally = Tally()
    rng = random.Random(f"{seed}:{name}")
    one = ENTRY_POINTS[name](rng, tally)
    start = time.perf_counter()
    for k in range(count):
        t0, cpu0 = time.perf_counter(), time.thread_time()
        try:
            one()
        except PropertyError as exc:
            tally.violations += 1
            if len(tally.first_violations) < 5:
                tally.first_violations.append(str(exc)[:300])
        except Exception as exc:  # escaped: a violation too
            tally.violations += 1
            if len(tally.first_violations) < 5:
                tally.first_violations.append(f"{type(exc).__name__}: {exc}"[:300])
        dt, cpu = time.perf_counter() - t0, time.thread_time() - cpu0
        tally.inputs += 1
        if k == 0:  # the first input loads compiled kernels (the endpoint's autopilot)
            continue
        tally.max_input_s = max(tally.max_input_s, dt)
        if cpu > max_input_s:  # CPU time: a busy machine that deschedules the bench is no hang
            tally.violations += 1
            if len(tally.first_violations) < 5:
                tally.first_violations.append(f"one input took {cpu:.3f} s of CPU")
    tally.seconds = time.perf_counter() - start
    return tally


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="fuzz.py", description=__doc__.split("\n\n")[0],
        formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--count", type=int, default=1_000_000,
                        help="inputs per entry point (default 10^6)")
    parser.add_argument("--seed", type=int, default=0, help="seed of the generators")
    parser.add_argument("--only", nargs="+", choices=sorted(ENTRY_POINTS), default=None,
                        help="fuzz only these entry points")
    parser.add_argument("--max-input-s", type=float, default=1.0,
                        help="an input taking more CPU time than this is a hang (s)")
    args = parser.parse_args(argv)
    names = args.only or list(ENTRY_POINTS)
    results: dict[str, Tally] = {}
    with stderr_captured() as stderr:
        for name in names:
            tally = fuzz(name, args.count, args.seed, args.max_input_s)
            results[name] = tally
            print(f"{name:17s} {tally.inputs:9d} inputs, {tally.accepted:9d} accepted, "
                  f"{tally.refused:9d} refused, {tally.violations} violations, "
                  f"slowest {tally.max_input_s * 1e3:.2f} ms, {tally.seconds:.1f} s", flush=True)
            for text in tally.first_violations:
                print(f"    {text}", flush=True)
        written = stderr()
    if written:
        print(f"stderr ({len(written)} bytes): {written[:500]!r}")
    violations = sum(t.violations for t in results.values())
    print(json.dumps({"count": args.count, "seed": args.seed,
                      "entry_points": {n: t.to_json() for n, t in results.items()},
                      "violations": violations, "stderr_bytes": len(written)}))
    return 1 if violations or written else 0


if __name__ == "__main__":
    sys.exit(main())
