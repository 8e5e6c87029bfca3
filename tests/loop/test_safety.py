"""The safety rules: stale, lost, out of mode, deformed, fenced; and their compiled flags."""

from __future__ import annotations

import numpy as np
import pytest

from gcs.config import SafetyConfig
from gcs.loop._safety import DEFORMED, LOST, STALE, SafetyReason, evaluate, rule_flags

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
