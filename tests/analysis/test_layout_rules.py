"""The house rules of gcs/analysis that tests/test_layout.py does not check: no function
longer than a screen, so that each reads as one idea."""

from __future__ import annotations

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
PACKAGE = ROOT / "gcs" / "analysis"
MAX_LINES = 80
"""The longest a function or method may be, from its ``def`` line to the last line of its
body (docstring included)."""


def _lengths(path: Path) -> list[tuple[str, int]]:
    """Each function and method of ``path`` (nested ones too) with its length in lines."""
    tree = ast.parse(path.read_text("utf-8"))
    return [(f"{path.name}:{node.lineno} {node.name}", (node.end_lineno or node.lineno)
             - node.lineno + 1) for node in ast.walk(tree)
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef))]


def test_no_function_in_the_analysis_is_longer_than_80_lines() -> None:
    files = sorted(PACKAGE.glob("*.py"))
    assert len(files) > 5  # the package is where this test expects it
    long = [f"{name}: {n} lines" for path in files for name, n in _lengths(path)
            if n > MAX_LINES]
    assert not long, "\n".join(long)


def test_the_length_check_counts_from_def_to_the_last_line(tmp_path: Path) -> None:
    body = "\n".join(f"    x{i} = {i}" for i in range(MAX_LINES - 2))
    src = tmp_path / "m.py"
    src.write_text(f'def f() -> None:\n    """Doc."""\n{body}\n    return None\n')
    [(name, n)] = _lengths(src)
    assert name == "m.py:1 f"
    assert n == MAX_LINES + 1
