"""Bad configs and scenarios found by an adversarial test: each refused in one line.

Every bad team or scenario file is refused with one line naming the file and the
field, exit status 2, within 2 s; physically impossible teams are refused too.
``test_bad_config_table.py`` runs a hundred mutated teams through ``gcs analyze``.
"""

from __future__ import annotations

import contextlib
import io
import json
import math
import time
from pathlib import Path
from typing import Any
from unittest import mock

import numpy as np
import pytest
import yaml

import gcs.app as gcs_app
from gcs.analysis import analyze, safe_guidance
from gcs.analysis._violations import gain_violation
from gcs.app import load_scenario
from gcs.cli import main
from gcs.common import ConfigError, load_yaml
from gcs.config import load_team
from gcs.formation import build_formation, motion_basis
from gcs.loop import OperatorCommand
from tests.support.commands import gcs_here, run_gcs
from tests.support.paths import SHORT, SQUARE
from vehicles import BEBOP2, load_airframe

PAIR = Path("tests/data/bebop_pair.yaml")


def square(tmp_path: Path, mutate: Any = None, name: str = "team.yaml") -> Path:
    """The square with ``mutate`` applied, as a file (its airframe by absolute path)."""
    data = yaml.safe_load(Path(SQUARE).read_text())
    data["airframe"] = str(Path("configs/airframes/bebop2.yaml").resolve())
    if mutate is not None:
        mutate(data)
    path = tmp_path / name
    path.write_text(yaml.safe_dump(data))
    return path


def cli(*argv: str) -> tuple[int, str, str, float]:
    """``gcs ARGV`` in this process: exit status, stdout, stderr, seconds of CPU (what the
    refusal costs, whatever else loads the machine)."""
    out, err = io.StringIO(), io.StringIO()
    start = time.process_time()

    def no_flight(*_args: object, **_kwargs: object) -> None:
        raise AssertionError("the config and scenario were accepted: gcs fly started a flight")

    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err), \
            mock.patch.object(gcs_app, "fly", no_flight):
        code = main(list(argv))
    return code, out.getvalue(), err.getvalue(), time.process_time() - start


def refused_by_cli(command: str, *argv: str, file: Path, field: str, words: str = "") -> str:
    """The one stderr line of a refused config: exit 2, file and field named, within 2 s."""
    code, out, err, seconds = cli(command, *argv)
    assert code == 2, out + err
    assert out == ""
    lines = err.splitlines()
    assert len(lines) == 1, err
    assert "Traceback" not in err
    line = lines[0]
    assert line.startswith(f"gcs {command}: error: {file}: {field}"), line
    assert words in line, line
    assert seconds < 2.0
    return line


def refused(path: Path, field: str, words: str = "", file: Path | None = None) -> str:
    """load_team refuses ``path`` in one line naming ``file`` (default: the team file) and
    ``field``; ``gcs analyze`` too, with status 2."""
    with pytest.raises(ConfigError) as info:
        load_team(path)
    text = str(info.value)
    assert "\n" not in text
    assert text.startswith(f"{file or path}: {field}"), text
    assert words in text, text
    refused_by_cli("analyze", str(path), file=file or path, field=field, words=words)
    return text


# -- guidance rates --------------------------------------------------------------------


@pytest.mark.parametrize("rate, setpoint_rate", [(1e-9, 1e-9), (1e-9, 12.0), (0.1, 0.1),
                                                 (1000.0, 1000.0), (60.0, 60.0)])
def test_a_guidance_rate_no_loop_can_run_is_refused(tmp_path: Path, rate: float,
                                                    setpoint_rate: float) -> None:
    """``rate_hz: 1e-9`` analysed OK and ``gcs fly`` spun forever on a 31-year period."""
    path = square(tmp_path, lambda d: d["guidance"].update(rate_hz=rate,
                                                           setpoint_rate_hz=setpoint_rate))
    refused(path, "guidance.rate_hz", "must be")


@pytest.mark.parametrize("setpoint_rate", [200.0, 1e6])
def test_a_setpoint_rate_beyond_100_hz_is_refused(tmp_path: Path, setpoint_rate: float) -> None:
    path = square(tmp_path, lambda d: d["guidance"].update(setpoint_rate_hz=setpoint_rate))
    refused(path, "guidance.setpoint_rate_hz", "at most 100")


def test_the_rate_bounds_are_what_the_guidance_can_mean(tmp_path: Path) -> None:
    for rate, setpoints in ((0.5, 0.5), (50.0, 100.0), (4.0, 100.0)):
        load_team(square(tmp_path, lambda d, r=rate, s=setpoints: d["guidance"].update(
            rate_hz=r, setpoint_rate_hz=s)))


# -- a pair --------------------------------------------------------------------------


def test_a_pair_is_a_rigid_team_and_its_motion_basis_exists() -> None:
    """Two vehicles, one edge: a LinAlgError from the motion synthesis before."""
    f = build_formation([1, 2], [(1, 2)], positions=np.array([[0.6, 0.0], [-0.6, 0.0]]))
    basis = motion_basis(f)
    # along the edge: both vehicles move with the team
    v = basis.desired_velocities(basis.translate_x)
    np.testing.assert_allclose(v, [[1.0, 0.0], [1.0, 0.0]], atol=1e-12)
    # across it, or spinning: no vehicle can (its one edge has no sideways component)
    assert not np.any(basis.translate_y) and not np.any(basis.rotate)
    assert basis.unavailable == ("translate_y", "rotate")
    assert basis.angular_rate(0.2, 1.0) == 0.0  # not 0.2 / 0
    A = basis.velocity_matrix(0.5, 0.5, 1.0, 1.0)
    assert np.all(np.isfinite(A))


def test_a_rigid_team_has_every_motion() -> None:
    for path in sorted(Path("configs").glob("bebop_*.yaml")):
        assert motion_basis(load_team(path).formation).unavailable == ()


def test_a_pair_analyzes_cleanly() -> None:
    result = analyze(load_team(PAIR))
    assert result.ok, result.violations
    assert result.vehicles == 2
    assert all(math.isfinite(x) for x in result.gain_terms.values())
    assert any("sideways" in w for w in result.warnings), result.warnings
    code, out, err, _ = cli("analyze", str(PAIR))
    assert (code, err) == (0, ""), out + err
    assert "result: OK" in out
    code, out, err, _ = cli("analyze", str(PAIR), "--json")
    assert code == 0 and json.loads(out)["ok"] is True


def test_a_pair_that_could_spin_says_it_cannot(tmp_path: Path) -> None:
    data = yaml.safe_load(PAIR.read_text())
    data["airframe"] = str(BEBOP2.resolve())
    data["guidance"]["max_rotation_disagreement"] = 0.2
    path = tmp_path / "pair.yaml"
    path.write_text(yaml.safe_dump(data))
    result = analyze(load_team(path))
    assert any("cannot spin" in w and "max_rotation_disagreement" in w
               for w in result.warnings), result.warnings


# -- bytes that are no text -------------------------------------------------------------


def _utf16(tmp_path: Path) -> Path:
    path = tmp_path / "utf16.yaml"
    path.write_bytes(Path(SQUARE).read_text().encode("utf-16"))
    return path


def _binary(tmp_path: Path) -> Path:
    path = tmp_path / "binary.yaml"
    path.write_bytes(bytes(range(256)) * 4)
    return path


def _latin1(tmp_path: Path) -> Path:
    path = tmp_path / "latin1.yaml"
    path.write_bytes(Path(SQUARE).read_bytes() + "# r\xe9glage\n".encode("latin-1"))
    return path


def _nul(tmp_path: Path) -> Path:
    path = tmp_path / "nul.yaml"
    path.write_bytes(b"name: x\x00\x00\nvehicles: []\n")
    return path


NOT_TEXT = {"utf-16": _utf16, "binary": _binary, "latin-1": _latin1, "nul": _nul}


@pytest.mark.parametrize("kind", NOT_TEXT)
def test_a_config_that_is_not_utf8_text_is_refused_in_one_line(tmp_path: Path,
                                                                kind: str) -> None:
    """UTF-16 and binary files gave a UnicodeDecodeError traceback."""
    path = NOT_TEXT[kind](tmp_path)
    with pytest.raises(ConfigError) as info:
        load_yaml(path)
    assert str(info.value).startswith(f"{path}: "), info.value
    refused_by_cli("analyze", str(path), file=path, field="")


@pytest.mark.parametrize("kind", NOT_TEXT)
def test_a_scenario_that_is_not_utf8_text_is_refused_in_one_line(tmp_path: Path,
                                                                  kind: str) -> None:
    path = NOT_TEXT[kind](tmp_path)
    refused_by_cli("fly", "--config", SQUARE, "--scenario", str(path), file=path, field="")


@pytest.mark.parametrize("kind", ["utf-16", "binary"])
def test_an_airframe_that_is_not_utf8_text_is_refused_naming_it(tmp_path: Path,
                                                                 kind: str) -> None:
    frame = NOT_TEXT[kind](tmp_path)
    path = square(tmp_path, lambda d: d.update(airframe=str(frame)))
    refused(path, "", file=frame)


def test_the_utf16_message_says_what_to_do(tmp_path: Path) -> None:
    path = _utf16(tmp_path)
    with pytest.raises(ConfigError, match=r"UTF-16.*UTF-8"):
        load_yaml(path)


def test_a_huge_file_is_refused_quickly(tmp_path: Path) -> None:
    path = tmp_path / "huge.yaml"
    path.write_text(Path(SQUARE).read_text() + ("# padding " * 100 + "\n") * 20000)
    refused_by_cli("analyze", str(path), file=path, field="", words="too large")


def test_deep_nesting_is_refused_in_one_line(tmp_path: Path) -> None:
    path = tmp_path / "deep.yaml"
    path.write_text("name: " + "[" * 20000 + "]" * 20000 + "\n")
    refused_by_cli("analyze", str(path), file=path, field="", words="nested")


def test_a_directory_given_as_the_config_says_so(tmp_path: Path) -> None:
    refused_by_cli("analyze", str(tmp_path), file=tmp_path, field="", words="is a directory")


def test_a_duplicate_key_is_refused(tmp_path: Path) -> None:
    """The second ``c1`` silently won before."""
    path = tmp_path / "twice.yaml"
    text = Path(SQUARE).read_text().replace("airframes/bebop2.yaml",
                                            str(BEBOP2.resolve()))
    path.write_text(text.replace("  c1: 0.17\n", "  c1: 0.17\n  c1: 0.9\n"))
    refused(path, "guidance.c1", "given twice")


# -- signing keys ------------------------------------------------------------------------


def _keyed(tmp_path: Path, key: bytes | None) -> Path:
    """The square with signed links, vehicle 3's key file holding ``key`` (None: absent)."""
    for vid in (1, 2, 4):
        (tmp_path / f"v{vid}.key").write_text((bytes([vid]) * 32).hex() + "\n")
    if key is not None:
        (tmp_path / "v3.key").write_bytes(key)
    return square(tmp_path, lambda d: d.update(links=[
        {"sysid": vid, "signing_key": f"v{vid}.key"} for vid in (1, 2, 3, 4)]))


@pytest.mark.parametrize("key, words", [(None, "cannot read"), (b"0123", "32 raw bytes"),
                                        (b"\x00" * 32, "all zeros"),
                                        (b"zz" * 32, "hexadecimal")])
def test_a_missing_or_bad_signing_key_is_a_config_error(tmp_path: Path, key: bytes | None,
                                                        words: str) -> None:
    """A missing key was a SimStartError traceback in ``gcs fly`` (the sim host read it)."""
    path = _keyed(tmp_path, key)
    text = refused(path, "links[2].signing_key", words)
    assert "v3.key" in text


def test_a_missing_signing_key_stops_gcs_fly_before_the_simulator(tmp_path: Path) -> None:
    path = _keyed(tmp_path, None)
    refused_by_cli("fly", "--config", str(path), "--scenario", SHORT, file=path,
                   field="links[2].signing_key", words="cannot read")


def test_good_signing_keys_load(tmp_path: Path) -> None:
    load_team(_keyed(tmp_path, (bytes([3]) * 32)))


# -- physics ------------------------------------------------------------------------------


def _airframe(tmp_path: Path, **changes: Any) -> Path:
    data = yaml.safe_load(BEBOP2.read_text())
    data.update(changes)
    path = tmp_path / "frame.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


def test_an_airframe_that_cannot_hover_is_refused(tmp_path: Path) -> None:
    """Rotors of 4 x 1e-7 x 1086^2 = 0.47 N under a 3.9 N weight: analyze said OK."""
    frame = _airframe(tmp_path, thrust_coefficient=1e-7)
    with pytest.raises(ConfigError) as info:
        load_airframe(frame)
    text = str(info.value)
    assert text.startswith(f"{frame}: thrust_coefficient: "), text
    assert "0.472 N" in text and "3.92 N" in text and "cannot hover" in text, text
    refused(square(tmp_path, lambda d: d.update(airframe=str(frame))), "thrust_coefficient",
            "cannot hover", file=frame)


def test_an_inline_airframe_that_cannot_hover_names_the_team_file(tmp_path: Path) -> None:
    def inline(d: dict[str, Any]) -> None:
        d["airframe"] = {**yaml.safe_load(BEBOP2.read_text()), "rotor_speed_max": 100.0}
    refused(square(tmp_path, inline), "airframe.thrust_coefficient", "rotor_speed_max")


def test_a_thrust_reference_beyond_the_rotors_is_refused(tmp_path: Path) -> None:
    frame = _airframe(tmp_path, thrust_reference=20.0)
    with pytest.raises(ConfigError, match=r"frame.yaml: thrust_reference: 20 N exceeds the "
                                          r"full-speed thrust 7.47 N"):
        load_airframe(frame)


def test_impossible_inertia_is_refused(tmp_path: Path) -> None:
    frame = _airframe(tmp_path, inertia=[0.001, 0.001, 0.01])
    with pytest.raises(ConfigError, match=r"frame.yaml: inertia: .*triangle"):
        load_airframe(frame)


def test_a_team_whose_vehicles_cannot_lift_their_share_is_a_violation(tmp_path: Path) -> None:
    """Full thrust above the weight, below weight plus payload share: the analysis says so
    with the numbers."""
    frame = _airframe(tmp_path, thrust_reference=4.0)  # 7.47 N at full speed
    path = square(tmp_path, lambda d: (d.update(airframe=str(frame)),
                                       d["payload"].update(mass=3.0)))
    result = analyze(load_team(path))
    terms = {v.term: v.message for v in result.violations}
    assert "airframe.thrust_max" in terms, terms
    assert "7.47 N" in terms["airframe.thrust_max"], terms


# -- limits that contradict each other ------------------------------------------------------


CONTRADICTIONS: dict[str, tuple[Any, str, str]] = {
    "altitude range upside down": (
        lambda d: d.update(operator={"altitude_min": 3.0, "altitude_max": 1.0}),
        "operator.altitude_min", "above operator.altitude_max"),
    "altitude above the geofence": (
        lambda d: d.update(operator={"altitude_max": 10.0}),
        "operator.altitude_max", "above safety.geofence_altitude"),
    "lift above the highest altitude": (
        lambda d: d.update(flight={"lift_height": 5.0}),
        "flight.lift_height", "operator.altitude_max"),
    "take-off under the ground": (
        lambda d: d.update(flight={"takeoff_slack": 2.0}),
        "flight.takeoff_slack", "below the ground"),
    "payload cannot be set down": (
        lambda d: d.update(operator={"altitude_min": 1.0}),
        "operator.altitude_min", "set down"),
    "geofence smaller than the team": (
        lambda d: d.update(safety={"geofence_xy": 1.0, "geofence_margin": 0.1}),
        "safety.geofence_xy", "scale_max"),
    "scale step beyond the range": (
        lambda d: d["guidance"].update(scale_step=5.0),
        "guidance.scale_step", "scale_max"),
    "vehicles closer than their rotors": (
        lambda d: [v.update(position=[x * 0.1 for x in v["position"]]) for v in d["vehicles"]],
        "vehicles", "apart"),
}


@pytest.mark.parametrize("case", CONTRADICTIONS)
def test_limits_that_contradict_each_other_are_refused(tmp_path: Path, case: str) -> None:
    """``altitude_min`` above ``altitude_max`` was accepted; the flight then "completed"
    with the payload 0.2 m up."""
    mutate, field, words = CONTRADICTIONS[case]
    refused(square(tmp_path, mutate), field, words)


# -- scenarios beyond the team's ranges --------------------------------------------------------


def _scenario(tmp_path: Path, *steps: dict[str, Any]) -> Path:
    path = tmp_path / "scenario.yaml"
    path.write_text(yaml.safe_dump({"name": "bad", "steps": [
        {"action": "arm"}, {"action": "takeoff"}, {"action": "lift"}, *steps]}))
    return path


@pytest.mark.parametrize("step, field, words", [
    ({"scale": 50}, "steps[3].scale", "guidance.scale_max"),
    ({"scale": 0.01}, "steps[3].scale", "guidance.scale_min"),
    ({"altitude": 1000}, "steps[3].altitude", "operator.altitude_max"),
    ({"scale_steps": 40}, "steps[3].scale_steps", "guidance.scale_max"),
])
def test_a_scenario_beyond_the_teams_ranges_is_refused(tmp_path: Path, step: dict[str, Any],
                                                       field: str, words: str) -> None:
    """``scale: 50`` and ``altitude: 1000`` were clipped silently and the flight "passed"."""
    path = _scenario(tmp_path, step)
    team = load_team(SQUARE)
    with pytest.raises(ConfigError) as info:
        gcs_app.check_scenario(load_scenario(path), team, str(path))
    assert str(info.value).startswith(f"{path}: {field}: "), info.value
    assert words in str(info.value)
    refused_by_cli("fly", "--config", SQUARE, "--scenario", str(path), file=path, field=field,
                   words=words)


def test_the_shipped_scenarios_fit_the_shipped_teams() -> None:
    for team in sorted(Path("configs").glob("bebop_*.yaml")):
        for scenario in sorted(Path("configs/scenarios").glob("*.yaml")):
            gcs_app.check_scenario(load_scenario(scenario), load_team(team), str(scenario))


@pytest.mark.parametrize("step, field", [
    ({"wait": 1e300}, "steps[3].wait"),
    ({"sticks": {"forward": 1.0}, "duration": 1e12}, "steps[3].duration"),
    ({"action": "land", "timeout": 1e300}, "steps[3].timeout"),
    ({"sticks": {"forward": 1.0}}, "steps[3].duration"),
    ({"wait": 2, "duration": 3}, "steps[3].duration"),
])
def test_a_scenario_step_that_would_never_end_or_do_nothing_is_refused(
        tmp_path: Path, step: dict[str, Any], field: str) -> None:
    path = _scenario(tmp_path, step)
    refused_by_cli("fly", "--config", SQUARE, "--scenario", str(path), file=path, field=field)


# -- messages that said the wrong thing ------------------------------------------------------


def test_a_position_far_out_is_out_of_range_not_collinear(tmp_path: Path) -> None:
    path = square(tmp_path, lambda d: d["vehicles"][0].update(position=[1e300, 0.0]))
    text = refused(path, "vehicles[0].position[0]", "at most 10000")
    assert "collinear" not in text


def test_a_directory_given_as_airframe_says_it_is_a_directory(tmp_path: Path) -> None:
    path = square(tmp_path, lambda d: d.update(airframe=str(tmp_path)))
    text = refused(path, "airframe", "is a directory")
    assert "not found" not in text


@pytest.mark.parametrize("literal, value", [("1.0e9", 1e9), ("1e9", 1e9), ("2E-1", 0.2),
                                            ("1.5e+0", 1.5), ("-3e2", -300.0)])
def test_yaml_numbers_with_exponents_are_numbers(tmp_path: Path, literal: str,
                                                 value: float) -> None:
    """PyYAML's YAML 1.1 resolver read ``1.0e9`` as a string: "expected a number, got a
    string" blamed the user for a valid number."""
    path = tmp_path / "n.yaml"
    path.write_text(f"x: {literal}\ny: '{literal}'\n")
    assert load_yaml(path) == {"x": value, "y": literal}


def test_an_exponent_number_out_of_range_is_out_of_range(tmp_path: Path) -> None:
    path = tmp_path / "team.yaml"
    text = Path(SQUARE).read_text().replace("airframes/bebop2.yaml", str(BEBOP2.resolve()))
    path.write_text(text.replace("rate_hz: 4.0", "rate_hz: 1.0e9"))
    line = refused(path, "guidance.rate_hz", "at most 50, got 1e+09")
    assert "string" not in line
    path.write_text(text.replace("c1: 0.17", "c1: 1.7e-1"))
    assert load_team(path).config.guidance.c1 == 0.17


def test_a_huge_speed_is_out_of_range_and_numbers_are_short(tmp_path: Path) -> None:
    """``max_speed: 1e300`` printed a 300-digit number and blamed the gains."""
    path = square(tmp_path, lambda d: d["guidance"].update(max_speed=1e300))
    text = refused(path, "guidance.max_speed", "at most")
    assert len(text) < 200, text


def test_a_violation_prints_numbers_short() -> None:
    """Eq. max's terms and the fixes in %g when they are huge, not 300 digits."""
    v = gain_violation({"c1_speed": 1.7e299, "c2_distance": 0.9, "mu_rotation": 0.4},
                       {"c1_speed": 1e300, "c2_distance": 1.7, "mu_rotation": 2.0}, 1.5)
    assert len(v.message) < 400, v.message
    assert "1.7e+299" in v.message, v.message


# -- non-finite numbers anywhere ------------------------------------------------------------------


def _numeric_leaves(data: Any, where: str = "") -> list[tuple[str, list[Any]]]:
    """(field path, key path) of every number in a YAML tree."""
    out: list[tuple[str, list[Any]]] = []
    items = (data.items() if isinstance(data, dict) else enumerate(data)
             if isinstance(data, list) else ())
    for key, value in items:
        sub = f"{where}[{key}]" if isinstance(key, int) else (f"{where}.{key}" if where
                                                              else str(key))
        if isinstance(value, int | float) and not isinstance(value, bool):
            out.append((sub, [key]))
        else:
            out += [(f, [key, *path]) for f, path in _numeric_leaves(value, sub)]
    return out


def _full_square() -> dict[str, Any]:
    """The square with every optional section written out, edges with distances."""
    data = yaml.safe_load(Path(SQUARE).read_text())
    data["airframe"] = yaml.safe_load(BEBOP2.read_text())
    data["edges"] = [{"tail": t, "head": h} for t, h in data["edges"]]
    data["analysis"].update(max_speed_error=1.0, payload_share=3, gravity=9.81)
    data["operator"] = {"deadzone": 0.05, "expo": 0.3, "stick_timeout": 1.0,
                        "altitude_rate": 0.3, "altitude_min": 0.0, "altitude_max": 4.0,
                        "altitude_step": 0.1, "scale_rate": 0.05}
    data["safety"] = {"stale_after": 0.5, "land_after": 3.0, "geofence_xy": 4.0,
                      "geofence_altitude": 4.0, "geofence_margin": 0.5, "recover_after": 1.0,
                      "deformed_land_growth": 0.3}
    data["flight"] = {"takeoff_slack": 0.15, "lift_height": 1.0, "lift_rate": 0.1,
                      "altitude_tolerance": 0.1, "takeoff_timeout": 30.0, "abort_hold": 1.0}
    data["gcs"] = {"system_id": 245, "component_id": 190, "heartbeat_period_s": 1.0,
                   "timesync_period_s": 1.0}
    data["links"] = [{"sysid": i, "signing_link_id": 0, "component_id": 1, "baud": 57600,
                      "command_timeout_s": 1.0, "command_retries": 2,
                      "heartbeat_timeout_s": 3.0} for i in (1, 2, 3, 4)]
    return data


FULL_SQUARE_LEAVES = _numeric_leaves(_full_square())


def test_the_full_square_loads_and_has_every_numeric_field() -> None:
    assert analyze(load_team_from(_full_square())).ok
    assert len(FULL_SQUARE_LEAVES) > 60


def load_team_from(data: dict[str, Any]) -> Any:
    import tempfile

    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "full.yaml"
        path.write_text(yaml.safe_dump(data))
        return load_team(path)


@pytest.mark.parametrize("bad", [math.nan, math.inf, -math.inf])
def test_a_non_finite_number_anywhere_is_refused_naming_the_field(tmp_path: Path,
                                                                   bad: float) -> None:
    for field, keys in FULL_SQUARE_LEAVES:
        data = _full_square()
        node = data
        for key in keys[:-1]:
            node = node[key]
        node[keys[-1]] = bad
        path = square(tmp_path, lambda d, data=data: (d.clear(), d.update(data)))
        with pytest.raises(ConfigError) as info:
            load_team(path)
        assert str(info.value).startswith(f"{path}: {field}: "), (field, str(info.value))


@pytest.mark.parametrize("bad", [".nan", ".inf", "-.inf"])
@pytest.mark.parametrize("step, field", [
    ("{scale: X}", "steps[0].scale"), ("{altitude: X}", "steps[0].altitude"),
    ("{wait: X}", "steps[0].wait"), ("{sticks: {forward: X}, duration: 1}",
                                     "steps[0].sticks.forward"),
    ("{sticks: {forward: 1}, duration: X}", "steps[0].duration"),
    ("{action: arm, timeout: X}", "steps[0].timeout"),
])
def test_a_non_finite_scenario_number_is_refused(tmp_path: Path, bad: str, step: str,
                                                 field: str) -> None:
    path = tmp_path / "s.yaml"
    path.write_text(f"name: s\nsteps:\n  - {step.replace('X', bad)}\n")
    with pytest.raises(ConfigError) as info:
        load_scenario(path)
    assert str(info.value).startswith(f"{path}: {field}: "), info.value


# -- subprocesses: what a user sees --------------------------------------------------------------


@pytest.mark.parametrize("kind", ["utf-16", "binary"])
def test_gcs_analyze_of_bytes_is_one_line_in_a_subprocess(tmp_path: Path, kind: str) -> None:
    path = NOT_TEXT[kind](tmp_path)
    out = run_gcs("analyze", str(path), timeout=120)
    assert out.returncode == 2, out.stderr
    assert out.stderr.count("\n") == 1 and out.stderr.startswith(
        f"gcs analyze: error: {path}: "), out.stderr


def test_gcs_analyze_of_a_pair_in_a_subprocess() -> None:
    out = run_gcs("analyze", str(PAIR), timeout=120)
    assert out.returncode == 0, out.stdout + out.stderr
    assert "result: OK" in out.stdout and out.stderr == ""


def test_a_pair_flies_the_short_flight_in_lockstep() -> None:
    """The pair lifts, flies forward, holds through the spin it cannot make, sets down and
    lands: ``gcs fly`` hung on it before (the LinAlgError killed the loop)."""
    out = run_gcs("fly", "--config", str(PAIR), "--scenario", SHORT, "--json", timeout=400)
    assert out.returncode == 0, out.stdout[-2000:] + out.stderr[-4000:]
    data = json.loads(out.stdout.splitlines()[-1])
    assert data["completed"] is True, data


def test_a_scale_below_the_smallest_certified_is_named_and_held_there(tmp_path: Path) -> None:
    """Shrunk to the square's guidance.scale_min 0.3, accelerating at its limit would put
    all of the payload on one vehicle, beyond its full thrust: the analysis raises the
    smallest scale flown, a scenario asking for less is told the scale flown, and the
    operator command (the one the GCS flies, from ``safe_guidance``) holds it there."""
    team = load_team(SQUARE)
    a = analyze(team)
    assert team.config.guidance.scale_min == 0.3 and 0.5 < a.scale_min_flown < 0.55
    assert any(w.startswith(f"the GCS flies scales from {a.scale_min_flown:g}, not "
                            f"guidance.scale_min 0.3: at 0.3, accelerating at "
                            f"limits.accel_norm 2.18 m/s^2 puts 1.000 of the payload")
               for w in a.warnings), a.warnings
    scenario = tmp_path / "shrink.yaml"
    scenario.write_text("name: shrink\nsteps:\n  - {action: arm}\n  - {scale: 0.4}\n")
    (warning,) = gcs_app.check_scenario(load_scenario(scenario), team, str(scenario))
    assert warning.startswith(f"{scenario}: steps[1].scale: 0.4 is below "
                              f"{a.scale_min_flown:.4f}")
    assert warning.endswith(f"the GCS flies {a.scale_min_flown:.4f}")
    operator = OperatorCommand(team.config.operator, safe_guidance(team, a))
    assert operator.set_scale(0.3) == a.scale_min_flown
    assert operator.set_scale(0.9) == 0.9  # the paper flight's shrink is flown
    json_scales = json.loads(gcs_here("analyze", SQUARE, "--json").stdout)["scales_flown"]
    assert json_scales == {"min": a.scale_min_flown, "max": pytest.approx(a.scale_max_flown)}


def test_a_scale_beyond_the_safe_deformation_is_named_with_the_scale_flown() -> None:
    """The paper flight's scale 1.1 on the square is capped in flight at what the analysis'
    safe deformation allows; ``check_scenario`` says so instead of flying it silently."""
    scenario = "configs/scenarios/paper_flight.yaml"
    team = load_team(SQUARE)
    (warning,) = gcs_app.check_scenario(load_scenario(scenario), team, scenario)
    flown = safe_guidance(team, analyze(team)).scale_max
    assert 1.0 < flown < 1.1
    assert warning.startswith(f"{scenario}: steps[12].scale: 1.1 is above {flown:.4f}")
    assert warning.endswith(f"the GCS flies {flown:.4f}")
