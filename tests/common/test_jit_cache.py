"""The numba cache check: a change to any source a kernel is built from drops the tree's cache."""

from __future__ import annotations

import os
from pathlib import Path

from gcs.common import _jit_cache
from gcs.common._jit_cache import kernel_sources, refresh_numba_cache
from tests.support.paths import ROOT

TREES = [ROOT / "gcs", ROOT / "vehicles", ROOT / "sim"]


def _tree(tmp_path: Path) -> Path:
    root = tmp_path / "pkgx"
    (root / "sub").mkdir(parents=True)
    (root / "__init__.py").write_text('"""A tree."""\n')
    (root / "sub" / "__init__.py").write_text(
        '"""A subpackage re-exporting its modules."""\n\n'
        "from pkgx.sub._gain import GAIN\nfrom pkgx.sub._other import OTHER\n")
    (root / "sub" / "_gain.py").write_text("GAIN = 2.0\n")
    (root / "sub" / "_other.py").write_text("OTHER = 1.0\n")
    (root / "_helper.py").write_text("from pkgx.sub import GAIN\n\nSCALE = GAIN\n")
    (root / "_kernels.py").write_text(
        "from gcs.common import kernel\nfrom pkgx import _helper\n\n"
        "@kernel()\ndef double(x):\n    return _helper.SCALE * x\n")
    (root / "host.py").write_text("from pkgx import _kernels\n")  # imports a kernel, is none
    return root


def _stale_files(root: Path) -> list[Path]:
    files = []
    for cache in (root / "__pycache__", root / "sub" / "__pycache__"):
        cache.mkdir(exist_ok=True)
        files += [cache / "_kernels.double-5.py311.nbi", cache / "_kernels.double-5.py311.1.nbc"]
    for f in files:
        f.write_bytes(b"old")
    return files


def test_kernel_sources_follow_imports_to_the_defining_module(tmp_path: Path) -> None:
    root = _tree(tmp_path)
    names = [p.relative_to(tmp_path).as_posix() for p in kernel_sources(root, [root])]
    assert names == ["pkgx/_helper.py", "pkgx/_kernels.py", "pkgx/sub/_gain.py"]


def test_a_changed_source_drops_the_cache_of_the_whole_tree(tmp_path: Path) -> None:
    root = _tree(tmp_path)
    refresh_numba_cache(root, [root])
    files = _stale_files(root)
    refresh_numba_cache(root, [root])
    assert all(f.exists() for f in files)  # nothing changed: the cache stays
    (root / "host.py").write_text("# edited, no kernel reaches it\n")
    (root / "sub" / "_other.py").write_text("OTHER = 3.0\n")  # re-exported beside GAIN
    refresh_numba_cache(root, [root])
    assert all(f.exists() for f in files)
    (root / "sub" / "_gain.py").write_text("GAIN = 3.0\n")  # a constant a kernel bakes in
    refresh_numba_cache(root, [root])
    assert not any(f.exists() for f in files)


def test_the_project_trees_fingerprint_what_their_kernels_compile_in() -> None:
    """The autopilot's kernels bake in the wire's mode and setpoint numbers; the sim's inline
    the autopilot's. A module imported by a kernel's module counts even when no kernel uses
    it (the fleet table's profile types); a package's other modules do not."""
    def sources(tree: str) -> set[str]:
        return {p.relative_to(ROOT).as_posix() for p in kernel_sources(ROOT / tree, TREES)}

    vehicles, sim, gcs = sources("vehicles"), sources("sim"), sources("gcs")
    wire = {"gcs/wire/_modes.py", "gcs/wire/_setpoints.py"}
    assert wire <= vehicles and wire <= sim
    assert "vehicles/_indi.py" in sim and "vehicles/_kernel.py" in sim
    assert "gcs/guidance/_udi.py" in gcs and "gcs/wire/_stamp.py" in gcs
    assert not [p for p in vehicles | sim if p.startswith(("gcs/link/", "gcs/loop/"))]
    assert "gcs/link/_manager.py" not in gcs and "gcs/loop/_runtime.py" not in gcs


def test_an_untouched_tree_is_not_read_again_and_an_edit_is(tmp_path: Path,
                                                             monkeypatch) -> None:  # type: ignore[no-untyped-def]
    """The full check parses every source (about 0.3 s in each simulator and GCS process);
    with no module file touched since, a stat of each is enough."""
    root = _tree(tmp_path)
    monkeypatch.setattr(_jit_cache, "_SETTLED_S", 0.0)  # as if written long ago
    refresh_numba_cache(root, [root])
    files = _stale_files(root)
    read = []
    real = _jit_cache.kernel_sources
    monkeypatch.setattr(_jit_cache, "kernel_sources",
                        lambda *a: read.append(1) or real(*a))  # type: ignore[func-returns-value]
    refresh_numba_cache(root, [root])
    assert read == [] and all(f.exists() for f in files)
    # an edit of the same size, its time set back to the old one: the inode's change
    # time still tells
    gain = root / "sub" / "_gain.py"
    before = gain.stat()
    gain.write_text("GAIN = 3.0\n")
    os.utime(gain, ns=(before.st_atime_ns, before.st_mtime_ns))
    refresh_numba_cache(root, [root])
    assert read == [1] and not any(f.exists() for f in files)


def test_a_tree_edited_just_now_is_read_on_every_check(tmp_path: Path,
                                                        monkeypatch) -> None:  # type: ignore[no-untyped-def]
    root = _tree(tmp_path)  # written this instant: its stat cannot be trusted yet
    read = []
    real = _jit_cache.kernel_sources
    monkeypatch.setattr(_jit_cache, "kernel_sources",
                        lambda *a: read.append(1) or real(*a))  # type: ignore[func-returns-value]
    refresh_numba_cache(root, [root])
    refresh_numba_cache(root, [root])
    assert read == [1, 1]
