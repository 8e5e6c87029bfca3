"""Typed, validated configuration objects built from YAML.

Every configuration in the project is a frozen dataclass. This module turns a
YAML mapping into such an object, checking types and bounds field by field, so
that a wrong file is refused with one line naming the file, the field and what
is wrong (``ConfigError``) instead of failing later inside a numeric kernel.

Bounds and units live in the dataclass fields' metadata, written with
:func:`field`::

    @dataclass(frozen=True)
    class Payload:
        mass: float = field(doc="payload mass, kg", gt=0.0)

A field without ``default`` is required: a file that leaves it out is refused
(``missing required field``). Physical figures and gains get no default, so a
forgotten one can never be silently replaced by another vehicle's or the
paper's value; defaults are for engineering choices only.
"""

from __future__ import annotations

import dataclasses
import math
import types
import typing
from collections.abc import Mapping
from pathlib import Path
from typing import Any, Literal, TypeVar, get_args, get_origin, get_type_hints

import yaml

from gcs.common._shipped import missing_config_hint

__all__ = ["ConfigError", "field", "from_mapping", "load_yaml"]

T = TypeVar("T")

_MISSING = dataclasses.MISSING


class ConfigError(ValueError):
    """A configuration that cannot be used; ``str()`` is one line: ``source: where: what``."""

    def __init__(self, source: str, where: str, what: str) -> None:
        self.source = source
        self.where = where
        self.what = what
        super().__init__(f"{source}: {where}: {what}" if where else f"{source}: {what}")


def field(
    *,
    doc: str = "",
    default: Any = _MISSING,
    default_factory: Any = _MISSING,
    gt: float | None = None,
    ge: float | None = None,
    lt: float | None = None,
    le: float | None = None,
    min_len: int | None = None,
) -> Any:
    """A dataclass field with a documented meaning/unit and numeric bounds checked on load."""
    meta = {"doc": doc, "gt": gt, "ge": ge, "lt": lt, "le": le, "min_len": min_len}
    if default_factory is not _MISSING:
        return dataclasses.field(default_factory=default_factory, metadata=meta)
    return dataclasses.field(default=default, metadata=meta)


def load_yaml(path: str | Path) -> Any:
    """Read a YAML file; unreadable or malformed files raise ConfigError."""
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as exc:
        raise ConfigError(str(path), "", f"cannot read file ({exc.strerror})"
                          f"{missing_config_hint(path)}") from None
    try:
        return yaml.safe_load(text)
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f"line {mark.line + 1}" if mark is not None else ""
        problem = getattr(exc, "problem", None) or "malformed YAML"
        raise ConfigError(str(path), where, f"invalid YAML: {problem}") from None


def from_mapping(cls: type[T], data: Any, source: str, where: str = "") -> T:
    """Build dataclass ``cls`` from a mapping, checking every field.

    Unknown keys are refused (a typo must not silently fall back to a default).
    """
    if not isinstance(data, Mapping):
        raise ConfigError(source, where, f"expected a mapping, got {_kind(data)}")
    hints = get_type_hints(cls)
    fields = {f.name: f for f in dataclasses.fields(cls)}  # type: ignore[arg-type]
    unknown = [k for k in data if k not in fields]
    if unknown:
        known = ", ".join(sorted(fields))
        raise ConfigError(source, _join(where, str(unknown[0])), f"unknown field (known: {known})")
    kwargs: dict[str, Any] = {}
    for name, f in fields.items():
        sub = _join(where, name)
        if name not in data:
            if f.default is _MISSING and f.default_factory is _MISSING:
                raise ConfigError(source, sub, "missing required field")
            continue
        value = _convert(hints[name], data[name], source, sub)
        _check_bounds(f.metadata, value, source, sub)
        kwargs[name] = value
    try:
        return cls(**kwargs)
    except ConfigError:
        raise
    except (ValueError, TypeError) as exc:  # __post_init__ cross-field checks
        raise ConfigError(source, where, str(exc)) from None


def _join(where: str, name: str) -> str:
    if name.startswith("["):
        return f"{where}{name}"
    return f"{where}.{name}" if where else name


def _kind(value: Any) -> str:
    if value is None:
        return "nothing (null)"
    return {bool: "a boolean", int: "an integer", float: "a number", str: "a string",
            list: "a list", dict: "a mapping"}.get(type(value), type(value).__name__)


def _convert(tp: Any, value: Any, source: str, where: str) -> Any:
    origin = get_origin(tp)
    args = get_args(tp)
    if origin in (typing.Union, types.UnionType):
        if value is None and type(None) in args:
            return None
        inner = [a for a in args if a is not type(None)]
        return _convert(inner[0], value, source, where)
    if origin is Literal:
        if value not in args:
            allowed = ", ".join(repr(a) for a in args)
            raise ConfigError(source, where, f"must be one of {allowed}, got {value!r}")
        return value
    if origin is tuple:
        if not isinstance(value, list | tuple):
            raise ConfigError(source, where, f"expected a list, got {_kind(value)}")
        if len(args) == 2 and args[1] is Ellipsis:
            return tuple(
                _convert(args[0], v, source, f"{where}[{i}]") for i, v in enumerate(value)
            )
        if len(value) != len(args):
            raise ConfigError(source, where, f"expected {len(args)} values, got {len(value)}")
        return tuple(_convert(a, v, source, f"{where}[{i}]") for i, (a, v) in
                     enumerate(zip(args, value, strict=True)))
    if origin is dict:
        if not isinstance(value, Mapping):
            raise ConfigError(source, where, f"expected a mapping, got {_kind(value)}")
        return {_convert(args[0], k, source, where): _convert(args[1], v, source, f"{where}.{k}")
                for k, v in value.items()}
    if isinstance(tp, type) and dataclasses.is_dataclass(tp):
        if isinstance(value, tp):  # already built and validated (e.g. from its own file)
            return value
        return from_mapping(tp, value, source, where)
    if tp is float:
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise ConfigError(source, where, f"expected a number, got {_kind(value)}")
        if not math.isfinite(value):
            raise ConfigError(source, where, f"must be finite, got {value}")
        return float(value)
    if tp is int:
        if isinstance(value, bool) or not isinstance(value, int):
            raise ConfigError(source, where, f"expected an integer, got {_kind(value)}")
        return value
    if tp is bool:
        if not isinstance(value, bool):
            raise ConfigError(source, where, f"expected true or false, got {_kind(value)}")
        return value
    if tp is str:
        if not isinstance(value, str):
            raise ConfigError(source, where, f"expected a string, got {_kind(value)}")
        return value
    raise TypeError(f"typed_config cannot convert to {tp!r} at {where}")  # programming error


def _check_bounds(meta: Mapping[str, Any], value: Any, source: str, where: str) -> None:
    if value is None:
        return
    items = value if isinstance(value, tuple) else (value,)
    least = meta.get("min_len")
    if least is not None and isinstance(value, tuple) and len(value) < least:
        raise ConfigError(source, where, f"needs at least {least} entries, got {len(value)}")
    for v in items:
        if not isinstance(v, int | float) or isinstance(v, bool):
            continue
        for key, ok, text in (
            ("gt", lambda a, b: a > b, "greater than"),
            ("ge", lambda a, b: a >= b, "at least"),
            ("lt", lambda a, b: a < b, "less than"),
            ("le", lambda a, b: a <= b, "at most"),
        ):
            bound = meta.get(key)
            if bound is not None and not ok(v, bound):
                raise ConfigError(source, where, f"must be {text} {bound:g}, got {v:g}")
