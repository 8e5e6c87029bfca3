"""The spin's rope lead acts only while the thrusts show the ropes carrying the payload.

Four ArduCopter SITL copters, which carry no payload, flown through the paper's spin
with the square's ``rope_lag`` turned up to 1.46 rad/s against a commanded 0.4 and were
aborted with their shape 1.2 m off: the lead, sized for the design's rope pulls, had no
pull to cancel. Here the real loop (``Runtime`` over scripted ArduPilot links) is asked
for the lead with the thrusts of a team whose ropes hang slack, then of one carrying.
"""

from __future__ import annotations

import numpy as np

from gcs.guidance import MotionDemand
from gcs.loop import FleetState
from tests.scripted_autopilot import HOVER_THRUST, peer_team


def fleet(team_positions: np.ndarray, thrust: float) -> FleetState:
    n = len(team_positions)
    p = np.column_stack((team_positions, np.full(n, -2.5)))
    return FleetState(t=10.0, ids=(1, 2, 3, 4), p_ned=p, v_ned=np.zeros((n, 3)),
                      yaw=np.zeros(n), tilt=np.zeros(n), age=np.zeros(n),
                      heartbeat_age=np.zeros(n), armed=np.ones(n, dtype=bool),
                      battery=np.full(n, 90.0), modes=("GUIDED",) * n,
                      thrust=np.full(n, thrust), thrust_age=np.zeros(n))


def test_the_spins_rope_lead_needs_the_thrusts_to_show_the_ropes_carrying() -> None:
    with peer_team({vid: ("ardupilot", {}) for vid in (1, 2, 3, 4)}) as bench:
        runtime, team = bench.runtime, bench.team
        sharing = runtime.load_sharing
        assert sharing is not None and team.config.guidance.rope_lag > 0
        spin = MotionDemand(forward=0.0, right=0.0, rotate=1.0, scale=1.0)
        zero = np.zeros((4, 2))
        slack = fleet(team.formation.positions, HOVER_THRUST)
        sharing.observe_slack(5.0, slack.thrust, slack.tilt)  # hovering, ropes slack

        # copters with no payload: the thrust stays the slack hover's
        assert np.all(runtime._rope_lead(slack, spin, zero, carrying=True) == 0.0)
        assert any("the ropes carry 0.00 of the payload's weight" in e.text
                   and "rope lead" in e.text for e in runtime.events())

        # the ropes carrying the payload: each thrust up by its quarter of its weight
        per_vehicle = team.config.payload.mass / 4 / team.config.airframe.mass
        carrying = fleet(team.formation.positions, HOVER_THRUST * (1 + per_vehicle))
        lead = runtime._rope_lead(carrying, spin, zero, carrying=True)
        speed = np.linalg.norm(lead, axis=1)
        assert np.all(speed > 0.05), lead  # along each vehicle's motion about the centroid
        radial = np.einsum("ij,ij->i", lead, team.formation.positions)
        assert np.allclose(radial, 0.0, atol=1e-9)

        # thrusts not known: the lead acts, as it did before there were thrusts
        unknown = fleet(team.formation.positions, HOVER_THRUST)
        unknown.thrust_age[:] = np.inf
        assert np.all(np.linalg.norm(runtime._rope_lead(unknown, spin, zero, carrying=True),
                                     axis=1) > 0.05)
