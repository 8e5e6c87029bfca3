"""A team's certificates: one CA and a certificate per role (``gcs certs``).

Why: zenoh over TLS with mutual authentication admits only peers whose
certificate the team's CA signed, and its access control tells the roles
apart by the certificate's common name (:mod:`gcs.transport._acl`). So one
command makes the whole set, in one folder::

    ca.pem  ca.key                 the team's CA (keep ca.key off the field machines)
    sim.pem sim.key                CN "sim":    the simulator
    gcs.pem gcs.key                CN "gcs":    the ground station
    viewer.pem viewer.key          CN "viewer": read-only peers

Keys are EC P-256, written mode 0600 in a folder made 0700. Every
certificate serves both ends of a connection (peers listen and connect) and
names, as subject alternative names, ``localhost``, 127.0.0.1, ::1 and the
hosts given: zenoh checks the name of the host it connects to against them.
Nothing is overwritten unless asked (``force``): new certificates lock out
every machine that still has the old ones.
"""

from __future__ import annotations

import datetime
import ipaddress
import os
import re
from collections.abc import Sequence
from pathlib import Path

from cryptography import x509
from cryptography.hazmat.primitives import hashes, serialization
from cryptography.hazmat.primitives.asymmetric import ec
from cryptography.x509.oid import ExtendedKeyUsageOID, NameOID

from gcs.common import ConfigError
from gcs.transport._acl import ROLES

__all__ = ["CA_NAME", "DEFAULT_DAYS", "certificate_files", "make_team_certificates"]

CA_NAME = "ca"
"""Base name of the CA's files (``ca.pem``, ``ca.key``)."""

DEFAULT_DAYS = 1825
"""Validity of the role certificates, days (the CA's is twice as long)."""

_LOCAL = ("localhost", "127.0.0.1", "::1")
_HOSTNAME = re.compile(r"(?=.{1,253}$)[A-Za-z0-9]([A-Za-z0-9-]{0,61}[A-Za-z0-9])?"
                       r"(\.[A-Za-z0-9]([A-Za-z0-9-]{0,61}[A-Za-z0-9])?)*\.?")


def certificate_files(folder: Path) -> list[Path]:
    """Every file :func:`make_team_certificates` writes into ``folder``."""
    return [folder / f"{name}.{ext}" for name in (CA_NAME, *ROLES) for ext in ("pem", "key")]


def _alt_name(host: str) -> x509.GeneralName:
    try:
        return x509.IPAddress(ipaddress.ip_address(host))
    except ValueError:
        pass
    if not _HOSTNAME.fullmatch(host):
        raise ConfigError("--hosts", "", f"{host!r} is neither an IP address nor a host name")
    return x509.DNSName(host.rstrip("."))


def _write(path: Path, data: bytes, mode: int) -> None:
    fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, mode)
    with os.fdopen(fd, "wb") as f:
        f.write(data)


def _name(common_name: str, team: str) -> x509.Name:
    return x509.Name([x509.NameAttribute(NameOID.ORGANIZATION_NAME, team),
                      x509.NameAttribute(NameOID.COMMON_NAME, common_name)])


def _usage(*, ca: bool) -> x509.KeyUsage:
    return x509.KeyUsage(digital_signature=True, content_commitment=False,
                         key_encipherment=False, data_encipherment=False, key_agreement=False,
                         key_cert_sign=ca, crl_sign=ca, encipher_only=False,
                         decipher_only=False)


def make_team_certificates(folder: str | Path, hosts: Sequence[str] = (), *,
                           force: bool = False, days: int = DEFAULT_DAYS,
                           team: str = "formation-gcs team") -> list[Path]:
    """Write a new CA and the role certificates into ``folder``; returns the files written.

    Raises ConfigError (one line) for a bad host name, an existing file without
    ``force``, or a folder that cannot be written.
    """
    folder = Path(folder)
    if days < 1:
        raise ConfigError("--days", "", f"must be at least 1, got {days}")
    alt_names = list(dict.fromkeys(_alt_name(h) for h in (*_LOCAL, *hosts)))
    files = certificate_files(folder)
    if not force:
        for path in files:
            if path.exists():
                raise ConfigError(str(path), "", "exists already; --force makes a new team "
                                  "CA and certificates (every machine then needs the new ones)")
    now = datetime.datetime.now(datetime.UTC)
    start = now - datetime.timedelta(minutes=5)  # clocks of a lab differ a little
    ca_key = ec.generate_private_key(ec.SECP256R1())
    ca_name = _name(f"{team} CA", team)
    ca = (x509.CertificateBuilder().subject_name(ca_name).issuer_name(ca_name)
          .public_key(ca_key.public_key()).serial_number(x509.random_serial_number())
          .not_valid_before(start).not_valid_after(now + datetime.timedelta(days=2 * days))
          .add_extension(x509.BasicConstraints(ca=True, path_length=0), critical=True)
          .add_extension(_usage(ca=True), critical=True)
          .add_extension(x509.SubjectKeyIdentifier.from_public_key(ca_key.public_key()),
                         critical=False)
          .sign(ca_key, hashes.SHA256()))
    issued: list[tuple[str, bytes, bytes]] = [(CA_NAME, _pem(ca), _pem_key(ca_key))]
    for role in ROLES:
        key = ec.generate_private_key(ec.SECP256R1())
        cert = (x509.CertificateBuilder().subject_name(_name(role, team)).issuer_name(ca_name)
                .public_key(key.public_key()).serial_number(x509.random_serial_number())
                .not_valid_before(start).not_valid_after(now + datetime.timedelta(days=days))
                .add_extension(x509.BasicConstraints(ca=False, path_length=None), critical=True)
                .add_extension(_usage(ca=False), critical=True)
                .add_extension(x509.ExtendedKeyUsage([ExtendedKeyUsageOID.SERVER_AUTH,
                                                      ExtendedKeyUsageOID.CLIENT_AUTH]),
                               critical=False)
                .add_extension(x509.SubjectAlternativeName(alt_names), critical=False)
                .add_extension(x509.AuthorityKeyIdentifier.from_issuer_public_key(
                    ca_key.public_key()), critical=False)
                .sign(ca_key, hashes.SHA256()))
        issued.append((role, _pem(cert), _pem_key(key)))
    try:
        folder.mkdir(mode=0o700, parents=True, exist_ok=True)
        for path in files:
            path.unlink(missing_ok=True)  # only with force: checked above
        for name, cert_pem, key_pem in issued:
            _write(folder / f"{name}.pem", cert_pem, 0o644)
            _write(folder / f"{name}.key", key_pem, 0o600)
    except OSError as exc:
        raise ConfigError(str(exc.filename or folder), "",
                          f"cannot write the certificates ({exc.strerror})") from None
    return files


def _pem(cert: x509.Certificate) -> bytes:
    return cert.public_bytes(serialization.Encoding.PEM)


def _pem_key(key: ec.EllipticCurvePrivateKey) -> bytes:
    return key.private_bytes(serialization.Encoding.PEM, serialization.PrivateFormat.PKCS8,
                             serialization.NoEncryption())
