"""The operator's command: one object written by any source, read by the 4 Hz loop.

The browser, the gamepad and scripted scenarios all write here, through the
same methods, so they behave the same way: sticks get a deadzone and expo;
scale moves in steps within the configured range; the scale and altitude
targets are followed at limited rates; guidance can be switched off. Sticks written by a
source that then goes quiet fall back to zero after ``stick_timeout`` (a
browser tab closed with a stick held must not keep the team moving).

Thread-safe: sources write from their own threads, the loop takes a
:class:`OperatorSnapshot` per tick.
"""

from __future__ import annotations

import math
import threading
from dataclasses import dataclass

import numpy as np

from gcs.config import GuidanceConfig, OperatorConfig
from gcs.guidance import MotionDemand

__all__ = ["OperatorCommand", "OperatorSnapshot", "ramp", "shape_stick"]


def shape_stick(value: float, *, deadzone: float, expo: float) -> float:
    """Deadzone then expo: ``(1 - expo) x + expo x^3`` on the rescaled travel, in [-1, 1]."""
    x = float(np.clip(value, -1.0, 1.0))
    mag = abs(x)
    if mag <= deadzone:
        return 0.0
    x = np.sign(x) * (mag - deadzone) / (1.0 - deadzone)
    return float((1.0 - expo) * x + expo * x**3)


@dataclass(frozen=True)
class OperatorSnapshot:
    """What the loop uses in one tick."""

    demand: MotionDemand
    altitude: float  # rate-limited altitude target above the ground, m
    altitude_target: float  # where the operator wants to go, m
    scale_target: float  # the shape's scale the operator asked for
    guidance_on: bool
    source: str  # who wrote the sticks last


class OperatorCommand:
    """Sticks, scale, altitude and guidance switch of the super-vehicle.

    Scale and altitude are targets followed at the configured rates: a step in
    the desired distances would be a step disturbance to the whole team.

    Args:
        operator: input shaping config.
        guidance: scale range and step.
        now: time of creation on the loop's clock, s.
    """

    def __init__(self, operator: OperatorConfig, guidance: GuidanceConfig, *,
                 now: float = 0.0) -> None:
        self._cfg = operator
        self._g = guidance
        self._lock = threading.Lock()
        self._sticks = (0.0, 0.0, 0.0)
        self._stick_time = now
        self._source = "none"
        self._scale = 1.0  # rate-limited ramp towards the target
        self._scale_target = 1.0
        self._alt_target = 0.0
        self._alt = 0.0
        self._alt_time = now
        self._alt_rate = operator.altitude_rate
        self._alt_band: tuple[float, float, float] | None = None  # lo, hi, rate inside
        self._guidance_on = True

    def set_sticks(self, forward: float, right: float, rotate: float, *, now: float,
                   source: str = "script") -> None:
        """Raw stick positions in [-1, 1] (values outside are clipped)."""
        for name, value in (("forward", forward), ("right", right), ("rotate", rotate)):
            if not np.isfinite(value):
                raise ValueError(f"operator stick {name} from {source} is not a number: {value}")
        c = self._cfg
        shaped = tuple(shape_stick(v, deadzone=c.deadzone, expo=c.expo)
                       for v in (forward, right, rotate))
        with self._lock:
            self._sticks = shaped  # type: ignore[assignment]
            self._stick_time = now
            self._source = source

    def set_scale(self, scale: float) -> float:
        """Scale of the shape, clipped to the configured range; returns the value kept."""
        if not np.isfinite(scale):
            raise ValueError(f"operator scale is not a number: {scale}")
        with self._lock:
            self._scale_target = float(np.clip(scale, self._g.scale_min, self._g.scale_max))
            return self._scale_target

    def step_scale(self, steps: int) -> float:
        """Grow (+) or shrink (-) the shape by whole configured steps."""
        with self._lock:
            current = self._scale_target
        return self.set_scale(round(current + steps * self._g.scale_step, 6))

    def set_altitude(self, altitude: float, *, now: float, rate: float | None = None,
                     slow: tuple[float, float, float] | None = None) -> float:
        """Altitude target above the ground, m; followed at ``rate`` m/s (default: config).

        ``slow = (low, high, rate)``: between the altitudes ``low`` and ``high`` the
        ramp moves at that slower rate (the band where the ropes take or give up the
        payload's weight, so the tension changes as slowly as the vehicles can follow).
        Any later call without it ends the band.
        """
        if not np.isfinite(altitude):
            raise ValueError(f"operator altitude is not a number: {altitude}")
        for value in (rate,) + ((slow[2],) if slow is not None else ()):
            if value is not None and not value > 0.0:  # NaN included: it would skip the ramp
                raise ValueError(f"operator altitude rate must be positive, got {value}")
        if slow is not None and not slow[0] <= slow[1]:
            raise ValueError(f"operator slow band must run from low to high, got {slow[:2]}")
        with self._lock:
            self._advance(now)
            self._alt_target = float(np.clip(altitude, self._cfg.altitude_min,
                                             self._cfg.altitude_max))
            self._alt_rate = self._cfg.altitude_rate if rate is None else min(
                rate, self._cfg.altitude_rate)
            self._alt_band = None if slow is None else (
                float(slow[0]), float(slow[1]), min(float(slow[2]), self._alt_rate))
            return self._alt_target

    def step_altitude(self, steps: int, *, now: float) -> float:
        """Raise (+) or lower (-) the altitude target by whole configured steps."""
        with self._lock:
            target = self._alt_target
        return self.set_altitude(target + steps * self._cfg.altitude_step, now=now)

    def reset_altitude(self, altitude: float, *, now: float) -> None:
        """Jump both target and ramp to ``altitude`` (e.g. after take-off)."""
        if not math.isfinite(altitude):
            raise ValueError(f"operator altitude is not a number: {altitude}")
        with self._lock:
            self._alt = self._alt_target = float(altitude)
            self._alt_time = now
            self._alt_band = None

    def set_guidance(self, on: bool) -> None:
        """Switch the formation motion on or off (off: the team holds its shape)."""
        with self._lock:
            self._guidance_on = bool(on)

    def release(self, *, now: float, source: str = "system") -> None:
        """Centre all sticks (abort, loss of control source)."""
        with self._lock:
            self._sticks = (0.0, 0.0, 0.0)
            self._stick_time = now
            self._source = source

    def _advance(self, now: float) -> None:
        dt = max(0.0, now - self._alt_time)
        self._alt = ramp(self._alt, self._alt_target, dt, self._alt_rate, self._alt_band)
        step = self._cfg.scale_rate * dt
        self._scale += min(max(self._scale_target - self._scale, -step), step)
        self._alt_time = now

    def snapshot(self, now: float) -> OperatorSnapshot:
        """The command for the tick at ``now`` (advances the altitude ramp)."""
        with self._lock:
            self._advance(now)
            sticks = self._sticks
            if now - self._stick_time > self._cfg.stick_timeout:
                sticks = (0.0, 0.0, 0.0)
            if not self._guidance_on:
                sticks = (0.0, 0.0, 0.0)
            demand = MotionDemand(forward=sticks[0], right=sticks[1], rotate=sticks[2],
                                  scale=self._scale)
            return OperatorSnapshot(demand=demand, altitude=self._alt,
                                    altitude_target=self._alt_target,
                                    scale_target=self._scale_target,
                                    guidance_on=self._guidance_on, source=self._source)


def ramp(value: float, target: float, dt: float, rate: float,
         slow: tuple[float, float, float] | None = None) -> float:
    """``value`` moved towards ``target`` for ``dt`` s at ``rate``, and at the slow band's
    rate while it is inside the band ``(low, high, rate)``.

    Plain floats: a numpy call on a scalar costs tens of us in the 4 Hz loop (cold).
    """
    if slow is None:
        step = rate * dt
        return value + min(max(target - value, -step), step)
    low, high, slow_rate = slow
    up = target > value
    while dt > 0.0 and value != target:
        inside = low <= value < high if up else low < value <= high
        # the next place the rate changes: a band edge ahead, or the target
        if up:
            edge = low if value < low else (high if value < high else math.inf)
            stop = min(edge, target)
        else:
            edge = high if value > high else (low if value > low else -math.inf)
            stop = max(edge, target)
        speed = slow_rate if inside else rate
        reach = abs(stop - value) / speed
        if reach >= dt:
            return value + (speed * dt if up else -speed * dt)
        value, dt = stop, dt - reach
    return value
