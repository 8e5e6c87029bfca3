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
import importlib.util
import os
import re
import threading
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

from numba import njit
from numba.core.caching import FunctionCache

__all__ = ["kernel", "kernel_sources", "refresh_numba_cache"]

_STAMP = "numba-sources.sha256"
_STAT_STAMP = "numba-sources.stat"
_SETTLED_S = 2.0
"""A file modified more recently than this is not trusted by its stat alone: an edit
within the file system's time-stamp tick could leave size and time unchanged."""
_KERNEL = re.compile(r"^\s*@(?:\w+\.)*kernel\(", re.MULTILINE)

#: The project's package trees: a kernel may compile in constants and functions from any.
_TREES = ("gcs", "vehicles", "sim")

_checked: set[str] = set()
_lock = threading.Lock()


def _module_files(roots: Sequence[Path]) -> dict[str, Path]:
    """Dotted module name -> file, for every module under the package trees ``roots``."""
    modules: dict[str, Path] = {}
    for d in roots:
        for p in d.rglob("*.py"):
            parts = p.relative_to(d.parent).with_suffix("").parts
            modules[".".join(parts[:-1] if parts[-1] == "__init__" else parts)] = p
    return modules


def _reexports(init: Path) -> dict[str, str]:
    """Name -> defining module, for the names a package's ``__init__`` imports."""
    found: dict[str, str] = {}
    for node in ast.parse(init.read_text("utf-8")).body:
        if isinstance(node, ast.ImportFrom) and node.module and not node.level:
            for alias in node.names:
                found[alias.asname or alias.name] = node.module
    return found


def _imported(node: ast.ImportFrom, modules: dict[str, Path]) -> list[str]:
    """The project modules a ``from M import a, b`` reads: each name's defining module.

    A name a package re-exports leads to the module defining it, not to the
    whole package, so one re-exported constant does not tie a kernel to every
    module of that package.
    """
    base = node.module or ""
    if base not in modules:
        return []
    if modules[base].name != "__init__.py":
        return [base]
    exports = _reexports(modules[base])
    out = []
    for alias in node.names:
        sub = f"{base}.{alias.name}"
        if sub in modules:
            out.append(sub)
        elif exports.get(alias.name) in modules:
            out.append(exports[alias.name])
        else:
            out.append(base)
    return out


def kernel_sources(tree: Path, roots: Sequence[Path]) -> list[Path]:
    """Modules a kernel of ``tree`` may be compiled from: every module of the tree with a
    ``@kernel`` and everything those import, followed into all the package trees ``roots``.
    """
    modules = _module_files([tree, *roots])
    pending = [name for name, path in modules.items()
               if path.is_relative_to(tree) and _KERNEL.search(path.read_text("utf-8"))]
    needed: set[str] = set()
    while pending:
        name = pending.pop()
        if name in needed:
            continue
        needed.add(name)
        for node in ast.walk(ast.parse(modules[name].read_text("utf-8"))):
            if isinstance(node, ast.ImportFrom) and not node.level:
                pending.extend(_imported(node, modules))
            elif isinstance(node, ast.Import):
                pending.extend(alias.name for alias in node.names if alias.name in modules)
    return sorted(modules[name] for name in needed)


def refresh_numba_cache(tree: Path, roots: Sequence[Path]) -> None:
    """Drop the numba cache under ``tree`` if a source its kernels are built from changed.

    The cache files of every ``__pycache__`` in the tree go; the fingerprint is
    kept in the tree's top ``__pycache__``. Unwritable cache directories (numba
    then caches elsewhere) are left alone. Where no module file of the trees was
    touched since the last check (the same sizes and times, none of them recent),
    the sources are not read again.
    """
    quick = tree / "__pycache__" / _STAT_STAMP
    seen, newest = _stat_key([tree, *roots])
    try:
        if quick.read_text(encoding="ascii") == seen \
                and (tree / "__pycache__" / _STAMP).is_file():
            return  # no source file touched since the last full check
    except OSError:
        pass
    if _fingerprint_check(tree, roots) and time.time() - newest > _SETTLED_S:
        try:  # atomically: another process may be reading it
            tmp = quick.with_suffix(f".{os.getpid()}.tmp")
            tmp.write_text(seen, encoding="ascii")
            os.replace(tmp, quick)
        except OSError:
            pass


def _stat_key(roots: Sequence[Path]) -> tuple[str, float]:
    """A digest of every module file's path, size and times under the package trees
    ``roots``, and the newest modification time among them (s since the epoch). Reading
    them costs a stat each; parsing them for :func:`kernel_sources`, about 0.3 s a
    process."""
    digest = hashlib.sha256()
    newest = 0.0
    for name, path in sorted(_module_files(roots).items()):
        st = path.stat()
        digest.update(f"{name}\0{path}\0{st.st_size}\0{st.st_mtime_ns}\0{st.st_ctime_ns}"
                      f"\0{st.st_ino}\n".encode())
        newest = max(newest, st.st_mtime, st.st_ctime)
    return digest.hexdigest(), newest


def _fingerprint_check(tree: Path, roots: Sequence[Path]) -> bool:
    """The full check of :func:`refresh_numba_cache`; False where the cache directory
    could not be written."""
    digest = hashlib.sha256()
    for path in kernel_sources(tree, roots):
        digest.update(f"{path.relative_to(path.parents[1])}\0".encode())
        digest.update(path.read_bytes())
    fingerprint = digest.hexdigest()
    stamp = tree / "__pycache__" / _STAMP
    try:
        if stamp.read_text(encoding="ascii") == fingerprint:
            return True
    except OSError:
        pass
    try:
        for cache in tree.rglob("__pycache__"):
            for stale in [*cache.glob("*.nbi"), *cache.glob("*.nbc")]:
                stale.unlink(missing_ok=True)
        stamp.parent.mkdir(exist_ok=True)
        stamp.write_text(fingerprint, encoding="ascii")
    except OSError:
        return False
    return True


def _tree_dir(name: str) -> Path | None:
    """Where the package tree ``name`` is installed (found, not imported)."""
    spec = importlib.util.find_spec(name)
    return Path(spec.origin).parent if spec is not None and spec.origin else None


def _check_tree(module: str) -> None:
    """Refresh the cache of ``module``'s tree, once per process."""
    tree = module.partition(".")[0]
    with _lock:
        if tree in _checked or tree not in _TREES:
            return
        _checked.add(tree)
        roots = [d for d in map(_tree_dir, _TREES) if d is not None]
        here = _tree_dir(tree)
        if here is not None:
            refresh_numba_cache(here, roots)


class _CheckedCache:
    """numba's per-function disk cache, made at first use, after its tree's check.

    numba makes a dispatcher's cache when the function is decorated, which
    probes the cache directory; this one waits for the first build.
    """

    def __init__(self, py_func: Callable[..., Any]) -> None:
        self._py_func = py_func
        self._cache: FunctionCache | None = None

    def _real(self) -> FunctionCache:
        if self._cache is None:
            _check_tree(self._py_func.__module__)
            self._cache = FunctionCache(self._py_func)
        return self._cache

    def load_overload(self, sig: Any, target_context: Any) -> Any:
        return self._real().load_overload(sig, target_context)

    def save_overload(self, sig: Any, data: Any) -> None:
        self._real().save_overload(sig, data)

    def __getattr__(self, name: str) -> Any:  # cache_path, enable, disable, flush
        return getattr(self._real(), name)


def kernel(*, nogil: bool = False) -> Callable[[Callable[..., Any]], Any]:
    """``numba.njit(cache=True)`` whose cache is checked against its sources at first build."""

    def build(fn: Callable[..., Any]) -> Any:
        dispatcher: Any = njit(nogil=nogil)(fn)
        dispatcher._cache = _CheckedCache(fn)  # what njit(cache=True) sets, made lazily
        return dispatcher

    return build
