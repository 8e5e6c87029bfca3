"""The decoder's own unpacking builds exactly the message pymavlink's decode builds."""

from __future__ import annotations

import numpy as np
import pytest
from pymavlink.dialects.v20 import ardupilotmega as v20

from gcs.wire import FrameDecoder, MavlinkEncoder, SigningKey, unpack_v2

_INT_RANGES = {"int8_t": (-128, 127), "uint8_t": (0, 255), "int16_t": (-32768, 32767),
               "uint16_t": (0, 65535), "int32_t": (-2**31, 2**31 - 1), "uint32_t": (0, 2**32 - 1),
               "int64_t": (-2**63, 2**63 - 1), "uint64_t": (0, 2**64 - 1)}


def _random_values(cls: type, rng: np.random.Generator, *, zeros: bool) -> list[float | int]:
    values: list[float | int] = []
    for kind in cls.fieldtypes:
        if zeros and rng.random() < 0.5:  # trailing zeros are cut from the wire: padded back
            values.append(0)
        elif kind in ("float", "double"):
            values.append(float(np.float32(rng.normal(0, 100))) if kind == "float"
                          else float(rng.normal(0, 1e6)))
        else:
            lo, hi = _INT_RANGES[kind]
            values.append(int(rng.integers(lo, hi, endpoint=True, dtype=np.uint64
                                           if kind == "uint64_t" else np.int64)))
    return values


_SCALAR_TYPES = sorted((cls for cls in v20.mavlink_map.values()
                        if all(n == 1 for n in cls.lengths)
                        and not any(t.startswith("char") for t in cls.fieldtypes)),
                       key=lambda c: c.id)


def _state(msg: v20.MAVLink_message) -> dict[str, object]:
    h = msg.get_header()
    return {"fields": msg.to_dict(), "buf": bytes(msg.get_msgbuf()),
            "payload": bytes(msg.get_payload()), "crc": msg.get_crc(),
            "header": (h.msgId, h.incompat_flags, h.compat_flags, h.mlen, h.seq, h.srcSystem,
                       h.srcComponent), "signed": msg._signed, "link": msg._link_id,
            "names": msg.get_fieldnames(), "type": msg.get_type()}


@pytest.mark.parametrize("signed", [False, True])
def test_every_scalar_message_type_unpacks_like_pymavlink(signed: bool) -> None:
    assert len(_SCALAR_TYPES) > 100  # most of the dialect, all the telemetry the GCS reads
    key = SigningKey(bytes(range(40, 72))) if signed else None
    sender = MavlinkEncoder(system_id=7, component_id=1, signing_key=key, link_id=2)
    ours = FrameDecoder(datagram=True, signing_key=key)
    theirs = v20.MAVLink(None, 0, 0)
    rng = np.random.default_rng(3)
    for cls in _SCALAR_TYPES:
        for zeros in (False, True):
            frame = sender.encode(cls(*_random_values(cls, rng, zeros=zeros)))
            (got,) = ours.feed(frame)
            want = theirs.decode(bytearray(frame))
            if signed:  # pymavlink without a key does not check; the decoder did
                want._signed, want._link_id = True, frame[-13]
            assert _state(got) == _state(want), cls.msgname


def test_types_with_arrays_or_text_are_left_to_pymavlink() -> None:
    sender = MavlinkEncoder(system_id=7, component_id=1)
    text = sender.encode(sender.mav.statustext_encode(4, b"hello"))
    quaternion = sender.encode(sender.mav.attitude_quaternion_encode(
        1, 1.0, 0.0, 0.0, 0.0, 0.1, 0.2, 0.3, [1.0, 0.0, 0.0, 0.0]))
    for frame, msgid in ((text, v20.MAVLINK_MSG_ID_STATUSTEXT),
                         (quaternion, v20.MAVLINK_MSG_ID_ATTITUDE_QUATERNION)):
        assert unpack_v2(bytearray(frame), msgid=msgid, signature_len=0) is None
    got = FrameDecoder(datagram=True).feed(text + quaternion)
    assert got[0].text == "hello" and got[1].repr_offset_q == [1.0, 0.0, 0.0, 0.0]
