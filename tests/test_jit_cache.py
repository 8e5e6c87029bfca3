"""The numba cache check: a change to any source a kernel is built from drops the tree's cache."""

from __future__ import annotations

from pathlib import Path

from gcs.common import kernel_sources, refresh_numba_cache


def _tree(tmp_path: Path) -> Path:
    root = tmp_path / "pkgx"
    (root / "sub").mkdir(parents=True)
    (root / "__init__.py").write_text('"""A tree."""\n')
    (root / "sub" / "__init__.py").write_text('"""A subpackage."""\n')
    (root / "sub" / "_helper.py").write_text("GAIN = 2.0\n")
    (root / "sub" / "_unused.py").write_text("OTHER = 1.0\n")
    (root / "_kernels.py").write_text(
        "from gcs.common import kernel\nfrom pkgx.sub import _helper\n\n"
        "@kernel()\ndef double(x):\n    return _helper.GAIN * x\n")
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


def test_kernel_sources_follow_imports_across_subpackages(tmp_path: Path) -> None:
    root = _tree(tmp_path)
    names = [p.relative_to(tmp_path).as_posix() for p in kernel_sources([root])]
    assert names == ["pkgx/_kernels.py", "pkgx/sub/__init__.py", "pkgx/sub/_helper.py"]


def test_a_changed_source_drops_the_cache_of_the_whole_tree(tmp_path: Path) -> None:
    root = _tree(tmp_path)
    refresh_numba_cache(root, [root])
    files = _stale_files(root)
    refresh_numba_cache(root, [root])
    assert all(f.exists() for f in files)  # nothing changed: the cache stays
    (root / "host.py").write_text("# edited, no kernel reaches it\n")
    (root / "sub" / "_unused.py").write_text("OTHER = 3.0\n")
    refresh_numba_cache(root, [root])
    assert all(f.exists() for f in files)
    (root / "sub" / "_helper.py").write_text("GAIN = 3.0\n")  # a kernel's constant
    refresh_numba_cache(root, [root])
    assert not any(f.exists() for f in files)
