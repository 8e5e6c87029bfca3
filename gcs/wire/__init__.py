"""MAVLink 2 on the wire: what a GCS and a vehicle must agree on, byte for byte.

The dialect, framing and checksums, signing, the setpoint, telemetry and mode
numbers, the zenoh key names (:mod:`gcs.wire.keys`), the wire formats of the
sim clock and the sim's truth, and the WGS-84 geodesy of global positions (the
team frame's too). The simulated vehicles (``vehicles/``) and the sim
host (``sim/``) use this package and nothing of the GCS's link layer.

Modules:

    ``_clockwire``  Wire format of the sim clock and of lockstep acknowledgements on zenoh.
    ``_crc``        MAVLink's frame checksum (CRC-16/MCRF4XX with the message type's
                    CRC_EXTRA byte).
    ``_decoder``    MAVLink byte-stream decoding that never raises: bad input is counted and
                    dropped.
    ``_dialect``    The one pymavlink dialect the project speaks, and name look-ups into it.
    ``_encoder``    MAVLink 2 encoding for one sender (the GCS, or one simulated vehicle).
    ``_geodetic``   Geodetic positions, local NED frames and the team frame, on the WGS-84
                    ellipsoid.
    ``_modes``      Flight-mode numbers of every autopilot the GCS drives, in one place.
    ``_seal``       Authenticated zenoh payloads that are not MAVLink: clock, clock ack,
                    truth, control.
    ``_setpoints``  Acceleration setpoints as ``SET_POSITION_TARGET_LOCAL_NED`` (frame
                    LOCAL_NED).
    ``_signing``    MAVLink 2 message signing: key files and the check of incoming
                    signatures.
    ``_simtruth``   Sim-only truth on the wire: what a real flight cannot measure (payload,
                    ropes).
    ``_stamp``      Many packed MAVLink 2 frames numbered and checksummed in one compiled
                    pass.
    ``_telemetry``  Latest telemetry of one vehicle, kept as immutable records.
    ``_unpack``     Building a pymavlink message from a checked MAVLink 2 frame, without
                    pymavlink's decode.
    ``keys``        Every zenoh key expression of the fleet, in one place for the GCS and
                    the sim.
"""

from gcs.common import lazy_modules
from gcs.wire._clockwire import (
    ACK_FORMAT,
    CLOCK_MAX_BYTES,
    ClockGuard,
    ClockSample,
    ClockVerdict,
    decode_ack,
    decode_clock,
    decode_time,
    encode_ack,
    encode_clock,
    encode_time,
)
from gcs.wire._crc import frame_crc
from gcs.wire._decoder import DecodeStats, FrameDecoder
from gcs.wire._dialect import MavMessage, command_name, mavlink, message_id
from gcs.wire._encoder import (
    DEFAULT_GCS_COMPONENT_ID,
    DEFAULT_GCS_SYSTEM_ID,
    EncoderBatch,
    MavlinkEncoder,
    distinct_rows,
)
from gcs.wire._geodetic import (
    Geodetic,
    ecef_to_geodetic,
    geodetic_mean,
    geodetic_median,
    geodetic_to_ecef,
    geodetic_to_ned,
    local_origin,
    ned_to_geodetic,
)
from gcs.wire._modes import (
    CUSTOM_MODE_ENABLED,
    SAFETY_ARMED,
    SIM_PX4_MODES,
    CopterMode,
    Px4AutoSubMode,
    Px4MainMode,
    SimMode,
    copter_mode_text,
    heartbeat_mode_text,
    px4_base_mode,
    px4_custom_mode,
    px4_mode_text,
    sim_mode_for_px4,
    sim_mode_of,
    sim_mode_text,
    split_px4_custom_mode,
)
from gcs.wire._results import CommandResult
from gcs.wire._seal import SEAL_OVERHEAD, Sealer, SealError, Unsealer
from gcs.wire._setpoints import (
    SETPOINT_MESSAGE,
    AccelSetpoint,
    SetpointKind,
    SetpointPacker,
    TypeMask,
    accel_setpoint_fields,
    read_setpoint,
)
from gcs.wire._signing import (
    SigningKey,
    load_signing_key,
    parse_signing_key,
    signing_timestamp,
    write_signing_key,
)
from gcs.wire._simtruth import TRUTH_MAX_BYTES, SimTruth, vec3
from gcs.wire._stamp import crc_accumulate
from gcs.wire._telemetry import (
    OFFBOARD_LOST_TEXT,
    TELEMETRY_MAX_ABS,
    Attitude,
    Heartbeat,
    LocalPosition,
    Severity,
    StatusText,
    SystemStatus,
    Telemetry,
    TelemetryRecord,
    TelemetryStore,
    ThrustTarget,
)
from gcs.wire._unpack import unpack_v2

__all__ = [
    "ACK_FORMAT",
    "CLOCK_MAX_BYTES",
    "CUSTOM_MODE_ENABLED",
    "DEFAULT_GCS_COMPONENT_ID",
    "DEFAULT_GCS_SYSTEM_ID",
    "OFFBOARD_LOST_TEXT",
    "SAFETY_ARMED",
    "SEAL_OVERHEAD",
    "SETPOINT_MESSAGE",
    "SIM_PX4_MODES",
    "TELEMETRY_MAX_ABS",
    "TRUTH_MAX_BYTES",
    "AccelSetpoint",
    "Attitude",
    "ClockGuard",
    "ClockSample",
    "ClockVerdict",
    "CommandResult",
    "CopterMode",
    "DecodeStats",
    "EncoderBatch",
    "FrameDecoder",
    "Geodetic",
    "Heartbeat",
    "LocalPosition",
    "MavMessage",
    "MavlinkEncoder",
    "Px4AutoSubMode",
    "Px4MainMode",
    "SealError",
    "Sealer",
    "SetpointKind",
    "SetpointPacker",
    "Severity",
    "SigningKey",
    "SimMode",
    "SimTruth",
    "StatusText",
    "SystemStatus",
    "Telemetry",
    "TelemetryRecord",
    "TelemetryStore",
    "ThrustTarget",
    "TypeMask",
    "Unsealer",
    "accel_setpoint_fields",
    "command_name",
    "copter_mode_text",
    "crc_accumulate",
    "decode_ack",
    "decode_clock",
    "decode_time",
    "distinct_rows",
    "ecef_to_geodetic",
    "encode_ack",
    "encode_clock",
    "encode_time",
    "frame_crc",
    "geodetic_mean",
    "geodetic_median",
    "geodetic_to_ecef",
    "geodetic_to_ned",
    "heartbeat_mode_text",
    "keys",
    "load_signing_key",
    "local_origin",
    "mavlink",
    "message_id",
    "ned_to_geodetic",
    "parse_signing_key",
    "px4_base_mode",
    "px4_custom_mode",
    "px4_mode_text",
    "read_setpoint",
    "signing_timestamp",
    "sim_mode_for_px4",
    "sim_mode_of",
    "sim_mode_text",
    "split_px4_custom_mode",
    "unpack_v2",
    "vec3",
    "write_signing_key",
]

__getattr__ = lazy_modules(__name__, ("keys",))
