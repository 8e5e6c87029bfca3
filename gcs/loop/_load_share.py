"""Load sharing: each vehicle's altitude trimmed so the payload's weight splits as designed.

Why: four or more taut ropes hold a point payload with more ropes than its balance
needs, and the split between them is decided by the ropes' stretch: on the paper's
square a diagonal pair 0.2 mm higher than the other carries twice its load (in the
simulator, whose autopilots hold their altitude to a fraction of a millimetre, untrimmed
pairs fly at 0.33 and 0.17 of the payload for tens of seconds; real vehicles' heights
differ by centimetres, enough to leave a diagonal slack). The analysis certifies each
vehicle for its design share only if something keeps the split there.

The GCS reads each vehicle's collective thrust (``ATTITUDE_TARGET``, which PX4 and
ArduCopter send). Each vehicle's thrust with its rope slack (hovering below the lower
half of the pickup band: :meth:`LoadSharing.observe_slack`) is what holds it up alone; above
that, the rest is its rope's pull, in the vehicle's own thrust units, so the split is
known while the payload is still being picked up, and a vehicle a little heavier than
the others (another battery) is not taken for one carrying more. Without that hover
(a GCS that joined a flight in the air) the thrusts give the split with one airframe
for the team, the payload hanging (:func:`estimated_shares`). The part of the split the
payload's balance leaves free (:func:`free_split`: load moved between ropes with the
same total and the same moments) is driven to the split at the desired shape by a trim
of each vehicle's altitude setpoint in proportion to its excess share
(``flight.load_share_gain``), approached over :data:`FILTER_S` and never more than
``flight.load_share_trim_max``: a vehicle carrying more than its share is lowered. The
trims act from the bottom of the pickup band, so the rope that goes taut first (the
vehicle the shape holds furthest out) is let down before it takes the payload alone: on
a pentagon, trims acting only once the payload hangs leave one rope at 0.40 of the payload
at lift-off against a design 0.25. (An integral trim oscillates: the split answers a trim
only as the guidance moves the shape, over tens of seconds.)

The same thrusts say how fast the ropes take the payload (:attr:`LoadSharing.carried_rate`):
the pickup's rope lead (gcs/guidance/_rope_lead.py) leads each vehicle's growing pull by
it, the drag that leaves the pentagon's stiffest vehicle taut first.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["CARRIED_RATE_S", "FILTER_S", "SLACK_S", "LoadSharing", "estimated_shares",
           "free_split"]

FILTER_S = 1.0
"""Time constant of the trims' approach to their target, s."""

SLACK_S = 2.0
"""Time constant of the average of each vehicle's thrust with its rope slack, s."""

CARRIED_RATE_S = 0.5
"""Time constant of the average of the rate at which the ropes take the payload, s (the
thrusts' noise apart, the pickup's rise kept: it takes about two seconds)."""


def free_split(xy: np.ndarray) -> np.ndarray:
    """(n, n) projector onto the vertical loads that leave a payload's balance unchanged:
    no total, no moment about any horizontal axis; ``xy`` (n, 2) the vehicles' horizontal
    places, in any frame and at any scale and heading of one shape (the span of the
    balance's rows does not change). Zero for three vehicles or fewer not on a line."""
    n = len(xy)
    balance = np.vstack([np.ones(n), xy[:, 0], xy[:, 1]])
    return np.eye(n) - np.linalg.pinv(balance) @ balance


def _vertical(thrust: np.ndarray, tilt: np.ndarray) -> np.ndarray:
    """(n,) each vehicle's vertical thrust, in its thrust's units."""
    return np.asarray(thrust, dtype=float) * np.cos(tilt)


def estimated_shares(thrust: np.ndarray, tilt: np.ndarray, vehicle_mass: float,
                     payload_mass: float) -> np.ndarray:
    """(n,) fraction of the payload's weight on each vehicle, from each one's collective
    thrust (any common scale) and tilt (rad), for vehicles of one airframe in steady
    flight: the vertical thrusts add up to (n m + M) g, of which m g is each vehicle's.
    NaN where the thrusts hold nobody up (none positive in total: on the ground)."""
    vertical = _vertical(thrust, tilt)
    n = len(vertical)
    total = float(vertical.sum())
    if not total > 0.0:
        return np.full(n, math.nan)
    return (vertical * (n * vehicle_mass + payload_mass) / total - vehicle_mass) / payload_mass


class LoadSharing:
    """The altitude trims of one team (z down, m); not thread-safe (the loop's tick).

    Args:
        xy: (n, 2) the desired shape's places.
        target: (n,) the share of the payload's weight each vehicle carries at the desired
            shape (the analysis' split at rest).
        vehicle_mass, payload_mass: kg.
        gain: trim per unit of share off target, m.
        trim_max: largest trim, m (the trims shrink together, so they still move load
            only between ropes).
    """

    def __init__(self, xy: np.ndarray, target: np.ndarray, *, vehicle_mass: float,
                 payload_mass: float, gain: float, trim_max: float) -> None:
        self._free = free_split(np.asarray(xy, dtype=float))
        self._target = np.asarray(target, dtype=float)
        self._masses = (vehicle_mass, payload_mass)
        self.gain, self.trim_max = gain, trim_max
        self.trims = np.zeros(len(self._target))
        """(n,) the current altitude trims, m, z down: added to each vehicle's setpoint."""
        self.active = bool(np.abs(self._free).max() > 1e-9) and gain > 0.0
        """Whether the team has a free split to share (four or more vehicles, not a line)."""
        self.slack: np.ndarray | None = None
        """(n,) each vehicle's vertical thrust with its rope slack (its units), or None
        before any such hover."""
        self.carried_rate = 0.0
        """How fast the share of the payload's weight on the ropes grows, 1/s (falling:
        below 0; 0 when not known): what the pickup's rope lead leads."""
        self._carried: tuple[float, float] | None = None  # (t, share) at the last look

    def observe_slack(self, dt: float, thrust: np.ndarray, tilt: np.ndarray) -> None:
        """Average each vehicle's vertical thrust over ``dt`` seconds with every rope slack
        (airborne, below the taut-rope altitude): what holds each up alone."""
        vertical = _vertical(thrust, tilt)
        if not (np.all(np.isfinite(vertical)) and np.all(vertical > 0.0)
                and math.isfinite(dt) and dt > 0.0):
            return
        if self.slack is None:
            self.slack = vertical
        else:
            self.slack = self.slack + min(1.0, dt / SLACK_S) * (vertical - self.slack)

    def excess(self, thrust: np.ndarray, tilt: np.ndarray) -> np.ndarray:
        """(n,) each vehicle's load beyond its share of what the ropes now carry, as a
        fraction of the payload's weight (NaN where not known): from the thrusts above
        each one's slack-rope thrust, or without it from the thrusts' ratios."""
        if self.slack is None:
            return estimated_shares(thrust, tilt, *self._masses) - self._target
        pull, weight = self._pulls(thrust, tilt, self.slack)
        return (pull - self._target * float(pull.sum())) / weight

    def carried(self, thrust: np.ndarray, tilt: np.ndarray) -> float:
        """The share of the payload's weight the ropes carry (NaN before the slack-rope
        thrusts are known): the thrusts above them, over the payload's weight."""
        if self.slack is None:
            return math.nan
        pull, weight = self._pulls(thrust, tilt, self.slack)
        return float(pull.sum()) / weight

    def _pulls(self, thrust: np.ndarray, tilt: np.ndarray,
               slack: np.ndarray) -> tuple[np.ndarray, float]:
        """(n,) each rope's vertical pull, and the payload's weight, in thrust units."""
        vehicle_mass, payload_mass = self._masses
        return (_vertical(thrust, tilt) - slack,
                float(slack.mean()) * payload_mass / vehicle_mass)

    def observe_carried(self, t: float, thrust: np.ndarray | None,
                        tilt: np.ndarray) -> float:
        """Follow :attr:`carried_rate` to time ``t`` (s) with the latest thrusts (None:
        not fresh: the rate is forgotten); the rate."""
        share = self.carried(thrust, tilt) if thrust is not None else math.nan
        if not math.isfinite(share):
            self._carried, self.carried_rate = None, 0.0
            return 0.0
        last = self._carried
        if last is not None and t > last[0]:
            dt = t - last[0]
            step = min(1.0, dt / CARRIED_RATE_S)
            self.carried_rate += step * ((share - last[1]) / dt - self.carried_rate)
        if last is None or t > last[0]:
            self._carried = (t, share)
        return self.carried_rate

    def update(self, dt: float, thrust: np.ndarray, tilt: np.ndarray) -> np.ndarray:
        """Move the trims ``dt`` seconds on the latest thrusts and tilts (finite, every
        vehicle's: the caller checks they are fresh and the ropes may be taut); the trims."""
        if not self.active or not (math.isfinite(dt) and dt > 0.0):
            return self.trims
        excess = self.excess(thrust, tilt)
        if not np.all(np.isfinite(excess)):
            return self.trims
        off = self._free @ excess
        step = min(1.0, dt / FILTER_S)
        self.trims = self.trims + step * (self.gain * off - self.trims)
        return self._bounded()

    def _bounded(self) -> np.ndarray:
        largest = float(np.abs(self.trims).max())
        if largest > self.trim_max:  # shrunk whole: a trim that stays a free split
            self.trims *= self.trim_max / largest
        return self.trims

    def reset(self) -> None:
        """Every trim back to zero and the slack thrusts forgotten (a new flight)."""
        self.trims = np.zeros_like(self.trims)
        self.slack = None
        self._carried, self.carried_rate = None, 0.0
