"""MAVLink 2 codec: real frames, noise, truncation, corruption; both GCS and vehicle sides."""

from __future__ import annotations

import math

import numpy as np
import pytest
from pymavlink.dialects.v20 import ardupilotmega as v20

from gcs.wire import (
    DEFAULT_GCS_SYSTEM_ID,
    SETPOINT_MESSAGE,
    EncoderBatch,
    FrameDecoder,
    MavlinkEncoder,
    SetpointKind,
    SetpointPacker,
    SigningKey,
    accel_setpoint_fields,
    read_setpoint,
)
from gcs.wire._encoder import frame_dtype, packed_rows
from gcs.wire._setpoints import (
    MASK_ACCEL,
    MASK_ACCEL_XY_POS_Z,
    accel_setpoint_message,
    packed_setpoints,
)


def gcs_encoder() -> MavlinkEncoder:
    return MavlinkEncoder(system_id=DEFAULT_GCS_SYSTEM_ID, component_id=190)


def heartbeat(encoder: MavlinkEncoder, custom_mode: int = 0) -> bytes:
    return encoder.encode(encoder.mav.heartbeat_encode(
        v20.MAV_TYPE_QUADROTOR, v20.MAV_AUTOPILOT_GENERIC, 0, custom_mode, 0))


def test_frames_are_mavlink2_with_own_ids_and_wrapping_sequence() -> None:
    gcs = gcs_encoder()
    frames = [heartbeat(gcs) for _ in range(300)]
    assert DEFAULT_GCS_SYSTEM_ID == 245
    assert all(f[0] == 0xFD for f in frames)
    assert {(f[5], f[6]) for f in frames} == {(245, 190)}
    assert [f[4] for f in frames[:3]] == [0, 1, 2]
    assert frames[256][4] == 0 and frames[299][4] == 43
    assert gcs.frames_sent == 300


def test_vehicle_side_encoder_round_trip_through_gcs_decoder() -> None:
    vehicle = MavlinkEncoder(system_id=3, component_id=1)
    decoder = FrameDecoder(datagram=True)
    msgs = [
        vehicle.mav.local_position_ned_encode(1500, 1.0, -2.0, -3.5, 0.1, 0.2, -0.3),
        vehicle.mav.attitude_quaternion_encode(1500, 1.0, 0.0, 0.0, 0.0, 0.1, 0.2, 0.3),
        vehicle.mav.statustext_encode(4, b"rope taut"),
        vehicle.mav.command_ack_encode(400, 0, 0, 0, 245, 190),
    ]
    out = decoder.feed(b"".join(vehicle.encode(m) for m in msgs))
    assert [m.get_type() for m in out] == ["LOCAL_POSITION_NED", "ATTITUDE_QUATERNION",
                                           "STATUSTEXT", "COMMAND_ACK"]
    assert all((m.get_srcSystem(), m.get_srcComponent()) == (3, 1) for m in out)
    assert (out[0].x, out[0].z, out[0].vz) == pytest.approx((1.0, -3.5, -0.3))
    assert out[2].text == "rope taut"
    assert (out[3].command, out[3].target_system) == (400, 245)
    assert decoder.stats().frames == 4 and decoder.stats().dropped == 0


def test_identity_is_validated() -> None:
    with pytest.raises(ValueError, match="system id"):
        MavlinkEncoder(system_id=0, component_id=1)
    with pytest.raises(ValueError, match="component id"):
        MavlinkEncoder(system_id=1, component_id=256)


def test_random_bytes_are_counted_and_frames_inside_noise_survive() -> None:
    rng = np.random.default_rng(20190520)
    vehicle = MavlinkEncoder(system_id=1, component_id=1)
    for datagram in (True, False):
        decoder = FrameDecoder(datagram=datagram)
        got = 0
        sent = 0
        total = 0
        for _ in range(60):
            noise = rng.integers(0, 256, int(rng.integers(1, 400)), dtype=np.uint8).tobytes()
            frame = heartbeat(vehicle, custom_mode=7)
            sent += 1
            data = noise + frame
            total += len(data)
            if datagram:
                got += len(decoder.feed(data))
            else:  # a stream cut into arbitrary chunks
                cuts = sorted(rng.integers(0, len(data), 4).tolist())
                for a, b in zip([0, *cuts], [*cuts, len(data)], strict=True):
                    got += len(decoder.feed(data[a:b]))
        stats = decoder.stats()
        assert got == sent, f"datagram={datagram}"
        assert stats.garbage_bytes > 1000
        assert stats.frames == sent
        assert stats.bytes_received == total


def test_pure_noise_never_raises() -> None:
    rng = np.random.default_rng(7)
    decoder = FrameDecoder(datagram=False)
    magic_heavy = np.array([0xFD, 0xFE, 0x00, 0x01, 0xFF], dtype=np.uint8)
    for i in range(300):
        if i % 2:
            chunk = rng.integers(0, 256, 97, dtype=np.uint8).tobytes()
        else:
            chunk = rng.choice(magic_heavy, 97).tobytes()
        decoder.feed(chunk)
    decoder.flush()
    stats = decoder.stats()
    assert stats.frames == 0
    assert stats.garbage_bytes + stats.bad_crc + stats.truncated + stats.unknown_message > 0


def test_truncated_frames_are_counted() -> None:
    vehicle = MavlinkEncoder(system_id=1, component_id=1)
    frame = vehicle.encode(vehicle.mav.local_position_ned_encode(1, 1, 2, 3, 4, 5, 6))
    datagram = FrameDecoder(datagram=True)
    assert datagram.feed(frame[:-5]) == []
    assert datagram.stats().truncated >= 1
    assert len(datagram.feed(frame)) == 1  # the next datagram is unaffected

    stream = FrameDecoder(datagram=False)
    assert stream.feed(frame[:-5]) == []  # waits for the rest
    assert stream.stats().truncated == 0
    stream.flush()
    assert stream.stats().truncated >= 1
    assert len(stream.feed(frame)) == 1


def test_truncated_frame_in_a_stream_does_not_hold_back_the_next() -> None:
    vehicle = MavlinkEncoder(system_id=1, component_id=1)
    first = vehicle.encode(vehicle.mav.local_position_ned_encode(1, 1, 2, 3, 4, 5, 6))
    second = heartbeat(vehicle)
    for cut in range(1, len(first) - 1):
        stream = FrameDecoder(datagram=False)
        out = stream.feed(first[:cut] + second)
        assert [m.get_type() for m in out] == ["HEARTBEAT"], cut
        # Cut short inside the bytes that follow: a truncation if the declared
        # length runs past the data, otherwise indistinguishable from a bad CRC.
        stats = stream.stats()
        assert stats.truncated + stats.bad_crc == 1, cut


def test_corrupted_byte_fails_crc_and_neighbours_survive() -> None:
    vehicle = MavlinkEncoder(system_id=1, component_id=1)
    frames = [vehicle.encode(vehicle.mav.local_position_ned_encode(i, i, 0, 0, 0, 0, 0))
              for i in range(3)]
    bad = bytearray(frames[1])
    bad[12] ^= 0x40
    decoder = FrameDecoder(datagram=True)
    out = decoder.feed(frames[0] + bytes(bad) + frames[2])
    assert [m.time_boot_ms for m in out] == [0, 2]
    assert decoder.stats().bad_crc >= 1


def test_unknown_message_id_is_counted_and_skipped() -> None:
    vehicle = MavlinkEncoder(system_id=1, component_id=1)
    good = heartbeat(vehicle)
    unknown = bytearray(good)
    unknown[7:10] = (0xEE, 0xEE, 0x0E)  # message id 0x0EEEEE: not in the dialect
    decoder = FrameDecoder(datagram=True)
    out = decoder.feed(bytes(unknown) + good)
    assert len(out) == 1
    assert decoder.stats().unknown_message == 1


def test_mavlink1_frames_are_read_on_unsigned_links() -> None:
    mav1 = v20.MAVLink(None, 1, 1)
    frame = mav1.heartbeat_encode(2, 3, 0, 4, 0).pack(mav1, force_mavlink1=True)
    assert frame[0] == 0xFE
    out = FrameDecoder(datagram=True).feed(frame)
    assert [(m.get_type(), m.custom_mode) for m in out] == [("HEARTBEAT", 4)]


def test_setpoint_messages_round_trip_for_both_kinds() -> None:
    gcs = gcs_encoder()
    decoder = FrameDecoder(datagram=True)
    xy_z = accel_setpoint_message(target_system=2, target_component=1,
                                  time_boot_ms=1234, accel_xy_ned=(0.5, -0.25), z_ned=-1.2)
    acc = accel_setpoint_message(target_system=2, target_component=1,
                                 time_boot_ms=1250, accel_xy_ned=(0.5, -0.25), az_ned=-0.4)
    a, b = decoder.feed(gcs.encode(xy_z) + gcs.encode(acc))
    first, second = read_setpoint(a), read_setpoint(b)
    assert first is not None and second is not None
    assert (a.type_mask, b.type_mask) == (MASK_ACCEL_XY_POS_Z, MASK_ACCEL) == (3387, 3135)
    assert first.kind is SetpointKind.ACCEL_XY_POS_Z and first.z_ned == pytest.approx(-1.2)
    assert first.accel_ned[:2] == pytest.approx((0.5, -0.25)) and math.isnan(first.accel_ned[2])
    assert second.kind is SetpointKind.ACCEL and second.z_ned is None
    assert second.accel_ned == pytest.approx((0.5, -0.25, -0.4))
    assert (a.target_system, a.coordinate_frame) == (2, v20.MAV_FRAME_LOCAL_NED)


@pytest.mark.parametrize("signed", [False, True])
def test_fast_framing_gives_the_bytes_pymavlink_gives(signed: bool) -> None:
    """encode_fields (no message object) and encode (pymavlink) agree byte for byte."""
    key = SigningKey(bytes(range(7, 39))) if signed else None
    fast, slow = (MavlinkEncoder(system_id=245, component_id=190, signing_key=key, link_id=3,
                                 wall_clock=lambda: 1.7e9) for _ in range(2))
    rng = np.random.default_rng(1)
    for k in range(300):  # wraps the sequence number
        kw = {"target_system": 1 + k % 250, "target_component": k % 2, "time_boot_ms": k * 250,
              "accel_xy_ned": tuple(rng.normal(0, 1, 2)) if k % 3 else (0.0, 0.0)}
        kw |= {"z_ned": -1.5} if k % 2 else {"az_ned": float(rng.normal()) if k % 5 else 0.0}
        assert fast.encode_fields(SETPOINT_MESSAGE, *accel_setpoint_fields(**kw)) == \
            slow.encode(accel_setpoint_message(**kw))
    # trailing zeros of the payload are dropped, as MAVLink 2 requires
    position = v20.MAVLink_local_position_ned_message
    values = (5, 1.0, 2.0, -3.0, 0.0, 0.0, 0.0)
    frame = fast.encode_fields(position, *values)
    assert frame == slow.encode(position(*values)) and frame[1] == 16
    (decoded,) = FrameDecoder(datagram=True, signing_key=key,
                              wall_clock=lambda: 1.7e9).feed(frame)
    assert (decoded.x, decoded.y, decoded.z, decoded.vz) == (1.0, 2.0, -3.0, 0.0)


@pytest.mark.parametrize("signed", ["none", "all", "some"])
def test_a_fleets_packed_setpoints_are_the_frames_encoded_one_by_one(signed: str) -> None:
    """packed_setpoints + EncoderBatch.stamp (the loop's path), and + restamp row by row,
    == accel_setpoint_fields + encode_fields, sequence numbers and signatures included."""
    key = SigningKey(bytes(range(3, 35)))
    keys = {"none": [None] * 5, "all": [key] * 5, "some": [None, key, None, None, key]}[signed]

    def encoders() -> list[MavlinkEncoder]:
        return [MavlinkEncoder(system_id=245, component_id=190, signing_key=k,
                               wall_clock=lambda: 1.7e9) for k in keys]

    batch_side, row_side, single_side = encoders(), encoders(), encoders()
    batch = EncoderBatch(batch_side)
    rng = np.random.default_rng(4)
    for tick in range(300):  # wraps every sequence number
        accel = rng.normal(0, 1, (5, 2))
        kind = np.array([MASK_ACCEL_XY_POS_Z, MASK_ACCEL, MASK_ACCEL_XY_POS_Z, MASK_ACCEL,
                         MASK_ACCEL_XY_POS_Z])
        vertical = rng.normal(-1, 0.5, 5)
        times = np.arange(5) * 1000 + tick * 250
        packed = packed_setpoints(target_system=np.arange(1, 6), target_component=np.ones(5, int),
                                  time_boot_ms=times, accel_xy_ned=accel, vertical=vertical,
                                  kind=kind)
        stamped = batch.stamp(packed, SETPOINT_MESSAGE.crc_extra)
        for i, enc in enumerate(row_side):
            channel = {"z_ned": vertical[i]} if kind[i] == MASK_ACCEL_XY_POS_Z else \
                {"az_ned": vertical[i]}
            one = single_side[i].encode_fields(SETPOINT_MESSAGE, *accel_setpoint_fields(
                target_system=i + 1, target_component=1, time_boot_ms=int(times[i]),
                accel_xy_ned=(accel[i, 0], accel[i, 1]), **channel))
            assert enc.restamp(packed[i].tobytes(), SETPOINT_MESSAGE.crc_extra) == one
            assert stamped[i] == one, (tick, i)
    assert [e.frames_sent for e in batch_side] == [300] * 5
    (decoded,) = FrameDecoder(datagram=True, signing_key=key if keys[4] else None,
                              wall_clock=lambda: 1.7e9).feed(one)
    assert read_setpoint(decoded) is not None and decoded.target_system == 5


def test_the_loops_setpoint_packer_packs_as_packed_setpoints() -> None:
    """SetpointPacker (one kernel per tick) == packed_setpoints with time_boot_ms counted from
    each vehicle's boot time, wrapping at 2^32 ms like the field."""
    rng = np.random.default_rng(9)
    for n in (1, 7, 100):
        kind = rng.choice([MASK_ACCEL, MASK_ACCEL_XY_POS_Z], n)
        targets, boot = rng.integers(1, 250, n), rng.uniform(0, 100, n)
        packer = SetpointPacker(target_system=targets, target_component=np.ones(n, int),
                                kind=kind, boot_time=boot)
        for now in (150.25, 4.3e6 + 0.5):  # the second is past 2^32 ms since boot
            accel, vertical = rng.normal(0, 1, (n, 2)), rng.normal(-1, 1, n)
            stamps = ((now - boot) * 1000).astype(np.int64) & 0xFFFFFFFF
            assert np.array_equal(packer.pack(now, accel, vertical), packed_setpoints(
                target_system=targets, target_component=np.ones(n, int), time_boot_ms=stamps,
                accel_xy_ned=accel, vertical=vertical, kind=kind))


def test_encoders_shared_by_two_batches_keep_consecutive_sequence_numbers() -> None:
    """A batch keeps its encoders' counters in one table; an encoder taken by another batch,
    or encoding on its own meanwhile, goes on from where it was."""
    position = v20.MAVLink_local_position_ned_message
    key = SigningKey(bytes(range(5, 37)))
    encoders = [MavlinkEncoder(system_id=i + 1, component_id=1, signing_key=key if i == 2 else None,
                               wall_clock=lambda: 1.7e9) for i in range(4)]
    first, second = EncoderBatch(encoders[:3]), EncoderBatch(encoders[1:])
    expected, count = [0] * 4, [0] * 4
    rng = np.random.default_rng(7)

    def packed(n: int) -> np.ndarray:
        return packed_rows(position, n, {"x": rng.normal(size=n), "time_boot_ms": 1})

    def check(frames: list[bytes], which: list[int]) -> None:
        for frame, i in zip(frames, which, strict=True):
            assert (frame[4], frame[5]) == (expected[i], i + 1), (which, i)
            assert frame[2] == (v20.MAVLINK_IFLAG_SIGNED if i == 2 else 0)  # vehicle 3 signs
            expected[i] = (expected[i] + 1) & 0xFF
            count[i] += 1

    for round_ in range(600):  # wraps every sequence number twice
        step = round_ % 4
        if step == 0:
            check(first.stamp(packed(3), position.crc_extra), [0, 1, 2])
        elif step == 1:
            check(second.stamp(packed(3), position.crc_extra), [1, 2, 3])
        elif step == 2:
            rows = [0, 2]
            data, width, lengths = first.stamp_buffer(packed(2), position.crc_extra, rows)
            check([data[k * width:k * width + n] for k, n in enumerate(lengths)], rows)
        else:
            i = round_ % 3 + 1
            check([encoders[i].encode(position(1, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0))], [i])
    assert [e.frames_sent for e in encoders] == count == [300, 350, 500, 200]
    with pytest.raises(ValueError, match="appears twice"):
        EncoderBatch([encoders[0], encoders[0]])
    for wrong in ([3], [-1], [1, 1]):  # the kernel has no bounds checks: refused before it
        with pytest.raises(ValueError, match=r"rows must be distinct, in 0\.\.2"):
            first.stamp_buffer(packed(len(wrong)), position.crc_extra, wrong)
    assert [e.frames_sent for e in encoders] == count  # nothing numbered by the refusals


def test_a_batch_drops_trailing_zeros_per_row_as_single_encoding_does() -> None:
    position = v20.MAVLink_local_position_ned_message
    rows = np.array([[5, 1.0, 2.0, -3.0, 0.0, 0.0, 0.0], [6, 1.0, 2.0, -3.0, 0.5, 0.0, 0.25],
                     [0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]])
    packed = packed_rows(position, 3, dict(zip(position.ordered_fieldnames, rows.T, strict=True)))
    frames = EncoderBatch([gcs_encoder() for _ in range(3)]).stamp(packed, position.crc_extra)
    single = gcs_encoder()
    for frame, values in zip(frames, rows.tolist(), strict=True):
        single.seq = 0
        assert frame == single.encode(position(int(values[0]), *values[1:]))
    assert [f[1] for f in frames] == [16, 28, 1]  # payload lengths: zeros dropped, at least 1
    with pytest.raises(ValueError, match="3 packed frames for 2 encoders"):
        EncoderBatch([gcs_encoder(), gcs_encoder()]).stamp(packed, position.crc_extra)


def test_messages_with_array_fields_cannot_be_packed_in_bulk() -> None:
    with pytest.raises(ValueError, match="ATTITUDE_QUATERNION: only messages of scalar"):
        frame_dtype(v20.MAVLink_attitude_quaternion_message)


def test_setpoint_needs_exactly_one_finite_vertical_channel() -> None:
    common = {"target_system": 2, "target_component": 1, "time_boot_ms": 0}
    with pytest.raises(ValueError, match="exactly one"):
        accel_setpoint_message(accel_xy_ned=(0, 0), **common)
    with pytest.raises(ValueError, match="exactly one"):
        accel_setpoint_message(accel_xy_ned=(0, 0), z_ned=-1, az_ned=0, **common)
    with pytest.raises(ValueError, match="finite"):
        accel_setpoint_message(accel_xy_ned=(math.nan, 0), z_ned=-1, **common)


def test_other_position_targets_are_not_acceleration_setpoints() -> None:
    mav = gcs_encoder().mav
    position = mav.set_position_target_local_ned_encode(0, 2, 1, v20.MAV_FRAME_LOCAL_NED, 0xDF8,
                                                        1, 2, 3, 0, 0, 0, 0, 0, 0, 0, 0)
    body = mav.set_position_target_local_ned_encode(0, 2, 1, v20.MAV_FRAME_BODY_NED, MASK_ACCEL,
                                                    0, 0, 0, 0, 0, 0, 1, 1, 1, 0, 0)
    assert read_setpoint(position) is None and read_setpoint(body) is None
    assert read_setpoint(mav.heartbeat_encode(0, 0, 0, 0, 0)) is None


def test_a_long_stream_round_trips_whole_with_wrapping_sequence_numbers() -> None:
    """2000 frames (the sequence number wraps seven times): every one decodes, in order,
    with nothing counted as garbage. Speed is bench/link_latency.py's business."""
    gcs = gcs_encoder()
    decoder = FrameDecoder(datagram=True)
    n = 2000
    msg = accel_setpoint_message(target_system=2, target_component=1, time_boot_ms=0,
                                 accel_xy_ned=(0.1, 0.2), z_ned=-1.0)
    decoded = [m for _ in range(n) for m in decoder.feed(gcs.encode(msg))]
    assert len(decoded) == n
    assert [m.get_seq() for m in decoded] == [k % 256 for k in range(n)]
    assert all((m.afx, m.afy, m.z) == pytest.approx((0.1, 0.2, -1.0)) for m in decoded)
    stats = decoder.stats()
    assert (stats.frames, stats.garbage_bytes, stats.bad_crc) == (n, 0, 0)
