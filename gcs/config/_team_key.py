"""The team key: one MAVLink 2 signing key per user, made on first use, so that
nothing but this user's GCS can command the simulated team.

Why: signing that has to be set up is signing nobody sets up. The GCS and the
simulator it starts (or that the same user starts with ``gcs sim``) read the
same owner-only file in the user's config directory; a stranger on the network
has no key, and the vehicles refuse every frame of theirs. Copy the file to
another machine (``gcs key --show`` prints where it is) to fly across hosts.

Which link uses which key (:func:`link_key`): a link that names a key file uses
it; ``signing_key: team`` uses the team key; a link that names none uses the
team key if it is simulated (profile ``sim``) and nothing if it is a real
autopilot, which the page then shows as unsigned, in red, until the key is
installed on it (``gcs key --install``). ``gcs.signing: false`` in the team
file, or ``--insecure`` on the command line, turns the team key off.
"""

from __future__ import annotations

import hashlib
import os
import secrets
import tempfile
from pathlib import Path

from gcs.common import ConfigError
from gcs.config._links import GcsLinkConfig, LinkConfig
from gcs.wire import SigningKey, load_signing_key, parse_signing_key

__all__ = [
    "TEAM_KEY",
    "default_team_key_path",
    "ensure_team_key",
    "key_fingerprint",
    "key_from_passphrase",
    "link_key",
    "seal_key",
    "signing_line",
    "team_key_path",
]

TEAM_KEY = "team"
"""``signing_key: team`` in a link: sign it with the team key."""

_APP_DIR = "formation-gcs"
_KEY_FILE = "team.key"


def default_team_key_path() -> Path:
    """``$XDG_CONFIG_HOME/formation-gcs/team.key`` (``~/.config`` without XDG)."""
    base = os.environ.get("XDG_CONFIG_HOME") or ""
    root = Path(base) if base and Path(base).is_absolute() else Path.home() / ".config"
    return root / _APP_DIR / _KEY_FILE


def team_key_path(settings: GcsLinkConfig, base_dir: Path) -> Path:
    """The team key file ``settings`` name (relative to the team file), or the default."""
    if settings.team_key is None:
        return default_team_key_path()
    path = Path(settings.team_key).expanduser()
    return path if path.is_absolute() else base_dir / path


def ensure_team_key(path: Path) -> tuple[SigningKey, bool]:
    """The key in ``path``, made (random, mode 0600, folder 0700) if there is none yet.

    Returns the key and whether it was just made. Two processes starting at once
    make one key between them: the file appears whole (written aside, then linked
    in place, which fails if the other process won), and the loser reads it.
    """
    if path.exists():
        return load_signing_key(path), False
    try:
        path.parent.mkdir(mode=0o700, parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(prefix=".team-key-", dir=path.parent)
    except OSError as exc:
        raise ConfigError(str(path), "", f"cannot create the team signing key "
                                         f"({exc.strerror})") from None
    try:
        with os.fdopen(fd, "w", encoding="ascii") as f:  # mkstemp makes it 0600
            f.write(secrets.token_bytes(32).hex() + "\n")
        try:
            os.link(tmp, path)
            created = True
        except FileExistsError:
            created = False
    except OSError as exc:
        raise ConfigError(str(path), "", f"cannot create the team signing key "
                                         f"({exc.strerror})") from None
    finally:
        Path(tmp).unlink(missing_ok=True)
    return load_signing_key(path), created


def key_from_passphrase(passphrase: str, source: str = "<passphrase>") -> SigningKey:
    """The key MAVProxy's ``signing key <passphrase>`` and ``signing setup`` use:
    SHA-256 of the passphrase (so a MAVProxy user can join a signed team)."""
    if not passphrase:
        raise ConfigError(source, "", "passphrase is empty")
    return parse_signing_key(hashlib.sha256(passphrase.encode()).digest(), source)


def key_fingerprint(key: SigningKey) -> str:
    """A short public name of a key (first 8 hex digits of its SHA-256), safe to print."""
    return hashlib.sha256(key.secret).hexdigest()[:8]


def seal_key(settings: GcsLinkConfig, base_dir: Path) -> SigningKey | None:
    """The team key that seals the simulator's clock, truth, acks and control (and signs
    its vehicles), or None with signing off: the GCS and the simulator ask here alike."""
    if not settings.signing:
        return None
    return ensure_team_key(team_key_path(settings, base_dir))[0]


def signing_line(settings: GcsLinkConfig, base_dir: Path) -> str:
    """One line for the console on how the team is signed, making the key if needed
    (before a simulator is started, so that the two never race to make it)."""
    if not settings.signing:
        return ("MAVLink signing is OFF (--insecure or gcs.signing: false): anyone who "
                "reaches a port can command the vehicles")
    path = team_key_path(settings, base_dir)
    key, created = ensure_team_key(path)
    made = "made a new team key" if created else "team key"
    return f"signing: {made} {key_fingerprint(key)} in {path}"


def link_key(link: LinkConfig, *, settings: GcsLinkConfig,
             base_dir: Path) -> SigningKey | None:
    """The key that signs ``link`` (see the module docstring), made on first use."""
    if link.signing_key is not None and link.signing_key != TEAM_KEY:
        path = link.signing_key_path(base_dir)
        assert path is not None
        return load_signing_key(path)
    if link.signing_key == TEAM_KEY:
        return ensure_team_key(team_key_path(settings, base_dir))[0]
    return seal_key(settings, base_dir) if link.profile == "sim" else None
