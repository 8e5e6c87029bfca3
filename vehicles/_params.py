"""The parameters of a simulated vehicle: its autopilot's real tunables, under PX4's names.

Why: ground stations download every parameter before they show a vehicle
(QGroundControl waits for it, MAVProxy counts ``param_count``), and a GCS
reads and sets the tilt limit (``MPC_TILTMAX_AIR``) before it arms a team.
Each parameter is one field of the vehicle's own
:class:`~vehicles.AutopilotConfig` (setting it reconfigures that vehicle's
autopilot at once, :meth:`vehicles.Autopilot.configure`) or a fixed fact a
PX4 ground station expects. Names are PX4's where PX4 has the same setting;
``INDI_`` names this autopilot's own settings. Values travel as PX4 sends
them: ``REAL32`` as the float, ``INT32`` as the integer's four bytes in the
float field (byte-wise encoding, announced in AUTOPILOT_VERSION).

A PARAM_SET is answered by the PARAM_VALUE of what the parameter holds
afterwards: the new value, or the old one when the set is refused (unknown
type, wrong type, not finite, out of the config field's bounds, or a
read-only parameter), the reason then in :attr:`SetResult.refusal`.
"""

from __future__ import annotations

import dataclasses
import math
import struct
from dataclasses import dataclass
from enum import IntEnum

from gcs.common import ConfigError, from_mapping
from gcs.wire import mavlink
from vehicles._autopilot import Autopilot
from vehicles._config import AutopilotConfig
from vehicles._state import SHARED_SETTINGS

__all__ = ["PARAM_ID_LEN", "PX4_AUTOSTART_QUAD_X", "Param", "ParamTable", "ParamType",
           "SetResult"]

PARAM_ID_LEN = 16
"""Longest parameter name (PARAM_VALUE ``param_id``, not NUL-terminated at 16)."""

PX4_AUTOSTART_QUAD_X = 4001
"""``SYS_AUTOSTART``: PX4's generic quadrotor x airframe."""

_NO_STICKS = 4
"""``COM_RC_IN_MODE`` 4: PX4's "stick input disabled" (the vehicle has no RC)."""

_INT32 = struct.Struct("<i")
_FLOAT = struct.Struct("<f")


class ParamType(IntEnum):
    """MAV_PARAM_TYPE of the parameters."""

    INT32 = mavlink.MAV_PARAM_TYPE_INT32
    REAL32 = mavlink.MAV_PARAM_TYPE_REAL32


@dataclass(frozen=True)
class Param:
    """One parameter: a config field (or one element of a tuple field), or a fixed value."""

    name: str
    kind: ParamType
    setting: str | None = None
    """:class:`~vehicles.AutopilotConfig` field it is; None for a fixed value."""
    element: int | None = None
    """Index into a tuple field (the gains per body axis)."""
    fixed: int | None = None
    """Value of a fixed parameter."""

    @property
    def writable(self) -> bool:
        """Whether PARAM_SET may change it (fixed values and the team's shared loop rate and
        filter cutoffs may not)."""
        return self.setting is not None and self.setting not in SHARED_SETTINGS


def _real(name: str, setting: str, element: int | None = None) -> Param:
    return Param(name, ParamType.REAL32, setting, element)


_SETTINGS = (
    # PX4's names for the same settings
    _real("MPC_TILTMAX_AIR", "bank_max_deg"),  # deg; here roll and pitch each, not the tilt
    _real("MPC_TKO_SPEED", "climb_rate"),
    _real("MPC_LAND_SPEED", "land_speed"),
    _real("MIS_TAKEOFF_ALT", "takeoff_altitude"),
    _real("COM_OF_LOSS_T", "setpoint_timeout"),
    _real("COM_DISARM_LAND", "touchdown_time"),
    # this INDI autopilot's own
    _real("INDI_LOOP_HZ", "rate_hz"),
    _real("INDI_ACC_CUTOFF", "accel_filter_cutoff_hz"),
    _real("INDI_RATE_CUTOFF", "rate_filter_cutoff_hz"),
    _real("INDI_ACC_ERR_XY", "accel_error_max_xy"),
    _real("INDI_ACC_ERR_Z", "accel_error_max_z"),
    *(_real(f"INDI_ATT_GAIN_{axis}", "attitude_gain", k) for k, axis in enumerate("XYZ")),
    *(_real(f"INDI_RATE_GAIN_{axis}", "rate_gain", k) for k, axis in enumerate("XYZ")),
    _real("INDI_ALT_KP", "altitude_kp"),
    _real("INDI_ALT_KV", "altitude_kv"),
    _real("INDI_HOLD_KP", "hold_kp"),
    _real("INDI_HOLD_KV", "hold_kv"),
    _real("INDI_TKO_TOL", "takeoff_tolerance"),
    _real("INDI_HOLD_TOUT", "hold_timeout"),
    _real("INDI_GND_CLEAR", "ground_clearance"),
    _real("INDI_IDLE_THR", "idle_thrust_fraction"),
    _real("INDI_THR_FLOOR", "thrust_floor_fraction"),
    _real("INDI_ATT_CORR", "attitude_correction_gain"),
)


def parameters(sysid: int) -> tuple[Param, ...]:
    """Every parameter of vehicle ``sysid``, in index order (by name, as PX4 lists them)."""
    fixed = (Param("SYS_AUTOSTART", ParamType.INT32, fixed=PX4_AUTOSTART_QUAD_X),
             Param("MAV_SYS_ID", ParamType.INT32, fixed=sysid),
             Param("COM_RC_IN_MODE", ParamType.INT32, fixed=_NO_STICKS))
    return tuple(sorted((*_SETTINGS, *fixed), key=lambda p: p.name))


@dataclass(frozen=True)
class SetResult:
    """What a PARAM_SET did: the parameter to answer with (None: no such parameter) and, when
    refused, why."""

    index: int | None
    refusal: str = ""


class ParamTable:
    """The parameters of vehicle ``index`` of ``autopilot``, MAVLink system ``sysid``."""

    def __init__(self, autopilot: Autopilot, index: int, *, sysid: int) -> None:
        self._autopilot = autopilot
        self._vehicle = index
        self._params = parameters(sysid)
        self._by_name = {p.name: k for k, p in enumerate(self._params)}

    @property
    def count(self) -> int:
        """Number of parameters (PARAM_VALUE ``param_count``)."""
        return len(self._params)

    def __getitem__(self, index: int) -> Param:
        return self._params[index]

    def index_of(self, name: str) -> int | None:
        """Index of parameter ``name``, None if there is none."""
        return self._by_name.get(name)

    def value(self, index: int) -> float:
        """The parameter's value (an integer for INT32)."""
        p = self._params[index]
        if p.fixed is not None:
            return p.fixed
        assert p.setting is not None
        value = getattr(self._autopilot.vehicle_config(self._vehicle), p.setting)
        return float(value if p.element is None else value[p.element])

    def wire_value(self, index: int) -> float:
        """PARAM_VALUE ``param_value``: the float, or an INT32's bytes read as a float."""
        value = self.value(index)
        if self._params[index].kind is ParamType.INT32:
            return float(_FLOAT.unpack(_INT32.pack(int(value)))[0])
        return value

    def set(self, name: str, wire_value: float, wire_type: int) -> SetResult:
        """Apply a PARAM_SET of ``name`` to ``wire_value`` sent as MAV_PARAM_TYPE ``wire_type``."""
        index = self.index_of(name)
        if index is None:
            return SetResult(None, f"{name}: no such parameter")
        p = self._params[index]
        if wire_type != p.kind:
            return SetResult(index, f"{name}: is {p.kind.name}, not type {wire_type}")
        if not p.writable:
            return SetResult(index, f"{name}: read-only")
        assert p.setting is not None  # writable
        if not math.isfinite(wire_value):
            return SetResult(index, f"{name}: not a finite number")
        config = self._autopilot.vehicle_config(self._vehicle)
        value: object = float(wire_value)
        if p.element is not None:
            items = list(getattr(config, p.setting))
            items[p.element] = value
            value = items
        try:
            new = from_mapping(AutopilotConfig, {**_fields(config), p.setting: value}, name)
        except ConfigError as exc:
            return SetResult(index, f"{name}: {exc.what}")
        self._autopilot.configure(self._vehicle, new)
        return SetResult(index)


def _fields(config: AutopilotConfig) -> dict[str, object]:
    """The config as the mapping :func:`gcs.common.from_mapping` reads (tuples stay tuples)."""
    return {f.name: getattr(config, f.name) for f in dataclasses.fields(config)}
