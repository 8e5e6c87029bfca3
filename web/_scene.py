"""The 3-D scene: the team, its ropes and payload, its shape, drawn with viser.

The scene is in NED, the navigation frame used everywhere inside; the one
conversion to the viewer is ``set_up_direction("-z")`` (up is minus down).
Every kind of thing is one scene node whatever the team size (batched meshes,
line-segment sets), so a frame costs a fixed handful of messages; viser sends
only the properties that changed. Call :meth:`SceneView.draw` inside
``server.atomic()`` so a frame reaches the browser whole.
"""

from __future__ import annotations

import numpy as np
import viser

from web import palette
from web._frame import SceneFrame, TeamView

__all__ = ["LABELS_PER_FRAME", "LABEL_STEP", "SceneView"]

_EMPTY_SEGMENTS = np.zeros((1, 2, 3))

LABELS_PER_FRAME = 24
"""At most this many id labels move per frame (the ones that moved most): with a large
team each label still follows at several hertz, and a frame's cost stays bounded."""

LABEL_STEP = 0.01
"""A label moves once its vehicle is this far from where the label is, m."""


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
        self._set_segments(self._edges, frame.edges, frame.edge_colors)
        self._set_segments(self._ghost, frame.ghost_edges, palette.GHOST)
        self._set_segments(self._trails, frame.trails, frame.trail_colors)
        if len(frame.velocity):
            sent.set(self._arrows, "points", frame.velocity)
            sent.set(self._arrows, "colors",
                     np.broadcast_to(palette.VELOCITY, (len(frame.velocity), 3)))
        sent.set(self._arrows, "visible", bool(len(frame.velocity)))
