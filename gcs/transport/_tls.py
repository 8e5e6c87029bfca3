"""This process's TLS material for zenoh: which files, checked before zenoh reads them.

Why: zenoh reports a missing key, a certificate of another team or an
expired one as a failed handshake in its log, long after start, or as a
multi-line error from deep inside; the user needs one line that names the
file and what is wrong with it, before anything is opened. So the files are
read and checked here (the certificate is the CA's, valid now, names this
role, and the key is its key), and zenoh gets the checked paths.
"""

from __future__ import annotations

import datetime
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

from cryptography import x509
from cryptography.exceptions import InvalidSignature
from cryptography.hazmat.primitives import serialization
from cryptography.x509.oid import NameOID

from gcs.common import ConfigError, FieldError, field
from gcs.transport._acl import ROLES, Role, access_control

__all__ = ["TlsFiles", "TlsSettings", "check_tls", "tls_sections"]


@dataclass(frozen=True)
class TlsSettings:
    """Where this process's certificate is, and whether peers are held to their role."""

    dir: str | None = field(
        doc="folder made by `gcs certs`: ca.pem and <role>.pem, <role>.key", default=None)
    role: Role = field(doc="this process's role, 'sim', 'gcs' or 'viewer': which certificate "
                           "of the folder it presents", default="gcs")
    ca: str | None = field(doc="the team's CA certificate (default: <dir>/ca.pem)",
                           default=None)
    certificate: str | None = field(doc="this process's certificate (default: <dir>/<role>.pem)",
                                    default=None)
    key: str | None = field(doc="its private key (default: <dir>/<role>.key)", default=None)
    access_control: bool = field(
        doc="refuse, key expression by key expression, what a peer's role may not do "
            "(zenoh access control by certificate common name)", default=True)

    def __post_init__(self) -> None:
        if self.role not in ROLES:
            raise FieldError("role", f"must be one of {', '.join(ROLES)}, got {self.role!r}")
        if self.dir is None and None in (self.ca, self.certificate, self.key):
            raise ValueError("give dir (a folder made by `gcs certs`) or all of ca, "
                             "certificate and key")

    def paths(self) -> tuple[Path, Path, Path]:
        """(CA certificate, certificate, key), as given (relative to the current folder)."""
        folder = Path(self.dir or ".").expanduser()

        def pick(given: str | None, default: str) -> Path:
            return Path(given).expanduser() if given is not None else folder / default

        return (pick(self.ca, "ca.pem"), pick(self.certificate, f"{self.role}.pem"),
                pick(self.key, f"{self.role}.key"))

    def resolved(self, base_dir: str | Path) -> TlsSettings:
        """The same settings with relative paths taken from ``base_dir`` (a team file's
        folder)."""
        def absolute(p: str | None) -> str | None:
            if p is None:
                return None
            path = Path(p).expanduser()
            return str(path if path.is_absolute() else Path(base_dir) / path)

        return replace(self, dir=absolute(self.dir), ca=absolute(self.ca),
                       certificate=absolute(self.certificate), key=absolute(self.key))


@dataclass(frozen=True)
class TlsFiles:
    """Checked TLS files: they exist, parse, belong together and are valid now."""

    ca: Path
    certificate: Path
    key: Path
    role: Role
    not_after: datetime.datetime
    """When the certificate expires (UTC)."""


def _read(path: Path, where: str) -> bytes:
    try:
        return path.read_bytes()
    except FileNotFoundError:
        raise ConfigError(str(path), where, "no such file (`gcs certs DIR` makes the team's "
                                            "certificates)") from None
    except IsADirectoryError:
        raise ConfigError(str(path), where, "is a folder, not a file") from None
    except OSError as exc:
        raise ConfigError(str(path), where, f"cannot read it ({exc.strerror})") from None


def _certificate(path: Path, where: str) -> x509.Certificate:
    data = _read(path, where)
    try:
        return x509.load_pem_x509_certificate(data)
    except ValueError:
        raise ConfigError(str(path), where, "not a PEM certificate") from None


def check_tls(settings: TlsSettings) -> TlsFiles:
    """Read and check the files of ``settings``; raises ConfigError (one line) naming the
    file and the field at fault."""
    ca_path, cert_path, key_path = settings.paths()
    ca = _certificate(ca_path, "tls.ca")
    cert = _certificate(cert_path, "tls.certificate")
    try:
        cert.verify_directly_issued_by(ca)
    except (ValueError, TypeError, InvalidSignature):
        raise ConfigError(str(cert_path), "tls.certificate",
                          f"not issued by the CA in {ca_path} (a certificate of another "
                          f"team?)") from None
    now = datetime.datetime.now(datetime.UTC)
    for path, where, c in ((ca_path, "tls.ca", ca), (cert_path, "tls.certificate", cert)):
        if now > c.not_valid_after_utc:
            raise ConfigError(str(path), where, f"expired on {c.not_valid_after_utc:%Y-%m-%d}"
                                                f" (`gcs certs --force` makes new ones)")
        if now < c.not_valid_before_utc:
            raise ConfigError(str(path), where, f"not valid before "
                                                f"{c.not_valid_before_utc:%Y-%m-%d %H:%M} UTC "
                                                f"(is this machine's clock right?)")
    names = [a.value for a in cert.subject.get_attributes_for_oid(NameOID.COMMON_NAME)]
    if names[:1] != [settings.role]:
        raise ConfigError(str(cert_path), "tls.certificate",
                          f"its common name is {names[0] if names else 'missing'!r}, not this "
                          f"process's role {settings.role!r} (tls.role)")
    data = _read(key_path, "tls.key")
    try:
        key = serialization.load_pem_private_key(data, password=None)
    except (ValueError, TypeError):
        raise ConfigError(str(key_path), "tls.key",
                          "not an unencrypted PEM private key") from None
    if key.public_key() != cert.public_key():
        raise ConfigError(str(key_path), "tls.key", f"is not the key of {cert_path}")
    return TlsFiles(ca=ca_path, certificate=cert_path, key=key_path, role=settings.role,
                    not_after=cert.not_valid_after_utc)


def tls_sections(settings: TlsSettings) -> dict[str, Any]:
    """zenoh configuration entries (path -> JSON value) for ``settings``, files checked."""
    files = check_tls(settings)
    sections: dict[str, Any] = {"transport/link/tls": {
        "root_ca_certificate": str(files.ca),
        "listen_private_key": str(files.key), "listen_certificate": str(files.certificate),
        "connect_private_key": str(files.key), "connect_certificate": str(files.certificate),
        "enable_mtls": True,
    }}
    if settings.access_control:
        sections["access_control"] = access_control()
    return sections
