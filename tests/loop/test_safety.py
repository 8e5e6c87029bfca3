"""Operator command shaping and the safety rules."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from gcs.config import OperatorConfig, SafetyConfig, load_team
from gcs.loop import OperatorCommand
from gcs.loop._operator import ramp, shape_stick
from gcs.loop._safety import DEFORMED, LOST, STALE, SafetyReason, evaluate, rule_flags

OP = OperatorConfig(deadzone=0.1, expo=0.5, stick_timeout=1.0, altitude_rate=0.5,
                    altitude_max=3.0, altitude_step=0.25)
GUI = dataclasses.replace(load_team("configs/bebop_square.yaml").config.guidance, scale_min=0.5,
                          scale_max=1.5, scale_step=0.05)


def test_deadzone_and_expo() -> None:
    assert shape_stick(0.05, deadzone=0.1, expo=0.5) == 0.0
    assert shape_stick(1.0, deadzone=0.1, expo=0.5) == pytest.approx(1.0)
    assert shape_stick(-1.0, deadzone=0.1, expo=0.5) == pytest.approx(-1.0)
    assert shape_stick(3.0, deadzone=0.1, expo=0.5) == pytest.approx(1.0)
    half = shape_stick(0.55, deadzone=0.1, expo=0.5)
    assert half == pytest.approx(0.5 * 0.5 + 0.5 * 0.125)
    assert shape_stick(-0.55, deadzone=0.1, expo=0.5) == pytest.approx(-half)


def test_sticks_scale_and_timeout() -> None:
    op = OperatorCommand(OP, GUI, now=0.0)
    op.set_sticks(1.0, 0.0, -1.0, now=0.0, source="browser")
    snap = op.snapshot(0.5)
    assert (snap.demand.forward, snap.demand.rotate) == (pytest.approx(1.0), pytest.approx(-1.0))
    assert snap.source == "browser"
    assert op.snapshot(1.5).demand.forward == 0.0  # source went quiet
    assert op.step_scale(+3) == pytest.approx(1.15)
    assert op.snapshot(3.0).demand.scale == pytest.approx(1.0 + 1.5 * 0.05)  # ramps
    assert op.snapshot(10.0).demand.scale == pytest.approx(1.15)
    assert op.step_scale(+100) == pytest.approx(1.5)
    assert op.set_scale(0.1) == pytest.approx(0.5)
    assert op.snapshot(100.0).demand.scale == pytest.approx(0.5)
    with pytest.raises(ValueError, match="forward from pad"):
        op.set_sticks(float("nan"), 0, 0, now=1.0, source="pad")


def test_altitude_is_rate_limited() -> None:
    op = OperatorCommand(OP, GUI, now=0.0)
    op.set_altitude(2.0, now=0.0)
    assert op.snapshot(1.0).altitude == pytest.approx(0.5)
    assert op.snapshot(10.0).altitude == pytest.approx(2.0)
    assert op.set_altitude(9.0, now=10.0) == pytest.approx(3.0)  # clipped to the ceiling
    op.step_altitude(-2, now=10.0)
    assert op.snapshot(20.0).altitude == pytest.approx(2.5)
    for rate in (float("nan"), 0.0, -1.0):  # NaN would skip the ramp: a jump, not a climb
        with pytest.raises(ValueError, match="altitude rate must be positive"):
            op.set_altitude(2.0, now=20.0, rate=rate)
    with pytest.raises(ValueError, match="altitude is not a number"):
        op.reset_altitude(float("inf"), now=20.0)
    assert op.snapshot(21.0).altitude_target == pytest.approx(2.5)  # untouched by the refusals


def test_the_pickup_band_is_climbed_and_descended_at_its_slow_rate() -> None:
    """Lift and set-down (gcs.loop._runtime): the ropes take the weight between 0.8 and
    1.0 m; the ramp crosses that band at 0.02 m/s and the rest at 0.1 m/s."""
    band = (0.8, 1.0, 0.02)
    assert ramp(0.7, 2.0, 1.0, 0.1, band) == pytest.approx(0.8)  # up to the band's edge
    assert ramp(0.7, 2.0, 2.0, 0.1, band) == pytest.approx(0.82)  # then slowly
    assert ramp(0.7, 2.0, 1.0 + 10.0 + 1.0, 0.1, band) == pytest.approx(1.1)  # out at full rate
    assert ramp(1.1, 0.5, 1.0 + 10.0 + 2.0, 0.1, band) == pytest.approx(0.6)  # and down
    assert ramp(0.9, 0.95, 100.0, 0.1, band) == pytest.approx(0.95)  # never past the target
    assert ramp(0.7, 2.0, 1.0, 0.1) == pytest.approx(0.8)  # no band: one rate
    op = OperatorCommand(OP, GUI, now=0.0)
    op.reset_altitude(0.7, now=0.0)
    op.set_altitude(1.7, now=0.0, rate=0.1, slow=band)
    assert op.snapshot(2.0).altitude == pytest.approx(0.82)
    op.set_altitude(1.7, now=2.0, rate=0.1)  # a new target without a band ends it
    assert op.snapshot(3.0).altitude == pytest.approx(0.92)
    with pytest.raises(ValueError, match="altitude rate must be positive"):
        op.set_altitude(1.7, now=3.0, slow=(0.8, 1.0, 0.0))
    with pytest.raises(ValueError, match="from low to high"):
        op.set_altitude(1.7, now=3.0, slow=(1.0, 0.8, 0.02))


def test_guidance_off_zeroes_motion() -> None:
    op = OperatorCommand(OP, GUI, now=0.0)
    op.set_sticks(0.8, 0.8, 0.8, now=0.0)
    op.set_guidance(False)
    snap = op.snapshot(0.1)
    assert not snap.guidance_on
    assert (snap.demand.forward, snap.demand.right, snap.demand.rotate) == (0.0, 0.0, 0.0)


SAFE = SafetyConfig(stale_after=0.5, land_after=3.0, geofence_xy=4.0, geofence_altitude=3.0)
IDS = [1, 2, 3, 4]
SQUARE = np.array([[0.5, 0.5, -1.0], [-0.5, 0.5, -1.0], [-0.5, -0.5, -1.0], [0.5, -0.5, -1.0]])


def test_all_fresh_and_inside_is_ok() -> None:
    v = evaluate(SAFE, IDS, np.full(4, 0.1), SQUARE, safe_radius=0.79)
    assert not v.freeze and not v.land and v.events == ()


def test_stale_vehicle_freezes_and_is_named() -> None:
    v = evaluate(SAFE, IDS, np.array([0.1, 0.7, 0.1, 0.1]), SQUARE, safe_radius=0.79)
    assert v.freeze and not v.land
    assert [(e.reason, e.vehicle) for e in v.events] == [(SafetyReason.STALE, 2)]


def test_lost_vehicle_lands_the_team() -> None:
    age = np.array([0.1, 0.1, np.inf, 3.5])
    v = evaluate(SAFE, IDS, age, SQUARE, safe_radius=0.79)
    assert v.freeze and v.land
    assert {(e.reason, e.vehicle) for e in v.events} == {(SafetyReason.LOST, 3),
                                                         (SafetyReason.LOST, 4)}
    assert "never heard from" in v.events[0].text


def test_the_geofence_is_not_a_freeze_rule() -> None:
    """The fence limits the motion (gcs.loop._geofence): freezing every stick left a team
    at the fence no way back."""
    p = SQUARE.copy()
    p[3, 0] = 4.2
    p[1, 2] = -4.5
    assert evaluate(SAFE, IDS, np.full(4, 0.1), p, safe_radius=10.0) == evaluate(
        SAFE, IDS, np.full(4, 0.1), SQUARE, safe_radius=10.0)


def test_deformation_beyond_safe_bound_holds() -> None:
    p = SQUARE.copy()
    p[0, :2] = [1.0, 1.0]
    v = evaluate(SAFE, IDS, np.full(4, 0.1), p, safe_radius=0.79)
    assert v.freeze and v.hold and not v.land
    assert v.events[0].reason is SafetyReason.DEFORMATION and v.events[0].vehicle == 1
    radius = np.linalg.norm(p[:, :2] - p[:, :2].mean(axis=0), axis=1)
    assert v.deformation == pytest.approx(radius.max())
    assert "holding (each vehicle on its own point)" in v.events[0].text


def test_unknown_position_does_not_raise() -> None:
    p = SQUARE.copy()
    p[2] = np.nan
    v = evaluate(SAFE, IDS, np.full(4, 0.1), p, safe_radius=0.79)
    assert v.freeze and v.events[0].reason is SafetyReason.STALE


def test_compiled_rule_flags_are_the_rules_as_array_masks() -> None:
    """rule_flags against the rules written as plain numpy masks, on random teams with
    NaN positions, never-heard vehicles, stale and lost ones."""
    rng = np.random.default_rng(7)
    for _ in range(300):
        n = int(rng.integers(1, 12))
        age = rng.choice([0.1, 0.4, 0.6, 2.0, 3.5, np.inf, np.nan], n,
                         p=[0.6, 0.1, 0.08, 0.08, 0.06, 0.04, 0.04])
        p = rng.normal(0, 2.5, (n, 3))
        p[rng.random(n) < 0.05, rng.integers(0, 3)] = np.nan
        r = np.empty(n)
        flags = rule_flags(age, p, 3.0, 0.5, 2.0, r)
        known = np.all(np.isfinite(p), axis=1)
        with np.errstate(invalid="ignore"):
            lost = age > 3.0
            fresh = np.isfinite(age) & (age <= 0.5) & known
        radius = np.linalg.norm(p[:, :2] - p[:, :2].mean(axis=0), axis=1)
        deformed = fresh.all() & (radius > 2.0)
        assert np.array_equal(flags & LOST > 0, lost)
        assert np.array_equal(flags & STALE > 0, ~fresh)
        assert np.array_equal(flags & DEFORMED > 0, deformed)
        if fresh.all():
            assert r == pytest.approx(radius)


OFFBOARD = ("OFFBOARD",) * 4


def test_a_vehicle_out_of_the_gcs_mode_freezes_the_motion() -> None:
    modes = ("OFFBOARD", "OFFBOARD", "HOLD", "OFFBOARD")
    v = evaluate(SAFE, IDS, np.full(4, 0.1), SQUARE, safe_radius=0.79, modes=modes,
                 expected=OFFBOARD, coming_down=np.zeros(4, dtype=bool))
    assert v.freeze and not v.land
    assert [(e.reason, e.vehicle) for e in v.events] == [(SafetyReason.MODE, 3)]
    assert v.events[0].text == "vehicle 3: in HOLD, not OFFBOARD: motion frozen"
    # all in the mode: nothing to report
    v = evaluate(SAFE, IDS, np.full(4, 0.1), SQUARE, safe_radius=0.79, modes=OFFBOARD,
                 expected=OFFBOARD, coming_down=np.zeros(4, dtype=bool))
    assert v.events == ()


def test_a_vehicle_coming_down_on_its_own_lands_the_team() -> None:
    modes = ("GUIDED", "LAND", "GUIDED", "GUIDED")
    v = evaluate(SAFE, IDS, np.full(4, 0.1), SQUARE, safe_radius=0.79, modes=modes,
                 expected=("GUIDED",) * 4, coming_down=np.array([False, True, False, False]))
    assert v.freeze and v.land
    assert [(e.reason, e.vehicle) for e in v.events] == [(SafetyReason.COMING_DOWN, 2)]
    assert v.events[0].text == "vehicle 2: coming down on its own (LAND): landing the team"


def test_a_silent_vehicle_is_reported_silent_not_out_of_mode() -> None:
    modes = ("OFFBOARD", "unknown", "OFFBOARD", "OFFBOARD")
    v = evaluate(SAFE, IDS, np.array([0.1, np.inf, 0.1, 0.1]), SQUARE, safe_radius=0.79,
                 modes=modes, expected=OFFBOARD, coming_down=np.ones(4, dtype=bool))
    assert [(e.reason, e.vehicle) for e in v.events] == [(SafetyReason.LOST, 2)]
