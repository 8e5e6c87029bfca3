"""What each role of a team may do on zenoh, as zenoh's access control by certificate.

Why: TLS with mutual authentication keeps out whoever has no certificate of
the team's CA, but every certificate holder could still publish anything. The
certificate's common name is its role (``gcs certs`` writes CN = role), and
zenoh's ``access_control`` matches a peer by that name
(``subjects: [{cert_common_names: [...]}]``), so each process refuses, key
expression by key expression, what the peer's role may not do:

=========  ==========================================  ====================================
role       publishes                                   subscribes to
=========  ==========================================  ====================================
sim        ``from_vehicle``, clock, ``sim/truth``;     ``to_vehicle``, ``clock/ack``,
           the vehicles' liveliness tokens             ``sim/control``
gcs        ``to_vehicle``, ``clock/ack``,              everything under ``fleet/**``
           ``sim/control``
viewer     nothing                                     everything under ``fleet/**``
=========  ==========================================  ====================================

Every process applies the same table to each peer (default: deny, so a peer
with no certificate, or a name not in the table, gets and gives nothing):

- *ingress*: the peer's puts on what its role publishes, its subscriptions
  (and liveliness subscriptions) on what it may read, its tokens if it is a sim;
- *egress*: samples and tokens on what the peer may read; this process's own
  subscription declarations on any fleet key (they only name keys; without
  them the peer would not know where to send what it may publish).

zenoh matches a message when a rule's key expression *includes* the message's
(``nodes_including`` in zenoh's ``authorization.rs``): a wider subscription,
such as a viewer's ``fleet/**`` to a sim, is refused as a whole. The patterns
follow :mod:`gcs.wire.keys`, any fleet name (a fleet is a name; the team's
certificates are what make a team).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from types import MappingProxyType
from typing import Any, Literal

__all__ = ["RIGHTS", "ROLES", "Role", "RoleRights", "access_control"]

Role = Literal["sim", "gcs", "viewer"]
"""A process's part in a team; its certificate's common name."""

ROLES: tuple[Role, ...] = ("sim", "gcs", "viewer")
"""Every role, in the order ``gcs certs`` writes their certificates."""

_FLEET = "fleet/*"
_TO_VEHICLE = f"{_FLEET}/vehicle/*/mavlink/to_vehicle"
_FROM_VEHICLE = f"{_FLEET}/vehicle/*/mavlink/from_vehicle"
_ALIVE = f"{_FLEET}/alive/*"
_CLOCK = f"{_FLEET}/clock"
_CLOCK_ACK = f"{_FLEET}/clock/ack"
_TRUTH = f"{_FLEET}/sim/truth"
_CONTROL = f"{_FLEET}/sim/control"
_EVERYTHING = "fleet/**"


@dataclass(frozen=True)
class RoleRights:
    """Key expressions a role may publish on, read, and declare liveliness tokens on."""

    publishes: tuple[str, ...]
    reads: tuple[str, ...]
    tokens: tuple[str, ...] = ()


RIGHTS: Mapping[Role, RoleRights] = MappingProxyType({
    "sim": RoleRights(publishes=(_FROM_VEHICLE, _CLOCK, _TRUTH),
                      reads=(_TO_VEHICLE, _CLOCK_ACK, _CONTROL), tokens=(_ALIVE,)),
    "gcs": RoleRights(publishes=(_TO_VEHICLE, _CLOCK_ACK, _CONTROL), reads=(_EVERYTHING,)),
    "viewer": RoleRights(publishes=(), reads=(_EVERYTHING,)),
})
"""The team's table (see the module docstring)."""

_WATCH = ["declare_liveliness_subscriber", "liveliness_query"]


def _rules(role: Role, rights: RoleRights) -> list[dict[str, Any]]:
    """The allow rules for a peer of ``role``; empty key lists are left out (zenoh refuses)."""
    wanted: list[tuple[str, list[str], str, tuple[str, ...]]] = [
        ("publishes", ["put", "delete"], "ingress", rights.publishes),
        ("subscribes", ["declare_subscriber"], "ingress", rights.reads),
        ("watches", _WATCH, "ingress", rights.reads),
        ("declares-tokens", ["liveliness_token"], "ingress", rights.tokens),
        ("receives", ["put", "delete"], "egress", rights.reads),
        ("sees-tokens", ["liveliness_token"], "egress", rights.reads),
        ("is-told-of-subscribers", ["declare_subscriber", *_WATCH], "egress", (_EVERYTHING,)),
    ]
    return [{"id": f"{role}-{name}", "messages": messages, "flows": [flow],
             "permission": "allow", "key_exprs": list(exprs)}
            for name, messages, flow, exprs in wanted if exprs]


def access_control(rights: Mapping[Role, RoleRights] = RIGHTS) -> dict[str, Any]:
    """zenoh's ``access_control`` section for the team's roles (default deny)."""
    rules: list[dict[str, Any]] = []
    policies: list[dict[str, Any]] = []
    for role, r in rights.items():
        mine = _rules(role, r)
        rules += mine
        policies.append({"id": role, "rules": [rule["id"] for rule in mine],
                         "subjects": [role]})
    return {"enabled": True, "default_permission": "deny", "rules": rules,
            "subjects": [{"id": role, "cert_common_names": [role]} for role in rights],
            "policies": policies}
