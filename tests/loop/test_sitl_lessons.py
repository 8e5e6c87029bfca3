"""What the loop learnt from four ArduCopter SITL copters flown by hand, held to the real loop
(``Runtime`` over scripted ArduPilot links) with the telemetry of those moments.

The spin's rope lead acts only while the thrusts show the ropes carrying the payload. Four
ArduCopter SITL copters, which carry no payload, flown through the paper's spin
with the square's ``rope_lag`` turned up to 1.46 rad/s against a commanded 0.4 and were
aborted with their shape 1.2 m off: the lead, sized for the design's rope pulls, had no
pull to cancel.

A vehicle that a pilot (or another ground station) took out of GUIDED and that then falls
away below the team is coming down on its own, and the team lands: one switched to LOITER
by MAVProxy fell to the ground (no transmitter's throttle in SITL) while the team hovered
above it until it disarmed, 12 s later.
"""

from __future__ import annotations

import numpy as np

from gcs.guidance import MotionDemand
from tests.support.scripted_autopilot import HOVER_THRUST, fleet_state, peer_team


def test_the_spins_rope_lead_needs_the_thrusts_to_show_the_ropes_carrying() -> None:
    with peer_team({vid: ("ardupilot", {}) for vid in (1, 2, 3, 4)}) as bench:
        runtime, team = bench.runtime, bench.team
        sharing = runtime.load_sharing
        lead_of = runtime.stages.guidance.rope_lead.apply
        assert sharing is not None and team.config.guidance.rope_lag > 0
        spin = MotionDemand(forward=0.0, right=0.0, rotate=1.0, scale=1.0)
        zero = np.zeros((4, 2))
        slack = fleet_state(team.formation.positions, HOVER_THRUST)
        sharing.observe_slack(5.0, slack.thrust, slack.tilt)  # hovering, ropes slack

        # copters with no payload: the thrust stays the slack hover's
        assert np.all(lead_of(slack, spin, zero, carrying=True) == 0.0)
        assert any("the ropes carry 0.00 of the payload's weight" in e.text
                   and "rope lead" in e.text for e in runtime.events())

        # the ropes carrying the payload: each thrust up by its quarter of its weight
        per_vehicle = team.config.payload.mass / 4 / team.config.airframe.mass
        carrying = fleet_state(team.formation.positions, HOVER_THRUST * (1 + per_vehicle))
        lead = lead_of(carrying, spin, zero, carrying=True)
        speed = np.linalg.norm(lead, axis=1)
        assert np.all(speed > 0.05), lead  # along each vehicle's motion about the centroid
        radial = np.einsum("ij,ij->i", lead, team.formation.positions)
        assert np.allclose(radial, 0.0, atol=1e-9)

        # thrusts not known: the lead acts, as it did before there were thrusts
        unknown = fleet_state(team.formation.positions, HOVER_THRUST)
        unknown.thrust_age[:] = np.inf
        assert np.all(np.linalg.norm(lead_of(unknown, spin, zero, carrying=True),
                                     axis=1) > 0.05)


def test_a_vehicle_out_of_its_mode_falling_below_the_team_is_coming_down() -> None:
    with peer_team({vid: ("ardupilot", {}) for vid in (1, 2, 3, 4)}) as bench:
        runtime, team = bench.runtime, bench.team
        level = fleet_state(team.formation.positions, HOVER_THRUST, modes=("GUIDED",) * 4)
        assert not runtime.modes.coming_down(level).any()
        loiter = ("GUIDED", "LOITER", "GUIDED", "GUIDED")
        held = fleet_state(team.formation.positions, HOVER_THRUST, modes=loiter)
        held.p_ned[1, 2] += 0.3  # a pilot's LOITER, 0.3 m lower: frozen, not landed
        assert not runtime.modes.coming_down(held).any()
        falling = fleet_state(team.formation.positions, HOVER_THRUST, modes=loiter)
        falling.p_ned[1, 2] += 0.8
        assert runtime.modes.coming_down(falling).tolist() == [False, True, False, False]
        low_in_guided = fleet_state(team.formation.positions, HOVER_THRUST,
                                    modes=("GUIDED",) * 4)
        low_in_guided.p_ned[1, 2] += 0.8  # on the GCS's setpoints: the GCS's own business
        assert not runtime.modes.coming_down(low_in_guided).any()
        landing = fleet_state(team.formation.positions, HOVER_THRUST,
                              modes=("GUIDED", "LAND", "GUIDED", "GUIDED"))
        assert runtime.modes.coming_down(landing).tolist() == [False, True, False, False]
