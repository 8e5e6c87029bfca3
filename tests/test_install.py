"""A wheel install, outside any checkout, finds the configs it ships.

The simulator reads its airframe and world from them and ``gcs demo`` its
default team and gamepad mapping; an installed package run from another
directory used to find none of them (they were read from beside the sources).
The test builds the project's wheel, installs it alone into a fresh venv that
borrows the dependencies of this one, and runs it from an empty directory.
"""

from __future__ import annotations

import os
import shutil
import site
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SHIPPED = Path("share") / "formation-gcs" / "configs"


def run(cmd: list[str], cwd: Path, timeout: float = 180) -> subprocess.CompletedProcess[str]:
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "VIRTUAL_ENV")}
    return subprocess.run(cmd, cwd=cwd, env=env, capture_output=True, text=True,
                          timeout=timeout, check=False)


@pytest.fixture(scope="module")
def installed(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path]:
    """(venv, an empty working directory) with the project's wheel installed in the venv."""
    base = tmp_path_factory.mktemp("install")
    source, wheels, venv, work = (base / d for d in ("source", "wheels", "venv", "work"))
    work.mkdir()
    # built from a copy: setuptools writes build/ and *.egg-info beside the sources
    shutil.copytree(ROOT, source, ignore=shutil.ignore_patterns(
        ".git", "build", "*.egg-info", "__pycache__", ".*_cache", "out", "*.tlog"))
    done = run([sys.executable, "-m", "pip", "wheel", "--quiet", "--no-deps",
                "--no-build-isolation", "-w", str(wheels), str(source)], cwd=base, timeout=300)
    assert done.returncode == 0, done.stderr
    wheel = next(wheels.glob("formation_gcs-*.whl"))
    done = run([sys.executable, "-m", "venv", "--without-pip", str(venv)], cwd=base)
    assert done.returncode == 0, done.stderr
    # the dependencies: this environment's site directories, after the venv's own (a
    # path line in a .pth; .pth files inside them, this checkout's editable hook among
    # them, are not run). --system-site-packages would give the base interpreter's
    # instead when this one is itself a venv.
    (inner,) = venv.glob("lib/python*/site-packages")
    outer = [*site.getsitepackages(), site.getusersitepackages()]
    (inner / "outer-environment.pth").write_text(
        "".join(f"{d}\n" for d in outer if Path(d).is_dir()))
    done = run([sys.executable, "-m", "pip", "--python", str(venv / "bin" / "python"),
                "install", "--quiet", "--no-deps", str(wheel)], cwd=base)
    assert done.returncode == 0, done.stderr
    return venv, work


def test_the_wheel_ships_the_configs(installed: tuple[Path, Path]) -> None:
    venv, work = installed
    python = str(venv / "bin" / "python")
    probe = ("import gcs, gcs.cli, web._launch, sim._ready_team, vehicles._airframe; "
             "print(gcs.__file__); print(gcs.cli._default_team()); "
             "print(web._launch.default_gamepad()); print(vehicles._airframe.BEBOP2); "
             "print(sim._ready_team.DEFAULT_WORLD_CONFIG)")
    done = run([python, "-c", probe], cwd=work)
    assert done.returncode == 0, done.stderr
    package, team, pad, airframe, world = (Path(p) for p in done.stdout.split())
    assert package.is_relative_to(venv), f"{package}: not the wheel's copy"
    shipped = venv / SHIPPED
    assert team == shipped / "bebop_square.yaml"
    assert pad == shipped / "gamepad.yaml"
    assert airframe == shipped / "airframes" / "bebop2.yaml"
    assert world == shipped / "sim" / "default.yaml"
    for path in (team, pad, airframe, world, shipped / "scenarios" / "short_flight.yaml"):
        assert path.is_file(), path


def test_the_wheel_ships_the_page_script(installed: tuple[Path, Path]) -> None:
    venv, work = installed
    probe = ("import web._browser_script as b; s = b.script_source(); "
             "print(b.__file__); print(len(s), 'const CFG = {' in s)")
    done = run([str(venv / "bin" / "python"), "-c", probe], cwd=work)
    assert done.returncode == 0, done.stderr
    module, size, filled = done.stdout.split()
    assert Path(module).is_relative_to(venv) and int(size) > 5000 and filled == "True"


def test_the_installed_commands_run_from_an_empty_directory(
        installed: tuple[Path, Path]) -> None:
    venv, work = installed
    gcs = str(venv / "bin" / "gcs")
    team = venv / SHIPPED / "bebop_square.yaml"
    # the README's path outside a checkout: refused, naming where the shipped one is
    done = run([gcs, "analyze", "configs/bebop_square.yaml"], cwd=work)
    assert done.returncode != 0 and done.stdout == ""
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and f"the shipped one is {team}" in lines[0], done.stderr
    done = run([gcs, "analyze", str(team)], cwd=work)
    assert done.returncode == 0, done.stderr
    assert "5.230" in done.stdout  # the vertical load of the paper's team
    # the simulator builds the world from the shipped airframe and world files
    done = run([gcs, "sim", "--config", str(team), "--speed", "max", "--duration", "0.5",
                "--listen", "tcp/127.0.0.1:0"], cwd=work)
    assert done.returncode == 0, done.stderr
