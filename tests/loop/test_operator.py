"""Operator command shaping: sticks through deadzone and expo, their timeout, altitude
and scale at their rates."""

from __future__ import annotations

import dataclasses

import pytest

from gcs.config import OperatorConfig, load_team
from gcs.loop import OperatorCommand
from gcs.loop._operator import ramp, shape_stick

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
    """Lift and set-down (gcs.loop._actions, gcs.loop._phase_stage): the ropes take the
    weight between 0.8 and 1.0 m; the ramp crosses that band at 0.02 m/s and the rest at 0.1 m/s."""
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
