"""The house rules of the code base, checked: public APIs, layering, imports that do no work.

Each package's ``__init__`` states its API (``__all__``); its other modules are
private (``_name.py``) and no other package reaches into them. Packages form
layers without cycles, ``gcs`` never imports ``sim``, the simulated vehicles load
nothing of the GCS's link layer, ``gcs analyze`` and ``gcs report`` load nothing of
the page, and importing any package runs no work (the numba cache check waits for
the first kernel built). The tests mirror the packages (``tests/README.md``). The
loop's modules and classes and the analysis' functions stay small enough to read one
at a time.
"""

from __future__ import annotations

import ast
import importlib
import subprocess
import sys
from pathlib import Path

import pytest

from tests.support.logfiles import ardupilot_log
from tests.support.paths import ROOT, SQUARE

TREES = ("gcs", "vehicles", "sim", "web")


def _packages() -> list[str]:
    return sorted(".".join(p.parent.relative_to(ROOT).parts)
                  for tree in TREES for p in (ROOT / tree).rglob("__init__.py"))


def _modules() -> dict[str, Path]:
    out = {}
    for tree in TREES:
        for p in (ROOT / tree).rglob("*.py"):
            parts = p.relative_to(ROOT).with_suffix("").parts
            out[".".join(parts[:-1] if parts[-1] == "__init__" else parts)] = p
    return out


def _package_of(module: str, modules: dict[str, Path]) -> str:
    """The graph node of a module: its package (a package's ``__init__`` belongs to it); the
    modules beside ``gcs``'s lazy ``__init__`` (the command line) are nodes of their own."""
    if modules[module].name == "__init__.py":
        return module
    package = module.rpartition(".")[0]
    return module if package == "gcs" else package


def _imports(path: Path) -> list[str]:
    """Every module an import statement of ``path`` names (``from a import b`` gives a and
    a.b; relative imports resolved against the file's package)."""
    names = []
    package = ".".join(path.relative_to(ROOT).parent.parts)
    for node in ast.walk(ast.parse(path.read_text("utf-8"))):
        if isinstance(node, ast.Import):
            names += [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = package.rsplit(".", node.level - 1)[0] if node.level > 1 else package
            module = node.module
            if node.level:
                module = f"{base}.{node.module}" if node.module else base
            if module:
                names += [module] + [f"{module}.{a.name}" for a in node.names]
    return names


def _resolve(name: str, modules: dict[str, Path]) -> str | None:
    """The project module ``name`` refers to, or None for an outside or attribute name."""
    return name if name in modules else None


def package_graph() -> dict[str, set[str]]:
    """Package -> the packages its modules import (entry points ``__main__`` left out)."""
    modules = _modules()
    graph: dict[str, set[str]] = {_package_of(m, modules): set() for m in modules}
    for name, path in modules.items():
        if path.stem == "__main__":
            continue  # nothing imports an entry point: it closes no cycle
        here = _package_of(name, modules)
        for imported in _imports(path):
            target = _resolve(imported, modules)
            if target is not None:
                there = _package_of(target, modules)
                if there != here:
                    graph[here].add(there)
    return graph


def find_cycle(graph: dict[str, set[str]]) -> list[str] | None:
    """One cycle of ``graph`` as a path that ends where it starts, or None."""
    state: dict[str, int] = {}
    stack: list[str] = []

    def visit(node: str) -> list[str] | None:
        state[node] = 1
        stack.append(node)
        for nxt in sorted(graph[node]):
            if state.get(nxt) == 1:
                return [*stack[stack.index(nxt):], nxt]
            if nxt not in state and (found := visit(nxt)) is not None:
                return found
        stack.pop()
        state[node] = 2
        return None

    for node in sorted(graph):
        if node not in state and (found := visit(node)) is not None:
            return found
    return None


@pytest.mark.parametrize("package", _packages())
def test_a_package_states_its_public_api(package: str) -> None:
    mod = importlib.import_module(package)
    api = getattr(mod, "__all__", None)
    assert api is not None, f"{package} has no __all__"
    assert mod.__doc__, f"{package} has no docstring"
    for name in api:
        assert hasattr(mod, name), f"{package}.__all__ names {name!r}, which it does not define"
    folder = ROOT / package.replace(".", "/")
    public = sorted(p.stem for p in folder.glob("*.py")
                    if not p.stem.startswith("_") and p.stem != "cli")
    public += sorted(p.parent.name for p in folder.glob("*/__init__.py"))
    missing = [m for m in public if m not in api]
    assert not missing, f"{package}: public modules missing from __all__: {missing}"


def test_no_package_reaches_into_another_packages_private_modules() -> None:
    """Nor do the benches and examples: they use the packages' APIs (tests may reach in)."""
    modules = _modules()
    offences = []
    scripts = {f"{p.parent.name}/{p.name}": p for d in ("bench", "examples")
               for p in (ROOT / d).glob("*.py")}
    for name, path in [*modules.items(), *scripts.items()]:
        here = _package_of(name, modules) if name in modules else name
        for imported in _imports(path):
            target = _resolve(imported, modules)
            if target is None or _package_of(target, modules) == here:
                continue
            if target.rpartition(".")[2].startswith("_") and not target.endswith("__main__"):
                offences.append(f"{name} imports {target}")
    assert not offences, "\n".join(offences)


def test_the_packages_have_no_import_cycle() -> None:
    cycle = find_cycle(package_graph())
    assert cycle is None, "package cycle: " + " -> ".join(cycle or [])


def test_the_cycle_check_finds_a_cycle() -> None:
    graph = package_graph()
    assert find_cycle(graph) is None
    graph["gcs.wire"].add("gcs.link")  # the wire using the link layer, as it once did
    assert find_cycle(graph) is not None


#: The layers of README.md and gcs/README.md: a package imports only lower ones.
LAYERS = {
    "gcs": 0,  # its __init__ imports nothing: gcs.<name> loads a subpackage lazily
    "gcs.common": 0,
    "gcs.wire": 1,
    "gcs.transport": 2, "vehicles": 2,
    "gcs.formation": 3,
    "gcs.config": 4,
    "gcs.guidance": 5, "gcs.analysis": 5, "gcs.link": 5, "sim": 5,
    "gcs.loop": 6,
    "gcs.flightlog": 7,
    "gcs.app": 8,
    "gcs.testing": 9,  # SimTeam flies on gcs.app
    "web": 9,
    "gcs.cli": 10,
}


def test_the_layers_are_as_documented() -> None:
    graph = package_graph()
    assert set(graph) - {"gcs.__main__"} == set(LAYERS), "a package without a layer"
    upward = [f"{a} -> {b}" for a, targets in graph.items() if a in LAYERS
              for b in targets if b != "gcs" and LAYERS[b] >= LAYERS[a]]
    assert not upward, "imports against the layers: " + ", ".join(upward)
    assert not graph["vehicles"] & {"gcs.transport", "gcs.config", "gcs.link"}


def test_the_gcs_never_imports_the_simulator() -> None:
    """README: ``gcs`` starts ``python -m sim`` as a process and never imports ``sim`` (the
    layers alone would let ``gcs.app`` and above)."""
    offences = [f"{name} imports {imported}" for name, path in _modules().items()
                if name.split(".")[0] == "gcs"
                for imported in _imports(path) if imported.split(".")[0] == "sim"]
    assert not offences, "\n".join(offences)


#: The folders of tests/ that are not a package's (tests/README.md): the command line's
#: (gcs/cli.py), the whole system's, the browser's, the fuzzers', the helpers and the data.
SUITE_FOLDERS = {"cli", "integration", "browser", "fuzz", "support", "data"}


def test_the_tests_mirror_the_packages() -> None:
    """Each folder of ``tests/`` is a package's (``tests/wire`` for ``gcs/wire``, ``tests/sim``
    for ``sim``) or one of :data:`SUITE_FOLDERS`, and a package itself (data aside), so
    that its modules import as ``tests.<folder>.<module>``."""
    packages = {p.rpartition(".")[2] for p in _packages() if p != "gcs"}
    folders = {p.name for p in (ROOT / "tests").iterdir()
               if p.is_dir() and not p.name.startswith((".", "__"))}
    strays = sorted(folders - packages - SUITE_FOLDERS)
    assert not strays, f"tests/ folders of no package: {strays}"
    missing = sorted(f for f in folders - {"data"}
                     if not (ROOT / "tests" / f / "__init__.py").is_file())
    assert not missing, f"tests/ folders without __init__.py: {missing}"


def _loaded_after(statement: str) -> set[str]:
    code = f"import sys\n{statement}\nprint(' '.join(sorted(sys.modules)))"
    out = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True,
                         text=True, timeout=120, check=True)
    return set(out.stdout.split())


def test_a_simulated_vehicle_loads_nothing_of_the_gcs_link_layer() -> None:
    loaded = _loaded_after("import vehicles.endpoint")
    gcs = sorted(m for m in loaded if m.split(".")[0] == "gcs")
    assert "gcs.wire" in loaded  # it does speak the wire
    assert not [m for m in gcs if m.split(".")[1:2] not in (["common"], ["wire"], [])], gcs
    assert "pymavlink.mavutil" not in loaded


_IMPORT_PROBE = """
import sys
from gcs.common import _jit_cache
import gcs.common
calls = []
def spy(*args):
    calls.append(args)
_jit_cache.refresh_numba_cache = spy  # whoever calls the cache check at import is seen
gcs.common.refresh_numba_cache = spy
touched = []
def hook(event, args):
    if event in ("os.mkdir", "os.remove", "os.rename", "os.replace", "os.rmdir"):
        touched.append(str(args[0]))
    elif event == "open" and len(args) > 1 and args[1] and any(c in str(args[1]) for c in "wax+"):
        touched.append(str(args[0]))
sys.addaudithook(hook)
import gcs.app, gcs.cli, gcs.flightlog, vehicles, vehicles.endpoint, sim, web
print(len(calls))
print([t for t in touched if t.startswith(sys.argv[1]) and ".pyc" not in t])
print(sorted(_jit_cache._checked))
from gcs.wire import crc_accumulate
crc_accumulate(0, 0xFFFF)
print(sorted(_jit_cache._checked))
"""


def test_importing_the_packages_does_no_work() -> None:
    """No cache check, no file written, moved or removed in the project at import (Python's
    own .pyc files aside); the first kernel built checks its tree's cache."""
    out = subprocess.run([sys.executable, "-c", _IMPORT_PROBE, str(ROOT)], cwd=ROOT,
                         capture_output=True, text=True, timeout=300, check=True)
    calls, touched, before, after = out.stdout.splitlines()
    assert (calls, touched, before) == ("0", "[]", "[]")
    assert after == "['gcs']"


_COMMAND_PROBE = """
import contextlib, io, sys
from gcs.cli import main
with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
    code = main(sys.argv[1:])
print(code)
print(' '.join(sorted(sys.modules)))
"""


@pytest.mark.parametrize("command", ["analyze", "report"])
def test_analyze_and_report_load_nothing_of_the_page(command: str, tmp_path: Path) -> None:
    """README: ``gcs analyze`` and ``gcs report`` load neither viser nor ``web`` (the page's
    server and its libraries: seconds of CPU at start, for a command that serves no page).
    Each runs in a process of its own to the end, on the paper's square and on a small
    recorded log."""
    if command == "analyze":
        args = ["analyze", SQUARE]
    else:
        log = ardupilot_log(tmp_path / "flight.tlog", shared_origin=True, seconds=2.0)
        args = ["report", str(log), "--out", str(tmp_path / "report")]
    out = subprocess.run([sys.executable, "-c", _COMMAND_PROBE, *args], cwd=ROOT,
                         capture_output=True, text=True, timeout=300, check=True)
    code, modules = out.stdout.splitlines()[-2:]
    assert code == "0", out.stdout + out.stderr
    page = sorted({m.split(".")[0] for m in modules.split()} & {"viser", "web"})
    assert not page, f"gcs {command} loaded {' and '.join(page)}"


def test_public_modules_load_on_first_use() -> None:
    """``import web`` does not load the test viewer, nor ``import vehicles`` the endpoint."""
    assert not {"web.wireviewer", "vehicles.endpoint"} & _loaded_after("import web, vehicles")
    assert "web.wireviewer" in _loaded_after("import web\nweb.wireviewer")


def test_the_gcs_and_the_simulator_start_without_the_report_and_fitting_libraries() -> None:
    """Every `gcs fly` and `python -m sim` pays its imports at start (a test suite starts
    hundreds): matplotlib (0.35 s) loads with the first report, scipy.optimize (0.45 s)
    with the first formation given by distances, and scipy.signal (0.6 s) never (the
    autopilots' filters are computed in closed form)."""
    heavy = {"matplotlib", "scipy.optimize", "scipy.signal"}
    started = _loaded_after("import gcs.app, gcs.cli, gcs.flightlog, sim.__main__, web\n"
                            "from vehicles._butterworth import butterworth2\n"
                            "butterworth2(5.0, 512.0)")
    assert not heavy & started
    assert {"matplotlib", "scipy.optimize"} <= _loaded_after(
        "from gcs.formation._graph import realize_positions\nimport numpy as np\n"
        "realize_positions(3, np.array([[0, 1], [1, 2], [2, 0]]), np.ones(3))\n"
        "import gcs.flightlog._report")


# -- small units: the loop's modules and classes, the analysis' functions --------------------

LOOP_MODULE_LINES = 400
"""The longest a module of gcs/loop may be (gcs/loop/README.md: each stage a unit of its own)."""
LOOP_CLASS_METHODS = 20
"""The most functions a class of gcs/loop may define (properties and setters count)."""
ANALYSIS_FUNCTION_LINES = 80
"""The longest a function of gcs/analysis may be, from its ``def`` to its body's last line."""


def _function_lengths(path: Path) -> list[tuple[str, int]]:
    """Each function and method of ``path`` (nested ones too) with its length in lines."""
    tree = ast.parse(path.read_text("utf-8"))
    return [(f"{path.name}:{node.lineno} {node.name}", (node.end_lineno or node.lineno)
             - node.lineno + 1) for node in ast.walk(tree)
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef))]


def _class_methods(path: Path) -> list[tuple[str, int]]:
    """Each class of ``path`` with the number of functions defined in its body."""
    tree = ast.parse(path.read_text("utf-8"))
    return [(f"{path.name} {node.name}",
             sum(isinstance(item, (ast.FunctionDef, ast.AsyncFunctionDef))
                 for item in node.body))
            for node in ast.walk(tree) if isinstance(node, ast.ClassDef)]


def test_no_module_of_the_loop_is_over_400_lines() -> None:
    files = sorted((ROOT / "gcs" / "loop").glob("*.py"))
    assert len(files) > 10  # the package is where this test expects it
    long = [f"{p.name}: {n} lines" for p in files
            if (n := len(p.read_text("utf-8").splitlines())) > LOOP_MODULE_LINES]
    assert not long, "\n".join(long)


def test_no_class_of_the_loop_has_more_than_20_methods() -> None:
    big = [f"{name}: {n} methods" for p in sorted((ROOT / "gcs" / "loop").glob("*.py"))
           for name, n in _class_methods(p) if n > LOOP_CLASS_METHODS]
    assert not big, "\n".join(big)


def test_no_function_of_the_analysis_is_longer_than_80_lines() -> None:
    files = sorted((ROOT / "gcs" / "analysis").glob("*.py"))
    assert len(files) > 5  # the package is where this test expects it
    long = [f"{name}: {n} lines" for path in files for name, n in _function_lengths(path)
            if n > ANALYSIS_FUNCTION_LINES]
    assert not long, "\n".join(long)


def test_the_counts_are_of_lines_from_def_to_the_end_and_of_a_class_own_functions(
        tmp_path: Path) -> None:
    body = "\n".join(f"    x{i} = {i}" for i in range(ANALYSIS_FUNCTION_LINES - 2))
    src = tmp_path / "m.py"
    src.write_text(f'def f() -> None:\n    """Doc."""\n{body}\n    return None\n')
    assert _function_lengths(src) == [("m.py:1 f", ANALYSIS_FUNCTION_LINES + 1)]
    src.write_text("class C:\n    @property\n    def a(self) -> int:\n        return 1\n\n"
                   "    @a.setter\n    def a(self, v: int) -> None:\n        pass\n\n"
                   "    def b(self) -> None:\n        def inner() -> None:\n            pass\n")
    assert _class_methods(src) == [("m.py C", 3)]  # a nested function is not a method


def test_the_tick_runs_its_stages_in_the_order_the_loops_map_gives() -> None:
    """gcs/loop/README.md's table and Runtime.stages name the stages in the same order."""
    from gcs.loop import Stages

    readme = (ROOT / "gcs" / "loop" / "README.md").read_text("utf-8")
    order = list(Stages.__dataclass_fields__)
    rows = [line.split("|")[2].strip() for line in readme.splitlines()
            if line.startswith("| ") and line.split("|")[1].strip().isdigit()]
    named = {"load_share": "load sharing", "phase": "phase, before the motion"}
    positions = [rows.index(named.get(f, f)) for f in order]
    assert positions == sorted(positions), (order, rows)
