"""Keep numba's on-disk cache honest across files.

``@njit(cache=True)`` recompiles a function when its own file changes, but not
when a function it calls from another file does: after editing, say,
``vehicles/indi.py`` the cached ``sim.physics.run_lockstep`` would keep
running the old INDI. Each kernel package therefore fingerprints the sources
its kernels are compiled from (every module with an ``@njit`` and everything
those import from the scanned packages, constants and NamedTuples included)
and, when the fingerprint differs from the one stored next to the cache,
deletes the package's cache files before anything is compiled. Editing a
module that no kernel reaches (a host, a CLI) leaves the cache alone.
"""

from __future__ import annotations

import ast
import hashlib
import re
from collections.abc import Sequence
from pathlib import Path

__all__ = ["kernel_sources", "refresh_numba_cache"]

_STAMP = "numba-sources.sha256"
_KERNEL = re.compile(r"^@njit", re.MULTILINE)


def kernel_sources(source_dirs: Sequence[Path]) -> list[Path]:
    """Modules in ``source_dirs`` (package directories) that compiled kernels depend on."""
    modules = {f"{d.name}.{p.stem}": p for d in source_dirs for p in d.glob("*.py")}
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
            elif isinstance(node, ast.Import):
                pending.extend(alias.name for alias in node.names if alias.name in modules)
    return sorted(modules[name] for name in needed)


def refresh_numba_cache(package_dir: Path, source_dirs: Sequence[Path]) -> None:
    """Drop ``package_dir``'s numba cache if a kernel source in ``source_dirs`` changed.

    Unwritable cache directories (numba then caches elsewhere) are left alone.
    """
    digest = hashlib.sha256()
    for path in kernel_sources(source_dirs):
        digest.update(f"{path.parent.name}/{path.name}\0".encode())
        digest.update(path.read_bytes())
    fingerprint = digest.hexdigest()
    cache = package_dir / "__pycache__"
    stamp = cache / _STAMP
    try:
        if stamp.read_text(encoding="ascii") == fingerprint:
            return
    except OSError:
        pass
    try:
        for stale in [*cache.glob("*.nbi"), *cache.glob("*.nbc")]:
            stale.unlink(missing_ok=True)
        cache.mkdir(exist_ok=True)
        stamp.write_text(fingerprint, encoding="ascii")
    except OSError:
        return
