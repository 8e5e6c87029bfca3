"""A small quadrotor model (arms, rotor discs, a nose) as one triangle mesh.

One mesh drawn once per vehicle with viser's batched meshes: a whole team is a
single scene node, so its update is one message whatever the team size. The
model is in the body frame FRD (x forward, y right, z down), sized from the
airframe so that what the operator sees has the real arm geometry; the nose
wedge shows the heading.
"""

from __future__ import annotations

import numpy as np

__all__ = ["quad_mesh", "yaw_wxyz"]


def _box(center: tuple[float, float, float], size: tuple[float, float, float],
         yaw: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """A box (8 vertices, 12 triangles) turned by ``yaw`` about body z."""
    hx, hy, hz = (s / 2 for s in size)
    v = np.array([[x, y, z] for x in (-hx, hx) for y in (-hy, hy) for z in (-hz, hz)])
    c, s = np.cos(yaw), np.sin(yaw)
    v = v @ np.array([[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]]) + np.asarray(center)
    f = np.array([[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1],
                  [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]])
    return v, f


def _disc(center: tuple[float, float, float], radius: float, thickness: float,
          segments: int) -> tuple[np.ndarray, np.ndarray]:
    """A flat cylinder about body z: two fans and a rim."""
    a = 2.0 * np.pi * np.arange(segments) / segments
    ring = np.column_stack((radius * np.cos(a), radius * np.sin(a)))
    cx, cy, cz = center
    top = np.column_stack((ring[:, 0] + cx, ring[:, 1] + cy, np.full(segments, cz - thickness / 2)))
    bottom = top.copy()
    bottom[:, 2] = cz + thickness / 2
    v = np.vstack((top, bottom, [[cx, cy, cz - thickness / 2], [cx, cy, cz + thickness / 2]]))
    k = np.arange(segments)
    k1 = (k + 1) % segments
    ct, cb = 2 * segments, 2 * segments + 1
    faces = np.vstack((
        np.column_stack((np.full(segments, ct), k1, k)),
        np.column_stack((np.full(segments, cb), k + segments, k1 + segments)),
        np.column_stack((k, k1, k1 + segments)),
        np.column_stack((k, k1 + segments, k + segments)),
    ))
    return v, faces


def quad_mesh(arm_x: float, arm_y: float, *, rotor_radius: float | None = None,
              segments: int = 16) -> tuple[np.ndarray, np.ndarray]:
    """Vertices (V, 3) float32 and faces (F, 3) uint32 of a quadrotor in FRD, metres.

    Args:
        arm_x, arm_y: rotor offsets from the centre of mass along body x and y, m.
        rotor_radius: rotor disc radius, m (default: 70 % of the shorter offset).
        segments: polygon count of each rotor disc.
    """
    r = rotor_radius if rotor_radius is not None else 0.7 * min(arm_x, arm_y)
    arm_len = float(np.hypot(arm_x, arm_y))
    arm_w = 0.15 * r
    parts = [_box((0.0, 0.0, 0.0), (0.9 * arm_x, 0.6 * arm_y, 0.35 * r))]
    for sx in (1.0, -1.0):
        for sy in (1.0, -1.0):
            yaw = float(np.arctan2(sy * arm_y, sx * arm_x))
            parts.append(_box((sx * arm_x / 2, sy * arm_y / 2, 0.0), (arm_len, arm_w, arm_w), yaw))
            parts.append(_disc((sx * arm_x, sy * arm_y, -0.6 * arm_w), r, 0.06 * r, segments))
    # nose wedge: a flat triangle pointing forward, thick enough to see from the side
    nose_v = np.array([p for z in (-0.2 * r, 0.2 * r) for p in (
        (0.45 * arm_x, -0.3 * arm_y, z), (0.45 * arm_x, 0.3 * arm_y, z), (1.6 * arm_x, 0.0, z))])
    nose_f = np.array([[0, 2, 1], [3, 4, 5], [0, 1, 4], [0, 4, 3], [1, 2, 5], [1, 5, 4],
                       [0, 3, 5], [0, 5, 2]])
    parts.append((nose_v, nose_f))
    vertices, faces, offset = [], [], 0
    for v, f in parts:
        vertices.append(v)
        faces.append(f + offset)
        offset += len(v)
    return np.vstack(vertices).astype(np.float32), np.vstack(faces).astype(np.uint32)


def yaw_wxyz(yaw: np.ndarray) -> np.ndarray:
    """Quaternions (n, 4), scalar first, of rotations by ``yaw`` (n,) rad about NED down."""
    yaw = np.asarray(yaw, dtype=float)
    half = 0.5 * np.where(np.isfinite(yaw), yaw, 0.0)
    q = np.zeros((len(half), 4))
    q[:, 0] = np.cos(half)
    q[:, 3] = np.sin(half)
    return q
