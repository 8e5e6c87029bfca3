"""The rope's pull turning with a spinning team, or growing as the ropes take the payload,
led by the autopilot's lag.

Why: each carrying vehicle's autopilot cancels the rope's horizontal pull
``F`` through its acceleration loop, which follows an external force with a
lag ``tau`` (filters, attitude loop, rotors). While the team spins at
``omega`` about the down axis, ``F`` turns with it, ``dF/dt = omega z x F``,
and the autopilot is left ``tau dF/dt / m`` short, against the turn. At the
paper's 0.4 rad/s on the square that is about 0.13 m/s^2 per vehicle: without
the lead the team turns at a third of the commanded rate while the guidance's
centripetal feed-forward, sized for the commanded rate, pulls the shape in (0.17 m).
The autopilot's estimate of the pull is ``F(t - tau)``, so the vehicle gets
``(F(t) - F(t - tau)) / m = tau dF/dt / m`` more than commanded; commanding
``-tau omega z x F / m`` more cancels it.

The same lag acts while the ropes take the payload's weight in the pickup (or give
it up in the set-down): each rope's pull grows as ``f F`` with ``f`` the share of the
weight the ropes carry, and the vehicle is left ``tau df/dt F / m`` short, inward.
On the pentagon in ``tests/data`` that drag, uneven (the vehicles the shape holds
least go furthest), lets one rope take 0.34 of the payload at lift-off against a
design 0.25; led by ``-tau df/dt F / m`` (:func:`rope_growth_lead`) the ropes take it
within 0.18-0.23 each.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["rope_growth_lead", "rope_pull_ned", "rope_turn_lead"]


def rope_pull_ned(pull_body: np.ndarray, heading: float) -> np.ndarray:
    """(n, 2) horizontal rope pulls in NED from the team's body frame (x forward, y
    right), with the team turned ``heading`` rad from north towards east."""
    c, s = math.cos(heading), math.sin(heading)
    x, y = pull_body[:, 0], pull_body[:, 1]
    return np.stack([c * x - s * y, s * x + c * y], axis=1)


def rope_turn_lead(pull_ned: np.ndarray, omega: float, lag: float,
                   mass: float) -> np.ndarray:
    """(n, 2) acceleration, m/s^2, that cancels an autopilot's lag ``lag`` (s) behind
    the horizontal rope pulls ``pull_ned`` (n, 2, N) turning at ``omega`` (rad/s,
    clockwise seen from above) on vehicles of ``mass`` kg: along each vehicle's
    motion, as the lag brakes it."""
    k = -lag * omega / mass
    return np.stack([-k * pull_ned[:, 1], k * pull_ned[:, 0]], axis=1)


def rope_growth_lead(pull_ned: np.ndarray, rate: float, lag: float,
                     mass: float) -> np.ndarray:
    """(n, 2) acceleration, m/s^2, that cancels an autopilot's lag ``lag`` (s) behind
    the horizontal rope pulls growing as ``f pull_ned`` (n, 2, N: the pulls with the
    whole payload hanging), ``f`` the share of the payload's weight the ropes carry,
    rising at ``rate`` (1/s; falling below 0) on vehicles of ``mass`` kg: against each
    pull."""
    return (-lag * rate / mass) * pull_ned
