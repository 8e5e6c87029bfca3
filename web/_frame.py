"""What the scene shows in one frame, computed as plain arrays (NED, SI).

Separating "what to draw" from "how viser draws it" keeps the numbers testable
without a browser and lets the benchmark time the two halves. Nothing here
talks to viser or to the links.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

from gcs.analysis import Analysis
from gcs.config import Team
from gcs.formation import fit_shape
from gcs.loop import FleetState
from gcs.wire import SimTruth
from web import palette
from web._quadmesh import yaw_wxyz
from web._trails import Trails
from web.palette import VehicleState

__all__ = ["FOOT_MARK", "SceneFrame", "TeamView", "build_frame", "drop_line", "frame_reach",
           "rope_pull_estimate", "vehicle_states"]

_HOLD_WORDS = ("HOLD", "LOITER", "POSCTL", "BRAKE")
_LAND_WORDS = ("LAND", "RTL")

LABEL_LIFT = 0.18
"""Height of a vehicle's id label above the vehicle, m."""

ARROW_SECONDS = 1.0
"""A velocity arrow is where the vehicle will be in this time, m per (m/s)."""

FOOT_MARK = 0.08
"""Half-size of the cross that marks the ground under the payload, m."""


@dataclass(frozen=True, eq=False)
class TeamView:
    """What the scene needs to know about a team, fixed for a flight."""

    ids: tuple[int, ...]
    desired_xy: np.ndarray  # (n, 2) desired positions in the team body frame, scale 1, m
    edges: np.ndarray  # (m, 2) vehicle indices (tail, head)
    distances: np.ndarray  # (m,) desired distances at scale 1, m
    rope_length: float  # m
    nominal_tension: float  # rope tension at equilibrium, N
    stale_after: float  # s
    error_full: float = 0.3  # distance error shown fully red, m (paper's worst observed)
    mass: float = math.nan  # one vehicle's mass, kg (NaN: no rope pull estimate)
    nominal_pull: float = math.nan  # horizontal rope pull at the nominal shape (eq. Th), N

    @classmethod
    def from_team(cls, team: Team, analysis: Analysis) -> TeamView:
        f = team.formation
        return cls(ids=f.ids, desired_xy=f.positions, edges=f.edges, distances=f.distances,
                   rope_length=team.config.payload.rope_length,
                   nominal_tension=analysis.equilibrium_tension,
                   stale_after=team.config.safety.stale_after,
                   mass=team.config.airframe.mass, nominal_pull=analysis.rope_pull_nominal)

    @property
    def n(self) -> int:
        return len(self.ids)


@dataclass(frozen=True, eq=False)
class SceneFrame:
    """Everything drawn in one frame; hidden vehicles have scale 0."""

    p_ned: np.ndarray  # (n, 3) vehicle positions (0 where unknown), m
    known: np.ndarray  # (n,) bool
    wxyz: np.ndarray  # (n, 4) heading quaternions
    scales: np.ndarray  # (n,) 1 shown, 0 hidden
    states: np.ndarray  # (n,) VehicleState
    colors: np.ndarray  # (n, 3) uint8
    label_p: np.ndarray  # (n, 3) m
    velocity: np.ndarray  # (k, 2, 3) arrow start and end, m
    ropes: np.ndarray  # (r, 2, 3) vehicle to payload, m
    rope_colors: np.ndarray  # (r, 2, 3) uint8
    payload_p: np.ndarray | None  # (3,) m, None while the team is unknown
    payload_measured: bool  # payload and rope tensions from the simulator's truth; else the
    # payload is placed from geometry and the ropes coloured by the pull estimated from tilt
    edges: np.ndarray  # (e, 2, 3) formation edges with both ends known, m
    edge_colors: np.ndarray  # (e, 2, 3) uint8
    ghost_edges: np.ndarray  # (m, 2, 3) or (0, 2, 3): desired shape fitted to the team, m
    trails: np.ndarray  # (t, 2, 3) m
    trail_colors: np.ndarray  # (t, 2, 3) uint8
    centroid: np.ndarray | None  # (3,) m
    drop: np.ndarray  # (3, 2, 3) or (0, 2, 3): the payload's drop line to the ground and a
    # cross at its foot, m
    payload_height: float  # the payload's height above the ground (z = 0), m (NaN: unknown)


@functools.lru_cache(maxsize=64)
def _mode_states(modes: tuple[str, ...]) -> np.ndarray:
    """VehicleState implied by each flight mode name (modes change rarely: cached)."""
    states = np.full(len(modes), VehicleState.OK, dtype=int)
    for i, mode in enumerate(modes):
        upper = mode.upper()
        if any(w in upper for w in _LAND_WORDS):
            states[i] = VehicleState.LANDING
        elif any(w in upper for w in _HOLD_WORDS):
            states[i] = VehicleState.HOLDING
    states.flags.writeable = False
    return states


def vehicle_states(fleet: FleetState, stale_after: float) -> np.ndarray:
    """Each vehicle's :class:`VehicleState` from telemetry age and flight mode."""
    states = _mode_states(fleet.modes).copy()
    fresh = np.isfinite(fleet.age) & (fleet.age <= stale_after)
    states[~fresh] = VehicleState.STALE
    return states


def rope_pull_estimate(mass: float, tilt: np.ndarray, accel_cmd: np.ndarray,
                       gravity: float = 9.80665) -> np.ndarray:
    """Horizontal rope pull per vehicle from its tilt, N (quasi-static, a lower bound).

    A vehicle that holds its altitude and tilts by ``tilt`` pushes sideways with
    about ``m g tan(tilt)``; what its commanded acceleration does not explain is
    the rope pulling it. Ignoring the rope's vertical load makes this a lower
    bound; it is only meaningful in steady flight.
    """
    side = mass * (gravity * np.tan(np.nan_to_num(tilt)) -
                   np.linalg.norm(np.nan_to_num(accel_cmd), axis=1))
    return np.where(np.isfinite(tilt), np.maximum(side, 0.0), np.nan)


def _rope_colors(view: TeamView, fleet: FleetState, known: np.ndarray, tension: np.ndarray,
                 measured: bool, accel_cmd: np.ndarray | None) -> np.ndarray:
    """Colour per known vehicle's rope: the simulator's tension against its equilibrium,
    else the pull estimated from tilt against the nominal pull (eq. Th), the same scale."""
    if measured:
        return palette.tension_colors(tension[known], view.nominal_tension)
    accel = np.zeros((view.n, 2)) if accel_cmd is None or len(accel_cmd) != view.n \
        else accel_cmd
    pull = rope_pull_estimate(view.mass, fleet.tilt, accel)
    return palette.tension_colors(pull[known], view.nominal_pull)


def _payload(view: TeamView, p: np.ndarray, known: np.ndarray,
             truth: SimTruth | None) -> tuple[np.ndarray | None, bool, np.ndarray]:
    """Payload position, whether measured, and each vehicle's rope tension (NaN: unknown)."""
    tension = np.full(view.n, np.nan)
    if truth is not None and set(truth.ids) >= set(view.ids):
        order = [truth.ids.index(vid) for vid in view.ids]
        tension = np.asarray(truth.rope_tension)[order]
        return np.asarray(truth.payload_p_ned, dtype=float), True, tension
    if not known.any():
        return None, False, tension
    # hanging below the centroid on taut ropes, or resting on the ground (z = 0)
    c = p[known].mean(axis=0)
    r = float(np.mean(np.linalg.norm(p[known, :2] - c[:2], axis=1)))
    drop = math.sqrt(max(view.rope_length**2 - r**2, 0.0))
    return np.array([c[0], c[1], min(c[2] + drop, 0.0)]), False, tension


def drop_line(p: np.ndarray | None) -> np.ndarray:
    """The vertical line from ``p`` (3,) down to the ground (NED z = 0, the team's home
    level) and a cross at its foot, as segments (3, 2, 3); none for an unknown point."""
    if p is None or not np.isfinite(p).all():
        return np.zeros((0, 2, 3))
    foot = np.array([p[0], p[1], 0.0])
    across = np.array([[FOOT_MARK, 0.0, 0.0], [0.0, FOOT_MARK, 0.0]])
    return np.stack((np.stack((p, foot)), np.stack((foot - across[0], foot + across[0])),
                     np.stack((foot - across[1], foot + across[1]))))


def frame_reach(frame: SceneFrame) -> float:
    """How far the team and its payload reach from the team's centroid, horizontally, m
    (0: the team is not known)."""
    if frame.centroid is None:
        return 0.0
    p = frame.p_ned[frame.known]
    if frame.payload_p is not None:
        p = np.vstack((p, frame.payload_p))
    return float(np.max(np.hypot(p[:, 0] - frame.centroid[0], p[:, 1] - frame.centroid[1])))


def _pairs(colors: np.ndarray) -> np.ndarray:
    """Per-segment colours (k, 3) -> per-end colours (k, 2, 3)."""
    return np.repeat(colors[:, None, :], 2, axis=1)


def build_frame(view: TeamView, fleet: FleetState, *, scale: float, truth: SimTruth | None,
                trails: Trails, accel_cmd: np.ndarray | None = None) -> SceneFrame:
    """The scene for the fleet's state; ``scale`` is the operator's shape scale.

    ``trails`` is only read: the caller samples it (at its own rate). ``accel_cmd``
    (n, 2), the loop's latest command, sharpens the rope pull estimated without truth.
    """
    known = np.isfinite(fleet.p_ned).all(axis=1)
    everyone = bool(known.all())
    p = fleet.p_ned if everyone else np.where(known[:, None], fleet.p_ned, 0.0)
    states = vehicle_states(fleet, view.stale_after)

    v = np.where(np.isnan(fleet.v_ned), 0.0, fleet.v_ned)
    moving = known & (np.einsum("ij,ij->i", v, v) > 0.02**2)
    velocity = np.empty((int(moving.sum()), 2, 3))
    velocity[:, 0] = p[moving]
    velocity[:, 1] = p[moving] + ARROW_SECONDS * v[moving]

    payload_p, measured, tension = _payload(view, p, known, truth)
    hanging = p[known]
    ropes = np.empty((0 if payload_p is None else len(hanging), 2, 3))
    ropes[:, 0] = hanging
    ropes[:, 1] = payload_p if payload_p is not None else 0.0
    rope_colors = _pairs(_rope_colors(view, fleet, known, tension, measured, accel_cmd)
                         if payload_p is not None else np.zeros((0, 3), dtype=np.uint8))

    ends = view.edges if everyone else view.edges[known[view.edges].all(axis=1)]
    edges = p[ends]  # (e, 2, 3)
    z = edges[:, 0, :2] - edges[:, 1, :2]
    k = slice(None) if everyone else known[view.edges].all(axis=1)
    error = np.sqrt(np.einsum("ij,ij->i", z, z)) - scale * view.distances[k]
    edge_colors = _pairs(palette.error_colors(error, view.error_full))

    fitted = fit_shape(scale * view.desired_xy, p[:, :2] if everyone
                       else np.where(known[:, None], p[:, :2], np.nan))
    if fitted is None:
        ghost_edges = np.zeros((0, 2, 3))
    else:
        ghost_p = np.empty((view.n, 3))
        ghost_p[:, :2] = fitted
        ghost_p[:, 2] = hanging[:, 2].sum() / len(hanging)
        ghost_edges = ghost_p[view.edges]

    trail_seg, age = trails.segments()
    fade = 255.0 - (255.0 - palette.TRAIL) * np.sqrt(1.0 - age)[:, None]
    label_p = p.copy()
    label_p[:, 2] -= LABEL_LIFT
    return SceneFrame(
        p_ned=p, known=known, wxyz=yaw_wxyz(fleet.yaw), scales=known.astype(float),
        states=states, colors=palette.state_colors(states), label_p=label_p, velocity=velocity,
        ropes=ropes, rope_colors=rope_colors, payload_p=payload_p, payload_measured=measured,
        edges=edges, edge_colors=edge_colors, ghost_edges=ghost_edges, trails=trail_seg,
        trail_colors=_pairs(fade.astype(np.uint8)),
        centroid=hanging.sum(axis=0) / len(hanging) if len(hanging) else None,
        drop=drop_line(payload_p),
        payload_height=-float(payload_p[2]) if payload_p is not None else math.nan)
