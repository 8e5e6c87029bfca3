"""Where the configs shipped with the project are, in a checkout and once installed.

The simulator reads its airframe and world files from them, and ``gcs demo``
its default team and gamepad mapping, so they must be found however the
project was installed: beside the packages in a checkout (or an editable
install), else where a wheel puts its data files (``<prefix>/share/formation-gcs/
configs``, see ``[tool.setuptools] data-files`` in pyproject.toml). A
project directory's own ``configs/`` wins for the defaults a user may edit
(:func:`default_config`), never for the simulator's physics
(:func:`shipped_config`), which must not change with the directory a command
is started from.
"""

from __future__ import annotations

import site
import sys
from pathlib import Path

__all__ = ["LOCAL_CONFIGS", "default_config", "missing_config_hint", "shipped_config",
           "shipped_configs"]

LOCAL_CONFIGS = Path("configs")
"""A project directory's own configs, relative to the current directory."""

_DATA_DIR = Path("share") / "formation-gcs" / "configs"
"""Where a wheel's data files put the configs, under an installation prefix."""


def _candidates() -> list[Path]:
    beside = Path(__file__).resolve().parents[2] / "configs"  # gcs/common/ -> the checkout
    prefixes = [Path(sys.prefix), Path(site.getuserbase())]
    return [beside, *(prefix / _DATA_DIR for prefix in prefixes)]


def shipped_configs() -> Path:
    """The shipped configs directory (the checkout's when there is one)."""
    candidates = _candidates()
    for directory in candidates:
        if (directory / "airframes").is_dir():
            return directory
    return candidates[0]  # nothing installed: errors then name the checkout's path


def shipped_config(relative: str | Path) -> Path:
    """A shipped config file, e.g. ``shipped_config("airframes/bebop2.yaml")``."""
    return shipped_configs() / relative


def default_config(relative: str | Path) -> Path:
    """``configs/<relative>`` of the current directory if it has one, else the shipped one.

    For defaults a user may override by keeping a project directory (the team
    of ``gcs demo``, the gamepad mapping); when neither exists the local path
    is returned, so a message names what was looked for.
    """
    local = LOCAL_CONFIGS / relative
    if local.is_file():
        return local
    shipped = shipped_config(relative)
    return shipped if shipped.is_file() else local


def missing_config_hint(path: str | Path) -> str:
    """For a ``configs/...`` path that does not exist here: where the shipped copy is.

    A user of an installed package who types the README's ``configs/...`` paths
    outside a checkout otherwise gets a bare "no such file".
    """
    path = Path(path)
    if path.is_absolute() or path.exists() or path.parts[:1] != (LOCAL_CONFIGS.name,):
        return ""
    shipped = shipped_configs() / Path(*path.parts[1:])
    return f" (the shipped one is {shipped})" if shipped.is_file() else ""
