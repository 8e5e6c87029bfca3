"""The team key: made once per user, owner-only, shared by every process that needs it,
and which link it signs."""

from __future__ import annotations

import hashlib
import multiprocessing
import os
import stat
from pathlib import Path

import pytest

from gcs.common import ConfigError
from gcs.config import (
    TEAM_KEY,
    GcsLinkConfig,
    LinkConfig,
    default_team_key_path,
    ensure_team_key,
    key_from_passphrase,
    link_key,
    load_team,
)
from gcs.wire import write_signing_key
from tests.support.commands import run_gcs
from tests.support.paths import ROOT


def test_the_key_is_made_once_owner_only(tmp_path: Path) -> None:
    path = tmp_path / "cfg" / "formation-gcs" / "team.key"
    key, created = ensure_team_key(path)
    again, created_again = ensure_team_key(path)
    assert created and not created_again and key.secret == again.secret
    assert stat.S_IMODE(path.stat().st_mode) == 0o600
    assert stat.S_IMODE(path.parent.stat().st_mode) == 0o700
    assert list(path.parent.iterdir()) == [path]  # no temporary file left behind


def _make(path: str, out: multiprocessing.Queue) -> None:  # type: ignore[type-arg]
    out.put(ensure_team_key(Path(path))[0].secret)


def test_processes_starting_at_once_share_one_key(tmp_path: Path) -> None:
    path = tmp_path / "team.key"
    ctx = multiprocessing.get_context("fork")
    out: multiprocessing.Queue = ctx.Queue()  # type: ignore[type-arg]
    procs = [ctx.Process(target=_make, args=(str(path), out)) for _ in range(8)]
    for p in procs:
        p.start()
    secrets = {out.get(timeout=30) for _ in procs}
    for p in procs:
        p.join(timeout=30)
    assert len(secrets) == 1


def test_the_default_place_follows_xdg(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    monkeypatch.setenv("XDG_CONFIG_HOME", str(tmp_path))
    assert default_team_key_path() == tmp_path / "formation-gcs" / "team.key"
    monkeypatch.setenv("XDG_CONFIG_HOME", "relative/ignored")  # the XDG spec: absolute only
    assert default_team_key_path() == Path.home() / ".config" / "formation-gcs" / "team.key"


def test_which_link_the_team_key_signs(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    monkeypatch.setenv("XDG_CONFIG_HOME", str(tmp_path))
    own = write_signing_key(tmp_path / "own.key")
    on, off = GcsLinkConfig(), GcsLinkConfig(signing=False)
    sim = LinkConfig(sysid=1)
    px4 = LinkConfig(sysid=2, transport="udpin:0.0.0.0:14550", profile="px4")
    team = ensure_team_key(default_team_key_path())[0]

    def key(link: LinkConfig, settings: GcsLinkConfig) -> bytes | None:
        k = link_key(link, settings=settings, base_dir=tmp_path)
        return None if k is None else k.secret

    assert key(sim, on) == team.secret            # simulated: signed by default
    assert key(sim, off) is None                   # --insecure
    assert key(px4, on) is None                    # a real autopilot: not until installed
    px4_team = LinkConfig(sysid=2, transport="udpin:0.0.0.0:14550", profile="px4",
                          signing_key=TEAM_KEY)
    assert key(px4_team, on) == team.secret
    named = LinkConfig(sysid=3, signing_key="own.key")
    assert key(named, on) == key(named, off) == own.secret


def test_a_passphrase_key_is_mavproxys() -> None:
    """MAVProxy's ``signing key PASSPHRASE`` uses SHA-256 of the passphrase."""
    assert key_from_passphrase("lab team 7").secret == hashlib.sha256(b"lab team 7").digest()
    with pytest.raises(ConfigError, match="empty"):
        key_from_passphrase("")


def test_a_bad_team_key_file_is_refused_at_load(tmp_path: Path) -> None:
    (tmp_path / "bad.key").write_bytes(b"0" * 10)
    text = (ROOT / "configs" / "bebop_square.yaml").read_text().replace(
        "airframes/bebop2.yaml", str(ROOT / "configs" / "airframes" / "bebop2.yaml"))
    config = tmp_path / "team.yaml"
    config.write_text(text.replace("gcs:\n", "gcs:\n  team_key: bad.key\n", 1)
                      if "gcs:\n" in text else text + "\ngcs:\n  team_key: bad.key\n")
    with pytest.raises(ConfigError) as err:
        load_team(config)
    assert "gcs.team_key" in str(err.value) and "bad.key" in str(err.value)


def test_gcs_key_shows_makes_and_replaces(tmp_path: Path) -> None:
    env_home = os.environ["XDG_CONFIG_HOME"]
    path = Path(env_home) / "formation-gcs" / "team.key"
    out = run_gcs("key")
    assert out.returncode == 0 and str(path) in out.stdout, out.stdout + out.stderr
    before = path.read_bytes()
    refused = run_gcs("key", "--passphrase-stdin")
    assert refused.returncode == 2 and "--replace" in refused.stderr
    assert path.read_bytes() == before
