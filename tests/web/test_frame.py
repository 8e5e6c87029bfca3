"""What the scene draws: colours, the fitted ghost, trails, the vehicle model, one frame."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from gcs.analysis import analyze
from gcs.config import load_team
from gcs.formation import fit_shape
from gcs.loop import FleetState
from gcs.wire import SimTruth
from tests.support.colours import hue_apart, hue_saturation_value
from tests.support.paths import ROOT
from web import Trails, palette, quad_mesh
from web._frame import (
    LABEL_LIFT,
    TeamView,
    build_frame,
    frame_reach,
    rope_pull_estimate,
    vehicle_states,
)
from web._quadmesh import yaw_wxyz
from web._scene import compass_at
from web.palette import VehicleState

TEAM = load_team(ROOT / "configs" / "bebop_square.yaml")
VIEW = TeamView.from_team(TEAM, analyze(TEAM))


def fleet_at(p_xy: np.ndarray, *, z: float = -1.5, v: np.ndarray | None = None,
             age: np.ndarray | None = None, modes: tuple[str, ...] | None = None,
             t: float = 10.0) -> FleetState:
    n = len(p_xy)
    p = np.column_stack((p_xy, np.full(n, z)))
    return FleetState(t=t, ids=VIEW.ids, p_ned=p, v_ned=np.zeros((n, 3)) if v is None else v,
                      yaw=np.zeros(n), tilt=np.full(n, 0.1),
                      age=np.full(n, 0.05) if age is None else age,
                      heartbeat_age=np.full(n, 0.2), armed=np.ones(n, dtype=bool),
                      battery=np.full(n, 95.0), modes=modes or ("OFFBOARD",) * n)


def rotate(xy: np.ndarray, angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    return xy @ np.array([[c, s], [-s, c]])


# -- colours --------------------------------------------------------------------------


def test_tension_colours_read_slack_nominal_and_overload() -> None:
    t_eq = VIEW.nominal_tension
    rgb = palette.tension_colors(np.array([0.0, t_eq, 2 * t_eq, 5 * t_eq, np.nan]), t_eq)
    assert rgb.dtype == np.uint8 and rgb.shape == (5, 3)
    assert tuple(rgb[0]) == palette.SLACK
    assert tuple(rgb[1]) == palette.TAUT  # nominal
    assert tuple(rgb[2]) == tuple(rgb[3]) == palette.BAD  # twice nominal or more: red
    assert tuple(rgb[4]) == tuple(palette.UNKNOWN)


def test_error_colours_are_symmetric_and_saturate() -> None:
    rgb = palette.error_colors(np.array([0.0, 0.15, -0.15, 0.3, 2.0]), 0.3)
    assert tuple(rgb[0]) == palette.EDGE_OK
    assert tuple(rgb[1]) == tuple(rgb[2]) == palette.WARN
    assert tuple(rgb[3]) == tuple(rgb[4]) == palette.BAD


def test_only_an_ok_vehicle_is_green_and_only_the_payload_magenta() -> None:
    """Every other colour of the scene, every step of every ramp included, is at least 30
    degrees of hue from both, or too grey to be mistaken (saturation below 0.3)."""
    x = np.linspace(0.0, 3.0, 301)
    others = np.vstack([
        palette.tension_colors(x, 1.0), palette.error_colors(x, 1.0),
        palette.state_colors(np.array([s for s in palette.VehicleState
                                       if s is not palette.VehicleState.OK])),
        [palette.GHOST, palette.VELOCITY, palette.TRAIL, palette.UNKNOWN, palette.GEOFENCE,
         palette.PAYLOAD_ESTIMATED, palette.GROUND_MARK],
    ])
    hue, saturation, _ = hue_saturation_value(others)
    for own in (palette.OK, palette.PAYLOAD):
        (own_saturation,) = hue_saturation_value(np.array([own]))[1]
        assert own_saturation > 0.6
        close = (hue_apart(hue, own) < 30.0) & (saturation >= 0.3)
        assert not close.any(), (own, others[close][:5])
    assert tuple(palette.state_colors(np.array([palette.VehicleState.OK]))[0]) == palette.OK


def test_ramp_interpolates_between_stops() -> None:
    rgb = palette.ramp(np.array([0.5]), (0.0, 1.0), ((0, 0, 0), (200, 100, 50)))
    assert np.abs(rgb[0].astype(int) - (100, 50, 25)).max() <= 1


# -- ghost ----------------------------------------------------------------------------


def test_fit_recovers_a_rigidly_moved_shape() -> None:
    desired = VIEW.desired_xy
    actual = rotate(desired, 0.7) + [2.0, -1.0]
    np.testing.assert_allclose(fit_shape(desired, actual), actual, atol=1e-12)


def test_fit_keeps_the_desired_distances_of_a_deformed_team() -> None:
    rng = np.random.default_rng(3)
    actual = rotate(VIEW.desired_xy, -0.4) + [1.0, 1.0] + rng.normal(0, 0.05, (4, 2))
    ghost = fit_shape(VIEW.desired_xy, actual)
    assert ghost is not None
    e = VIEW.edges
    np.testing.assert_allclose(np.linalg.norm(ghost[e[:, 0]] - ghost[e[:, 1]], axis=1),
                               VIEW.distances, atol=1e-12)
    np.testing.assert_allclose(ghost.mean(axis=0), actual.mean(axis=0), atol=1e-12)


def test_fit_uses_the_known_vehicles_and_needs_two() -> None:
    actual = rotate(VIEW.desired_xy, 1.2) + [0.5, 0.0]
    partial = actual.copy()
    partial[1] = np.nan
    np.testing.assert_allclose(fit_shape(VIEW.desired_xy, partial), actual, atol=1e-12)
    partial[2:] = np.nan
    assert fit_shape(VIEW.desired_xy, partial) is None


# -- trails ---------------------------------------------------------------------------


def test_trails_sample_at_their_own_rate_and_keep_their_span() -> None:
    trails = Trails(2, span=2.0, rate=5.0)
    assert trails.capacity == 10
    assert trails.add(0.0, np.zeros((2, 3)))
    assert not trails.add(0.1, np.ones((2, 3)))  # too soon
    seg, age = trails.segments()
    assert seg.shape == (0, 2, 3) and age.shape == (0,)
    for k in range(1, 30):
        trails.add(0.2 * k, np.array([[k, 0.0, 0.0], [0.0, k, 0.0]]))
    seg, age = trails.segments()
    assert seg.shape == (2 * 9, 2, 3)  # capacity - 1 segments per vehicle
    np.testing.assert_allclose(seg[8], [[28, 0, 0], [29, 0, 0]])  # newest of vehicle 0
    assert age[0] > age[8] and np.all((age >= 0) & (age < 1))
    assert trails.segments()[0] is seg  # unchanged until the next sample


def test_trails_skip_unknown_samples() -> None:
    trails = Trails(1, span=1.0, rate=4.0)
    for k, x in enumerate((0.0, np.nan, 2.0, 3.0)):
        trails.add(0.25 * k, np.array([[x, 0.0, 0.0]]))
    seg, _ = trails.segments()
    np.testing.assert_allclose(seg, [[[2, 0, 0], [3, 0, 0]]])


# -- model ----------------------------------------------------------------------------


def test_quad_model_is_a_closed_index_set_pointing_forward() -> None:
    frame = TEAM.config.airframe
    v, f = quad_mesh(frame.arm_x, frame.arm_y)
    assert v.dtype == np.float32 and f.dtype == np.uint32
    assert f.min() == 0 and f.max() == len(v) - 1
    # the rotors sit at the airframe's arm offsets; the nose reaches furthest forward
    assert v[:, 0].max() > frame.arm_x and v[:, 0].min() > -1.1 * frame.arm_x - 0.07
    assert abs(v[:, 1].max() + v[:, 1].min()) < 1e-6  # left-right symmetric


def test_yaw_quaternion_turns_north_to_east() -> None:
    w, x, y, z = yaw_wxyz(np.array([math.pi / 2, np.nan]))[0]
    # rotating (1, 0, 0) by the quaternion
    r = np.array([1 - 2 * (y * y + z * z), 2 * (x * y + w * z), 2 * (x * z - w * y)])
    np.testing.assert_allclose(r, [0.0, 1.0, 0.0], atol=1e-12)
    np.testing.assert_allclose(yaw_wxyz(np.array([np.nan]))[0], [1, 0, 0, 0])


# -- one frame ------------------------------------------------------------------------


def test_states_from_age_and_mode() -> None:
    fleet = fleet_at(VIEW.desired_xy, age=np.array([0.1, 0.9, 0.1, np.inf]),
                     modes=("OFFBOARD", "OFFBOARD", "AUTO.LOITER", "HOLD"))
    states = vehicle_states(fleet, stale_after=0.5)
    assert list(states) == [VehicleState.OK, VehicleState.STALE, VehicleState.HOLDING,
                            VehicleState.STALE]
    landing = fleet_at(VIEW.desired_xy, modes=("LAND", "AUTO.LAND", "RTL", "DISARMED"))
    assert list(vehicle_states(landing, 0.5)) == [VehicleState.LANDING] * 3 + [VehicleState.OK]


def test_frame_of_a_perfect_team_with_sim_truth() -> None:
    xy = rotate(VIEW.desired_xy, 0.5) + [1.0, 2.0]
    v = np.tile([0.5, 0.0, 0.0], (4, 1))
    v[3] = 0.0
    fleet = fleet_at(xy, v=v)
    truth = SimTruth(t=10.0, ids=(4, 3, 2, 1), vehicle_p_ned=((0.0, 0.0, 0.0),) * 4,
                     payload_p_ned=(1.0, 2.0, -0.6), payload_v_ned=(0.0, 0.0, 0.0),
                     rope_tension=(0.0, 1.0, 2.0, 2 * VIEW.nominal_tension))
    frame = build_frame(VIEW, fleet, scale=1.0, truth=truth, trails=Trails(4))
    assert frame.known.all() and np.all(frame.scales == 1.0)
    np.testing.assert_allclose(frame.label_p[:, 2], -1.5 - LABEL_LIFT)
    assert frame.payload_measured
    np.testing.assert_allclose(frame.payload_p, [1.0, 2.0, -0.6])
    assert frame.ropes.shape == (4, 2, 3)
    # ropes follow the truth's vehicle order: vehicle 1 has the truth's last tension (red)
    assert tuple(frame.rope_colors[0, 0]) == palette.BAD
    assert tuple(frame.rope_colors[3, 1]) == palette.SLACK
    # exact shape: every edge at its desired length, the ghost on top of the team
    assert frame.edges.shape == (6, 2, 3)
    assert np.all(frame.edge_colors == palette.EDGE_OK)
    np.testing.assert_allclose(frame.ghost_edges, frame.edges, atol=1e-9)
    # arrows for the three moving vehicles, one second long
    assert frame.velocity.shape == (3, 2, 3)
    np.testing.assert_allclose(frame.velocity[:, 1] - frame.velocity[:, 0],
                               np.tile([0.5, 0.0, 0.0], (3, 1)))
    np.testing.assert_allclose(frame.centroid, [1.0, 2.0, -1.5], atol=1e-12)
    # the payload's drop line to the ground, a cross at its foot, its height
    np.testing.assert_allclose(frame.drop[0], [[1.0, 2.0, -0.6], [1.0, 2.0, 0.0]])
    np.testing.assert_allclose(frame.drop[1:, :, 2], 0.0)
    np.testing.assert_allclose(frame.drop[1:].mean(axis=1), [[1.0, 2.0, 0.0]] * 2)
    assert frame.payload_height == pytest.approx(0.6)
    # how far the team and its payload reach from the centroid: the square's corners
    assert frame_reach(frame) == pytest.approx(math.hypot(0.5, 0.5))
    sw = compass_at(frame.centroid, frame_reach(frame))  # south-west of the team, clear of it
    assert sw[2] == 0.0 and np.all(sw[:2] < [1.0, 2.0] - np.array(frame_reach(frame)))


def test_frame_without_truth_estimates_the_payload_and_hides_unknown_vehicles() -> None:
    xy = VIEW.desired_xy.copy()
    xy[2] = np.nan
    flying = build_frame(VIEW, fleet_at(xy, z=-2.0), scale=1.0, truth=None, trails=Trails(4))
    assert list(flying.scales) == [1.0, 1.0, 0.0, 1.0]
    assert not flying.known[2] and np.all(flying.p_ned[2] == 0.0)
    assert len(flying.edges) == 3  # only edges between known vehicles
    assert not flying.payload_measured and len(flying.ropes) == 3
    assert not np.any(np.all(flying.rope_colors == palette.UNKNOWN, axis=-1))  # estimated
    assert flying.payload_p is not None and -2.0 < flying.payload_p[2] < 0.0  # hanging
    grounded = build_frame(VIEW, fleet_at(VIEW.desired_xy, z=-0.2), scale=1.0, truth=None,
                           trails=Trails(4))
    assert grounded.payload_p is not None and grounded.payload_p[2] == 0.0  # on the ground
    nobody = np.full((4, 2), np.nan)
    empty = build_frame(VIEW, fleet_at(nobody), scale=1.0, truth=None, trails=Trails(4))
    assert empty.payload_p is None and empty.centroid is None
    assert len(empty.drop) == 0 and math.isnan(empty.payload_height) and frame_reach(empty) == 0
    assert len(empty.ropes) == len(empty.edges) == len(empty.ghost_edges) == 0


def test_without_truth_ropes_are_coloured_by_the_pull_estimated_from_tilt() -> None:
    """Real vehicles (no simulator): the ropes read slack, nominal or overloaded all the same."""
    g = 9.80665
    # tilts whose pull is none, the nominal (eq. Th) and twice it; one tilt unknown
    nominal_tilt = math.atan(VIEW.nominal_pull / (VIEW.mass * g))
    double_tilt = math.atan(2 * VIEW.nominal_pull / (VIEW.mass * g))
    fleet = fleet_at(VIEW.desired_xy, z=-2.0)
    fleet = dataclasses.replace(fleet, tilt=np.array([0.0, nominal_tilt, double_tilt, np.nan]))
    frame = build_frame(VIEW, fleet, scale=1.0, truth=None, trails=Trails(4))
    assert not frame.payload_measured
    colors = [tuple(int(c) for c in frame.rope_colors[i, 0]) for i in range(4)]
    assert colors == [palette.SLACK, palette.TAUT, palette.BAD,
                      tuple(int(c) for c in palette.UNKNOWN)]
    np.testing.assert_array_equal(
        frame.rope_colors[:3, 1],
        palette.tension_colors(rope_pull_estimate(VIEW.mass, fleet.tilt, np.zeros((4, 2))),
                               VIEW.nominal_pull)[:3])
    # a tilt the commanded acceleration explains is not rope pull
    accel = np.zeros((4, 2))
    accel[2] = [g * math.tan(double_tilt), 0.0]
    steering = build_frame(VIEW, fleet, scale=1.0, truth=None, trails=Trails(4), accel_cmd=accel)
    assert tuple(int(c) for c in steering.rope_colors[2, 0]) == palette.SLACK
    # a view without the airframe (a replayed log) cannot estimate: grey
    bare = dataclasses.replace(VIEW, mass=math.nan, nominal_pull=math.nan)
    unknown = build_frame(bare, fleet, scale=1.0, truth=None, trails=Trails(4))
    assert np.all(unknown.rope_colors == palette.UNKNOWN)


def test_edge_colours_follow_the_operator_scale() -> None:
    fleet = fleet_at(1.5 * VIEW.desired_xy)  # the shape grown by half
    at_one = build_frame(VIEW, fleet, scale=1.0, truth=None, trails=Trails(4))
    assert np.all(at_one.edge_colors == palette.BAD)  # 0.5 m and more too long
    at_scale = build_frame(VIEW, fleet, scale=1.5, truth=None, trails=Trails(4))
    assert np.all(at_scale.edge_colors == palette.EDGE_OK)
    np.testing.assert_allclose(at_scale.ghost_edges[:, :, :2], at_scale.edges[:, :, :2],
                               atol=1e-9)


@pytest.mark.parametrize("n_known", [0, 4])
def test_frame_arrays_have_the_shapes_viser_needs(n_known: int) -> None:
    xy = VIEW.desired_xy if n_known else np.full((4, 2), np.nan)
    frame = build_frame(VIEW, fleet_at(xy), scale=1.0, truth=None, trails=Trails(4))
    for seg, col in ((frame.ropes, frame.rope_colors), (frame.edges, frame.edge_colors),
                     (frame.trails, frame.trail_colors)):
        assert seg.ndim == 3 and seg.shape[1:] == (2, 3)
        assert col.shape == seg.shape and col.dtype == np.uint8
    assert frame.wxyz.shape == (4, 4) and frame.colors.dtype == np.uint8
