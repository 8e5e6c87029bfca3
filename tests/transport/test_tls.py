"""Zenoh across machines: TLS with mutual authentication and access control by role.

The certificates are made by ``gcs certs``. On loopback, real zenoh sessions show what each
role may read and publish; across three hosts (network namespaces), the simulator on one
(``python -m sim --tls``), the GCS on this one, and on a third a stranger without a
certificate, a stranger with another team's, a viewer and a second GCS. The peers sign
their commands with the team key, so that only the transport stands between them and the
vehicles.
"""

from __future__ import annotations

import functools
import json
import os
import stat
import subprocess
import sys
import threading
import time
import uuid
from collections.abc import Iterator
from pathlib import Path

import pytest
import zenoh
from cryptography import x509
from cryptography.x509.oid import NameOID

from gcs.app import SimProcess, free_tcp_port
from gcs.cli import main as gcs_main
from gcs.common import ConfigError
from gcs.config import GcsLinkConfig, load_team
from gcs.link import LinkManager
from gcs.testing import Host, NetnsUnavailableError
from gcs.transport import (
    RIGHTS,
    TlsSettings,
    ZenohSettings,
    certificate_files,
    check_tls,
    declare_alive,
    open_session,
    watch_alive,
)
from gcs.wire import keys

TEAM = load_team("configs/bebop_square.yaml")


def _certs(folder: Path, *hosts: str) -> Path:
    assert gcs_main(["certs", str(folder), "--hosts", *hosts] if hosts
                    else ["certs", str(folder)]) == 0
    return folder


@pytest.fixture(scope="module")
def certs(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return _certs(tmp_path_factory.mktemp("team") / "certs", "10.9.8.7", "sim.lab")


@pytest.fixture(scope="module")
def foreign(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Another team's certificates: the same names, another CA."""
    return _certs(tmp_path_factory.mktemp("other-team") / "certs")


# -- gcs certs -----------------------------------------------------------------------------


def test_gcs_certs_makes_a_ca_and_a_certificate_per_role(certs: Path) -> None:
    assert sorted(p.name for p in certs.iterdir()) == sorted(
        p.name for p in certificate_files(certs))
    assert stat.S_IMODE(certs.stat().st_mode) == 0o700
    ca = x509.load_pem_x509_certificate((certs / "ca.pem").read_bytes())
    for role in ("sim", "gcs", "viewer"):
        assert stat.S_IMODE((certs / f"{role}.key").stat().st_mode) == 0o600
        cert = x509.load_pem_x509_certificate((certs / f"{role}.pem").read_bytes())
        assert cert.subject.get_attributes_for_oid(NameOID.COMMON_NAME)[0].value == role
        cert.verify_directly_issued_by(ca)
        names = cert.extensions.get_extension_for_class(x509.SubjectAlternativeName).value
        assert {str(n.value) for n in names} >= {"localhost", "127.0.0.1", "10.9.8.7", "sim.lab"}
        assert check_tls(TlsSettings(dir=str(certs), role=role)).role == role
    assert stat.S_IMODE((certs / "ca.key").stat().st_mode) == 0o600


def test_gcs_certs_never_overwrites_without_force(tmp_path: Path,
                                                  capsys: pytest.CaptureFixture[str]) -> None:
    folder = _certs(tmp_path / "certs")
    before = (folder / "ca.pem").read_bytes()
    assert gcs_main(["certs", str(folder)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "ca.pem: exists already; --force" in err, err
    assert (folder / "ca.pem").read_bytes() == before
    assert gcs_main(["certs", str(folder), "--force"]) == 0
    assert (folder / "ca.pem").read_bytes() != before  # a new CA
    assert gcs_main(["certs", str(tmp_path / "x"), "--hosts", "no such host"]) == 2
    assert "'no such host' is neither an IP address nor a host name" in capsys.readouterr().err
    assert not (tmp_path / "x").exists()


# -- settings and their errors -------------------------------------------------------------


def test_tls_settings_make_every_endpoint_tls(certs: Path) -> None:
    tls = TlsSettings(dir=str(certs))
    s = ZenohSettings(listen=("tcp/0.0.0.0:7447",), connect=("tcp/10.9.8.7:7447",), tls=tls)
    assert s.listen == ("tls/0.0.0.0:7447",) and s.connect == ("tls/10.9.8.7:7447",)
    with pytest.raises(ValueError, match="with tls, endpoints must be tls/"):
        ZenohSettings(connect=("udp/10.9.8.7:7447",), tls=tls)
    with pytest.raises(ValueError, match="give dir"):
        TlsSettings(ca="ca.pem")
    assert ZenohSettings(tls=TlsSettings(dir="certs")).resolved("/teams").tls == \
        TlsSettings(dir="/teams/certs")


def test_bad_tls_files_are_one_line_naming_the_file_and_the_field(
        certs: Path, foreign: Path, tmp_path: Path) -> None:
    def error(settings: TlsSettings) -> str:
        with pytest.raises(ConfigError) as exc:
            open_session(ZenohSettings(connect=(), tls=settings))
        assert "\n" not in str(exc.value)
        return str(exc.value)

    missing = tmp_path / "none"
    assert error(TlsSettings(dir=str(missing))) == \
        f"{missing}/ca.pem: tls.ca: no such file (`gcs certs DIR` makes the team's certificates)"
    assert "gcs.pem: tls.certificate: not issued by the CA" in error(TlsSettings(
        dir=str(certs), certificate=str(foreign / "gcs.pem"), key=str(foreign / "gcs.key")))
    assert "viewer.pem: tls.certificate: its common name is 'viewer', not this process's " \
           "role 'gcs'" in error(TlsSettings(dir=str(certs), certificate=str(
               certs / "viewer.pem")))
    assert f"sim.key: tls.key: is not the key of {certs}/gcs.pem" in error(TlsSettings(
        dir=str(certs), key=str(certs / "sim.key")))
    garbage = tmp_path / "garbage.pem"
    garbage.write_bytes(b"\x00\xff" * 100)
    assert error(TlsSettings(dir=str(certs), ca=str(garbage))).endswith(
        "garbage.pem: tls.ca: not a PEM certificate")
    assert error(TlsSettings(dir=str(certs), key=str(garbage))).endswith(
        "garbage.pem: tls.key: not an unencrypted PEM private key")


def test_a_team_file_names_its_tls_folder(tmp_path: Path) -> None:
    def team_with(gcs: str) -> Path:
        path = tmp_path / "team.yaml"
        path.write_text(Path(TEAM.source).read_text().replace(
            "airframes/", f"{Path(TEAM.source).parent.resolve()}/airframes/") + f"\n{gcs}\n")
        return path

    zenoh_settings = load_team(team_with(
        "gcs: {zenoh: {connect: [tcp/10.9.8.7:7447], tls: {dir: certs}}}")).config.gcs.zenoh
    assert zenoh_settings.connect == ("tls/10.9.8.7:7447",)
    assert zenoh_settings.tls == TlsSettings(dir="certs", role="gcs", access_control=True)
    with pytest.raises(ConfigError, match=r"team\.yaml: gcs\.zenoh\.tls\.role: must be one of"):
        load_team(team_with("gcs: {zenoh: {tls: {dir: certs, role: pilot}}}"))
    with pytest.raises(ConfigError, match=r"gcs\.zenoh\.tls: give dir"):
        load_team(team_with("gcs: {zenoh: {tls: {key: gcs.key}}}"))


def test_python_m_sim_with_missing_certificates_says_so_in_one_line(tmp_path: Path) -> None:
    out = subprocess.run([sys.executable, "-m", "sim", "--config", TEAM.source, "--tls",
                          str(tmp_path), "--listen", f"tcp/127.0.0.1:{free_tcp_port()}"],
                         capture_output=True, text=True, timeout=60, check=False)
    assert out.returncode == 2, out.stderr
    assert out.stderr.strip() == f"sim: error: {tmp_path}/ca.pem: tls.ca: no such file " \
                                 f"(`gcs certs DIR` makes the team's certificates)"


# -- access control ------------------------------------------------------------------------


def _includes(patterns: tuple[str, ...], key: str) -> bool:
    return any(zenoh.KeyExpr(p).includes(zenoh.KeyExpr(key)) for p in patterns)


def test_the_roles_rights_cover_the_keys_the_processes_use() -> None:
    f = "team-a.b"
    to_vehicle = keys.mavlink(f, 7, keys.Direction.TO_VEHICLE)
    from_vehicle = keys.mavlink(f, 7, keys.Direction.FROM_VEHICLE)
    truth, control = keys.sim(f, "truth"), keys.sim(f, "control")
    sim, gcs, viewer = RIGHTS["sim"], RIGHTS["gcs"], RIGHTS["viewer"]
    for key in (from_vehicle, keys.clock(f), truth):
        assert _includes(sim.publishes, key) and not _includes(gcs.publishes, key)
    for key in (to_vehicle, keys.clock_ack(f), control):
        assert _includes(gcs.publishes, key) and _includes(sim.reads, key)
        assert not _includes(sim.publishes, key)
    assert _includes(sim.tokens, keys.alive(f, 7)) and not gcs.tokens and not viewer.tokens
    assert not viewer.publishes
    for key in (to_vehicle, from_vehicle, keys.clock(f), truth, control, keys.alive(f, 7)):
        assert _includes(gcs.reads, key) and _includes(viewer.reads, key)
    assert not _includes(sim.reads, from_vehicle) and not _includes(sim.reads, truth)


def _seen(appeared: set[int], sysid: int, up: bool) -> None:
    if up:
        appeared.add(sysid)


class _Peer:
    """A zenoh session that counts what it hears on the fleet's keys, by key."""

    def __init__(self, settings: ZenohSettings, fleet: str) -> None:
        self.session = open_session(settings)
        self.heard: dict[str, list[bytes]] = {}
        self._lock = threading.Lock()
        self._sub = self.session.declare_subscriber(f"fleet/{fleet}/**", self._on_sample)

    def _on_sample(self, sample: zenoh.Sample) -> None:
        with self._lock:
            self.heard.setdefault(str(sample.key_expr), []).append(sample.payload.to_bytes())

    def got(self, key: str) -> list[bytes]:
        with self._lock:
            return list(self.heard.get(key, []))

    def close(self) -> None:
        self._sub.undeclare()
        self.session.close()


def test_on_loopback_each_role_reads_and_publishes_only_what_it_may(
        certs: Path, foreign: Path) -> None:
    fleet = f"acl-{uuid.uuid4().hex[:8]}"
    endpoint = f"tls/127.0.0.1:{free_tcp_port()}"

    def tls(role: str, folder: Path = certs) -> TlsSettings:
        return TlsSettings(dir=str(folder), role=role)  # type: ignore[arg-type]

    sim_session = open_session(ZenohSettings(listen=(endpoint,), connect=(), tls=tls("sim")))
    heard_by_sim: list[tuple[str, bytes]] = []
    sim_keys = (keys.mavlink(fleet, 1, keys.Direction.TO_VEHICLE), keys.clock_ack(fleet),
                keys.sim(fleet, "control"))
    subs = [sim_session.declare_subscriber(
        k, lambda s: heard_by_sim.append((str(s.key_expr), s.payload.to_bytes())))
        for k in sim_keys]
    peers = {
        "gcs": _Peer(ZenohSettings(connect=(endpoint,), tls=tls("gcs")), fleet),
        "viewer": _Peer(ZenohSettings(connect=(endpoint,), tls=tls("viewer")), fleet),
        "plain": _Peer(ZenohSettings(connect=(endpoint.replace("tls/", "tcp/"),)), fleet),
        "foreign": _Peer(ZenohSettings(connect=(endpoint,), tls=tls("gcs", foreign)), fleet),
    }
    telemetry = keys.mavlink(fleet, 1, keys.Direction.FROM_VEHICLE)
    alive: dict[str, set[int]] = {"gcs": set(), "plain": set()}
    watchers = [watch_alive(peers[name].session, fleet=fleet,
                            on_change=functools.partial(_seen, alive[name]))
                for name in alive]
    tokens = [declare_alive(sim_session, fleet=fleet, sysid=1)] + [  # the others' are forged
        declare_alive(peers[name].session, fleet=fleet, sysid=k)
        for k, name in ((7, "viewer"), (8, "foreign"))]
    try:
        deadline = time.monotonic() + 10.0
        while not (peers["gcs"].got(telemetry) and peers["viewer"].got(telemetry)):
            assert time.monotonic() < deadline, "the team's peers never heard the sim"
            sim_session.put(telemetry, b"t")
            time.sleep(0.05)
        time.sleep(0.5)  # the strangers had as long as the team, and more
        for name, peer in peers.items():
            for key in sim_keys:
                peer.session.put(key, name.encode())
        time.sleep(0.5)
        assert {who for _, who in heard_by_sim} == {b"gcs"}
        assert {k for k, _ in heard_by_sim} == set(sim_keys)
        assert not peers["plain"].got(telemetry) and not peers["foreign"].got(telemetry)
        assert alive == {"gcs": {1}, "plain": set()}  # only a sim declares vehicles
    finally:
        for sub in subs + watchers:
            sub.undeclare()
        for token in tokens:
            token.undeclare()
        for peer in peers.values():
            peer.close()
        sim_session.close()


# -- three hosts -----------------------------------------------------------------------------

_PEER = """
import json, sys, time
import zenoh
from gcs.config import default_team_key_path, ensure_team_key
from gcs.link import CommandError, Link, LinkError
from gcs.transport import TlsSettings, ZenohSettings, ZenohTransport, open_session
from gcs.wire import mavlink
a = json.loads(sys.argv[1])
tls = None if a["certs"] is None else TlsSettings(dir=a["certs"], role=a["role"])
settings = ZenohSettings(connect=tuple(a["connect"]), tls=tls)
if a["impostor"] is None:
    session = open_session(settings)
else:  # trusts the team's CA (public) but presents a certificate of its own CA
    config = settings.to_config()
    for end in ("listen", "connect"):
        config.insert_json5(f"transport/link/tls/{end}_certificate",
                            json.dumps(a["impostor"] + "/gcs.pem"))
        config.insert_json5(f"transport/link/tls/{end}_private_key",
                            json.dumps(a["impostor"] + "/gcs.key"))
    session = zenoh.open(config)
heard = []  # what others said: its own frames to the vehicle are heard here too
sub = session.declare_subscriber("fleet/" + a["fleet"] + "/**", lambda s: heard.append(1)
                                 if not str(s.key_expr).endswith("to_vehicle") else None)
link = Link(a["sysid"], ZenohTransport.for_gcs(session, fleet=a["fleet"], sysid=a["sysid"]),
            gcs_system_id=a["gcs_id"], signing_key=ensure_team_key(default_team_key_path())[0],
            command_timeout_s=1.0, command_retries=1, timesync_period_s=0.0).start()
try:
    link.wait_for(lambda t: t.heartbeat is not None and t.position is not None,  # can arm
                  timeout_s=a["wait_s"], what="a HEARTBEAT and a position")
except LinkError:
    pass
try:
    link.command_long(mavlink.MAV_CMD_COMPONENT_ARM_DISARM, (1.0,))
    result = "ACCEPTED"
except CommandError as exc:
    result = exc.result.name
print(json.dumps({"heard": len(heard), "arm": result}), flush=True)
link.close()
sub.undeclare()
session.close()
"""
"""One peer on the third host: listens to the fleet, then tries to arm its vehicle with a
command signed with the team key; prints what it heard and the arm's outcome."""


def _run(*argv: str) -> None:
    out = subprocess.run(["ip", *argv], capture_output=True, text=True, check=False)
    if out.returncode != 0:
        raise NetnsUnavailableError(f"ip {' '.join(argv)}: {out.stderr.strip()}")


def _cable(a: Host, b: Host) -> tuple[str, str]:
    """A veth pair straight between two hosts on a subnet of their own, as two machines on a
    lab switch (a Host's own pair reaches only this machine); their two addresses."""
    ends = (f"lab{os.getpid() % 100000}a", f"lab{os.getpid() % 100000}b")
    subnet = f"10.250.{os.getpid() % 250}"
    _run("link", "add", ends[0], "type", "veth", "peer", "name", ends[1])
    addresses = (f"{subnet}.1", f"{subnet}.2")
    try:
        for host, end, address in zip((a, b), ends, addresses, strict=True):
            _run("link", "set", end, "netns", host.name)
            _run("-n", host.name, "addr", "add", f"{address}/24", "dev", end)
            _run("-n", host.name, "link", "set", end, "up")
    except NetnsUnavailableError:  # what is still here; the hosts take theirs with them
        subprocess.run(["ip", "link", "del", ends[0]], capture_output=True, check=False)
        raise
    return addresses


@pytest.fixture
def hosts() -> Iterator[tuple[Host, Host]]:
    made: list[Host] = []
    try:
        made += [Host(), Host()]
    except NetnsUnavailableError as exc:
        for h in made:
            h.close()
        pytest.skip(f"no other hosts on this machine: {exc}")
    try:
        yield made[0], made[1]
    finally:
        for h in made:
            h.close()


def test_across_three_hosts_only_the_team_reads_and_only_its_gcs_commands(
        hosts: tuple[Host, Host], tmp_path: Path, foreign: Path) -> None:
    sim_host, third = hosts
    try:
        sim_side, _ = _cable(sim_host, third)
    except NetnsUnavailableError as exc:
        pytest.skip(f"cannot cable two hosts: {exc}")
    certs = _certs(tmp_path / "certs", sim_host.address, sim_side)
    fleet = f"tls-{uuid.uuid4().hex[:8]}"
    port = free_tcp_port()
    with SimProcess(TEAM.source, endpoint=f"tcp/0.0.0.0:{port}", wrap=sim_host.command,
                    extra=("--tls", str(certs), "--fleet", fleet)) as sim:
        assert sim.endpoint == f"tcp/0.0.0.0:{port}"  # as given; the sim made it tls/
        settings = GcsLinkConfig(fleet=fleet, timesync_period_s=0.0, zenoh=ZenohSettings(
            connect=(f"tcp/{sim_host.address}:{port}",), tls=TlsSettings(dir=str(certs))))
        with LinkManager(TEAM.config.vehicle_links(), settings=settings,
                         base_dir=tmp_path) as manager:
            manager.links[1].wait_for(  # a position too: a vehicle without one refuses to arm
                lambda t: t.heartbeat is not None and t.position is not None, timeout_s=20.0,
                what="a HEARTBEAT and a position over TLS")
            over_tls = f"tls/{sim_side}:{port}"
            # name: (certificates, role, its own CA's, endpoints, vehicle, wait for a HEARTBEAT)
            # (the team's peers go on once they hear one; a session is up well within 5 s)
            peers = {
                "stranger": (None, "gcs", None, [f"tcp/{sim_side}:{port}", over_tls], 2, 5.0),
                "impostor": (str(certs), "gcs", str(foreign), [over_tls], 2, 5.0),
                "viewer": (str(certs), "viewer", None, [over_tls], 3, 20.0),
                "second gcs": (str(certs), "gcs", None, [over_tls], 4, 20.0),
            }
            procs = {name: subprocess.Popen(third.command(sys.executable, "-c", _PEER, json.dumps(
                {"certs": c, "role": role, "impostor": own, "connect": eps, "fleet": fleet,
                 "sysid": sysid, "gcs_id": 70 + k, "wait_s": wait})), stdout=subprocess.PIPE,
                stderr=subprocess.PIPE, text=True)
                for k, (name, (c, role, own, eps, sysid, wait)) in enumerate(peers.items())}
            # which vehicles ever said they were armed (an armed vehicle left on the ground
            # disarms itself after a while, as an autopilot does, and a busy machine may
            # take that long to run the peers)
            ever_armed: set[int] = set()
            watching = threading.Event()

            def watch() -> None:
                while not watching.wait(0.02):
                    for s in (1, 2, 3, 4):
                        hb = manager.links[s].telemetry.heartbeat
                        if hb is not None and hb.armed:
                            ever_armed.add(s)

            watcher = threading.Thread(target=watch, daemon=True)
            watcher.start()
            manager.profiles[1].arm()  # the team's GCS commands over TLS, meanwhile
            said = {}
            for name, proc in procs.items():
                out, err = proc.communicate(timeout=60)
                assert proc.returncode == 0, f"{name}: {err}"
                said[name] = json.loads(out.strip().splitlines()[-1])
            time.sleep(0.5)  # a vehicle armed by any of them has said so by now
            watching.set()
            watcher.join(timeout=5.0)
    assert said["stranger"] == {"heard": 0, "arm": "TIMEOUT"}, said
    assert said["impostor"] == {"heard": 0, "arm": "TIMEOUT"}, said
    assert said["viewer"]["heard"] > 0 and said["viewer"]["arm"] == "TIMEOUT", said
    assert said["second gcs"]["heard"] > 0 and said["second gcs"]["arm"] == "ACCEPTED", said
    assert ever_armed == {1, 4}, ever_armed
