"""Where each viewer's camera looks: framed on the team, following it, centred on demand.

Why here and per viewer: every browser has its own camera (viser's
``client.camera``), and what goes wrong is per viewer: one who joins while the
team is away from the origin, one who orbited, one whose camera fell behind.

* **First view**: the first frame that knows where the team is frames it
  (:func:`team_view`: looking at its centroid from behind and above, far enough
  for the whole team), whatever the team's distance from the origin.
* **Follow**: the point looked at moves with the team, absolutely, not by
  adding the team's motion to the camera the browser last reported: a report
  still on its way from before the last move would otherwise undo that move,
  and the camera would fall further behind with every one. The viewer's own choices
  are kept: orbit and zoom (the camera's offset from the point it looks at),
  and a pan (where the viewer moved that point, relative to the team). A
  reported point that is none of those this view set lately is the viewer's
  pan; while the viewer's hand is on the camera (a report this view did not
  set, in the last :data:`HANDS_OFF_S`) the camera is not moved from under it.
  One is not: the page's own first view (viser's initial camera, looking at
  the origin). The browser puts it back by itself while the page
  loads (when the initial camera and the scene's up direction arrive), even
  after it showed a framing; taken as a pan, it would leave a new viewer looking
  at the origin, wherever the team. The team is framed again instead (also after
  viser's "Reset View", which goes to that view).
* **Centre on team** (the View folder's button, key C): looks at the team again
  from the viewer's side at the framing distance and height; the pan is gone.
  The same happens when the team has landed.

Plain maths (:func:`team_view`) apart from the viser calls, so the framing is
tested without a browser.
"""

from __future__ import annotations

import collections
import math
import threading
import time
from collections.abc import Callable
from typing import Literal

import numpy as np
import viser

__all__ = ["CENTRE_HOTKEY", "CENTRE_LABEL", "FOLLOW_STEP", "FRAME_AGAIN_S", "HANDS_OFF_S",
           "MIN_VIEW_DISTANCE", "ViewControls", "team_view"]

FOLLOW_STEP = 0.02
"""The camera follows the team in steps of at least this, m (telemetry noise stays put)."""

CENTRE_LABEL = "Centre on team"
"""The View folder's button and the command palette's name of the centring."""

CENTRE_HOTKEY: Literal["C"] = "C"
"""Key of the centring (viser command hotkey, no modifier)."""

MIN_VIEW_DISTANCE = 4.3
"""Closest a framed view stands from the team's centroid, m (the square team fills about
half the view's height at it)."""

_VIEW_DIRECTION = np.array([-3.4, -1.0, -2.4]) / math.hypot(3.4, 1.0, 2.4)
"""From the point looked at to the camera, NED: behind (south, the team's forward is
north), a little west, and 34 degrees above."""

_FRAME_FACTOR = 3.5
"""Framing distance per metre of the team's reach (75 degree field of view, margin)."""

_MATCH = 1e-3
"""A reported point looked at within this of one this view set is that one, m."""

FRAME_AGAIN_S = 0.5
"""A framing the browser has not shown after this long is sent again, s."""

_PAGE_LOOK_AT = np.zeros(3)
"""Where the page's own first view looks, NED, m: the pages' ``initial_camera.look_at``
(web._ui, web._replay_page) and three.js's default before it arrives."""

HANDS_OFF_S = 0.5
"""The camera follows only once the viewer has left it alone this long, s."""


def team_view(centroid: np.ndarray, team_reach: float,
              direction: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Camera position and the point it looks at, framing a team (NED, m).

    ``direction`` (from the point looked at towards the camera) gives the bearing
    to view from (its height is replaced by the framing's); default: behind and
    to the left, as the page's first view.
    """
    look_at = np.asarray(centroid, dtype=float)
    d = _VIEW_DIRECTION.copy()
    if direction is not None and math.hypot(direction[0], direction[1]) > 1e-6:
        horizontal = math.hypot(_VIEW_DIRECTION[0], _VIEW_DIRECTION[1])
        bearing = math.atan2(direction[1], direction[0])
        d[0], d[1] = horizontal * math.cos(bearing), horizontal * math.sin(bearing)
    distance = max(MIN_VIEW_DISTANCE, _FRAME_FACTOR * team_reach)
    return look_at + distance * d, look_at


class ViewControls:
    """One viewer's camera and its View folder: "camera follows team", "Centre on team".

    Args:
        client: the viewer.
        order: where the folder goes in the viewer's panel.
        clock: the clock of :data:`HANDS_OFF_S` and :data:`FRAME_AGAIN_S`.
    """

    def __init__(self, client: viser.ClientHandle, *, order: float | None = None,
                 clock: Callable[[], float] = time.monotonic) -> None:
        self.client = client
        self.clock = clock
        """The clock of the hands-off and framing windows, s (a test steps its own)."""
        gui = client.gui
        with gui.add_folder("View", order=order):
            self.follow = gui.add_checkbox("camera follows team", True,
                                           hint="Orbit and zoom as you like: the view "
                                                "moves with the team.")
            self._centre_button = gui.add_button(CENTRE_LABEL, icon=viser.Icon.FOCUS_CENTERED,
                                                 hint=f"Key {CENTRE_HOTKEY}: look at the "
                                                      "team again.")
        self._centre_button.on_click(lambda _: self.request_centre())
        self._lock = threading.Lock()
        self._centre_asked = False
        self._framed = False
        self._shown = False  # the browser reported a view this one set since the framing
        self._framed_at = -math.inf  # when the framing was last sent (monotonic s)
        self._pan: np.ndarray | None = None  # where the viewer moved the point looked at
        self._side: np.ndarray | None = None  # the framing's side of the team (None: the
        # first view's)
        self._set: collections.deque[np.ndarray] = collections.deque(maxlen=16)
        self._set_at: collections.deque[np.ndarray] = collections.deque(maxlen=16)  # positions
        self._viewer_at = -math.inf  # when the viewer last moved the camera (monotonic s)
        self._hand: tuple[np.ndarray, np.ndarray] | None = None  # the last view update()
        # took for the viewer's hand (look_at, position): its report counts once
        client.camera.on_update(self._on_report)

    async def _on_report(self, camera: viser.CameraHandle) -> None:
        """The browser said where its camera is: a view this one set, or the viewer's own
        hand on the camera.

        A coroutine, so viser runs it on its loop right after it stored the report: a
        plain function would run on its thread pool, late on a loaded machine, and judge
        whatever camera is there by then (a later report, or a move half written), so a
        shown framing would go unseen and the viewer's own view be framed over.
        """
        with self._lock:  # never between a move's position and its point looked at
            look_at, position = _pose(camera)
            hand = self._hand
        if hand is not None and _same(look_at, hand[0]) and _same(position, hand[1]):
            return  # the frame loop already took this view for the viewer's hand
        if not self._was_set(look_at):
            if not _page_view(look_at):  # the page's own view is no hand of the viewer
                self._viewer_at = self.clock()
            return
        with self._lock:
            placed = list(self._set_at)
        if not any(_same(position, p) for p in placed):
            self._viewer_at = self.clock()  # orbiting or zooming about our point
        self._shown = True

    def request_centre(self) -> None:
        """Centre on the team at the next frame (any thread: a click, the hotkey)."""
        with self._lock:
            self._centre_asked = True

    def update(self, centroid: np.ndarray | None, team_reach: float, *,
               reframe: bool = False) -> None:
        """Once per frame, with the team's centroid (None: unknown) and reach, m.

        ``reframe``: the team has just landed; frame it again, as for a new viewer,
        if this viewer follows it.
        """
        if centroid is None or not np.isfinite(centroid).all():
            return
        with self._lock:
            asked, self._centre_asked = self._centre_asked, False
        camera = self.client.camera
        look_at, position = _pose(camera)
        # the browser does not show the framing: not yet, or it put its own first view
        # back over it (never a pan: framed again whatever it showed before)
        was_set = self._was_set(look_at)
        stale = not was_set and (_page_view(look_at) or not self._shown)
        if not self._framed or asked or (reframe and self.follow.value) or (
                stale and self.clock() - self._framed_at >= FRAME_AGAIN_S):
            # a new viewer: the page's first view; else from the viewer's own side. Framed
            # again until the browser shows it: one still loading puts its first camera
            # back over the framing, and reports that.
            if asked or reframe:
                self._side = position - look_at
            direction = self._side
            self._framed, self._shown = True, False
            self._framed_at = self.clock()
            self._pan = np.zeros(3)
            self._move(*team_view(centroid, team_reach, direction))
            return
        if stale:
            return
        if not self.follow.value:
            self._pan = None
            return
        if not was_set:  # the viewer's own view, seen here before viser's thread ran
            # _on_report for it (a loaded machine): the hand is on the camera from now
            self._viewer_at = max(self._viewer_at, self.clock())
            with self._lock:
                self._hand = (look_at, position)
        if self._pan is None or not was_set:
            self._pan = look_at - centroid  # follow from here: the viewer's own view
            self._known(look_at)  # known from now on, as the ones this view set
        target = centroid + self._pan
        if float(np.linalg.norm(target - look_at)) < FOLLOW_STEP:
            return
        if self.clock() - self._viewer_at < HANDS_OFF_S:
            return  # a move now would pull the camera from under the viewer's drag
        self._move(target + (position - look_at), target)

    def _was_set(self, look_at: np.ndarray) -> bool:
        with self._lock:  # the reports come on viser's threads
            known = list(self._set)
        return any(_same(look_at, s) for s in known)

    def _known(self, look_at: np.ndarray) -> None:
        with self._lock:
            self._set.append(np.array(look_at, dtype=float))

    def _move(self, position: np.ndarray, look_at: np.ndarray) -> None:
        """Put the camera at ``position`` looking at ``look_at``, in one message batch.

        viser's position setter carries look_at along by the same shift; look_at is
        then set to where it must end up (a no-op when the shift put it there).
        """
        self._known(look_at)
        camera = self.client.camera
        with self._lock:  # a report judged now sees the camera before or after, whole
            self._set_at.append(np.array(position, dtype=float))
            with self.client.atomic():
                camera.position = position
                camera.look_at = look_at


def _pose(camera: viser.CameraHandle) -> tuple[np.ndarray, np.ndarray]:
    """The camera's point looked at and position, of one report: viser replaces its
    camera state whole on its loop when a report arrives, between any two reads."""
    while True:
        look_at = np.array(camera.look_at, dtype=float)
        position = np.array(camera.position, dtype=float)
        if np.array_equal(look_at, camera.look_at):
            return look_at, position


def _same(a: np.ndarray, b: np.ndarray) -> bool:
    """Whether two camera points are one (within :data:`_MATCH` on every axis)."""
    return float(np.max(np.abs(np.asarray(a, dtype=float) - b))) < _MATCH


def _page_view(look_at: np.ndarray) -> bool:
    """The point looked at is the page's own first view's (unless this view set it)."""
    return _same(look_at, _PAGE_LOOK_AT)
