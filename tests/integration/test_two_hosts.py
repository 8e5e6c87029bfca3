"""Across two hosts over a telemetry radio's link: the simulator in a network namespace of its
own, the GCS here, 100 ms each way and 5 % loss between them (gcs.testing).

Real time (a paced simulator: the slow lossy link is the subject here; lockstep across
hosts is tests/integration/test_fly_connect_lockstep.py), so the flight takes as long as it flies;
what it checks is that the team keeps flying through the delays and stalls, not how
fast the machine is.
"""

from __future__ import annotations

import pytest

from gcs.app import SimProcess, fly, free_tcp_port, load_scenario
from gcs.config import load_team
from gcs.testing import Host, LossyRelay

TEAM = load_team("configs/bebop_square.yaml")
SHORT = load_scenario("configs/scenarios/short_flight.yaml")


@pytest.mark.long  # the short flight at 1x on the wall clock, over the slow link
def test_the_short_flight_completes_across_hosts_over_a_lossy_slow_link(
        other_host: Host) -> None:
    port = free_tcp_port()
    endpoint = f"tcp/{other_host.address}:{port}"
    with SimProcess(TEAM.source, endpoint=endpoint, speed="1", wrap=other_host.command), \
            LossyRelay((other_host.address, port), delay=0.1, loss=0.05, seed=3) as relay:
        result = fly(TEAM, SHORT, connect=f"tcp/127.0.0.1:{relay.port}", progress=False)
    m = result.metrics
    assert result.error is None, result.error
    assert m["payload_lift_m"] > 0.8 and "setting down" in m["phases"], m
    assert m["phases"][-1] == "landed", m
    assert relay.losses > 0  # the link did lose
