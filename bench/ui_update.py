"""The live page's cost and update rate, for 4 and 100 vehicles.

Why: the page's UI thread shares the GCS process (and its GIL) with the 4 Hz
guidance loop, so a frame must stay cheap (target: 2 ms for the paper's four
vehicles), and a viewer must see the team move at 20 updates a second or more.

Two measurements per team size, each with one real websocket viewer attached
(``web.wireviewer.WireViewer``):

* **frame cost** (server side): a real viser server and the page's scene
  (``web.SceneView``), the team moving every frame (positions,
  headings, velocities, rope tensions all change: the worst case for viser's
  send-only-what-changed), frames back to back. Reported: building the
  frame's arrays and handing them to viser (median and p99, ms) and the
  process CPU time per frame (which includes viser's serialisation on its
  own thread). The viewer here reads and discards (``decode=False``): it
  shares the measured process, and decoding there would be counted in the
  CPU time and compete with the timed frames for the GIL.
* **received rate**: the real page (``web.WebUi``: scene, status and plots,
  the viewer's panel and camera follow) of a real ``GcsApp`` whose telemetry
  and simulator truth are a moving team fed into its fleet table (no
  simulator: 100 simulated vehicles would measure the simulator). The viewer
  is its own process (``python -m web.wireviewer``), as a browser is, so its
  decoding does not share the page's GIL. Reported: how many windows per
  second carrying new vehicle positions the viewer *received* (not how often
  the UI thread drew: viser merges what is queued within a send window), the
  bytes per second it received, and the page's own frame rate and cost (its
  status line) meanwhile. Target: >= 20 Hz received.

    python bench/ui_update.py                            # a table, then one JSON object
    python bench/ui_update.py --frames 40 --seconds 2    # a quick smoke run
"""

from __future__ import annotations

import argparse
import json
import math
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import viser
import yaml

from gcs.analysis import analyze
from gcs.app import GcsApp, free_tcp_port
from gcs.config import Team, load_team
from gcs.loop import FleetState, FleetTable
from gcs.transport import ZenohSettings
from gcs.wire import SimTruth
from web import UI_RATE_HZ, SceneView, TeamView, Trails, WebUi, build_frame, quad_mesh
from web.wireviewer import WireViewer

ROOT = Path(__file__).resolve().parents[1]
SQUARE = ROOT / "configs" / "bebop_square.yaml"
FRAMES = 400
SECONDS = 6.0
WARMUP_S = 2.0
RATE_TARGET_HZ = 20.0
"""The issue's target for the UI update rate a viewer receives."""
CAMERA = ((-8.0, -2.0, -6.0), (0.0, 0.0, -1.0))
"""Where the frame-cost viewer looks from and at (NED), as a browser reports it."""


def moving_fleet(view: TeamView, t: float) -> tuple[FleetState, SimTruth]:
    """The team spinning slowly about a centroid that drifts north, 1.8 m up."""
    n = view.n
    c, s = math.cos(0.3 * t), math.sin(0.3 * t)
    xy = view.desired_xy @ np.array([[c, s], [-s, c]]) + [0.2 * t, 0.0]
    p = np.column_stack((xy, np.full(n, -1.8)))
    v = np.column_stack((-0.3 * xy[:, 1] + 0.2, 0.3 * xy[:, 0], np.zeros(n)))
    fleet = FleetState(t=t, ids=view.ids, p_ned=p, v_ned=v, yaw=np.full(n, 0.3 * t),
                       tilt=np.full(n, 0.15), age=np.full(n, 0.04), heartbeat_age=np.full(n, 0.3),
                       armed=np.ones(n, dtype=bool), battery=np.full(n, 90.0),
                       modes=("OFFBOARD",) * n)
    centroid = p.mean(axis=0)
    truth = SimTruth(t=t, ids=view.ids, vehicle_p_ned=tuple(map(tuple, p)),
                     payload_p_ned=(float(centroid[0]), float(centroid[1]), -0.8),
                     payload_v_ned=(0.2, 0.0, 0.0),
                     rope_tension=tuple(1.3 + 0.1 * np.sin(t + np.arange(n))))
    return fleet, truth


def ring_config(n: int, radius: float, directory: Path) -> Path:
    """A team file of ``n`` vehicles on a circle (each joined to its two neighbours on
    each side), the paper's airframe and gains; its GCS joins no zenoh peer. The circle
    grows to keep neighbours 0.6 m apart (clear of each other's rotors), and the shape
    is never shrunk."""
    radius = max(radius, 0.6 * n / (2 * np.pi))
    config = SQUARE.read_text()
    head, _, rest = config.partition("\nvehicles:")
    guidance = rest[rest.index("\nguidance:"):]
    a = 2 * np.pi * np.arange(n) / n
    lines = [head.replace("name: bebop_square", f"name: ring{n}")
             .replace("airframe: airframes/", f"airframe: {SQUARE.parent / 'airframes'}/"),
             "vehicles:"]
    lines += [f"  - {{id: {k + 1}, position: [{radius * math.cos(a[k]):.4f}, "
              f"{radius * math.sin(a[k]):.4f}]}}" for k in range(n)]
    lines.append("edges:")
    lines += [f"  - [{k + 1}, {(k + step) % n + 1}]" for k in range(n) for step in (1, 2)]
    team = yaml.safe_load("\n".join(lines) + guidance)
    # ropes that reach the payload under the centroid, and room above to lift it (the
    # square's 1.12 m ropes hang nothing from a wide ring)
    reach = math.ceil(radius * 1.5) + 3.0
    team["payload"]["rope_length"] = radius * 1.5
    team.setdefault("operator", {})["altitude_max"] = reach
    team.setdefault("safety", {}).update(geofence_xy=1000.0, geofence_altitude=reach)
    team["guidance"]["scale_min"] = 1.0
    team["gcs"] = {"zenoh": {"mode": "peer", "connect": []}}
    path = directory / f"ring{n}.yaml"
    path.write_text(yaml.safe_dump(team))
    return path


class MovingTeam(FleetTable):
    """The fleet table of a real GcsApp reading a moving team instead of telemetry.

    The simulator's truth (payload, rope tensions) is set on the app with each read,
    as the simulator's would arrive with the telemetry.
    """

    def __init__(self, app: GcsApp, view: TeamView) -> None:
        super().__init__(app.runtime.ids, app.runtime.profiles)
        self._app = app
        self._view = view

    def read(self, now: float) -> FleetState:
        fleet, truth = moving_fleet(self._view, now)
        self._app.truth = truth
        return fleet


def frame_cost(view: TeamView, mesh: tuple[np.ndarray, np.ndarray], *,
               frames: int = FRAMES) -> dict[str, float]:
    """Server-side cost of the scene's frames, back to back, one viewer attached."""
    port = free_tcp_port()
    server = viser.ViserServer(host="127.0.0.1", port=port, verbose=False)
    viewer = WireViewer(port, decode=False)
    try:
        scene = SceneView(server.scene, view, mesh, geofence_xy=4.0)
        trails = Trails(view.n)
        viewer.report_camera(*CAMERA)
        deadline = time.monotonic() + 10.0
        while not server.get_clients() and time.monotonic() < deadline:
            time.sleep(0.05)
        build, draw = [], []
        cpu0 = time.process_time()
        for k in range(frames):
            fleet, truth = moving_fleet(view, 0.05 * k)
            t0 = time.perf_counter()
            trails.add(fleet.t, fleet.p_ned)
            frame = build_frame(view, fleet, scale=1.0, truth=truth, trails=trails)
            t1 = time.perf_counter()
            with server.atomic():
                scene.draw(frame)
            t2 = time.perf_counter()
            build.append(t1 - t0)
            draw.append(t2 - t1)
            time.sleep(0.001)  # let viser's thread send, as between real frames
        server.flush()
        time.sleep(0.3)
        cpu = (time.process_time() - cpu0) / frames
    finally:
        viewer.close()
        server.stop()
    total = np.array(build) + np.array(draw)
    return {
        "vehicles": view.n,
        "edges": len(view.edges),
        "frame_ms_median": round(1e3 * float(np.median(total)), 3),
        "frame_ms_p99": round(1e3 * float(np.percentile(total, 99)), 3),
        "build_ms_median": round(1e3 * float(np.median(build)), 3),
        "draw_ms_median": round(1e3 * float(np.median(draw)), 3),
        "cpu_ms_per_frame": round(1e3 * cpu, 3),
    }


def received_rate(team: Team, *, seconds: float = SECONDS) -> dict[str, float]:
    """What one websocket viewer (its own process) receives from the real page of a GCS
    flying ``team``."""
    with GcsApp(team, zenoh_settings=ZenohSettings(mode="peer", connect=())) as app:
        view = TeamView.from_team(team, app.runtime.analysis)
        app.runtime.fleet_table = MovingTeam(app, view)
        ui = WebUi(app, port=free_tcp_port())
        try:
            app.start()
            ui.start()
            watch = subprocess.run(
                [sys.executable, "-m", "web.wireviewer", str(ui.server.get_port()),
                 "--node", "/team/vehicles", "--warmup", str(WARMUP_S),
                 "--seconds", str(seconds)],
                cwd=ROOT, capture_output=True, text=True, timeout=WARMUP_S + seconds + 60.0,
                check=True)
            page = ui.stats()
            ticks = app.runtime.stats()
        finally:
            ui.close()
    received = json.loads(watch.stdout.splitlines()[-1])
    return {
        "vehicles": view.n,
        "received_rate_hz": received["received_rate_hz"],
        "received_kb_per_s": received["received_kb_per_s"],
        "page_rate_hz": round(page.rate_hz, 2),
        "page_frame_ms_median": round(page.draw_ms, 3),
        "page_frame_ms_p99": round(page.draw_p99_ms, 3),
        "loop_overruns": ticks.overruns,
    }


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--frames", type=int, default=FRAMES, help="frames timed back to back")
    parser.add_argument("--seconds", type=float, default=SECONDS, metavar="S",
                        help="seconds the viewer's received rate is measured over")
    args = parser.parse_args(argv)
    square = load_team(SQUARE)
    frame = square.config.airframe
    mesh = quad_mesh(frame.arm_x, frame.arm_y)
    with tempfile.TemporaryDirectory() as tmp:
        ring = load_team(ring_config(100, 6.0, Path(tmp)))
        results = []
        for team in (square, ring):
            view = TeamView.from_team(team, analyze(team))
            results.append(frame_cost(view, mesh, frames=args.frames)
                           | received_rate(team, seconds=args.seconds))
    for r in results:
        print(f"{r['vehicles']:4d} vehicles: frame {r['frame_ms_median']:.2f} ms median "
              f"(p99 {r['frame_ms_p99']:.2f}; build {r['build_ms_median']:.2f}, "
              f"viser {r['draw_ms_median']:.2f}), CPU {r['cpu_ms_per_frame']:.2f} ms/frame; "
              f"a viewer of the real page received {r['received_rate_hz']:.1f} updates/s "
              f"({r['received_kb_per_s']:.0f} kB/s; the page drew {r['page_rate_hz']:.1f} "
              f"frames/s at {r['page_frame_ms_median']:.2f} ms, p99 "
              f"{r['page_frame_ms_p99']:.2f}; target {RATE_TARGET_HZ:g}/s received)")
    rates = {str(r["vehicles"]): r["received_rate_hz"] for r in results}
    print(json.dumps({"bench": "ui_update", "target_ms_4": 2.0, "rate_target_hz": RATE_TARGET_HZ,
                      "ui_thread_hz": UI_RATE_HZ, "received_rate_hz": rates,
                      "rate_ok": min(rates.values()) >= RATE_TARGET_HZ, "results": results}))


if __name__ == "__main__":
    main()
