"""Compiled kernels whose numba disk cache stays honest across files.

``@njit(cache=True)`` recompiles a function when its own file changes, but not
when a function it calls from another file does: after editing, say,
``vehicles/_indi.py`` the cached ``sim._physics.run_lockstep`` would keep
running the old INDI. :func:`kernel` is ``njit(cache=True)`` with one step
more: the first time any kernel of a package tree is compiled or loaded from
the cache in a process, the tree fingerprints the sources its kernels are
compiled from (every module with a ``@kernel`` and everything those import from
the scanned trees, constants and NamedTuples included) and, when the
fingerprint differs from the one stored beside the cache, deletes the tree's
cache files first. Editing a module that no kernel reaches (a host, a CLI)
leaves the cache alone, and importing a module does no work at all: the check
runs where a kernel is first built.
"""

from __future__ import annotations

import ast
import hashlib
import re
import threading
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

from numba import njit
from numba.core.caching import FunctionCache

__all__ = ["kernel", "kernel_sources", "refresh_numba_cache"]

_STAMP = "numba-sources.sha256"
_KERNEL = re.compile(r"^@kernel\b", re.MULTILINE)
_ROOT = Path(__file__).resolve().parents[2]

#: Which trees' sources key each tree's cache: the sim's kernels inline the autopilot's.
_SOURCES = {"gcs": ("gcs",), "vehicles": ("vehicles",), "sim": ("sim", "vehicles")}

_checked: set[str] = set()
_lock = threading.Lock()


def kernel_sources(source_dirs: Sequence[Path]) -> list[Path]:
    """Modules under ``source_dirs`` (package trees) that compiled kernels depend on."""
    modules: dict[str, Path] = {}
    for d in source_dirs:
        for p in d.rglob("*.py"):
            parts = p.relative_to(d.parent).with_suffix("").parts
            modules[".".join(parts[:-1] if parts[-1] == "__init__" else parts)] = p
    pending = [name for name, path in modules.items()
               if _KERNEL.search(path.read_text("utf-8"))]
    needed: set[str] = set()
    while pending:
        name = pending.pop()
        if name in needed:
            continue
        needed.add(name)
        for node in ast.walk(ast.parse(modules[name].read_text("utf-8"))):
            if isinstance(node, ast.ImportFrom) and node.module in modules:
                pending.append(node.module)
                pending.extend(f"{node.module}.{a.name}" for a in node.names
                               if f"{node.module}.{a.name}" in modules)
            elif isinstance(node, ast.Import):
                pending.extend(alias.name for alias in node.names if alias.name in modules)
    return sorted(modules[name] for name in needed)


def refresh_numba_cache(package_dir: Path, source_dirs: Sequence[Path]) -> None:
    """Drop the numba cache under ``package_dir`` if a kernel source in ``source_dirs`` changed.

    The cache files of every ``__pycache__`` in the tree go; the fingerprint is
    kept in the tree's top ``__pycache__``. Unwritable cache directories (numba
    then caches elsewhere) are left alone.
    """
    digest = hashlib.sha256()
    for path in kernel_sources(source_dirs):
        digest.update(f"{path.relative_to(path.parents[1])}\0".encode())
        digest.update(path.read_bytes())
    fingerprint = digest.hexdigest()
    stamp = package_dir / "__pycache__" / _STAMP
    try:
        if stamp.read_text(encoding="ascii") == fingerprint:
            return
    except OSError:
        pass
    try:
        for cache in package_dir.rglob("__pycache__"):
            for stale in [*cache.glob("*.nbi"), *cache.glob("*.nbc")]:
                stale.unlink(missing_ok=True)
        stamp.parent.mkdir(exist_ok=True)
        stamp.write_text(fingerprint, encoding="ascii")
    except OSError:
        return


def _check_tree(module: str) -> None:
    """Refresh the cache of ``module``'s tree, once per process."""
    tree = module.partition(".")[0]
    with _lock:
        if tree in _checked or tree not in _SOURCES:
            return
        _checked.add(tree)
        refresh_numba_cache(_ROOT / tree, [_ROOT / d for d in _SOURCES[tree]])


class _CheckedCache(FunctionCache):
    """numba's per-function disk cache, checked against the sources before its first use."""

    def __init__(self, py_func: Callable[..., Any]) -> None:
        self._module = py_func.__module__
        super().__init__(py_func)

    def load_overload(self, sig: Any, target_context: Any) -> Any:
        _check_tree(self._module)
        return super().load_overload(sig, target_context)


def kernel(*, nogil: bool = False) -> Callable[[Callable[..., Any]], Any]:
    """``numba.njit(cache=True)`` whose cache is checked against its sources at first build."""

    def build(fn: Callable[..., Any]) -> Any:
        dispatcher: Any = njit(cache=True, nogil=nogil)(fn)
        dispatcher._cache = _CheckedCache(fn)  # what enable_caching() sets, checked first
        return dispatcher

    return build
