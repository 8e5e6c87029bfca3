"""The 3-D scene: the team, its ropes and payload, its shape, drawn with viser.

The scene is in NED, the navigation frame used everywhere inside; the one
conversion to the viewer is ``set_up_direction("-z")`` (up is minus down).
Every kind of thing is one scene node whatever the team size (batched meshes,
line-segment sets), so a frame costs a fixed handful of messages; viser sends
only the properties that changed. Call :meth:`SceneView.draw` inside
``server.atomic()`` so a frame reaches the browser whole.
"""

from __future__ import annotations

import math

import numpy as np
import viser

from web import palette
from web._frame import SceneFrame, TeamView, frame_reach

__all__ = ["COMPASS", "LABELS_PER_FRAME", "LABEL_STEP", "SceneView", "compass_at",
           "ground_marks"]

_EMPTY_SEGMENTS = np.zeros((1, 2, 3))

LABELS_PER_FRAME = 24
"""At most this many id labels move per frame (the ones that moved most): with a large
team each label still follows at several hertz, and a frame's cost stays bounded."""

LABEL_STEP = 0.01
"""A label moves once its vehicle is this far from where the label is, m."""

COMPASS = 0.6
"""Length of the north arrow drawn on the ground beside the team, m."""

COMPASS_STEP = 0.05
"""The north arrow moves with the team in steps of at least this, m."""


def ground_marks(scene: viser.SceneApi, extent: float) -> None:
    """What tells distance and direction on the ground: the north and east axes through the
    origin, labelled every metre out to ``extent`` m and "N" and "E" at their ends, and a
    marker at the origin.

    The grid alone (a line every 0.5 m) gives neither the scale nor the way north.
    """
    mark = palette.GROUND_MARK
    reach = math.floor(extent)
    axes = np.array([[[-extent, 0.0, 0.0], [extent, 0.0, 0.0]],
                     [[0.0, -extent, 0.0], [0.0, extent, 0.0]]])
    scene.add_line_segments("/ground/axes", axes, mark, thickness=0.008)
    for k in (*range(-reach, 0), *range(1, reach + 1)):
        for axis, position in (("n", (k, 0.0, 0.0)), ("e", (0.0, k, 0.0))):
            scene.add_label(f"/ground/scale/{axis}{k}", f"{k} m", position=position,
                            font_size_mode="scene", font_scene_height=0.1,
                            anchor="top-left", depth_test=True)
    for name, position in (("N", (extent + 0.15, 0.0, 0.0)), ("E", (0.0, extent + 0.15, 0.0))):
        scene.add_label(f"/ground/axis_{name}", name, position=position,
                        font_size_mode="scene", font_scene_height=0.25,
                        anchor="center-center")
    scene.add_icosphere("/ground/origin", radius=0.04, color=mark, cast_shadow=False,
                        receive_shadow=False)
    scene.add_label("/ground/origin/label", "origin", anchor="top-right",
                    font_size_mode="scene", font_scene_height=0.1)


def compass_at(centroid: np.ndarray, team_reach: float) -> np.ndarray:
    """Where the north arrow starts: on the ground south-west of the team, clear of it
    (the side the first view looks from), m."""
    off = team_reach + 0.4
    return np.array([centroid[0] - off, centroid[1] - off, 0.0])


class _Sent:
    """The property values last handed to viser, so unchanged ones are not sent again.

    viser skips unchanged values itself, but only after a slow type-driven cast;
    comparing here first is what keeps a frame cheap.
    """

    def __init__(self) -> None:
        self._last: dict[tuple[int, str], object] = {}

    def set(self, handle: object, name: str, value: object) -> None:
        key = (id(handle), name)
        last = self._last.get(key)
        if last is not None:
            if isinstance(value, np.ndarray):
                if isinstance(last, np.ndarray) and last.shape == value.shape \
                        and np.array_equal(last, value):
                    return
            elif last is value or last == value:
                return
        setattr(handle, name, value)
        self._last[key] = value


class SceneView:
    """The scene nodes of one team.

    Args:
        scene: the server's scene (shared by every viewer).
        view: the team.
        mesh: vertices and faces of the vehicle model (FRD, m).
        geofence_xy: half-size of the horizontal geofence drawn on the ground, m.
        geofence_margin: its warning margin, drawn as a thinner box inside it, m (0: none).
    """

    def __init__(self, scene: viser.SceneApi, view: TeamView,
                 mesh: tuple[np.ndarray, np.ndarray], *, geofence_xy: float,
                 geofence_margin: float = 0.0) -> None:
        n = view.n
        scene.set_up_direction("-z")
        # no shadows: they cost every viewer's GPU (or CPU, without one) for little here;
        # no environment map: its reflections wash the state colours out
        scene.configure_default_lights(cast_shadow=False)
        scene.configure_environment_map(hdri=None)
        side = 2.0 * geofence_xy + 2.0
        scene.add_grid("/ground", width=side, height=side, plane="xy", cell_size=0.5,
                       section_size=1.0, shadow_opacity=0.0)
        ground_marks(scene, geofence_xy + 1.0)
        for name, g, thickness in (("geofence", geofence_xy, 0.02),
                                   ("geofence_margin", geofence_xy - geofence_margin, 0.006)):
            if name == "geofence_margin" and not geofence_margin > 0.0:
                continue
            corners = np.array([[g, g, 0.0], [g, -g, 0.0], [-g, -g, 0.0], [-g, g, 0.0]])
            scene.add_line_segments(f"/ground/{name}",
                                    np.stack((corners, np.roll(corners, -1, axis=0)), axis=1),
                                    palette.GEOFENCE, thickness=thickness)
        vertices, faces = mesh
        self._vehicles = scene.add_batched_meshes_simple(
            "/team/vehicles", vertices, faces, batched_wxyzs=np.tile([1.0, 0, 0, 0], (n, 1)),
            batched_positions=np.zeros((n, 3)), batched_scales=np.zeros(n),
            batched_colors=palette.state_colors(np.zeros(n, dtype=int)), lod="off",
            flat_shading=True, side="double", cast_shadow=False, receive_shadow=False)
        self._labels = [scene.add_label(f"/team/id_{vid}", str(vid), anchor="bottom-center",
                                        font_screen_scale=1.4, visible=False)
                        for vid in view.ids]
        self._payload = scene.add_icosphere("/team/payload", radius=0.07,
                                            color=tuple(palette.PAYLOAD), visible=False,
                                            cast_shadow=False, receive_shadow=False)
        self._payload_label = scene.add_label("/team/payload/name", "payload",
                                              position=(0.0, 0.0, 0.1), anchor="top-center")
        self._ropes = self._segments(scene, "/team/ropes", 0.008)
        self._drop = self._segments(scene, "/team/payload_drop", 0.004)
        self._height = scene.add_label("/team/payload_height", "", anchor="center-left",
                                       font_screen_scale=0.9, visible=False)
        self._height_p = np.full(3, np.inf)
        self._compass = scene.add_arrows(
            "/team/compass", np.array([[[0.0, 0.0, 0.0], [COMPASS, 0.0, 0.0]]]),
            palette.GROUND_MARK, shaft_radius=0.012, head_radius=0.04, head_length=0.12,
            visible=False)
        scene.add_label("/team/compass/north", "N", position=(COMPASS + 0.12, 0.0, 0.0),
                        font_size_mode="scene", font_scene_height=0.16, anchor="center-center")
        self._compass_p = np.full(3, np.inf)
        self._edges = self._segments(scene, "/team/edges", 0.015)
        self._ghost = self._segments(scene, "/team/ghost", 0.006)
        self._trails = self._segments(scene, "/team/trails", 0.006)
        self._arrows = scene.add_arrows("/team/velocity", _EMPTY_SEGMENTS,
                                        tuple(palette.VELOCITY), shaft_radius=0.008,
                                        head_radius=0.025, head_length=0.06, visible=False)
        self._label_p = np.full((n, 3), np.inf)
        self._sent = _Sent()

    @staticmethod
    def _segments(scene: viser.SceneApi, name: str,
                  thickness: float) -> viser.LineSegmentsHandle:
        return scene.add_line_segments(name, _EMPTY_SEGMENTS, (0, 0, 0), thickness=thickness,
                                       visible=False)

    def _set_segments(self, handle: viser.LineSegmentsHandle, points: np.ndarray,
                      colors: np.ndarray) -> None:
        """Show ``points`` (k, 2, 3) with ``colors`` (k, 2, 3) or (3,); hide when empty."""
        if len(points) == 0:
            self._sent.set(handle, "visible", False)
            return
        if np.ndim(colors) == 1:
            colors = np.broadcast_to(colors, points.shape)
        self._sent.set(handle, "points", points)
        self._sent.set(handle, "colors", colors)
        self._sent.set(handle, "visible", True)

    def _draw_labels(self, frame: SceneFrame) -> None:
        """Move the labels of the vehicles that moved most (at most LABELS_PER_FRAME)."""
        moved = np.linalg.norm(frame.label_p - self._label_p, axis=1)
        moved[~frame.known] = 0.0
        for i in np.argsort(-moved)[:LABELS_PER_FRAME]:
            if moved[i] < LABEL_STEP:
                break
            self._labels[i].position = frame.label_p[i]
            self._label_p[i] = frame.label_p[i]
        for i, label in enumerate(self._labels):
            self._sent.set(label, "visible", bool(frame.known[i]))

    def _draw_drop(self, frame: SceneFrame) -> None:
        """The payload's drop line and its height, labelled halfway down."""
        self._set_segments(self._drop, frame.drop, np.asarray(palette.GROUND_MARK))
        shown = len(frame.drop) > 0 and math.isfinite(frame.payload_height)
        if shown:
            middle = 0.5 * (frame.drop[0, 0] + frame.drop[0, 1])
            if float(np.max(np.abs(middle - self._height_p))) >= LABEL_STEP:
                self._height.position = middle
                self._height_p = middle
            self._sent.set(self._height, "text", f"{frame.payload_height:.2f} m")
        self._sent.set(self._height, "visible", shown)

    def _draw_compass(self, frame: SceneFrame) -> None:
        """The north arrow beside the team (the origin's axes may be far out of view)."""
        if frame.centroid is None:
            self._sent.set(self._compass, "visible", False)
            return
        at = compass_at(frame.centroid, frame_reach(frame))
        if float(np.max(np.abs(at - self._compass_p))) >= COMPASS_STEP:
            self._compass.position = at
            self._compass_p = at
        self._sent.set(self._compass, "visible", True)

    def draw(self, frame: SceneFrame) -> None:
        """Send one frame (only what changed goes out)."""
        sent = self._sent
        v = self._vehicles
        sent.set(v, "batched_positions", frame.p_ned)
        sent.set(v, "batched_wxyzs", frame.wxyz)
        sent.set(v, "batched_scales", frame.scales)
        sent.set(v, "batched_colors", frame.colors)
        self._draw_labels(frame)
        if frame.payload_p is None:
            sent.set(self._payload, "visible", False)
        else:
            self._payload.position = frame.payload_p
            color = palette.PAYLOAD if frame.payload_measured else palette.PAYLOAD_ESTIMATED
            sent.set(self._payload, "color", tuple(int(c) for c in color))
            sent.set(self._payload_label, "text", "payload" if frame.payload_measured
                     else "payload (estimated)")
            sent.set(self._payload, "visible", True)
        self._set_segments(self._ropes, frame.ropes, frame.rope_colors)
        self._draw_drop(frame)
        self._draw_compass(frame)
        self._set_segments(self._edges, frame.edges, frame.edge_colors)
        self._set_segments(self._ghost, frame.ghost_edges, palette.GHOST)
        self._set_segments(self._trails, frame.trails, frame.trail_colors)
        if len(frame.velocity):
            sent.set(self._arrows, "points", frame.velocity)
            sent.set(self._arrows, "colors",
                     np.broadcast_to(palette.VELOCITY, (len(frame.velocity), 3)))
        sent.set(self._arrows, "visible", bool(len(frame.velocity)))
