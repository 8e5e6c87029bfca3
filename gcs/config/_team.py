"""Team configuration: the shape, gains, limits, payload and airframe of one team.

A team file (``configs/*.yaml``) is loaded into a frozen :class:`TeamConfig`
and its shape into a :class:`~gcs.formation.Formation`; every mistake is refused
with one line naming the file, the field and what is wrong: wrong types and
values out of range, limits that contradict each other (altitude range, geofence,
lift and take-off heights, scale step), a physically impossible team (an airframe
that cannot hover, ropes that cannot reach, vehicles closer than their rotors) and
signing key files that are missing or no key (docs/teams.md lists them).

Vehicle positions are in the team's body frame: x forward, y right (NED-like),
metres. Edges are ``[tail, head]`` or ``[tail, head, distance]`` by vehicle id,
or mappings ``{tail: 1, head: 2, distance: 1.0}``.

Required fields have no default: the physical and gain figures of a team (its
airframe file, every field of ``guidance`` but the setpoint rate, the scale
range and the hold compensation, every field of ``limits`` and ``payload``, and
``analysis.max_distance_error`` and ``analysis.design_rope_angle_deg``), so a
file that forgets one is refused instead of flying the paper's numbers. The
defaults left are engineering choices that are not figures of the paper:
setpoint re-send rate, scale range, operator shaping, safety thresholds,
flight-phase heights and timings, standard gravity, links.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

import numpy as np

from gcs.common import STANDARD_GRAVITY, ConfigError, FieldError, field, from_mapping, load_yaml
from gcs.config._frame import TeamFrameConfig
from gcs.config._links import GcsLinkConfig, LinkConfig, check_links
from gcs.config._team_key import team_key_path
from gcs.formation import Formation, FormationError, build_formation
from gcs.wire import load_signing_key
from vehicles import Airframe, check_airframe, load_airframe

__all__ = [
    "AnalysisConfig",
    "ConfigError",
    "EdgeSpec",
    "FlightConfig",
    "GuidanceConfig",
    "LimitsConfig",
    "OperatorConfig",
    "PayloadConfig",
    "SafetyConfig",
    "Team",
    "TeamConfig",
    "VehicleSpec",
    "load_team",
]

MAX_EXTENT = 1e4
"""Largest vehicle coordinate and edge distance, m: a team flown by one GCS over its
radio links fits in a few kilometres (and beyond this, squares of distances lose
the precision the rigidity test needs)."""

MAX_SPEED = 20.0
"""Largest translation speed and speed error, m/s: above any rotorcraft that carries a
payload on ropes (the Bebop 2 flies at most 16 m/s, alone)."""


@dataclass(frozen=True)
class VehicleSpec:
    """One member of the team."""

    id: int = field(doc="MAVLink system id of the vehicle", ge=1, le=254)
    position: tuple[float, float] | None = field(
        doc="desired position in the team body frame (x forward, y right), m", default=None,
        ge=-MAX_EXTENT, le=MAX_EXTENT)


@dataclass(frozen=True)
class EdgeSpec:
    """One controlled distance between two vehicles (by id)."""

    tail: int = field(doc="vehicle id at the tail (z_k = p_tail - p_head)")
    head: int = field(doc="vehicle id at the head")
    distance: float | None = field(doc="desired distance, m (derived from positions if absent)",
                                   default=None, gt=0.0, le=MAX_EXTENT)


@dataclass(frozen=True)
class GuidanceConfig:
    """Gains and operator ranges of the formation-motion guidance (eq. udi)."""

    c1: float = field(doc="velocity gain c1, 1/s", gt=0.0)
    c2: float = field(doc="distance gain c2, 1/s^2", gt=0.0)
    rate_hz: float = field(doc="guidance rate, Hz (the loop's tick; 4 Hz in the paper)",
                           ge=0.5, le=50.0)
    max_speed: float = field(doc="translation speed at full stick, m/s", gt=0.0,
                             le=MAX_SPEED)
    max_rotation_disagreement: float = field(
        doc="largest rotation disagreement mu_r at full stick, m/s", ge=0.0, le=MAX_SPEED)
    setpoint_rate_hz: float = field(
        doc="setpoints per second to each vehicle: the latest guidance output is re-sent "
            "between ticks, so one late tick does not trip the autopilot's setpoint timeout "
            "(0.5 s in the sim, COM_OF_LOSS_T on PX4); a whole multiple of rate_hz",
        default=12.0, gt=0.0, le=100.0)
    scale_min: float = field(doc="smallest shape scale", default=0.3, gt=0.0)
    scale_max: float = field(doc="largest shape scale", default=2.0, gt=0.0)
    scale_step: float = field(doc="scale change per operator step", default=0.05, gt=0.0)
    hold_compensation: bool = field(
        doc="predict relative positions half a period ahead (see gcs.guidance)", default=True)
    rope_lag: float = field(
        doc="the vehicles' autopilots' lag in following an external force, s: while the "
            "team spins, each setpoint leads the rope's turning pull by it, and while the "
            "ropes take the payload (lifting, with load sharing) its growing pull "
            "(gcs/guidance/_rope_lead.py); 0 turns the leads off", default=0.0, ge=0.0,
        le=2.0)
    setpoint_lag: float = field(
        doc="the autopilots' lag in following an acceleration setpoint, s: the guidance "
            "predicts the relative positions this much further ahead (about 0.25 for "
            "ArduCopter; 0 for the simulated INDI vehicles, whose lag the hold's "
            "prediction covers)", default=0.0, ge=0.0, le=1.0)
    turn_compensation: bool = field(
        doc="the spin's feed-forward is the centripetal acceleration of the turn each "
            "vehicle's edges make, not of the commanded one, so that starting or stopping a "
            "spin does not pull the shape in or out (see gcs.guidance); false is eq. udi",
        default=True)

    @property
    def setpoints_per_tick(self) -> int:
        """Setpoints each vehicle gets per guidance tick (the tick's own included)."""
        return round(self.setpoint_rate_hz / self.rate_hz)

    def __post_init__(self) -> None:
        ratio = self.setpoint_rate_hz / self.rate_hz
        if ratio < 1.0 - 1e-9 or abs(ratio - round(ratio)) > 1e-6:
            raise ValueError(f"guidance.setpoint_rate_hz ({self.setpoint_rate_hz:g} Hz) must be a "
                             f"whole multiple of guidance.rate_hz ({self.rate_hz:g} Hz)")
        if self.scale_min > 1.0 or self.scale_max < 1.0:
            raise ValueError(f"guidance.scale_min/scale_max must bracket 1, got "
                             f"[{self.scale_min:g}, {self.scale_max:g}]")


@dataclass(frozen=True)
class LimitsConfig:
    """Physical and safety limits enforced on the vehicles and the guidance."""

    bank_deg: float = field(doc="largest roll/pitch angle, degrees", gt=0.0, lt=90.0)
    accel_norm: float = field(doc="saturation of the horizontal acceleration norm, m/s^2",
                              gt=0.0)
    accel_axis: float = field(doc="saturation of each horizontal acceleration axis, m/s^2",
                              gt=0.0)
    autopilot_tilt: Literal["check", "set"] = field(
        doc="a real autopilot's own tilt limit (ArduPilot ANGLE_MAX, PX4 MPC_TILTMAX_AIR) above "
            "bank_deg: refuse to arm (check), or set it to bank_deg and read it back (set)",
        default="check")

    @property
    def bank(self) -> float:
        """Bank limit, rad."""
        return math.radians(self.bank_deg)


@dataclass(frozen=True)
class PayloadConfig:
    """The suspended payload and its ropes."""

    mass: float = field(doc="payload mass M, kg", gt=0.0)
    rope_length: float = field(
        doc="rope length l of every vehicle, m; with rope_lengths it may be left out (it is "
            "then the longest of them)", gt=0.0, le=100.0)
    rope_lengths: tuple[float, ...] | None = field(
        doc="each vehicle's own rope length, m, in the order of vehicles (default: all "
            "rope_length)", default=None, gt=0.0, le=100.0)

    def lengths(self, n_vehicles: int) -> tuple[float, ...]:
        """Each vehicle's rope length, m, in team order."""
        if self.rope_lengths is not None:
            return self.rope_lengths
        return (self.rope_length,) * n_vehicles


@dataclass(frozen=True)
class AnalysisConfig:
    """Assumptions of the worst-case analysis (paper, section 'Force and worst case')."""

    max_distance_error: float = field(doc="worst distance error assumed in eq. max, m",
                                      gt=0.0)
    design_rope_angle_deg: float = field(
        doc="largest rope angle from the vertical the design must withstand, degrees",
        gt=0.0, lt=90.0)
    max_speed_error: float | None = field(
        doc="worst speed error ||e_v|| in eq. max, m/s (default: guidance.max_speed)",
        default=None, gt=0.0, le=MAX_SPEED)
    payload_share: int | None = field(
        doc="a vehicle may carry 1/share of the payload weight (default: vehicles - 1)",
        default=None, ge=1)
    gravity: float = field(doc="gravitational acceleration, m/s^2", default=STANDARD_GRAVITY,
                           gt=0.0, le=30.0)
    position_error: float = field(
        doc="how far (3-D) a vehicle may be off its place with the payload hanging, m: the "
            "worst share of the payload is taken over such errors", default=0.02, ge=0.0,
        le=1.0)
    hold_stiffness: float = field(
        doc="a vehicle's position hold in series with its rope, N/m: how far a rope's pull "
            "moves its vehicle (100 fits the simulator's vehicles)", default=100.0, gt=0.0,
        le=1e7)
    disturbance_accel: float = field(
        doc="steady acceleration per vehicle the guidance neither commands nor sees "
            "(tracking residual, gusts, rope pulls in motion), m/s^2: the shape's weakest "
            "mode must hold it within the safe deformation (0.025 covers the simulator's "
            "paper flight with gusts; measure your vehicles')", default=0.025, gt=0.0,
        le=10.0)


@dataclass(frozen=True)
class OperatorConfig:
    """How operator inputs (browser, gamepad, script) are shaped."""

    deadzone: float = field(doc="stick deadzone, fraction of full travel", default=0.05,
                            ge=0.0, lt=1.0)
    expo: float = field(doc="stick expo (0 linear, 1 cubic)", default=0.3, ge=0.0, le=1.0)
    stick_timeout: float = field(doc="sticks fall back to zero this long after the last "
                                 "input from a source, s", default=1.0, gt=0.0)
    altitude_rate: float = field(doc="largest rate of the altitude target, m/s", default=0.3,
                                 gt=0.0)
    altitude_min: float = field(doc="lowest altitude target above the ground, m", default=0.0,
                                ge=0.0)
    altitude_max: float = field(doc="highest altitude target above the ground, m", default=4.0,
                                gt=0.0)
    altitude_step: float = field(doc="altitude change per operator step, m", default=0.1,
                                 gt=0.0)
    scale_rate: float = field(doc="largest rate of change of the shape's scale, 1/s",
                              default=0.05, gt=0.0)

    def __post_init__(self) -> None:
        if self.altitude_min >= self.altitude_max:
            raise FieldError("altitude_min", f"{self.altitude_min:g} m is at or above "
                             f"operator.altitude_max ({self.altitude_max:g} m): no altitude "
                             f"is left to fly at")
        if self.altitude_step > self.altitude_max - self.altitude_min:
            raise FieldError("altitude_step", f"{self.altitude_step:g} m is wider than the "
                             f"whole altitude range operator.altitude_min..altitude_max "
                             f"[{self.altitude_min:g}, {self.altitude_max:g}] m")


@dataclass(frozen=True)
class SafetyConfig:
    """Safety rules of the GCS loop (each enforced in gcs/loop/_safety.py)."""

    stale_after: float = field(doc="telemetry older than this freezes the motion, s",
                               default=0.5, gt=0.0)
    land_after: float = field(doc="a vehicle silent this long lands the team, s", default=3.0,
                              gt=0.0)
    geofence_xy: float = field(doc="half-size of the horizontal geofence box around the "
                               "origin, m", default=4.0, gt=0.0)
    geofence_altitude: float = field(doc="highest altitude above the ground, m", default=4.0,
                                     gt=0.0)
    geofence_margin: float = field(doc="warning margin inside the geofence: closer to the fence "
                                   "than this warns, and the motion towards the fence is "
                                   "slowed to stop at it, m", default=0.5, ge=0.0)
    recovery: Literal["auto", "operator"] = field(
        doc="vehicles that dropped out of the streaming mode on a setpoint gap while flying, "
            "healthy and in shape: re-engaged by the GCS (auto) or on the operator's resume "
            "(operator)", default="auto")
    recover_after: float = field(doc="with automatic recovery, every link fresh this long "
                                 "before the vehicles are re-engaged, s", default=1.0, gt=0.0)
    deformed_land_growth: float = field(
        doc="while the team holds a shape deformed beyond the analysis' safe bound (each "
            "vehicle on its own point), the team lands if the deformation grows by this much "
            "more, m",
        default=0.3, gt=0.0)

    def __post_init__(self) -> None:
        if self.land_after < self.stale_after:
            raise ValueError(f"safety.land_after ({self.land_after:g} s) must not be shorter "
                             f"than safety.stale_after ({self.stale_after:g} s)")
        if self.geofence_margin >= self.geofence_xy:
            raise ValueError(f"safety.geofence_margin ({self.geofence_margin:g} m) must be "
                             f"smaller than safety.geofence_xy ({self.geofence_xy:g} m)")
        if self.geofence_margin >= self.geofence_altitude:
            raise FieldError("geofence_margin", f"{self.geofence_margin:g} m is not below "
                             f"safety.geofence_altitude ({self.geofence_altitude:g} m)")


@dataclass(frozen=True)
class FlightConfig:
    """Heights and timings of the flight phases (gcs/loop/_phases.py)."""

    takeoff_slack: float = field(doc="take off to this far below the altitude where the ropes "
                                 "become taut, m", default=0.15, ge=0.0)
    lift_height: float = field(doc="climb above the taut-rope altitude to lift the payload, m",
                               default=1.0, gt=0.0)
    lift_rate: float = field(doc="climb and descent rate while lifting and setting down the "
                             "payload, m/s: slow, so the ropes take the load gently",
                             default=0.1, gt=0.0)
    pickup_rate: float = field(doc="climb and descent rate inside the pickup band, where the "
                               "ropes take up or give up the payload's weight, m/s: the "
                               "tension then grows slowly enough for the vehicles' "
                               "autopilots to hold their places", default=0.02, gt=0.0)
    pickup_band: tuple[float, float] = field(
        doc="the pickup band: from this far below to this far above the taut-rope "
            "altitude, m", default=(0.10, 0.15))
    altitude_tolerance: float = field(doc="an altitude counts as reached within this, m",
                                      default=0.1, gt=0.0)
    takeoff_timeout: float = field(doc="longest take-off before it is declared failed, s",
                                   default=30.0, gt=0.0)
    abort_hold: float = field(doc="after an abort, hold this long before landing, s",
                              default=1.0, ge=0.0)
    load_sharing: bool = field(
        doc="trim each vehicle's altitude so the payload's weight splits over four or more "
            "ropes as at the desired shape, from the vehicles' collective thrusts "
            "(ATTITUDE_TARGET; gcs/loop/_load_share.py)", default=True)
    load_share_gain: float = field(
        doc="altitude trim per unit of share off target, m (a vehicle carrying 0.1 of the "
            "payload more than designed is lowered by a tenth of this)", default=0.4,
        ge=0.0, le=1.0)
    load_share_trim_max: float = field(doc="largest altitude trim of load sharing, m",
                                       default=0.05, gt=0.0, le=0.5)

    def __post_init__(self) -> None:
        below, above = self.pickup_band
        if not (math.isfinite(below) and math.isfinite(above) and below >= 0.0
                and above >= 0.0):
            raise FieldError("pickup_band", f"[{below:g}, {above:g}]: both heights must be "
                             "non-negative metres (below and above the taut-rope altitude)")
        if self.pickup_rate > self.lift_rate:
            raise FieldError("pickup_rate", f"{self.pickup_rate:g} m/s is faster than "
                             f"flight.lift_rate ({self.lift_rate:g} m/s): the pickup band is "
                             "the slow part of the lift")


@dataclass(frozen=True)
class TeamConfig:
    """Everything that defines one team; see configs/bebop_square.yaml."""

    name: str = field(doc="team name (also the zenoh fleet name)")
    airframe: Airframe = field(doc="airframe of every vehicle: a file path or a mapping")
    vehicles: tuple[VehicleSpec, ...] = field(doc="team members", min_len=2)
    edges: tuple[EdgeSpec, ...] = field(doc="controlled distances", min_len=1)
    guidance: GuidanceConfig = field(doc="guidance gains and ranges")
    limits: LimitsConfig = field(doc="limits")
    payload: PayloadConfig = field(doc="payload and ropes")
    analysis: AnalysisConfig = field(doc="worst-case analysis assumptions")
    operator: OperatorConfig = field(doc="operator input shaping",
                                     default_factory=OperatorConfig)
    safety: SafetyConfig = field(doc="safety rules", default_factory=SafetyConfig)
    flight: FlightConfig = field(doc="flight phases", default_factory=FlightConfig)
    gcs: GcsLinkConfig = field(doc="the GCS's identity and zenoh settings",
                               default_factory=GcsLinkConfig)
    links: tuple[LinkConfig, ...] | None = field(
        doc="how to reach each vehicle (default: every vehicle simulated, over zenoh)",
        default=None)
    team_frame: TeamFrameConfig = field(
        doc="how every vehicle is placed in one frame (docs/autopilots.md)",
        default_factory=TeamFrameConfig)

    def vehicle_links(self) -> tuple[LinkConfig, ...]:
        """The configured links, or a simulated zenoh link per vehicle."""
        if self.links is not None:
            return self.links
        return tuple(LinkConfig(sysid=v.id) for v in self.vehicles)


@dataclass(frozen=True, eq=False)
class Team:
    """A loaded team: its validated config, its formation and where it came from."""

    config: TeamConfig
    formation: Formation
    source: str

    def taut_altitude(self, scale: float = 1.0) -> float:
        """Vehicle altitude at which the first rope becomes taut, with the shape at ``scale``
        and the payload on the ground under the centroid, m (each rope its own length)."""
        return _taut_altitude(self.config, self.formation, scale)

    def without_signing(self) -> Team:
        """This team with the team key off (``--insecure``): its simulated links unsigned."""
        gcs = dataclasses.replace(self.config.gcs, signing=False)
        return dataclasses.replace(self, config=dataclasses.replace(self.config, gcs=gcs))


def _normalise(raw: Any, path: Path) -> Any:
    """Accept the short forms of the file (edge lists, airframe by path)."""
    if not isinstance(raw, dict):
        return raw
    raw = dict(raw)
    edges = raw.get("edges")
    if isinstance(edges, list):
        out = []
        for k, e in enumerate(edges):
            if isinstance(e, list):
                if len(e) not in (2, 3):
                    raise ConfigError(str(path), f"edges[{k}]",
                                      f"expected [tail, head] or [tail, head, distance], "
                                      f"got {len(e)} values")
                e = dict(zip(("tail", "head", "distance"), e, strict=False))
            out.append(e)
        raw["edges"] = out
    payload = raw.get("payload")
    if isinstance(payload, dict) and "rope_length" not in payload:
        ropes = payload.get("rope_lengths")
        if isinstance(ropes, list) and ropes and all(
                isinstance(r, int | float) and not isinstance(r, bool) for r in ropes):
            raw["payload"] = {**payload, "rope_length": max(ropes)}  # each checked later
    frame = raw.get("airframe")
    if isinstance(frame, str):
        frame_path = (path.parent / frame).resolve()
        if frame_path.is_dir():
            raise ConfigError(str(path), "airframe", f"{frame} is a directory, not an "
                                                     f"airframe file")
        if not frame_path.is_file():
            raise ConfigError(str(path), "airframe", f"file not found: {frame}")
        raw["airframe"] = load_airframe(frame_path)
    return raw


def load_team(path: str | Path, *, mapping: Any = None) -> Team:
    """Load and validate a team file; raises ConfigError (one line) on any mistake.

    ``mapping``: the team's contents in place of the file's (a config changed in memory,
    :func:`gcs.common.to_mapping`'s form), checked as the file would be; the file's
    directory still anchors relative paths (airframe, keys, certificates).
    """
    path = Path(path)
    raw = _normalise(load_yaml(path) if mapping is None else mapping, path)
    cfg = from_mapping(TeamConfig, raw, str(path))
    if not isinstance(raw.get("airframe"), Airframe):  # given inline: checked here
        check_airframe(cfg.airframe, str(path), "airframe")
    ids = [v.id for v in cfg.vehicles]
    have_pos = [v.position is not None for v in cfg.vehicles]
    if any(have_pos) and not all(have_pos):
        k = have_pos.index(False)
        raise ConfigError(str(path), f"vehicles[{k}].position",
                          "missing: give every vehicle a position, or none")
    positions = np.array([v.position for v in cfg.vehicles]) if all(have_pos) else None
    try:
        formation = build_formation(ids, [(e.tail, e.head) for e in cfg.edges],
                                    positions=positions,
                                    distances=[e.distance for e in cfg.edges])
    except FormationError as exc:
        raise ConfigError(str(path), exc.where, exc.what) from None
    if cfg.links is not None:
        check_links(cfg.links, gcs_system_id=cfg.gcs.system_id, source=str(path))
        linked = {link.sysid for link in cfg.links}
        for k, vid in enumerate(ids):
            if vid not in linked:
                raise ConfigError(str(path), f"vehicles[{k}].id",
                                  f"vehicle {vid} has no entry under links")
        for k, link in enumerate(cfg.links):
            if link.sysid not in ids:
                raise ConfigError(str(path), f"links[{k}].sysid",
                                  f"system id {link.sysid} is not a vehicle of the team")
    elif cfg.gcs.system_id in ids:
        k = ids.index(cfg.gcs.system_id)
        raise ConfigError(str(path), f"vehicles[{k}].id",
                          f"{cfg.gcs.system_id} is the GCS's own system id (gcs.system_id)")
    if cfg.limits.accel_axis > cfg.limits.accel_norm:
        raise ConfigError(str(path), "limits.accel_axis",
                          f"{cfg.limits.accel_axis:g} m/s^2 exceeds limits.accel_norm "
                          f"{cfg.limits.accel_norm:g} m/s^2")
    g = cfg.guidance
    if g.scale_step > g.scale_max - g.scale_min:  # here: the GCS may lower scale_max later
        raise ConfigError(str(path), "guidance.scale_step",
                          f"{g.scale_step:g} is wider than the whole scale range "
                          f"guidance.scale_min..scale_max [{g.scale_min:g}, {g.scale_max:g}]")
    _check_ropes(cfg, len(ids), str(path))
    _check_heights(cfg, formation, str(path))
    _check_room(cfg, formation, str(path))
    _check_signing_keys(cfg, path)
    return Team(config=cfg, formation=formation, source=str(path))


def _check_ropes(cfg: TeamConfig, n_vehicles: int, source: str) -> None:
    """One rope length per vehicle, and ``rope_length`` the longest when both are given."""
    ropes = cfg.payload.rope_lengths
    if ropes is None:
        return
    if len(ropes) != n_vehicles:
        raise ConfigError(source, "payload.rope_lengths",
                          f"{len(ropes)} lengths for {n_vehicles} vehicles: give one per "
                          f"vehicle, in the order of vehicles")
    if cfg.payload.rope_length != max(ropes):
        raise ConfigError(source, "payload.rope_length",
                          f"{cfg.payload.rope_length:g} m is not the longest of "
                          f"payload.rope_lengths ({max(ropes):g} m): leave it out")


def _taut_altitude(cfg: TeamConfig, formation: Formation, scale: float) -> float:
    """Vehicle altitude at which the first rope becomes taut, payload on the ground at the
    centroid (:meth:`Team.taut_altitude`), m."""
    ropes = np.asarray(cfg.payload.lengths(formation.n))
    r = scale * formation.radii
    return float(np.sqrt(np.maximum(ropes**2 - r**2, 0.0)).min())


def _check_heights(cfg: TeamConfig, formation: Formation, source: str) -> None:
    """Refuse altitude limits that contradict each other or the flight phases' heights."""
    op, fl, safety = cfg.operator, cfg.flight, cfg.safety
    ropes = cfg.payload.lengths(formation.n)
    for k, (rope, radius) in enumerate(zip(ropes, formation.radii, strict=True)):
        if rope <= radius:
            at = "payload.rope_length" if cfg.payload.rope_lengths is None else \
                f"payload.rope_lengths[{k}]"
            raise ConfigError(source, at,
                              f"{'ropes' if cfg.payload.rope_lengths is None else 'a rope'} of "
                              f"{rope:g} m cannot reach the payload under the centroid from "
                              f"{float(radius):.4g} m away")
    if op.altitude_max > safety.geofence_altitude:
        raise ConfigError(source, "operator.altitude_max",
                          f"{op.altitude_max:g} m is above safety.geofence_altitude "
                          f"({safety.geofence_altitude:g} m): the operator could fly the "
                          f"team out of its geofence")
    taut = _taut_altitude(cfg, formation, 1.0)
    if taut - fl.takeoff_slack <= 0.0:
        raise ConfigError(source, "flight.takeoff_slack",
                          f"{fl.takeoff_slack:g} m below the taut-rope altitude "
                          f"{taut:.3g} m puts the take-off altitude at or below the ground")
    if op.altitude_min > taut:
        raise ConfigError(source, "operator.altitude_min",
                          f"{op.altitude_min:g} m is above the taut-rope altitude "
                          f"{taut:.3g} m: the payload could never be set down")
    top = _taut_altitude(cfg, formation, cfg.guidance.scale_min)
    if top + fl.lift_height > op.altitude_max:
        raise ConfigError(source, "flight.lift_height",
                          f"lifting {fl.lift_height:g} m above the taut-rope altitude "
                          f"{top:.3g} m (at guidance.scale_min {cfg.guidance.scale_min:g}) "
                          f"climbs above operator.altitude_max ({op.altitude_max:g} m): "
                          f"{_lift_fixes(cfg, top)}")


def _lift_fixes(cfg: TeamConfig, top: float) -> str:
    """What brings the lift under the ceiling, each alone: a lower lift, a higher ceiling
    (with the geofence's), a larger smallest scale (the taut altitude at it) or shorter
    ropes."""
    lift, ceiling = cfg.flight.lift_height, cfg.operator.altitude_max
    fixes = []
    if ceiling - top > 0.0:
        fixes.append(f"flight.lift_height at most {_down(ceiling - top)}")
    need = top + lift
    raise_ = f"operator.altitude_max at least {_up(need)}"
    if need > cfg.safety.geofence_altitude:
        raise_ += f" with safety.geofence_altitude at least {_up(need)}"
    fixes.append(raise_)
    shorter = lift + top - ceiling
    fixes.append(f"ropes {_up(shorter)} m shorter")
    return "set " + ", or ".join(fixes)


def _down(x: float) -> str:
    return f"{math.floor(x * 1000.0) / 1000.0:.3f}"


def _up(x: float) -> str:
    return f"{math.ceil(x * 1000.0) / 1000.0:.3f}"


def _check_room(cfg: TeamConfig, formation: Formation, source: str) -> None:
    """Refuse a geofence the team cannot fit in, and vehicles closer than their rotors."""
    g, safety = cfg.guidance, cfg.safety
    reach = g.scale_max * float(formation.radii.max())
    if reach + safety.geofence_margin >= safety.geofence_xy:
        raise ConfigError(source, "safety.geofence_xy",
                          f"{safety.geofence_xy:g} m leaves no room for the team at "
                          f"guidance.scale_max {g.scale_max:g} ({reach:.3g} m from its centre "
                          f"to a vehicle) inside safety.geofence_margin "
                          f"{safety.geofence_margin:g} m")
    p = formation.positions
    gaps = np.linalg.norm(p[:, None, :] - p[None, :, :], axis=2)
    gaps[np.diag_indices(len(p))] = np.inf
    i, j = np.unravel_index(int(np.argmin(gaps)), gaps.shape)
    span = 2.0 * math.hypot(cfg.airframe.arm_x, cfg.airframe.arm_y)
    closest = float(gaps[i, j])
    if closest * g.scale_min < span:
        at = "vehicles" if closest < span else "guidance.scale_min"
        ids = formation.ids
        raise ConfigError(source, at,
                          f"vehicles {ids[i]} and {ids[j]} are {closest:.3g} m apart at "
                          f"scale 1 and {closest * g.scale_min:.3g} m at guidance.scale_min "
                          f"{g.scale_min:g}: closer than twice the airframe's rotor offset "
                          f"hypot(arm_x, arm_y) ({span:.3g} m), they would collide")


def _check_signing_keys(cfg: TeamConfig, path: Path) -> None:
    """Every signing key the links name exists and is a key: refused here, not when the
    simulator or a link first reads it."""
    for k, link in enumerate(cfg.links or ()):
        key_path = link.signing_key_path(path.parent)
        if key_path is None:
            continue
        try:
            load_signing_key(key_path)
        except ConfigError as exc:
            raise ConfigError(str(path), f"links[{k}].signing_key",
                              f"{link.signing_key}: {exc.what}") from None
    team_key = team_key_path(cfg.gcs, path.parent)
    if cfg.gcs.team_key is not None or team_key.exists():
        try:
            load_signing_key(team_key)
        except ConfigError as exc:
            raise ConfigError(str(path), "gcs.team_key", f"{team_key}: {exc.what}") from None

