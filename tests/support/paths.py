"""Where things are: the checkout, the configs the tests fly, the tests' own data files.

The tests run from the checkout's root (pytest's ``rootdir``), so the relative paths
(``SQUARE``, ``SHORT``, ``tests/data/...``) are as a user types them; ``ROOT`` is for
what must not depend on the working directory.
"""

from __future__ import annotations

from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
"""The checkout: this file is ``ROOT/tests/support/paths.py``."""
DATA = ROOT / "tests" / "data"
"""Teams, scenarios and logs of the tests' own (``tests/data``)."""
SQUARE = "configs/bebop_square.yaml"
"""The paper's team, relative to ``ROOT``."""
TEAMS = (SQUARE, "configs/bebop_triangle.yaml", "configs/bebop_hexagon.yaml")
"""The teams the project ships, relative to ``ROOT``."""
SHORT = "configs/scenarios/short_flight.yaml"
"""The short scenario, relative to ``ROOT``."""
SHIPPED = Path("share") / "formation-gcs" / "configs"
"""Where the wheel puts the configs it ships, under its environment's prefix."""
