"""MAVLink 2 signing between the sim host and the GCS, keyed by the same team file.

The team file's ``links`` name a key file per vehicle; the sim host signs with
it and refuses unsigned frames, the GCS's LinkManager signs with it too.
"""

from __future__ import annotations

import uuid
from pathlib import Path

import pytest

from gcs.app import SimProcess, free_tcp_port
from gcs.config import GcsLinkConfig, load_team
from gcs.config._team import ConfigError
from gcs.link import CommandError, Link, LinkManager
from gcs.transport import ZenohSettings, ZenohTransport
from gcs.wire import CommandResult, mavlink
from gcs.wire._signing import write_signing_key
from sim import DEFAULT_AUTOPILOT_CONFIG, DEFAULT_WORLD_CONFIG, load_world_config
from sim._host import SimHost
from sim._options import HostOptions
from tests.support.paths import ROOT
from vehicles import load_autopilot_config

CONFIG = ROOT / "configs" / "bebop_square.yaml"


def signed_team_file(folder: Path, key_name: str) -> Path:
    text = CONFIG.read_text().replace("airframes/bebop2.yaml",
                                      str(ROOT / "configs" / "airframes" / "bebop2.yaml"))
    links = "".join(f"  - {{sysid: {s}, signing_key: {key_name}}}\n" for s in (1, 2, 3, 4))
    path = folder / "signed_team.yaml"
    path.write_text(f"{text}\nlinks:\n{links}")
    return path


def test_signed_team_flies_only_with_the_key(tmp_path: Path) -> None:
    write_signing_key(tmp_path / "team.key")
    config = signed_team_file(tmp_path, "team.key")
    team = load_team(config)
    fleet = f"simsign-{uuid.uuid4().hex[:8]}"
    with SimProcess(config, endpoint=f"tcp/127.0.0.1:{free_tcp_port()}",
                    extra=("--fleet", fleet), ready_timeout=90.0) as sim:
        settings = GcsLinkConfig(fleet=fleet, timesync_period_s=0.0,
                                 zenoh=ZenohSettings(connect=(sim.endpoint,)))
        with LinkManager(team.config.vehicle_links(), settings=settings,
                         base_dir=tmp_path) as manager:
            manager.profiles[1].arm()  # signed both ways: acknowledged and confirmed
            assert manager.links[1].health.refused_signature == 0
            assert manager.links[1].health.signed  # the page shows no unsigned banner
            assert manager.session is not None
            stranger = Link(2, ZenohTransport.for_gcs(manager.session, fleet=fleet, sysid=2),
                            command_timeout_s=0.3, command_retries=1,
                            gcs_heartbeat_period_s=0.0, timesync_period_s=0.0).start()
            try:
                with pytest.raises(CommandError) as refused:
                    stranger.command_long(mavlink.MAV_CMD_COMPONENT_ARM_DISARM, (1.0,))
                assert refused.value.result is CommandResult.TIMEOUT  # unsigned: never heard
            finally:
                stranger.close()
            assert not manager.links[2].telemetry.heartbeat.armed  # type: ignore[union-attr]


def test_a_missing_key_file_is_a_config_error_before_anything_opens(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match=r"links\[0\]\.signing_key: absent\.key"):
        load_team(signed_team_file(tmp_path, "absent.key"))  # the team file refers to it
    write_signing_key(tmp_path / "absent.key")
    team = load_team(signed_team_file(tmp_path, "absent.key"))
    (tmp_path / "absent.key").unlink()  # gone after the team was loaded: the host says so
    with pytest.raises(ConfigError, match=r"absent\.key"):
        SimHost(team, HostOptions(listen=(f"tcp/127.0.0.1:{free_tcp_port()}",)),
                world_config=load_world_config(DEFAULT_WORLD_CONFIG),
                autopilot_config=load_autopilot_config(DEFAULT_AUTOPILOT_CONFIG))
