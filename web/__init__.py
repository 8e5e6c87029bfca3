"""The viser web application (scene, plots, operator controls, replay).

Modules:

    ``_actions``         What a viewer can do to the flight, in the loop's time.
    ``_browser_input``   What a browser sends about its keyboard and virtual sticks, and how
                         it is read.
    ``_browser_script``  The page's script: hotkeys, virtual sticks and a freshness badge
                         that viser lacks.
    ``_camera``          Where each viewer's camera looks: framed on the team, following
                         it, centred on demand.
    ``_control_lock``    Who may steer the team: at most one viewer at a time.
    ``_export``          ``gcs replay --export``: the replay as one HTML file a browser
                         opens offline (viser's recorded scene, the panels drawn over it).
    ``_events``          Events grouped as an operator reads them: one line per
                         condition, not per vehicle.
    ``_frame``           What the scene shows in one frame, computed as plain arrays (NED,
                         SI).
    ``_history``         A rolling window of what the paper's experiment figure shows.
    ``_launch``          ``gcs demo`` and ``gcs run``: a GCS with its page (and gamepad),
                         until Ctrl-C.
    ``_link_quality``    Link quality in %: the share of a vehicle's frames that arrived,
                         lately.
    ``_panel``           One viewer's control panel: abort, take control, sticks, scale,
                         altitude, phases.
    ``_plots``           Live plots like the paper's experiment figure, drawn with viser's
                         uPlot.
    ``_quadmesh``        A small quadrotor model (arms, rotor discs, a nose) as one triangle
                         mesh.
    ``_replay``          A recorded flight as the state at any moment: what the replay page
                         draws.
    ``_replay_page``     The replay page: a recorded flight drawn by the live page's scene
                         and plots.
    ``_scene``           The 3-D scene: the team, its ropes and payload, its shape, drawn
                         with viser.
    ``_status``          The status panel as HTML: flight phase, operator command, vehicles,
                         links, events.
    ``_timeline``        Replay time: where in the log the page is, and how fast it moves.
    ``_trails``          Short trails behind each vehicle: where the team has just been.
    ``_ui``              The live page of one GCS: a viser server and the thread that draws
                         it.
    ``_viser_threads``   Feeding viser from our own threads: its senders are woken on its
                         event loop only.
    ``palette``          Colours of the scene: what a colour means is decided here, once.
    ``wireviewer``       A viewer without a browser: a websocket client of a viser page that
                         decodes what it gets.
"""

from gcs.common import lazy_modules
from web._export import ExportResult, export_replay, run_export
from web._frame import TeamView, build_frame
from web._launch import run_demo, run_gcs
from web._quadmesh import quad_mesh
from web._replay_page import run_replay
from web._scene import SceneView
from web._trails import Trails
from web._ui import UI_RATE_HZ, WebUi

__all__ = [
    "UI_RATE_HZ",
    "ExportResult",
    "SceneView",
    "TeamView",
    "Trails",
    "WebUi",
    "build_frame",
    "export_replay",
    "palette",
    "quad_mesh",
    "run_demo",
    "run_export",
    "run_gcs",
    "run_replay",
    "wireviewer",
]

__getattr__ = lazy_modules(__name__, ("palette", "wireviewer"))
