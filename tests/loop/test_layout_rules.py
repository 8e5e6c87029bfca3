"""The house rules of gcs/loop that tests/test_layout.py does not check: the loop stays a
set of small units a newcomer can read one at a time (gcs/loop/README.md)."""

from __future__ import annotations

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
PACKAGE = ROOT / "gcs" / "loop"
MAX_MODULE_LINES = 400
MAX_METHODS = 20


def _methods(path: Path) -> list[tuple[str, int]]:
    """Each class of ``path`` with the number of functions defined in its body."""
    tree = ast.parse(path.read_text("utf-8"))
    return [(f"{path.name} {node.name}", sum(isinstance(item, (ast.FunctionDef,
                                                                ast.AsyncFunctionDef))
                                             for item in node.body))
            for node in ast.walk(tree) if isinstance(node, ast.ClassDef)]


def test_no_module_of_the_loop_is_over_400_lines() -> None:
    files = sorted(PACKAGE.glob("*.py"))
    assert len(files) > 10  # the package is where this test expects it
    long = [f"{p.name}: {n} lines" for p in files
            if (n := len(p.read_text("utf-8").splitlines())) > MAX_MODULE_LINES]
    assert not long, "\n".join(long)


def test_no_class_of_the_loop_has_more_than_20_methods() -> None:
    big = [f"{name}: {n} methods" for p in sorted(PACKAGE.glob("*.py"))
           for name, n in _methods(p) if n > MAX_METHODS]
    assert not big, "\n".join(big)


def test_the_method_count_counts_properties_and_setters(tmp_path: Path) -> None:
    src = tmp_path / "m.py"
    src.write_text("class C:\n    @property\n    def a(self) -> int:\n        return 1\n\n"
                   "    @a.setter\n    def a(self, v: int) -> None:\n        pass\n\n"
                   "    def b(self) -> None:\n        def inner() -> None:\n            pass\n")
    assert _methods(src) == [("m.py C", 3)]  # a nested function is not a method


def test_the_tick_runs_its_stages_in_the_order_the_map_gives() -> None:
    """gcs/loop/README.md's table and Runtime.stages name the stages in the same order."""
    from gcs.loop._runtime import Stages

    readme = (PACKAGE / "README.md").read_text("utf-8")
    order = [field for field in Stages.__dataclass_fields__]
    rows = [line.split("|")[2].strip() for line in readme.splitlines()
            if line.startswith("| ") and line.split("|")[1].strip().isdigit()]
    named = {"load_share": "load sharing", "phase": "phase, before the motion"}
    positions = [rows.index(named.get(f, f)) for f in order]
    assert positions == sorted(positions), (order, rows)
