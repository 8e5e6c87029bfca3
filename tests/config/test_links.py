"""Link configuration from YAML: valid files load, wrong ones fail in one line naming the field."""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml

from gcs.common import ConfigError, from_mapping
from gcs.config import ZENOH, GcsLinkConfig, LinkConfig
from gcs.config._links import links_from_list
from gcs.link import LinkError, LinkManager
from gcs.link._profile import ProfileName
from gcs.transport import MavutilTransport
from gcs.wire._signing import write_signing_key

TEAM = """
links:
  - {sysid: 1}
  - {sysid: 2, transport: "udpin:0.0.0.0:14551", profile: ardupilot,
     signing_key: keys/vehicle2.key, command_timeout_s: 0.5}
  - {sysid: 3, transport: /dev/ttyACM0, profile: px4, baud: 921600}
"""


def load(text: str, source: str = "team.yaml") -> tuple[LinkConfig, ...]:
    return links_from_list(yaml.safe_load(text)["links"], source)


def test_team_links_load() -> None:
    a, b, c = load(TEAM)
    assert (a.sysid, a.transport, a.profile, a.signing_key) == (1, ZENOH, "sim", None)
    assert (b.profile, b.signing_key, b.command_timeout_s) == ("ardupilot", "keys/vehicle2.key",
                                                               0.5)
    assert (c.transport, c.baud, c.profile) == ("/dev/ttyACM0", 921600, "px4")
    assert b.signing_key_path(Path("/etc/gcs")) == Path("/etc/gcs/keys/vehicle2.key")
    assert a.signing_key_path(Path("/etc/gcs")) is None
    assert {ProfileName(x.profile) for x in (a, b, c)} == set(ProfileName)


@pytest.mark.parametrize(("text", "message"), [
    ("links: [{transport: zenoh}]", "team.yaml: links[0].sysid: missing required field"),
    ("links: [{sysid: 300}]", "team.yaml: links[0].sysid: must be at most 255, got 300"),
    ("links: [{sysid: 1, profile: inav}]",
     "team.yaml: links[0].profile: must be one of 'sim', 'px4', 'ardupilot', got 'inav'"),
    ("links: [{sysid: 1, transport: 'udp 14550'}]",
     "team.yaml: links[0]: transport: must be 'zenoh' or a pymavlink connection string"),
    ("links: [{sysid: 1, transport: 'udpin:0.0.0.0:99999'}]",
     "team.yaml: links[0]: transport: must be 'zenoh'"),
    ("links: [{sysid: 1, sysdi: 2}]", "team.yaml: links[0].sysdi: unknown field"),
    ("links: [{sysid: 1}, {sysid: 1}]",
     "team.yaml: links[1].sysid: system id 1 already used by links[0]"),
    ("links: [{sysid: 245}]",
     "team.yaml: links[0].sysid: system id 245 is the GCS's own system id"),
    ("links: [{sysid: 1, transport: 'udpin:0.0.0.0:14550'}, "
     "{sysid: 2, transport: 'udpin:0.0.0.0:14550'}]",
     "team.yaml: links[1].transport: 'udpin:0.0.0.0:14550' already used by links[0]"),
    ("links: [{sysid: 1, command_retries: -1}]",
     "team.yaml: links[0].command_retries: must be at least 0, got -1"),
    ("links: {sysid: 1}", "team.yaml: links: expected a list of links, got dict"),
])
def test_bad_links_give_one_line_errors(text: str, message: str) -> None:
    with pytest.raises(ConfigError) as info:
        load(text)
    assert str(info.value).startswith(message)
    assert "\n" not in str(info.value)


def test_gcs_link_config_and_zenoh_settings() -> None:
    config = from_mapping(GcsLinkConfig, yaml.safe_load("""
        fleet: lab
        system_id: 240
        zenoh: {listen: ["tcp/127.0.0.1:7447"], connect: []}
    """), "gcs.yaml")
    assert (config.fleet, config.system_id, config.component_id) == ("lab", 240, 190)
    assert config.zenoh.listen == ("tcp/127.0.0.1:7447",) and config.zenoh.connect == ()
    assert GcsLinkConfig().system_id == 245 and GcsLinkConfig().zenoh.multicast_scouting is False
    with pytest.raises(ConfigError, match=r"^gcs\.yaml: zenoh: connect: zenoh endpoint must"):
        from_mapping(GcsLinkConfig, {"zenoh": {"connect": ["127.0.0.1:7447"]}}, "gcs.yaml")
    with pytest.raises(ConfigError, match=r"^gcs\.yaml: fleet: fleet name must be"):
        from_mapping(GcsLinkConfig, {"fleet": "lab/*"}, "gcs.yaml")
    with pytest.raises(ConfigError, match=r"^gcs\.yaml: zenoh\.mode: must be one of"):
        from_mapping(GcsLinkConfig, {"zenoh": {"mode": "router"}}, "gcs.yaml")
    with pytest.raises(ConfigError) as info:  # MAVProxy's and QGC's id: never ours
        from_mapping(GcsLinkConfig, {"system_id": 255}, "gcs.yaml")
    assert str(info.value).startswith("gcs.yaml: system_id: 255 is what MAVProxy and "
                                      "QGroundControl use")


def test_manager_opens_udp_links_with_signing_keys_relative_to_the_config(tmp_path: Path) -> None:
    (tmp_path / "keys").mkdir()
    write_signing_key(tmp_path / "keys" / "v2.key")
    configs = links_from_list([{"sysid": 2, "transport": "udpin:127.0.0.1:0",
                                "profile": "ardupilot", "signing_key": "keys/v2.key"}],
                              "team.yaml")
    with LinkManager(configs, base_dir=tmp_path, check_period_s=0.05) as manager:
        link = manager.links[2]
        assert isinstance(link.transport, MavutilTransport)
        assert manager.profiles[2].name is ProfileName.ARDUPILOT
        assert manager.session is None  # no zenoh link, no zenoh session
        assert manager.missing() == (2,)


def test_manager_names_the_vehicle_when_a_link_cannot_open(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match=r"absent\.key: cannot read signing key"):
        LinkManager([LinkConfig(sysid=5, signing_key="absent.key", transport="udpin:127.0.0.1:0")],
                    base_dir=tmp_path)
    configs = [LinkConfig(sysid=1, transport="udpin:127.0.0.1:0"),
               LinkConfig(sysid=4, transport="/dev/ttyNO_SUCH_PORT")]
    with pytest.raises(LinkError, match=r"^vehicle 4: .*/dev/ttyNO_SUCH_PORT"):
        LinkManager(configs, base_dir=tmp_path)
