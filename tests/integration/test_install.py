"""A wheel install, outside any checkout, finds the configs it ships.

The simulator reads its airframe and world from them and ``gcs demo`` its
default team and gamepad mapping; an installed package run from another
directory used to find none of them (they were read from beside the sources).
The test builds the project's wheel, installs it alone into a fresh venv that
borrows the dependencies of this one, and runs it from an empty directory.
"""

from __future__ import annotations

from pathlib import Path

from tests.support.commands import run_outside
from tests.support.paths import SHIPPED


def test_the_wheel_ships_the_configs(installed: tuple[Path, Path]) -> None:
    venv, work = installed
    python = str(venv / "bin" / "python")
    probe = ("import gcs, gcs.cli, web._launch, sim._ready_team, vehicles._airframe; "
             "print(gcs.__file__); print(gcs.cli._default_team()); "
             "print(web._launch.default_gamepad()); print(vehicles._airframe.BEBOP2); "
             "print(sim._ready_team.DEFAULT_WORLD_CONFIG)")
    done = run_outside([python, "-c", probe], cwd=work)
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
    done = run_outside([str(venv / "bin" / "python"), "-c", probe], cwd=work)
    assert done.returncode == 0, done.stderr
    module, size, filled = done.stdout.split()
    assert Path(module).is_relative_to(venv) and int(size) > 5000 and filled == "True"


def test_the_installed_commands_run_from_an_empty_directory(
        installed: tuple[Path, Path]) -> None:
    venv, work = installed
    gcs = str(venv / "bin" / "gcs")
    team = venv / SHIPPED / "bebop_square.yaml"
    # the README's path outside a checkout: refused, naming where the shipped one is
    done = run_outside([gcs, "analyze", "configs/bebop_square.yaml"], cwd=work)
    assert done.returncode != 0 and done.stdout == ""
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and f"the shipped one is {team}" in lines[0], done.stderr
    done = run_outside([gcs, "analyze", str(team)], cwd=work)
    assert done.returncode == 0, done.stderr
    assert "5.230" in done.stdout  # the vertical load of the paper's team
    # the simulator builds the world from the shipped airframe and world files
    done = run_outside([gcs, "sim", "--config", str(team), "--speed", "max", "--duration",
                        "0.5", "--listen", "tcp/127.0.0.1:0"], cwd=work)
    assert done.returncode == 0, done.stderr
