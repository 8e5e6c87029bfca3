"""The status panel and the plots' history, from the loop's own snapshots."""

from __future__ import annotations

import dataclasses
import html as html_lib
import math
import re

import numpy as np
import pytest

from gcs.analysis import analyze
from gcs.config import LinkConfig, load_team
from gcs.guidance import MotionDemand
from gcs.link import LinkHealth
from gcs.loop import (
    Event,
    FenceVerdict,
    FleetState,
    OperatorSnapshot,
    Phase,
    RuntimeSnapshot,
    TickStats,
)
from gcs.loop._safety import SafetyEvent, SafetyReason, SafetyVerdict
from gcs.wire import SimTruth
from tests.support.paths import ROOT
from web import TeamView, palette
from web._frame import rope_pull_estimate
from web._history import History
from web._status import (
    UiStats,
    event_filter_html,
    events_html,
    position_sources,
    signing_banner_html,
    summary_html,
    vehicles_html,
)

TEAM = load_team(ROOT / "configs" / "bebop_square.yaml")
VIEW = TeamView.from_team(TEAM, analyze(TEAM))
G = 9.80665


def snapshot(t: float = 5.0, *, xy: np.ndarray | None = None, v: np.ndarray | None = None,
             scale: float = 1.0, source: str = "browser#0", truth: SimTruth | None = None,
             safety: SafetyVerdict | None = None,
             events: tuple[Event, ...] = ()) -> RuntimeSnapshot:
    n = VIEW.n
    xy = VIEW.desired_xy if xy is None else xy
    fleet = FleetState(t=t, ids=VIEW.ids, p_ned=np.column_stack((xy, np.full(n, -1.8))),
                       v_ned=np.zeros((n, 3)) if v is None else v, yaw=np.zeros(n),
                       tilt=np.array([0.0, 0.1, 0.2, np.nan]), age=np.full(n, 0.05),
                       heartbeat_age=np.full(n, 0.4), armed=np.array([1, 1, 1, 0], bool),
                       battery=np.array([90.0, 80.0, 70.0, np.nan]),
                       modes=("OFFBOARD", "OFFBOARD", "HOLD", "DISARMED"))
    demand = MotionDemand(forward=0.5, right=-0.25, rotate=0.0, scale=scale)
    op = OperatorSnapshot(demand=demand, altitude=1.5, altitude_target=1.8,
                          scale_target=scale, guidance_on=True, source=source)
    return RuntimeSnapshot(fleet=fleet, phase=Phase.FORMATION, operator=op, demand=demand,
                           accel_cmd=np.zeros((n, 2)), distance_errors=np.zeros(len(VIEW.edges)),
                           safety=safety or SafetyVerdict(freeze=False, land=False, events=()),
                           compute_time=0.001, events=events, truth=truth)


def test_rope_pull_from_tilt() -> None:
    tilt = np.array([0.0, 0.3, 0.3, np.nan])
    accel = np.array([[0.0, 0.0], [0.0, 0.0], [G * math.tan(0.3), 0.0], [0.0, 0.0]])
    pull = rope_pull_estimate(0.4, tilt, accel)
    assert pull[0] == 0.0
    assert pull[1] == pytest.approx(0.4 * G * math.tan(0.3))
    assert pull[2] == pytest.approx(0.0, abs=1e-12)  # the command explains the tilt
    assert math.isnan(pull[3])


def test_summary_shows_phase_command_control_payload_and_timing() -> None:
    truth = SimTruth(t=5.0, ids=VIEW.ids, vehicle_p_ned=((0.0, 0.0, 0.0),) * 4,
                     payload_p_ned=(0.1, 0.2, -0.75), payload_v_ned=(0.3, 0.4, 0.0),
                     rope_tension=(1.2,) * 4)
    html = summary_html(snapshot(source="<b>evil</b>", truth=truth),
                        loop=TickStats(ticks=40, compute_last=0.001, compute_p99=0.002,
                                       jitter_p99=0.004, overruns=1),
                        control="viewer #2", ui=UiStats(rate_hz=25.0, draw_ms=1.2,
                                                       draw_p99_ms=2.5))
    assert re.search(r'data-gcs="phase"[^>]*>formation<', html)
    op = re.search(r'data-gcs="operator">([^<]*)<', html).group(1)  # type: ignore[union-attr]
    assert "fwd +0.50" in op and "right -0.25" in op and "alt 1.50 → 1.80 m" in op
    assert "&lt;b&gt;evil&lt;/b&gt;" in op  # a source name is text, never markup
    assert 'data-gcs="control">viewer #2<' in html
    assert "0.75 m up at (0.10, 0.20) m, speed 0.50 m/s" in html
    assert 'data-gcs="ui-rate">25.0<' in html and "overruns 1" in html
    assert "waiting" in summary_html(None, loop=None, control="", ui=None)
    grounded = SimTruth(t=5.0, ids=VIEW.ids, vehicle_p_ned=((0.0, 0.0, 0.0),) * 4,
                        payload_p_ned=(-0.001, 0.0, 0.0002), payload_v_ned=(0.0, 0.0, 0.0),
                        rope_tension=(0.0,) * 4)
    assert "0.00 m up at (0.00, 0.00) m" in summary_html(snapshot(truth=grounded), loop=None,
                                                         control="", ui=None)


def test_the_rope_legend_says_whether_ropes_are_measured_or_estimated() -> None:
    truth = SimTruth(t=5.0, ids=VIEW.ids, vehicle_p_ned=((0.0, 0.0, 0.0),) * 4,
                     payload_p_ned=(0.1, 0.2, -0.75), payload_v_ned=(0.3, 0.4, 0.0),
                     rope_tension=(1.2,) * 4)

    def legend(snap: RuntimeSnapshot) -> str:
        html = summary_html(snap, loop=None, control="", ui=None)
        return re.search(r'data-gcs="ropes"[^>]*>(.*?)</span></div>', html).group(1)  # type: ignore[union-attr]

    assert legend(snapshot(truth=truth)).startswith("tension (simulator)")
    estimated = legend(snapshot())  # real vehicles: no truth
    assert estimated.startswith("horizontal pull estimated from tilt")
    r, g, b = palette.TAUT
    assert "nominal (eq. Th)" in estimated and f"rgb({r},{g},{b})" in estimated
    partial = SimTruth(t=5.0, ids=VIEW.ids[:2], vehicle_p_ned=((0.0, 0.0, 0.0),) * 2,
                       payload_p_ned=(0.1, 0.2, -0.75), payload_v_ned=(0.3, 0.4, 0.0),
                       rope_tension=(1.2,) * 2)
    assert "estimated" in legend(snapshot(truth=partial))  # as the scene: truth for all or none
    rows = vehicles_html(snapshot(), health={}, truth=None, mass=0.4, stale_after=0.5)
    assert 'title="horizontal rope pull estimated from tilt' in rows


def test_the_safety_state_is_a_banner_with_its_reasons_and_vehicles() -> None:
    """Ok, frozen, landing: a banner each (it was a word of small orange text), naming
    each rule once with the vehicles it covers."""
    def banner(safety: SafetyVerdict) -> tuple[str, str]:
        html = summary_html(snapshot(safety=safety), loop=None, control="", ui=None)
        m = re.search(r'data-gcs-banner="safety" data-gcs-safety="(\w+)"[^>]*>([^<]*)<', html)
        assert m is not None, html
        return m.group(1), html_lib.unescape(m.group(2))

    assert banner(SafetyVerdict(freeze=False, land=False, events=())) == ("ok", "SAFETY OK")
    stale = tuple(SafetyEvent(SafetyReason.STALE, vid, f"vehicle {vid}: stale")
                  for vid in (3, 1, 2))
    state, text = banner(SafetyVerdict(freeze=True, land=False, events=stale))
    assert state == "frozen"
    assert text == "MOTION FROZEN: telemetry is stale — vehicles 1,2,3"
    lost = SafetyEvent(SafetyReason.LOST, 4, "vehicle 4: lost")
    state, text = banner(SafetyVerdict(freeze=True, land=True, events=(*stale, lost)))
    assert state == "landing"
    assert text == ("LANDING THE TEAM: telemetry is stale — vehicles 1,2,3; "
                    "link lost — vehicle 4")
    assert banner(SafetyVerdict(freeze=True, land=False, events=()))[0] == "waiting"
    held = summary_html(snapshot(safety=SafetyVerdict(freeze=True, land=False, events=(),
                                                      hold=True, deformation=1.2)),
                        loop=None, control="", ui=None)
    assert 'data-gcs-banner="safety"' not in held and 'data-gcs-banner="hold"' in held


def test_recovery_hold_and_geofence_are_banners() -> None:
    """What the operator must act on or know at once is a banner, not a line that scrolls
    away in the events: vehicles waiting for Resume, a held team, the geofence."""
    plain = summary_html(snapshot(), loop=None, control="", ui=None)
    assert re.findall(r'data-gcs-banner="(\w+)"', plain) == ["safety"]  # ok, and nothing more
    waiting = dataclasses.replace(
        snapshot(), recovery="vehicles 2, 3 out of the streaming mode: press Resume to fly "
                             "them again")
    html_ = summary_html(waiting, loop=None, control="", ui=None)
    assert 'data-gcs-banner="recovery"' in html_ and "press Resume" in html_
    held = SafetyVerdict(freeze=True, land=False, events=(), hold=True, deformation=1.2)
    html_ = summary_html(snapshot(safety=held), loop=None, control="", ui=None)
    assert 'data-gcs-banner="hold"' in html_ and "HOLDING" in html_
    fence = FenceVerdict(MotionDemand(), near=("east",), outside=(), above=False)
    html_ = summary_html(dataclasses.replace(snapshot(), fence=fence), loop=None, control="",
                         ui=None)
    assert 'data-gcs-banner="fence"' in html_ and "at the geofence (east)" in html_


def _cells(html: str, key: str) -> dict[str, list[str]]:
    rows = dict(re.findall(rf'data-gcs="{key}-(\d)">(.*?)</tr>', html))
    return {vid: [html_lib.unescape(re.sub("<[^>]+>", "", c)).strip()
                  for c in re.findall(r"<td[^>]*>(.*?)</td>", row)] for vid, row in rows.items()}


def test_vehicle_rows_show_state_mode_battery_tilt_rope_and_link() -> None:
    health = {1: LinkHealth(sysid=1, heartbeat_age_s=0.4, alive=True, frames_received=100,
                            frames_sent=50, packets_lost=3, refused_bad_crc=1,
                            refused_signature=0, refused_wrong_system=1, foreign_systems=(),
                            garbage_bytes=0, truncated=0, rtt_s=0.012)}
    stale = dataclasses.replace(snapshot(), fleet=dataclasses.replace(
        snapshot().fleet, age=np.array([0.05, 0.05, 0.05, 0.8])))
    html = vehicles_html(stale, health=health, truth=None, mass=0.4, stale_after=0.5,
                         voltage=np.array([11.94, 11.5, np.nan, 10.0]),
                         quality={1: 97.04, 2: 0.0},
                         sources={1: "local NED (shared)", 2: "local NED <x>"})
    vehicles, links = _cells(html, "vehicle"), _cells(html, "link")
    assert vehicles["1"] == ["1", "● ok", "OFFBOARD", "yes", "90", "11.9", "1.80", "0.0", "0.4",
                             "0.05", "0.00"]
    assert links["1"] == ["1", "97", "3", "2", "12", "local NED (shared)"]
    assert links["2"] == ["2", "0", "–", "–", "–", "local NED <x>"]  # escaped, then read back
    assert "local NED &lt;x&gt;" in html
    assert "holding" in vehicles["3"][1] and vehicles["3"][2] == "HOLD"
    assert vehicles["3"][5] == "–"  # no voltage known
    four = vehicles["4"]
    assert four[1] == "● stale" and four[9] == "0.8"  # the position's age, past stale_after
    assert 'color:#c0392b">0.8<' in html
    assert four[3:5] == ["no", "–"] and four[7] == "–"  # unknown
    assert links["4"] == ["4", "–", "–", "–", "–", "–"]  # no link data
    assert "rope pull ≈ N" in html
    truth = SimTruth(t=5.0, ids=(4, 3, 2, 1), vehicle_p_ned=((0.0, 0.0, 0.0),) * 4,
                     payload_p_ned=(0.0, 0.0, -0.7), payload_v_ned=(0.0, 0.0, 0.0),
                     rope_tension=(4.0, 3.0, 2.0, 1.25))
    measured = vehicles_html(snapshot(), health={}, truth=truth, mass=0.4, stale_after=0.5)
    assert "rope N (sim)" in measured
    assert _cells(measured, "vehicle")["1"][10] == "1.25"


def test_events_show_conditions_then_the_log_newest_first_escaped_and_coloured() -> None:
    events = tuple(Event(t=float(k), level=lvl, text=txt) for k, (lvl, txt) in enumerate(
        [("info", "phase: hover"), ("warning", "vehicle 2: <stale>"), ("error", "oops")]))
    html = events_html(events, start=1.0)
    top, log = html.split('data-gcs="event-log"')
    assert top.index("oops") < top.index("&lt;stale&gt;") and "phase: hover" not in top
    assert log.index("oops") < log.index("&lt;stale&gt;") < log.index("phase: hover")
    assert "#c0392b" in html and "#e67e22" in html
    assert re.search(r'data-level="info"><div[^>]*><span[^>]*>\s*-1.0 s</span> phase: hover<',
                     log)
    assert "no events" in events_html(())
    assert "no warnings" in events_html(events[:1])


def test_the_event_filter_hides_lower_levels_in_the_page() -> None:
    html = event_filter_html()
    assert re.findall(r'value="(\w+)"', html) == ["info", "warning", "error"]
    assert 'value="info" checked' in html
    assert ("input[value=error]:checked) [data-gcs=event-log] :is([data-level=info], "
            "[data-level=warning]){display:none}") in html


def test_history_keeps_a_window_of_distances_and_velocities() -> None:
    history = History(VIEW, window=10.0)
    for k in range(60):
        t = 0.25 * k
        v = np.tile([0.1 * k, -0.05 * k, 0.0], (4, 1))
        assert history.add(snapshot(t, xy=1.1 * VIEW.desired_xy, v=v, scale=1.1))
    assert not history.add(snapshot(14.75))  # the same tick again
    assert not history.add(snapshot(20.0, xy=np.full((4, 2), np.nan)))  # team not known
    s = history.series()
    assert s.t[0] >= 14.75 - 10.0 and s.t[-1] == 14.75 and len(history) == len(s.t) == 41
    np.testing.assert_allclose(s.distance, 1.1 * np.tile(VIEW.distances, (41, 1)))
    np.testing.assert_allclose(s.desired, s.distance)
    np.testing.assert_allclose(s.vx[-1], 5.9)
    np.testing.assert_allclose(s.vy[-1], -2.95)
    empty = History(VIEW).series()
    assert empty.distance.shape == (0, len(VIEW.edges)) and empty.vx.shape == (0, 4)


def test_the_position_source_follows_the_team_frame() -> None:
    """The simulator's team: its shared local frame; real autopilots (team_frame auto):
    each placed through its GPS origin; an origin the GCS sets, said so."""
    assert set(position_sources(TEAM).values()) == {"local NED (shared)"}
    px4 = tuple(LinkConfig(sysid=vid, transport=f"udpin:0.0.0.0:{14550 + vid}", profile="px4")
                for vid in (1, 2))
    mixed = dataclasses.replace(TEAM, config=dataclasses.replace(TEAM.config, links=px4 + tuple(
        LinkConfig(sysid=vid) for vid in (3, 4))))
    assert position_sources(mixed) == {1: "local NED + GPS origin", 2: "local NED + GPS origin",
                                       3: "local NED (shared)", 4: "local NED (shared)"}
    told = dataclasses.replace(mixed, config=dataclasses.replace(
        mixed.config, team_frame=dataclasses.replace(mixed.config.team_frame, mode="shared")))
    assert set(position_sources(told).values()) == {"local NED (shared)"}


def test_unsigned_links_are_a_red_banner() -> None:
    assert signing_banner_html([]) == ""
    one = signing_banner_html([3])
    assert 'data-gcs-banner="signing"' in one and "#c0392b" in one
    assert "UNSIGNED LINK: vehicle 3 obeys anyone" in one
    assert "vehicles 1, 2 obey anyone" in signing_banner_html([1, 2])
    page = summary_html(snapshot(), loop=None, control="", ui=None, unsigned=[2])
    assert "UNSIGNED LINK: vehicle 2" in page
    assert "UNSIGNED" not in summary_html(snapshot(), loop=None, control="", ui=None)
