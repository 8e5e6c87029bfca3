"""A hundred bad team configs through ``gcs analyze``: the count table of the issue.

Each case mutates ``configs/bebop_square.yaml`` (a wrong type, a value out of
range or not finite, limits that contradict each other, a missing or unknown
field, a physically impossible airframe or team, bytes that are no YAML text, a
huge or deeply nested file, ...) and runs ``gcs analyze`` on it, in a process of
its own (forked from a server that has the GCS loaded, so a hang can be stopped).
Each must end in one of two ways:

* a clear error: exit status 2, nothing on stdout, exactly one line on stderr
  naming the file and the field (and the expected fault), within 2 s of CPU;
* a correct violation, for a team that loads but breaks the analysis: exit status
  1 and a ``VIOLATION <field>`` line.

Anything else is counted as a traceback, a hang, accepted nonsense (exit 0) or an
unclear error, and fails the case. ``pytest -s`` prints the table.
"""

from __future__ import annotations

import contextlib
import copy
import io
import multiprocessing
import time
import traceback
from collections.abc import Callable
from dataclasses import dataclass
from multiprocessing.connection import Connection
from pathlib import Path
from typing import Any

import pytest
import yaml

from tests.support.paths import SQUARE
from vehicles import BEBOP2

#: Longest CPU time of one case, s (the issue's 2 s; CPU time, so that a loaded machine
#: does not fail it), and the wall time after which a case counts as a hang.
CPU_LIMIT_S = 2.0
HANG_S = 30.0

Mutation = Callable[[dict[str, Any]], object]


@dataclass(frozen=True)
class Case:
    """One bad config: how it is made, and what ``gcs analyze`` must say."""

    name: str
    field: str  # the field named after "FILE: " ("" for a fault of the whole file)
    words: str = ""  # a fragment of the fault
    code: int = 2  # 2: refused; 1: an analysis violation of ``field``
    data: Mutation | None = None  # a change to the square's YAML data
    text: Callable[[str], str] | None = None  # a change to the square's text
    raw: bytes | None = None  # the file's bytes
    frame: dict[str, Any] | bytes | None = None  # airframe file changes (named in the error)


def _set(section: str, **values: Any) -> Mutation:
    def change(d: dict[str, Any]) -> None:
        if not isinstance(d.get(section), dict):
            d[section] = {}
        d[section].update(values)
    return change


def _top(**values: Any) -> Mutation:
    return lambda d: d.update(values)


def _drop(*keys: str) -> Mutation:
    def change(d: dict[str, Any]) -> None:
        node = d
        for key in keys[:-1]:
            node = node[key]
        del node[keys[-1]]
    return change


def _vehicle(k: int, **values: Any) -> Mutation:
    return lambda d: d["vehicles"][k].update(values)


def _edge(k: int, value: Any) -> Mutation:
    return lambda d: d["edges"].__setitem__(k, value)


def _inline_frame(**values: Any) -> Mutation:
    return lambda d: d.update(airframe={**yaml.safe_load(BEBOP2.read_text()), **values})


def _links(**values: Any) -> Mutation:
    return lambda d: d.update(links=[{"sysid": i, **values} for i in (1, 2, 3, 4)])


NAN, INF = float("nan"), float("inf")
SQUARE_TEXT = Path(SQUARE).read_text()
SQUARE_BYTES = SQUARE_TEXT.encode()

CASES = [
    # -- wrong types
    Case("name a number", "name", "expected a string", data=_top(name=123)),
    Case("name null", "name", "expected a string", data=_top(name=None)),
    Case("vehicles a string", "vehicles", "expected a list", data=_top(vehicles="four")),
    Case("vehicles a mapping", "vehicles", "expected a list", data=_top(vehicles={"a": 1})),
    Case("vehicle an integer", "vehicles[0]", "expected a mapping",
         data=lambda d: d["vehicles"].__setitem__(0, 5)),
    Case("vehicle id a string", "vehicles[0].id", "expected an integer",
         data=_vehicle(0, id="one")),
    Case("vehicle id a float", "vehicles[0].id", "expected an integer", data=_vehicle(0, id=1.5)),
    Case("vehicle id a boolean", "vehicles[0].id", "expected an integer",
         data=_vehicle(0, id=True)),
    Case("position a string", "vehicles[0].position", "expected a list",
         data=_vehicle(0, position="0.5, 0.5")),
    Case("position of one value", "vehicles[0].position", "expected 2 values",
         data=_vehicle(0, position=[0.5])),
    Case("position of three values", "vehicles[0].position", "expected 2 values",
         data=_vehicle(0, position=[0.5, 0.5, 0.0])),
    Case("position a boolean", "vehicles[0].position[0]", "expected a number",
         data=_vehicle(0, position=[True, 0.5])),
    Case("edges a string", "edges", "expected a list", data=_top(edges="all")),
    Case("edge a string", "edges[0]", "expected a mapping", data=_edge(0, "1-2")),
    Case("edge head a string", "edges[0].head", "expected an integer", data=_edge(0, [1, "2"])),
    Case("edge distance a string", "edges[0].distance", "expected a number",
         data=_edge(0, [1, 2, "far"])),
    Case("guidance a list", "guidance", "expected a mapping", data=_top(guidance=[1, 2])),
    Case("c1 a word", "guidance.c1", "expected a number, got a string",
         data=_set("guidance", c1="fast")),
    Case("c1 a list", "guidance.c1", "expected a number", data=_set("guidance", c1=[0.17])),
    Case("hold compensation a word", "guidance.hold_compensation", "expected true or false",
         data=_set("guidance", hold_compensation="maybe")),
    Case("turn compensation a word", "guidance.turn_compensation", "expected true or false",
         data=_set("guidance", turn_compensation="yes")),
    Case("setpoint lag 2 s", "guidance.setpoint_lag", "at most 1",
         data=_set("guidance", setpoint_lag=2.0)),
    Case("bank null", "limits.bank_deg", "expected a number", data=_set("limits", bank_deg=None)),
    Case("payload a number", "payload", "expected a mapping", data=_top(payload=0.4)),
    Case("airframe a number", "airframe", "expected a mapping", data=_top(airframe=42)),
    Case("airframe a list", "airframe", "expected a mapping", data=_top(airframe=[])),
    Case("recovery unknown", "safety.recovery", "must be one of",
         data=_set("safety", recovery="never")),
    Case("links a mapping", "links", "expected a list", data=_top(links={"sysid": 1})),
    Case("profile unknown", "links[0].profile", "must be one of", data=_links(profile="dji")),
    Case("system id a string", "gcs.system_id", "expected an integer",
         data=_set("gcs", system_id="245")),
    Case("deadzone a percentage", "operator.deadzone", "expected a number",
         data=_set("operator", deadzone="5%")),
    Case("a list, not a mapping", "", "expected a mapping", text=lambda t: "- 1\n- 2\n"),
    Case("empty file", "", "expected a mapping", text=lambda t: ""),
    Case("only a comment", "", "expected a mapping", text=lambda t: "# nothing here\n"),
    Case("a plain word", "", "expected a mapping", text=lambda t: "square\n"),
    # -- out of range
    Case("vehicle id 0", "vehicles[0].id", "at least 1", data=_vehicle(0, id=0)),
    Case("vehicle id 300", "vehicles[0].id", "at most 254", data=_vehicle(0, id=300)),
    Case("negative c1", "guidance.c1", "greater than 0", data=_set("guidance", c1=-0.1)),
    Case("zero c2", "guidance.c2", "greater than 0", data=_set("guidance", c2=0)),
    Case("rate 1e-9 Hz", "guidance.rate_hz", "at least 0.5",
         data=_set("guidance", rate_hz=1e-9, setpoint_rate_hz=1e-9)),
    Case("rate 1000 Hz", "guidance.rate_hz", "at most 50",
         data=_set("guidance", rate_hz=1000.0, setpoint_rate_hz=1000.0)),
    Case("setpoint rate 1e6 Hz", "guidance.setpoint_rate_hz", "at most 100",
         data=_set("guidance", setpoint_rate_hz=1e6)),
    Case("speed 1e300", "guidance.max_speed", "at most 20", data=_set("guidance", max_speed=1e300)),
    Case("negative rotation", "guidance.max_rotation_disagreement", "at least 0",
         data=_set("guidance", max_rotation_disagreement=-1.0)),
    Case("bank 90 degrees", "limits.bank_deg", "less than 90", data=_set("limits", bank_deg=90)),
    Case("acceleration 0", "limits.accel_norm", "greater than 0",
         data=_set("limits", accel_norm=0)),
    Case("negative payload", "payload.mass", "greater than 0", data=_set("payload", mass=-0.4)),
    Case("rope of 0 m", "payload.rope_length", "greater than 0",
         data=_set("payload", rope_length=0)),
    Case("rope of 1 km", "payload.rope_length", "at most 100",
         data=_set("payload", rope_length=1000.0)),
    Case("rope angle 120", "analysis.design_rope_angle_deg", "less than 90",
         data=_set("analysis", design_rope_angle_deg=120)),
    Case("payload share 0", "analysis.payload_share", "at least 1",
         data=_set("analysis", payload_share=0)),
    Case("negative gravity", "analysis.gravity", "greater than 0",
         data=_set("analysis", gravity=-9.81)),
    Case("gravity 1e300", "analysis.gravity", "at most 30", data=_set("analysis", gravity=1e300)),
    Case("expo 2", "operator.expo", "at most 1", data=_set("operator", expo=2)),
    Case("deadzone 1", "operator.deadzone", "less than 1", data=_set("operator", deadzone=1.0)),
    Case("stale after 0 s", "safety.stale_after", "greater than 0",
         data=_set("safety", stale_after=0)),
    Case("position 1e300", "vehicles[0].position[0]", "at most 10000",
         data=_vehicle(0, position=[1e300, 0.5])),
    Case("negative edge distance", "edges[0].distance", "greater than 0",
         data=_edge(0, [1, 2, -1.0])),
    Case("GCS id 255", "gcs", "255", data=_set("gcs", system_id=255)),
    Case("link sysid 0", "links[0].sysid", "at least 1", data=_links(sysid=0)),
    Case("integer of 400 digits", "guidance.c1", "out of range",
         text=lambda t: t.replace("c1: 0.17", "c1: " + "9" * 400)),
    Case("integer of 5000 digits", "guidance.c1", "out of range",
         text=lambda t: t.replace("c1: 0.17", "c1: " + "9" * 5000)),
    Case("number of 1e400", "guidance.c1", "must be finite",
         text=lambda t: t.replace("c1: 0.17", "c1: 1e400")),
    Case("rate 1.0e9 (a YAML 1.2 number)", "guidance.rate_hz", "at most 50, got 1e+09",
         text=lambda t: t.replace("rate_hz: 4.0", "rate_hz: 1.0e9")),
    # -- not finite
    Case("c1 nan", "guidance.c1", "finite", data=_set("guidance", c1=NAN)),
    Case("payload mass inf", "payload.mass", "finite", data=_set("payload", mass=INF)),
    Case("position nan", "vehicles[0].position[0]", "finite",
         data=_vehicle(0, position=[NAN, 0.5])),
    Case("edge distance inf", "edges[0].distance", "finite", data=_edge(0, [1, 2, INF])),
    Case("gravity -inf", "analysis.gravity", "finite", data=_set("analysis", gravity=-INF)),
    Case("inline airframe mass nan", "airframe.mass", "finite", data=_inline_frame(mass=NAN)),
    Case("altitude max inf", "operator.altitude_max", "finite",
         data=_set("operator", altitude_max=INF)),
    # -- contradictions
    Case("scale range above 1", "guidance", "must bracket 1", data=_set("guidance", scale_min=1.2)),
    Case("scale range upside down", "guidance", "must bracket 1",
         data=_set("guidance", scale_min=0.9, scale_max=0.5)),
    Case("scale step beyond the range", "guidance.scale_step", "scale range",
         data=_set("guidance", scale_step=5.0)),
    Case("altitude range upside down", "operator.altitude_min", "above operator.altitude_max",
         data=_set("operator", altitude_min=3.0, altitude_max=1.0)),
    Case("altitude step beyond the range", "operator.altitude_step", "altitude range",
         data=_set("operator", altitude_step=10.0)),
    Case("land before stale", "safety", "land_after", data=_set("safety", land_after=0.1)),
    Case("geofence margin wider than the fence", "safety", "geofence_margin",
         data=_set("safety", geofence_margin=5.0)),
    Case("altitude above the geofence", "operator.altitude_max", "safety.geofence_altitude",
         data=_set("operator", altitude_max=10.0)),
    Case("lift above the highest altitude", "flight.lift_height", "operator.altitude_max",
         data=_set("flight", lift_height=5.0)),
    Case("take-off under the ground", "flight.takeoff_slack", "below the ground",
         data=_set("flight", takeoff_slack=2.0)),
    Case("pickup band below zero", "flight.pickup_band", "non-negative",
         data=_set("flight", pickup_band=[-0.1, 0.15])),
    Case("pickup faster than the lift", "flight.pickup_rate", "flight.lift_rate",
         data=_set("flight", pickup_rate=0.5)),
    Case("payload that cannot be set down", "operator.altitude_min", "set down",
         data=_set("operator", altitude_min=1.0)),
    Case("geofence smaller than the team", "safety.geofence_xy", "guidance.scale_max",
         data=_set("safety", geofence_xy=1.0, geofence_margin=0.1)),
    Case("axis limit above the norm", "limits.accel_axis", "exceeds limits.accel_norm",
         data=_set("limits", accel_axis=3.0)),
    Case("setpoints not a multiple", "guidance", "whole multiple",
         data=_set("guidance", setpoint_rate_hz=10.0)),
    Case("vehicles closer than their rotors", "vehicles", "collide",
         data=lambda d: [v.update(position=[0.1 * x for x in v["position"]])
                         for v in d["vehicles"]]),
    Case("vehicles collide at the smallest scale", "guidance.scale_min", "collide",
         data=_set("guidance", scale_min=0.1)),
    Case("distance off the positions", "edges[1].distance", "does not fit",
         data=_edge(1, [2, 4, 1.2])),
    Case("signing key missing", "links[0].signing_key", "cannot read",
         data=_links(signing_key="absent.key")),
    Case("signing key too short", "links[0].signing_key", "32 raw bytes",
         data=_links(signing_key="short.key")),
    Case("two links on one port", "links[1].transport", "already used",
         data=lambda d: d.update(links=[{"sysid": i, "transport": "udpin:0.0.0.0:14550"}
                                        for i in (1, 2, 3, 4)])),
    # -- physically impossible airframes and teams
    Case("airframe cannot hover", "thrust_coefficient", "cannot hover",
         frame={"thrust_coefficient": 1e-7}),
    Case("airframe thrust reference beyond its rotors", "thrust_reference",
         "exceeds the full-speed thrust", frame={"thrust_reference": 20.0}),
    Case("airframe inertia impossible", "inertia", "triangle inequality",
         frame={"inertia": [0.001, 0.001, 0.01]}),
    Case("inline airframe of 1000 kg", "airframe.thrust_coefficient", "cannot hover",
         data=_inline_frame(mass=1000.0)),
    Case("airframe mass negative", "mass", "greater than 0", frame={"mass": -1.0}),
    Case("airframe missing its mass", "mass", "missing required field", frame={"mass": None}),
    Case("ropes too short to reach", "payload.rope_length", "cannot reach",
         data=_set("payload", rope_length=0.6)),
    Case("payload too heavy for the thrust", "airframe.thrust_reference", "cannot carry",
         code=1, data=_set("payload", mass=2.0)),
    Case("payload too heavy to lift at all", "airframe.thrust_max", "cannot lift", code=1,
         data=_set("payload", mass=4.0)),
    Case("gains beyond eq. max", "guidance.c1", "eq. max", code=1,
         data=_set("guidance", c1=2.0)),
    Case("acceleration beyond the analysis", "limits.accel_norm", "exceeds", code=1,
         data=_set("limits", accel_norm=3.0, accel_axis=2.0)),
    Case("bank beyond the largest tilt", "limits.bank_deg", "largest tilt", code=1,
         data=_set("limits", bank_deg=50.0)),
    # -- missing and unknown fields
    Case("missing name", "name", "missing required field", data=_drop("name")),
    Case("missing vehicles", "vehicles", "missing required field", data=_drop("vehicles")),
    Case("missing edges", "edges", "missing required field", data=_drop("edges")),
    Case("missing airframe", "airframe", "missing required field", data=_drop("airframe")),
    Case("missing c2", "guidance.c2", "missing required field", data=_drop("guidance", "c2")),
    Case("missing analysis", "analysis", "missing required field", data=_drop("analysis")),
    Case("unknown top-level field", "vehicle", "unknown field", data=_top(vehicle=[])),
    Case("unknown guidance field", "guidance.C1", "unknown field", data=_set("guidance", C1=1)),
    Case("unknown vehicle field", "vehicles[0].pos", "unknown field",
         data=_vehicle(0, pos=[0, 0])),
    Case("no vehicles", "vehicles", "at least 2", data=_top(vehicles=[])),
    Case("no edges", "edges", "at least 1", data=_top(edges=[])),
    Case("one vehicle", "vehicles", "at least 2", data=lambda d: d.update(
        vehicles=d["vehicles"][:1], edges=[[1, 2]])),
    Case("a vehicle without a position", "vehicles[1].position", "missing",
         data=lambda d: d["vehicles"][1].pop("position")),
    Case("an edge of one value", "edges[0]", "expected [tail, head]", data=_edge(0, [1])),
    Case("an edge to an unknown vehicle", "edges[3].head", "unknown vehicle id 7",
         data=_edge(3, [1, 7])),
    Case("an edge to itself", "edges[0]", "to itself", data=_edge(0, [1, 1])),
    Case("an edge listed twice", "edges[1]", "listed twice", data=_edge(1, [2, 1])),
    Case("a duplicate vehicle id", "vehicles", "appears twice", data=_vehicle(2, id=1)),
    Case("not rigid", "edges", "not rigid",
         data=_top(edges=[[1, 2], [2, 3], [3, 4], [4, 1]])),
    Case("collinear", "edges", "collinear",
         data=lambda d: d.update(vehicles=[{"id": k + 1, "position": [float(k), 0.0]}
                                           for k in range(4)],
                                 edges=[[i, j] for i in range(1, 5) for j in range(i + 1, 5)])),
    Case("two vehicles in one place", "edges[0]", "same position",
         data=_vehicle(1, position=[0.5, 0.5])),
    Case("a vehicle without a link", "vehicles[3].id", "no entry under links",
         data=lambda d: d.update(links=[{"sysid": i} for i in (1, 2, 3)])),
    Case("a duplicate key", "guidance.c1", "given twice",
         text=lambda t: t.replace("  c1: 0.17\n", "  c1: 0.17\n  c1: 0.9\n")),
    Case("a duplicate section", "limits", "given twice",
         text=lambda t: t + "limits: {bank_deg: 80, accel_norm: 9, accel_axis: 9}\n"),
    # -- files
    Case("binary", "line 1", "not a text file", raw=bytes(range(256)) * 8),
    Case("UTF-16", "", "UTF-16", raw=SQUARE_TEXT.encode("utf-16")),
    Case("UTF-16 without a BOM", "", "UTF-16", raw=SQUARE_TEXT.encode("utf-16-le")),
    Case("Latin-1 comment", "line", "not UTF-8 text",
         raw=SQUARE_BYTES + "# réglage\n".encode("latin-1")),
    Case("a NUL byte", "line 2", "NUL", raw=b"name: x\n\x00\n"),
    Case("a control character", "line 1", "invalid YAML", raw=b"name: x\x07y\n"),
    Case("huge (comments)", "", "too large", raw=SQUARE_BYTES + b"# pad\n" * 200_000),
    Case("huge (a list)", "", "too large",
         raw=b"vehicles:\n" + b"  - {id: 1, position: [0.5, 0.5]}\n" * 100_000),
    Case("nested 10 000 deep", "line 1", "nested too deeply",
         raw=b"name: " + b"[" * 10_000 + b"]" * 10_000 + b"\n"),
    Case("nested 50 000 mappings deep", "line 1", "nested too deeply",
         raw=b"name: " + b"{a: " * 50_000 + b"1" + b"}" * 50_000 + b"\n"),
    Case("indented 300 deep", "line", "nested too deeply",
         raw=b"".join(b" " * i + b"a:\n" for i in range(300))),
    Case("a billion laughs", "a", "unknown field", raw=b"a: &a [1, 1, 1, 1, 1, 1, 1, 1, 1]\n" +
         b"".join(b"%c: &%c [" % (c, c) + b", ".join([b"*%c" % (c - 1)] * 9) + b"]\n"
                  for c in range(ord("b"), ord("j")))),
    Case("malformed YAML", "line", "invalid YAML", raw=b"name: x\nvehicles: [1, 2\n"),
    Case("tab indentation", "line", "invalid YAML", raw=b"guidance:\n\tc1: 0.17\n"),
    Case("a python tag", "line", "invalid YAML", raw=b"name: !!python/object:os.system x\n"),
    Case("airframe a directory", "airframe", "is a directory", data=_top(airframe=".")),
    Case("airframe missing", "airframe", "not found", data=_top(airframe="absent.yaml")),
    Case("airframe binary", "line 1", "not a text file", frame=bytes(range(256))),
    Case("airframe UTF-16", "", "UTF-16", frame=BEBOP2.read_text().encode("utf-16")),
]


def _write(case: Case, folder: Path) -> tuple[Path, Path]:
    """Write the case's files; (the team file, the file its error must name)."""
    folder.mkdir()
    path = folder / "team.yaml"
    named = path
    (folder / "short.key").write_text("0123\n")
    data = yaml.safe_load(SQUARE_TEXT)
    data["airframe"] = str(BEBOP2.resolve())
    if case.frame is not None:
        named = folder / "frame.yaml"
        if isinstance(case.frame, bytes):
            named.write_bytes(case.frame)
        else:
            frame = yaml.safe_load(BEBOP2.read_text())
            for key, value in case.frame.items():
                if value is None:
                    del frame[key]
                else:
                    frame[key] = value
            named.write_text(yaml.safe_dump(frame))
        data["airframe"] = str(named)
    if case.raw is not None:
        path.write_bytes(case.raw)
    elif case.text is not None:
        path.write_text(case.text(SQUARE_TEXT.replace("airframes/bebop2.yaml",
                                                      str(BEBOP2.resolve()))))
    else:
        if case.data is not None:
            data = copy.deepcopy(data)
            case.data(data)
        path.write_text(yaml.safe_dump(data))
    return path, named


def _analyze_in_child(path: str, conn: Connection) -> None:
    """``gcs analyze PATH`` in this (forked) process; sends what it printed and took."""
    from gcs.cli import main

    out, err = io.StringIO(), io.StringIO()
    wall, cpu = time.monotonic(), time.process_time()
    code: int | None = None
    trace = ""
    try:
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            code = main(["analyze", path])
    except BaseException:  # a traceback is what the table counts
        trace = traceback.format_exc()
    conn.send((code, out.getvalue(), err.getvalue(), trace, time.monotonic() - wall,
               time.process_time() - cpu))
    conn.close()


@dataclass(frozen=True)
class Outcome:
    """What one case did, and how the table counts it."""

    kind: str  # clear error, correct violation, traceback, hang, accepted nonsense, unclear
    code: int | None
    stdout: str
    stderr: str
    trace: str
    cpu: float
    wall: float


def _classify(case: Case, named: Path, result: tuple[Any, ...] | None) -> Outcome:
    if result is None:
        return Outcome("hang", None, "", "", "", HANG_S, HANG_S)
    code, out, err, trace, wall, cpu = result
    if trace or "Traceback" in err:
        kind = "traceback"
    elif cpu > CPU_LIMIT_S:
        kind = "hang"
    elif code == 0:
        kind = "accepted nonsense"
    elif code == 2:
        lines = err.splitlines()
        head = f"gcs analyze: error: {named}: {case.field}"
        clear = (case.code == 2 and out == "" and len(lines) == 1
                 and lines[0].startswith(head) and case.words in lines[0])
        kind = "clear error" if clear else "unclear error"
    elif code == 1:
        hits = [line for line in out.splitlines() if line.startswith("VIOLATION ")]
        clear = (case.code == 1 and err == "" and any(
            line.startswith(f"VIOLATION {case.field}") and case.words in line for line in hits))
        kind = "correct violation" if clear else "unclear error"
    else:
        kind = "unclear error"
    return Outcome(kind, code, out, err, trace, cpu, wall)


@pytest.fixture(scope="module")
def outcomes(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Outcome]:
    """Every case through ``gcs analyze``, each in a process forked from a loaded server."""
    ctx = multiprocessing.get_context("forkserver")
    ctx.set_forkserver_preload(["gcs.cli", "gcs.analysis", "gcs.config", __name__])
    root = tmp_path_factory.mktemp("bad_configs")
    results: dict[str, Outcome] = {}
    for k, case in enumerate(CASES):
        path, named = _write(case, root / f"case{k:03d}")
        receive, send = ctx.Pipe(duplex=False)
        child = ctx.Process(target=_analyze_in_child, args=(str(path), send))
        child.start()
        send.close()
        result = receive.recv() if receive.poll(HANG_S) else None
        if result is None:
            child.kill()
        child.join()
        results[case.name] = _classify(case, named, result)
    return results


KINDS = ["clear error", "correct violation", "traceback", "hang", "accepted nonsense",
         "unclear error"]


def table(outcomes: dict[str, Outcome]) -> str:
    """The count table, and the cases that went wrong."""
    counts = {kind: sum(o.kind == kind for o in outcomes.values()) for kind in KINDS}
    lines = [f"gcs analyze on {len(outcomes)} bad team configs:"]
    lines += [f"  {kind:<18} {counts[kind]:4d}" for kind in KINDS]
    slowest = max(outcomes.items(), key=lambda item: item[1].cpu)
    lines.append(f"  slowest: {slowest[0]} ({slowest[1].cpu:.2f} s CPU, "
                 f"{slowest[1].wall:.2f} s)")
    for name, o in outcomes.items():
        if o.kind not in ("clear error", "correct violation"):
            said = (o.trace.strip().splitlines() or o.stderr.splitlines()
                    or o.stdout.splitlines()[-1:] or [""])[-1]
            lines.append(f"  {o.kind}: {name}: exit {o.code}: {said[:200]}")
    return "\n".join(lines)


def test_there_are_at_least_80_bad_configs() -> None:
    assert len(CASES) >= 80
    assert len({c.name for c in CASES}) == len(CASES)


@pytest.mark.parametrize("case", CASES, ids=[c.name for c in CASES])
def test_a_bad_config_is_refused_clearly(outcomes: dict[str, Outcome], case: Case) -> None:
    o = outcomes[case.name]
    want = "clear error" if case.code == 2 else "correct violation"
    assert o.kind == want, (f"{o.kind} (exit {o.code}, {o.cpu:.2f} s CPU)\n"
                            f"stderr: {o.stderr}\nstdout: {o.stdout[-800:]}\n{o.trace}")


def test_the_count_table(outcomes: dict[str, Outcome]) -> None:
    print("\n" + table(outcomes))
    wanted = {"clear error": sum(c.code == 2 for c in CASES),
              "correct violation": sum(c.code == 1 for c in CASES)}
    assert {kind: sum(o.kind == kind for o in outcomes.values()) for kind in KINDS} == {
        **dict.fromkeys(KINDS, 0), **wanted}, table(outcomes)
