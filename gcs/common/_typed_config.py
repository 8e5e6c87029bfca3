"""Typed, validated configuration objects built from YAML.

Every configuration in the project is a frozen dataclass. This module turns a
YAML mapping into such an object, checking types and bounds field by field, so
that a wrong file is refused with one line naming the file, the field and what
is wrong (``ConfigError``) instead of failing later inside a numeric kernel.

A cross-field check in ``__post_init__`` raises :class:`FieldError` to name its
field (any other ``ValueError`` names the section).

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
import re
import stat
import types
import typing
from collections.abc import Mapping
from pathlib import Path
from typing import Any, Literal, TypeVar, get_args, get_origin, get_type_hints

import yaml

from gcs.common._shipped import missing_config_hint

__all__ = ["MAX_FILE_BYTES", "ConfigError", "FieldError", "field", "from_mapping", "load_yaml",
           "to_mapping"]

T = TypeVar("T")

_MISSING = dataclasses.MISSING

_LARGEST_INT = 2**63
"""Integers beyond this are refused as out of range (they do not fit a float's exponent
range or a C integer, and no field means one)."""


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


#: Largest config file read, bytes: a team of 254 vehicles with its links is under 64 KiB,
#: and even libyaml takes seconds over a few MiB of YAML.
MAX_FILE_BYTES = 256 * 1024


class FieldError(ValueError):
    """A cross-field check in a config's ``__post_init__`` that names the field at fault.

    ``from_mapping`` reports it as ``source: <where>.<field>: <what>``, so the field
    is named where every other mistake names it.
    """

    def __init__(self, field_name: str, what: str) -> None:
        self.field = field_name
        self.what = what
        super().__init__(f"{field_name}: {what}")


_EXPONENT_FLOAT = re.compile(r"^[-+]?(?:[0-9][0-9_]*(?:\.[0-9_]*)?|\.[0-9][0-9_]*)[eE][-+]?[0-9]+$")
"""Numbers with an exponent that YAML 1.2 reads as floats and PyYAML's YAML 1.1 resolver as
strings: ``1e9``, ``1.0e9``, ``2E-1`` (YAML 1.1 wants a dot and a signed exponent)."""


_BaseLoader: type = getattr(yaml, "CSafeLoader", yaml.SafeLoader)  # libyaml when available


class _Loader(_BaseLoader):
    """PyYAML's safe loader reading ``1e9`` and ``1.0e9`` as numbers."""


_Loader.add_implicit_resolver("tag:yaml.org,2002:float", _EXPONENT_FLOAT,
                              list("-+0123456789."))


def load_yaml(path: str | Path) -> Any:
    """Read a YAML file; unreadable, malformed or non-text files raise ConfigError.

    Refused in one line naming the file: what is no regular file (a directory, a
    device), more than :data:`MAX_FILE_BYTES`, bytes that are not UTF-8 (UTF-16,
    binary, NUL), YAML errors (with their line), nesting deeper than
    :data:`MAX_FLOW_DEPTH`, an integer too long to read, and a key given twice in
    one mapping (named by its field: YAML keeps the last silently). ``1e9`` and
    ``1.0e9`` are numbers, as in YAML 1.2.
    """
    path = Path(path)
    source = str(path)
    try:
        info = path.stat()
        if stat.S_ISDIR(info.st_mode):
            raise ConfigError(source, "", "is a directory, not a file")
        if not stat.S_ISREG(info.st_mode):
            raise ConfigError(source, "", "is not a regular file")
        if info.st_size > MAX_FILE_BYTES:
            raise ConfigError(source, "", f"file too large ({info.st_size} bytes; a config "
                                          f"is at most {MAX_FILE_BYTES} bytes)")
        data = path.read_bytes()
    except OSError as exc:
        raise ConfigError(source, "", f"cannot read file ({exc.strerror})"
                          f"{missing_config_hint(path)}") from None
    text = _decode(data, source)
    _check_depth(text, source)
    loader = _Loader(text)
    try:
        node = loader.get_single_node()
        if node is None:
            return None
        _check_nodes(node, source)
        return loader.construct_document(node)
    except yaml.reader.ReaderError as exc:
        line = text[:exc.position].count("\n") + 1
        char = exc.character if isinstance(exc.character, int) else ord(exc.character)
        raise ConfigError(source, f"line {line}", f"invalid YAML: character #x{char:04x} "
                          f"({exc.reason})") from None
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f"line {mark.line + 1}" if mark is not None else ""
        problem = getattr(exc, "problem", None) or "malformed YAML"
        raise ConfigError(source, where, f"invalid YAML: {problem}") from None
    except RecursionError:
        raise ConfigError(source, "", "invalid config: nested too deeply") from None
    finally:
        loader.dispose()


#: Deepest nesting read: ``[`` and ``{`` levels, and columns of leading indentation and
#: ``- `` markers. libyaml composes nodes recursively in C and overflows the stack
#: (a segmentation fault) some ten thousand levels down; configs nest a few levels.
MAX_FLOW_DEPTH = 64
MAX_BLOCK_COLUMN = 256

_QUOTED = re.compile(r'"(?:[^"\\\n]|\\.)*"' + r"|'(?:[^'\n]|'')*'")
_COMMENT = re.compile(r"(?:^|[ \t])#.*$", re.MULTILINE)
_LEADING = re.compile(r"[ \t?:-]*")


def _check_depth(text: str, source: str) -> None:
    """ConfigError for YAML nested deeper than a config can mean (see MAX_FLOW_DEPTH)."""
    plain = _COMMENT.sub("", _QUOTED.sub("", text))
    depth = 0
    for line, row in enumerate(plain.split("\n"), 1):
        if row[:1] not in ("", " ", "\t", "]", "}", ","):
            depth = 0  # a line at column 0 is outside any flow collection (or a YAML error)
        for ch in row:
            if ch in "[{":
                depth += 1
                if depth > MAX_FLOW_DEPTH:
                    raise ConfigError(source, f"line {line}", f"invalid config: nested too "
                                      f"deeply (more than {MAX_FLOW_DEPTH} levels of [ or {{)")
            elif ch in "]}":
                depth -= 1
        lead = _LEADING.match(row)
        if lead is not None and len(lead.group()) > MAX_BLOCK_COLUMN:
            raise ConfigError(source, f"line {line}", f"invalid config: nested too deeply "
                              f"(indented beyond column {MAX_BLOCK_COLUMN})")


def _decode(data: bytes, source: str) -> str:
    """UTF-8 text of a file (a BOM allowed); ConfigError naming the file otherwise."""
    head = data[:512]
    wide = head[:2] in (b"\xff\xfe", b"\xfe\xff") or (
        len(head) >= 4 and max(head[0::2].count(0), head[1::2].count(0)) >= len(head) // 4
        and min(head[0::2].count(0), head[1::2].count(0)) == 0)
    if wide:
        raise ConfigError(source, "", "the file is UTF-16 (or UTF-32) text, not UTF-8: "
                                      "save it as UTF-8")
    nul = data.find(b"\x00")
    if nul >= 0:
        line = data[:nul].count(b"\n") + 1
        raise ConfigError(source, f"line {line}",
                          f"not a text file (a NUL byte at offset {nul}): a config is a "
                          f"UTF-8 YAML file")
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        line = data[:exc.start].count(b"\n") + 1
        raise ConfigError(source, f"line {line}", f"not UTF-8 text (byte 0x{data[exc.start]:02x} "
                          f"at offset {exc.start}): a config is a UTF-8 YAML file") from None


def _check_nodes(root: yaml.Node, source: str) -> None:
    """ConfigError naming the field of a key given twice in one mapping, or of an integer
    too long to read (Python refuses more than 4300 digits with a ValueError)."""
    seen: set[int] = set()
    todo: list[tuple[yaml.Node, str]] = [(root, "")]
    while todo:
        node, where = todo.pop()
        if id(node) in seen:  # an alias: walked once
            continue
        seen.add(id(node))
        if isinstance(node, yaml.MappingNode):
            keys: dict[str, int] = {}
            for key_node, value_node in node.value:
                key = str(key_node.value) if isinstance(key_node, yaml.ScalarNode) else "?"
                sub = _join(where, key)
                if isinstance(key_node, yaml.ScalarNode) and key in keys:
                    raise ConfigError(source, sub, f"given twice (lines {keys[key]} and "
                                      f"{key_node.start_mark.line + 1}): YAML would keep "
                                      f"the last silently")
                keys[key] = key_node.start_mark.line + 1
                todo.append((value_node, sub))
        elif isinstance(node, yaml.SequenceNode):
            todo += [(item, f"{where}[{i}]") for i, item in enumerate(node.value)]
        elif node.tag == "tag:yaml.org,2002:int" and len(str(node.value)) > 40:
            raise ConfigError(source, where or f"line {node.start_mark.line + 1}",
                              f"out of range: an integer of {len(str(node.value))} digits")


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
    except FieldError as exc:  # a __post_init__ check that names its field
        raise ConfigError(source, _join(where, exc.field), exc.what) from None
    except (ValueError, TypeError) as exc:  # __post_init__ cross-field checks
        raise ConfigError(source, where, str(exc)) from None


def to_mapping(value: Any) -> Any:
    """The plain form of a config object (mappings, lists, numbers, strings, None): what
    :func:`from_mapping` builds the same object back from. Why: a config changed in
    memory reaches another process (the simulator) as it is, not as its file says."""
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return {f.name: to_mapping(getattr(value, f.name)) for f in dataclasses.fields(value)}
    if isinstance(value, tuple | list):
        return [to_mapping(v) for v in value]
    if isinstance(value, Mapping):
        return {k: to_mapping(v) for k, v in value.items()}
    return value


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
        if isinstance(value, int) and abs(value) > _LARGEST_INT:
            raise ConfigError(source, where, "out of range: an integer beyond 2^63")
        if not math.isfinite(value):
            raise ConfigError(source, where, f"must be finite, got {value}")
        return float(value)
    if tp is int:
        if isinstance(value, bool) or not isinstance(value, int):
            raise ConfigError(source, where, f"expected an integer, got {_kind(value)}")
        if abs(value) > _LARGEST_INT:
            raise ConfigError(source, where, "out of range: an integer beyond 2^63")
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
    items = ([(v, f"{where}[{i}]") for i, v in enumerate(value)] if isinstance(value, tuple)
             else [(value, where)])
    least = meta.get("min_len")
    if least is not None and isinstance(value, tuple) and len(value) < least:
        raise ConfigError(source, where, f"needs at least {least} entries, got {len(value)}")
    for v, at in items:
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
                raise ConfigError(source, at, f"must be {text} {bound:g}, got {v:g}")
