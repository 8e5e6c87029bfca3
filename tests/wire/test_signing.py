"""MAVLink 2 signing: key files, and signed links refusing what they must."""

from __future__ import annotations

import socket
import stat
import time
from collections.abc import Iterator
from pathlib import Path

import pytest
from pymavlink.dialects.v20 import ardupilotmega as v20

from gcs.common import ConfigError
from gcs.link import Link
from gcs.transport import MavutilTransport
from gcs.wire import FrameDecoder, MavlinkEncoder, SigningKey, load_signing_key
from gcs.wire._signing import (
    SignatureCheck,
    SignatureVerifier,
    signing_timestamp,
    write_signing_key,
)

KEY = SigningKey(bytes(range(100, 132)))
OTHER_KEY = SigningKey(bytes(range(1, 33)))


def vehicle_heartbeat(encoder: MavlinkEncoder) -> bytes:
    return encoder.encode(encoder.mav.heartbeat_encode(
        v20.MAV_TYPE_QUADROTOR, v20.MAV_AUTOPILOT_GENERIC, 0, 3, 0))


# -- key files ------------------------------------------------------------------------------


def test_key_file_as_raw_bytes_or_hex(tmp_path: Path) -> None:
    raw = tmp_path / "raw.key"
    raw.write_bytes(KEY.secret)
    hexed = tmp_path / "hex.key"
    hexed.write_text("  " + KEY.secret.hex().upper() + "\n")
    assert load_signing_key(raw).secret == KEY.secret
    assert load_signing_key(hexed).secret == KEY.secret
    assert "secret" not in repr(load_signing_key(raw)) and KEY.secret.hex() not in repr(KEY)


@pytest.mark.parametrize(("content", "what"), [
    (b"abc\n", "must be 32 raw bytes or 64 hexadecimal characters, got 4 bytes"),
    (b"zz" * 32, "must be hexadecimal"),
    (bytes(32), "all zeros"),
    (b"00" * 32 + b"\n", "all zeros"),
])
def test_bad_key_files_give_one_line_errors_naming_the_file(tmp_path: Path, content: bytes,
                                                            what: str) -> None:
    path = tmp_path / "vehicle2.key"
    path.write_bytes(content)
    with pytest.raises(ConfigError) as info:
        load_signing_key(path)
    text = str(info.value)
    assert text.startswith(f"{path}: ") and what in text and "\n" not in text


def test_missing_key_file(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match=r"nope\.key: cannot read signing key"):
        load_signing_key(tmp_path / "nope.key")


def test_write_signing_key_is_private_and_never_overwrites(tmp_path: Path) -> None:
    path = tmp_path / "new.key"
    key = write_signing_key(path)
    assert stat.S_IMODE(path.stat().st_mode) == 0o600
    assert load_signing_key(path).secret == key.secret
    assert write_signing_key(tmp_path / "b.key").secret != key.secret
    with pytest.raises(FileExistsError):
        write_signing_key(path)


# -- decoder-level verdicts ------------------------------------------------------------------


def test_signed_decoder_accepts_only_correct_signatures() -> None:
    signed = MavlinkEncoder(system_id=1, component_id=1, signing_key=KEY, link_id=3)
    unsigned = MavlinkEncoder(system_id=1, component_id=1)
    forged = MavlinkEncoder(system_id=1, component_id=1, signing_key=OTHER_KEY, link_id=3)
    decoder = FrameDecoder(datagram=True, signing_key=KEY)

    good = decoder.feed(vehicle_heartbeat(signed))
    assert len(good) == 1 and good[0].get_signed() and good[0].get_link_id() == 3
    assert decoder.feed(vehicle_heartbeat(unsigned)) == []
    assert decoder.feed(vehicle_heartbeat(forged)) == []
    stats = decoder.stats()
    assert (stats.frames, stats.refused_unsigned, stats.refused_bad_signature) == (1, 1, 1)


def test_replayed_signed_frame_is_refused() -> None:
    signed = MavlinkEncoder(system_id=1, component_id=1, signing_key=KEY)
    decoder = FrameDecoder(datagram=True, signing_key=KEY)
    frame = vehicle_heartbeat(signed)
    assert len(decoder.feed(frame)) == 1
    assert decoder.feed(frame) == []
    assert decoder.stats().refused_bad_signature == 1
    assert len(decoder.feed(vehicle_heartbeat(signed))) == 1  # newer timestamp: fine


def test_forged_frame_cannot_block_the_real_stream() -> None:
    """pymavlink records a stream's timestamp before checking the hash; we do not."""
    far_future = time.time() + 3600
    forged = MavlinkEncoder(system_id=1, component_id=1, signing_key=OTHER_KEY,
                            wall_clock=lambda: far_future)
    real = MavlinkEncoder(system_id=1, component_id=1, signing_key=KEY)
    decoder = FrameDecoder(datagram=True, signing_key=KEY)
    assert decoder.feed(vehicle_heartbeat(forged)) == []
    assert len(decoder.feed(vehicle_heartbeat(real))) == 1


def test_new_stream_more_than_a_minute_old_is_stale() -> None:
    old = MavlinkEncoder(system_id=1, component_id=1, signing_key=KEY,
                         wall_clock=lambda: time.time() - 120)
    frame = vehicle_heartbeat(old)
    verifier = SignatureVerifier(KEY)
    assert verifier.check(frame, signed=True, sysid=1, compid=1) is SignatureCheck.STALE
    assert signing_timestamp(1420070400.0 + 1.0) == 100_000


def test_tampered_signed_frame_is_dropped() -> None:
    signed = MavlinkEncoder(system_id=1, component_id=1, signing_key=KEY)
    frame = bytearray(vehicle_heartbeat(signed))
    frame[-1] ^= 1  # the hash
    decoder = FrameDecoder(datagram=True, signing_key=KEY)
    assert decoder.feed(bytes(frame)) == []
    assert decoder.stats().refused_bad_signature == 1


def test_unsigned_decoder_reads_signed_frames() -> None:
    signed = MavlinkEncoder(system_id=1, component_id=1, signing_key=KEY)
    assert len(FrameDecoder(datagram=True).feed(vehicle_heartbeat(signed))) == 1


def test_mavlink1_is_refused_on_a_signed_link() -> None:
    mav1 = v20.MAVLink(None, 1, 1)
    frame = mav1.heartbeat_encode(2, 3, 0, 4, 0).pack(mav1, force_mavlink1=True)
    decoder = FrameDecoder(datagram=True, signing_key=KEY)
    assert decoder.feed(frame) == []
    assert decoder.stats().refused_unsigned == 1


# -- a signed Link over real UDP -------------------------------------------------------------


@pytest.fixture
def signed_link() -> Iterator[tuple[Link, socket.socket, int]]:
    transport = MavutilTransport("udpin:127.0.0.1:0")
    address = transport.local_address
    assert address is not None
    link = Link(1, transport, signing_key=KEY, gcs_heartbeat_period_s=0.05,
                timesync_period_s=0.0)
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    sock.bind(("127.0.0.1", 0))
    sock.settimeout(2.0)
    with link:
        yield link, sock, address[1]
    sock.close()


def test_signed_link_refuses_unsigned_and_forged_then_accepts_signed(
        signed_link: tuple[Link, socket.socket, int]) -> None:
    link, sock, port = signed_link
    sock.sendto(vehicle_heartbeat(MavlinkEncoder(system_id=1, component_id=1)),
                ("127.0.0.1", port))
    sock.sendto(vehicle_heartbeat(MavlinkEncoder(system_id=1, component_id=1,
                                                 signing_key=OTHER_KEY)), ("127.0.0.1", port))
    deadline = time.monotonic() + 2.0
    while link.health.refused_signature < 2 and time.monotonic() < deadline:
        time.sleep(0.01)
    assert link.health.refused_signature == 2
    assert link.telemetry.heartbeat is None

    sock.sendto(vehicle_heartbeat(MavlinkEncoder(system_id=1, component_id=1, signing_key=KEY)),
                ("127.0.0.1", port))
    link.wait_for(lambda t: t.heartbeat is not None, timeout_s=2.0, what="signed heartbeat")
    assert link.health.refused == 2


def test_signed_link_signs_what_it_sends(signed_link: tuple[Link, socket.socket, int]) -> None:
    _, sock, port = signed_link
    signed = MavlinkEncoder(system_id=1, component_id=1, signing_key=KEY)
    sock.sendto(vehicle_heartbeat(signed), ("127.0.0.1", port))  # lets udpin learn our address
    vehicle_side = FrameDecoder(datagram=True, signing_key=KEY)
    deadline = time.monotonic() + 3.0
    got: list[object] = []
    while not got and time.monotonic() < deadline:
        data, _ = sock.recvfrom(1024)
        got = [m for m in vehicle_side.feed(data) if m.get_type() == "HEARTBEAT"]
    assert got, "no GCS heartbeat arrived"
    assert vehicle_side.stats().refused_signature == 0
    assert FrameDecoder(datagram=True, signing_key=OTHER_KEY).feed(data) == []
