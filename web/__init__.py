"""The viser web application (scene, plots, operator controls, replay).

Modules:

    ``_actions``         What a viewer can do to the flight, in the loop's time.
    ``_browser_input``   What a browser sends about its keyboard and virtual sticks, and how
                         it is read.
    ``_browser_script``  The page's input script: hotkeys and virtual sticks that viser
                         lacks.
    ``_control_lock``    Who may steer the team: at most one viewer at a time.
    ``_frame``           What the scene shows in one frame, computed as plain arrays (NED,
                         SI).
    ``_history``         A rolling window of what the paper's experiment figure shows.
    ``_launch``          ``gcs demo`` and ``gcs run``: a GCS with its page (and gamepad),
                         until Ctrl-C.
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
    ``_shapefit``        Where the desired shape would be if the team were perfect: the
                         ghost.
    ``_status``          The status panel as HTML: flight phase, operator command, vehicles,
                         links, events.
    ``_timeline``        Replay time: where in the log the page is, and how fast it moves.
    ``_trails``          Short trails behind each vehicle: where the team has just been.
    ``_ui``              The live page of one GCS: a viser server and the thread that draws
                         it.
    ``palette``          Colours of the scene: what a colour means is decided here, once.
    ``wireviewer``       A viewer without a browser: a websocket client of a viser page that
                         decodes what it gets.
"""

from web import palette, wireviewer
from web._actions import OperatorActions
from web._browser_input import (
    HOLD_ACTIONS,
    HOTKEYS,
    INPUT_TIMEOUT,
    STEP_ACTIONS,
    BrowserInput,
    InputTracker,
    parse_input,
)
from web._browser_script import (
    ABORT_ANSWER_WAIT_MS,
    ABORT_ANSWERS,
    ABORT_HOTKEY,
    ABORT_LABEL,
    ABORT_MODIFIER,
    CHANNEL_LABEL,
    SEND_PERIOD_MS,
    abort_keys,
    answer_abort,
    install_script,
    pads_html,
    script_source,
)
from web._control_lock import ControlLock
from web._frame import SceneFrame, TeamView, build_frame, rope_pull_estimate, vehicle_states
from web._history import History, Series
from web._launch import DEFAULT_GAMEPAD, default_gamepad, run_demo, run_gcs, serve
from web._panel import FOLLOW_STEP, HOTKEY_HELP, PHASE_BUTTONS, ControlPanel, abort_for
from web._plots import MAX_SERIES, PlotsView
from web._quadmesh import quad_mesh, yaw_wxyz
from web._replay import ReplayCursor, ReplayEvent, ReplayState, replay_view
from web._replay_page import ReplayUi, replay_summary_html, run_replay
from web._scene import LABEL_STEP, LABELS_PER_FRAME, SceneView
from web._shapefit import fit_shape
from web._status import (
    UiStats,
    events_html,
    rope_legend,
    summary_html,
    vehicle_table_html,
    vehicles_html,
)
from web._timeline import SPEEDS, Timeline
from web._trails import Trails
from web._ui import UI_RATE_HZ, WebUi, page_url

__all__ = [
    "ABORT_ANSWERS",
    "ABORT_ANSWER_WAIT_MS",
    "ABORT_HOTKEY",
    "ABORT_LABEL",
    "ABORT_MODIFIER",
    "CHANNEL_LABEL",
    "DEFAULT_GAMEPAD",
    "FOLLOW_STEP",
    "HOLD_ACTIONS",
    "HOTKEYS",
    "HOTKEY_HELP",
    "INPUT_TIMEOUT",
    "LABELS_PER_FRAME",
    "LABEL_STEP",
    "MAX_SERIES",
    "PHASE_BUTTONS",
    "SEND_PERIOD_MS",
    "SPEEDS",
    "STEP_ACTIONS",
    "UI_RATE_HZ",
    "BrowserInput",
    "ControlLock",
    "ControlPanel",
    "History",
    "InputTracker",
    "OperatorActions",
    "PlotsView",
    "ReplayCursor",
    "ReplayEvent",
    "ReplayState",
    "ReplayUi",
    "SceneFrame",
    "SceneView",
    "Series",
    "TeamView",
    "Timeline",
    "Trails",
    "UiStats",
    "WebUi",
    "abort_for",
    "abort_keys",
    "answer_abort",
    "build_frame",
    "default_gamepad",
    "events_html",
    "fit_shape",
    "install_script",
    "pads_html",
    "page_url",
    "palette",
    "parse_input",
    "quad_mesh",
    "replay_summary_html",
    "replay_view",
    "rope_legend",
    "rope_pull_estimate",
    "run_demo",
    "run_gcs",
    "run_replay",
    "script_source",
    "serve",
    "summary_html",
    "vehicle_states",
    "vehicle_table_html",
    "vehicles_html",
    "wireviewer",
    "yaw_wxyz",
]
