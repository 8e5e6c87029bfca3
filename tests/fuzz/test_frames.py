"""Fuzzing the MAVLink frame decoder at both ends: the GCS's ``gcs.wire.FrameDecoder`` and a
simulated vehicle's endpoint (``vehicles.endpoint.VehicleEndpoint.receive``, which decodes,
checks setpoints, answers commands on a real autopilot).

Anyone can send to a vehicle's UDP port or publish on its zenoh keys: noise,
frames cut, mutated or in noise, and frames with good checksums around
arbitrary payloads (any message type, any field values: NaN, infinities,
addressed to the vehicle or not). Nothing raises, nothing is slow, nothing
is printed, and whatever gives no message moved a counter.
``bench/fuzz.py --only gcs_frames vehicle_endpoint`` runs 10^6 inputs each.
"""

from __future__ import annotations

import struct
from collections import Counter

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from gcs.testing import field_layout, raw_frame
from gcs.wire import DecodeStats, FrameDecoder, MavlinkEncoder, SigningKey, mavlink
from sim import (
    DEFAULT_AIRFRAME,
    DEFAULT_AUTOPILOT_CONFIG,
    DEFAULT_WORLD_CONFIG,
    build_team,
    load_world_config,
    paper_square,
)
from tests.support.fuzzing import (
    assert_quiet,
    batches,
    datagrams,
    fuzz_settings,
    payloads,
    timed,
)
from vehicles import load_airframe, load_autopilot_config
from vehicles.endpoint import VehicleEndpoint

ALL_TYPES = sorted(mavlink.mavlink_map)
KEY = SigningKey(bytes(range(1, 33)))


def moved(before: DecodeStats, after: DecodeStats) -> int:
    """How many frames, garbage bytes and dropped frames a feed added."""
    return (after.frames - before.frames) + (after.garbage_bytes - before.garbage_bytes) \
        + (after.dropped - before.dropped)


_SIGNER = MavlinkEncoder(system_id=1, component_id=1, signing_key=KEY)


def _signed(body: bytes, pick: int) -> bytes:
    good = _SIGNER.encode(_SIGNER.mav.heartbeat_encode(2, 3, 0, 0, 0))  # a fresh timestamp
    return (good, body, good[:-1], good + body, body + good)[pick]


signed = st.builds(_signed, datagrams([0, 30, 32, 253]), st.integers(0, 4))
"""Frames signed with the link's key, around or beside unsigned ones with arbitrary
payloads (on a signed link every unsigned one is refused)."""


def test_the_gcs_decoder_never_raises_and_counts_what_it_drops(
        capfd: pytest.CaptureFixture[str], caplog: pytest.LogCaptureFixture) -> None:
    decoders = {"datagram": FrameDecoder(datagram=True),
                "stream": FrameDecoder(datagram=False),
                "signed": FrameDecoder(datagram=True, signing_key=KEY)}
    outcomes: Counter[str] = Counter()

    @fuzz_settings(1000)
    @given(batches(datagrams(ALL_TYPES) | signed), st.sampled_from(sorted(decoders)))
    def fuzz(inputs: list[bytes], which: str) -> None:
        decoder = decoders[which]
        for data in inputs:
            before = decoder.stats()
            with timed():
                messages = decoder.feed(data)
            after = decoder.stats()
            assert after.bytes_received == before.bytes_received + len(data)
            assert after.frames - before.frames == len(messages)
            if decoder.datagram and data:
                assert moved(before, after) > 0, data.hex()
            outcomes["messages"] += len(messages)
            outcomes["dropped"] += after.dropped - before.dropped
            outcomes["inputs"] += 1

    fuzz()
    assert_quiet(capfd, caplog)
    assert outcomes["inputs"] == 10_000
    assert outcomes["messages"] > 2000 and outcomes["dropped"] > 2000, outcomes


@pytest.fixture(scope="module")
def endpoint() -> tuple[VehicleEndpoint, list[bytes]]:
    """Vehicle 1 of the paper's square, on the ground, behind its endpoint."""
    world, autopilot = build_team(
        paper_square(), payload_mass=0.4, rng=np.random.default_rng(3),
        airframe=load_airframe(DEFAULT_AIRFRAME),
        world_config=load_world_config(DEFAULT_WORLD_CONFIG),
        autopilot_config=load_autopilot_config(DEFAULT_AUTOPILOT_CONFIG))
    world.run(autopilot, 1 / 16)
    sent: list[bytes] = []
    return VehicleEndpoint(autopilot, 0, sysid=1, measurements=world.measurements(),
                           send=sent.append), sent


HANDLED = [mavlink.MAVLINK_MSG_ID_COMMAND_LONG, mavlink.MAVLINK_MSG_ID_COMMAND_INT,
           mavlink.MAVLINK_MSG_ID_SET_POSITION_TARGET_LOCAL_NED, mavlink.MAVLINK_MSG_ID_TIMESYNC,
           mavlink.MAVLINK_MSG_ID_HEARTBEAT]
COMMANDS = [mavlink.MAV_CMD_COMPONENT_ARM_DISARM, mavlink.MAV_CMD_NAV_TAKEOFF,
            mavlink.MAV_CMD_NAV_LAND, mavlink.MAV_CMD_DO_SET_MODE,
            mavlink.MAV_CMD_SET_MESSAGE_INTERVAL, 0, 65535]


@st.composite
def commands(draw: st.DrawFn) -> bytes:
    """A COMMAND_LONG the vehicle knows, to it, with arbitrary parameters."""
    payload = bytearray(draw(payloads(mavlink.MAVLINK_MSG_ID_COMMAND_LONG)).ljust(33, b"\0"))
    payload[28:32] = draw(st.sampled_from(COMMANDS)).to_bytes(2, "little") + bytes((1, 1))
    return raw_frame(mavlink.MAVLINK_MSG_ID_COMMAND_LONG, bytes(payload))


_SETPOINT = mavlink.MAVLINK_MSG_ID_SET_POSITION_TARGET_LOCAL_NED
_FIELDS = {name: (offset, code) for name, offset, code, _ in field_layout(_SETPOINT)}


@st.composite
def setpoints(draw: st.DrawFn) -> bytes:
    """A SET_POSITION_TARGET_LOCAL_NED to the vehicle, often one it flies: LOCAL_NED, one of
    its two type masks, values in range (or not, or not finite)."""
    payload = bytearray(draw(payloads(_SETPOINT, target=1)).ljust(53, b"\0"))
    small = draw(st.binary(min_size=4, max_size=4))
    for k, name in enumerate(("afx", "afy", "afz", "z")):
        if small[k] & 1:  # a sane value more often than random bytes give one
            struct.pack_into("<f", payload, _FIELDS[name][0], (small[k] - 128) / 12.0)
    struct.pack_into("<H", payload, _FIELDS["type_mask"][0],
                     draw(st.sampled_from([3387, 3135, 3387 | 512, 0, 0xFFFF])))
    payload[_FIELDS["coordinate_frame"][0]] = draw(st.sampled_from([1, 1, 1, 8]))
    payload[_FIELDS["target_system"][0]], payload[_FIELDS["target_component"][0]] = 1, 1
    return raw_frame(_SETPOINT, bytes(payload))


def test_a_vehicle_endpoint_never_raises_and_counts_what_it_refuses(
        endpoint: tuple[VehicleEndpoint, list[bytes]], capfd: pytest.CaptureFixture[str],
        caplog: pytest.LogCaptureFixture) -> None:
    vehicle, sent = endpoint
    outcomes: Counter[str] = Counter()
    clock = [1.0]

    @fuzz_settings(500)
    @given(batches(datagrams(HANDLED, target=1) | datagrams(ALL_TYPES, target=1) | commands()
                    | setpoints()))
    def fuzz(inputs: list[bytes]) -> None:
        for data in inputs:
            before = vehicle.counters()
            with timed():
                vehicle.receive(data, clock[0])
                clock[0] += 1 / 128
                vehicle.update(clock[0])  # telemetry at whatever rates the commands set
            after = vehicle.counters()
            if data:
                assert moved(before.decode, after.decode) > 0, data.hex()
            outcomes["commands"] += after.commands - before.commands
            outcomes["setpoints"] += after.setpoints_accepted - before.setpoints_accepted
            outcomes["refused"] += after.setpoints_refused - before.setpoints_refused \
                + after.not_for_us - before.not_for_us \
                + after.decode.dropped - before.decode.dropped
            outcomes["inputs"] += 1
        sent.clear()

    fuzz()
    assert_quiet(capfd, caplog)
    assert outcomes["inputs"] == 5_000
    assert min(outcomes["commands"], outcomes["setpoints"], outcomes["refused"]) > 100, outcomes
