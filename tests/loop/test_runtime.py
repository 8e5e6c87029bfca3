"""A condition that holds tick after tick is said once, and again only after it cleared.

The loop clears the safety rule's warnings each tick (each one is said when it starts).
The loop's own once-only warnings (a vehicle's thrust missing for load sharing, a busy
lockstep action, a re-send failing, a position jump) were cleared with them, so a vehicle
whose ATTITUDE_TARGET stopped filled the event list with the same line four times a
second and pushed every other event out of the page's list.
"""

from __future__ import annotations

import numpy as np

from gcs.loop import Phase
from tests.support.scripted_autopilot import HOVER_THRUST, fleet_state, peer_team


def test_a_missing_thrust_is_said_once_while_it_lasts_and_again_when_it_comes_back() -> None:
    with peer_team({vid: ("ardupilot", {}) for vid in (1, 2, 3, 4)}) as bench:
        runtime, team = bench.runtime, bench.team
        high = 10.0 + team.taut_altitude(1.0)
        silent = fleet_state(team.formation.positions, HOVER_THRUST, altitude=high)
        assert silent.thrust_age is not None
        silent.thrust_age[2] = np.inf  # vehicle 3's ATTITUDE_TARGET stopped
        heard = fleet_state(team.formation.positions, HOVER_THRUST, altitude=high)

        def said() -> int:
            return sum("load sharing held" in e.text for e in runtime.events())

        now = 10.0
        for fleet in (silent,) * 12 + (heard,) * 2 + (silent,) * 12:
            now += 0.25
            # as each tick does: the safety rules, then load sharing
            runtime.stages.safety.judge(now, Phase.FORMATION, fleet, commanded=0.0)
            runtime.stages.load_share.update(now, fleet, Phase.FORMATION, 1.0)
            if fleet is heard:
                assert said() == 1
        assert said() == 2
        assert all("vehicle(s) 3" in e.text for e in runtime.events()
                   if "load sharing held" in e.text)
