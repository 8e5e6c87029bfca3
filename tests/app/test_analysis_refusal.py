"""A team that ``gcs analyze`` refuses is not flown: ``gcs fly``, ``gcs run`` and ``gcs demo``
say so at once with every violation (they used to sit in "connect" for 120 s of sim time,
then name the first violation only)."""

from __future__ import annotations

import time
from pathlib import Path

import pytest

from gcs.analysis import analyze
from gcs.config import load_team
from tests.support.commands import run_gcs
from tests.support.paths import ROOT, SHORT


@pytest.fixture(scope="module")
def refused_team(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The paper's square under a payload it cannot carry."""
    text = (ROOT / "configs" / "bebop_square.yaml").read_text().replace(
        "airframes/bebop2.yaml", str(ROOT / "configs" / "airframes" / "bebop2.yaml"))
    path = tmp_path_factory.mktemp("refused") / "heavy.yaml"
    lines = text.splitlines()
    start = lines.index("payload:")
    for k in range(start + 1, len(lines)):
        if lines[k].strip().startswith("mass:"):
            lines[k] = "  mass: 1.6"
            break
    path.write_text("\n".join(lines) + "\n")
    assert len(analyze(load_team(path)).violations) >= 2
    return path


@pytest.mark.parametrize("command", [
    ("fly", "--config", "{config}", "--scenario", SHORT),
    ("run", "--config", "{config}", "--port", "0"),
    ("demo", "--config", "{config}", "--port", "0"),
])
def test_a_refused_team_is_not_flown(refused_team: Path, command: tuple[str, ...]) -> None:
    start = time.monotonic()
    out = run_gcs(*(a.format(config=refused_team) for a in command), timeout=120)
    elapsed = time.monotonic() - start
    assert out.returncode == 1, out.stdout + out.stderr
    violations = analyze(load_team(refused_team)).violations
    lines = out.stderr.splitlines()
    assert lines[0].startswith(f"gcs {command[0]}: error: ") and "--override-analysis" in lines[0]
    assert [line.strip() for line in lines[1:]] == [f"{v.term}: {v.message}" for v in violations]
    assert "signing" not in out.stderr and "starting" not in out.stdout  # nothing started
    assert elapsed < 60, elapsed  # not the 120 s of a flight that waits in "connect"


def test_the_api_refuses_a_refused_team_before_starting_anything(
        refused_team: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """``SimTeam`` (and ``Team.connect``) raise at once, every violation in the line, and
    start no simulator: a test author's flight does not wait in "connect" to fail."""
    from gcs.common import ConfigError
    from gcs.testing import SimTeam

    def no_simulator(*_args: object, **_kwargs: object) -> None:
        raise AssertionError("a simulator was started for a refused team")

    monkeypatch.setattr("gcs.app._fly.SimProcess", no_simulator)
    violations = analyze(load_team(refused_team)).violations
    with pytest.raises(ConfigError) as refused:
        SimTeam(refused_team)
    said = str(refused.value)
    assert said.startswith(f"{refused_team}: gcs analyze refuses this team "
                           f"({len(violations)} violation(s); override_analysis flies it")
    assert said.split("): ", 1)[1].split(" | ") == [f"{v.term}: {v.message}" for v in violations]
    assert "\n" not in said
