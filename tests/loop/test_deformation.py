"""What a team deformed beyond the safe bound does (gcs.loop._deformation): hold, re-form a
deformation the positions can be trusted for, land one that keeps growing."""

from __future__ import annotations

import numpy as np

from gcs.loop._deformation import JUMP_M, PROBE_S, Deformation, DeformationPolicy

SQUARE = np.array([[0.5, 0.5], [-0.5, 0.5], [-0.5, -0.5], [0.5, -0.5]])
STILL = np.zeros((4, 2))


def run(policy: DeformationPolicy, positions: list[np.ndarray], deformed: list[bool],
        dt: float = 0.25) -> list[Deformation]:
    """Feed one tick per position set; the decisions."""
    out = []
    for k, (p, bad) in enumerate(zip(positions, deformed, strict=True)):
        t = k * dt
        policy.observe(p, STILL, np.full(4, t), in_shape=not bad)
        radius = float(np.hypot(*(p - p.mean(axis=0)).T).max())
        out.append(policy.update(t, deformed=bad, deformation=radius, p_xy=p))
    return out


def drift(metres: float) -> np.ndarray:
    p = SQUARE.copy()
    p[0, 0] += metres
    return p


def test_a_deformation_grown_from_a_good_shape_is_held_then_re_formed() -> None:
    policy = DeformationPolicy(growth=0.3)
    steps = [drift(0.0)] * 4 + [drift(0.1 * k) for k in range(1, 5)] + [drift(0.4)] * 8
    decisions = run(policy, steps, [False] * 6 + [True] * 10)
    assert policy.trusted
    held = decisions.index(Deformation.HOLD)
    assert decisions[held:held + round(PROBE_S / 0.25)] == [Deformation.HOLD] * 4
    assert decisions[-1] is Deformation.REFORM
    assert policy.hold_points is not None


def test_a_start_out_of_shape_is_held_for_good() -> None:
    policy = DeformationPolicy(growth=0.3)
    decisions = run(policy, [drift(1.4)] * 20, [True] * 20)
    assert not policy.trusted and set(decisions) == {Deformation.HOLD}


def test_a_jump_takes_the_trust_away_until_the_team_is_in_shape_again() -> None:
    policy = DeformationPolicy(growth=0.3)
    jump = JUMP_M + 0.1
    decisions = run(policy, [drift(0.0)] * 4 + [drift(jump)] * 12, [False] * 4 + [True] * 12)
    assert not policy.trusted and set(decisions[4:]) == {Deformation.HOLD}
    run(policy, [drift(0.0)], [False])
    assert not policy.trusted  # back in shape, but by a jump too
    run(policy, [drift(0.0)], [False])
    assert policy.trusted  # in shape with no jump: trusted again


def test_a_deformation_that_keeps_growing_lands_the_team() -> None:
    policy = DeformationPolicy(growth=0.3)
    steps = [drift(0.0)] * 4 + [drift(0.1 * k) for k in range(1, 16)]
    decisions = run(policy, steps, [False] * 5 + [True] * 14)
    assert decisions[-1] is Deformation.LAND
