"""How the GCS places every vehicle in one frame: the ``team_frame:`` section of a team file.

Real autopilots each keep their own local origin (ArduPilot and PX4 set it at
their first GPS fix), so their LOCAL_POSITION_NED are not in one frame. The
GCS flies the formation in one NED frame about a team origin, tied to each
vehicle's local frame in one of three ways (``mode``):

* ``global``: each vehicle's own origin (GPS_GLOBAL_ORIGIN, or its
  GLOBAL_POSITION_INT beside its LOCAL_POSITION_NED) places its local frame
  in the team frame; the default for PX4 and ArduPilot links;
* ``set_origin``: the GCS gives every vehicle one origin
  (SET_GPS_GLOBAL_ORIGIN) before arming and checks each answers with it; the
  local frames are then one (GPS-less and motion-capture setups);
* ``shared``: the local frames are one already (this project's simulator, one
  motion-capture system); the default for simulated links.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass
from typing import Literal

from gcs.common import FieldError, field

__all__ = ["GeoPoint", "TeamFrameConfig"]

FrameMode = Literal["global", "set_origin", "shared"]


@dataclass(frozen=True)
class GeoPoint:
    """A place on the WGS-84 ellipsoid."""

    lat: float = field(doc="latitude, degrees north", ge=-90.0, le=90.0)
    lon: float = field(doc="longitude, degrees east", ge=-180.0, le=180.0)
    alt: float = field(doc="altitude above mean sea level, m", ge=-1000.0, le=10000.0)


@dataclass(frozen=True)
class TeamFrameConfig:
    """The frame the formation is flown in (see the module docstring)."""

    mode: Literal["auto", "global", "set_origin", "shared"] = field(
        doc="global: each vehicle placed through its own origin; set_origin: one origin sent "
            "to every vehicle before arming; shared: the local frames are one already; auto: "
            "shared when every link is simulated, global otherwise", default="auto")
    origin: GeoPoint | None = field(
        doc="the team origin {lat, lon, alt}: set_origin sends it to every vehicle (needed "
            "there); global places the team frame about it (default: the mean of the "
            "vehicles' own origins, where they stood at their first fix)", default=None)
    origin_tolerance: float = field(
        doc="set_origin: farthest a vehicle's reported origin may lie from the team origin, m",
        default=0.05, gt=0.0, le=100.0)

    def __post_init__(self) -> None:
        if self.mode == "set_origin" and self.origin is None:
            raise FieldError("origin", "team_frame.mode set_origin needs the origin to send "
                                       "every vehicle ({lat: ..., lon: ..., alt: ...})")

    def resolved(self, profiles: Iterable[str]) -> FrameMode:
        """The mode for links with these profiles (``auto`` resolved)."""
        if self.mode != "auto":
            return self.mode
        return "shared" if all(p == "sim" for p in profiles) else "global"
