"""Quaternion helpers, quaternions stored as (x, y, z, w) like YADE's minieigen (no YADE)."""
from __future__ import annotations

import numpy as np


def to_matrix(q) -> np.ndarray:
    """(..., 4) unit quaternions -> (..., 3, 3) rotation matrices."""
    q = np.asarray(q, float)
    x, y, z, w = q[..., 0], q[..., 1], q[..., 2], q[..., 3]
    r = np.empty(q.shape[:-1] + (3, 3))
    r[..., 0, 0] = 1 - 2 * (y * y + z * z)
    r[..., 0, 1] = 2 * (x * y - z * w)
    r[..., 0, 2] = 2 * (x * z + y * w)
    r[..., 1, 0] = 2 * (x * y + z * w)
    r[..., 1, 1] = 1 - 2 * (x * x + z * z)
    r[..., 1, 2] = 2 * (y * z - x * w)
    r[..., 2, 0] = 2 * (x * z - y * w)
    r[..., 2, 1] = 2 * (y * z + x * w)
    r[..., 2, 2] = 1 - 2 * (x * x + y * y)
    return r


def multiply(a, b) -> np.ndarray:
    """Hamilton product a * b of (..., 4) quaternions."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    ax, ay, az, aw = np.moveaxis(a, -1, 0)
    bx, by, bz, bw = np.moveaxis(b, -1, 0)
    return np.stack([aw * bx + ax * bw + ay * bz - az * by,
                     aw * by - ax * bz + ay * bw + az * bx,
                     aw * bz + ax * by - ay * bx + az * bw,
                     aw * bw - ax * bx - ay * by - az * bz], -1)


def relative_rotation_vectors(q, q0) -> np.ndarray:
    """Rotation vectors (rad, axis x angle) taking orientation q0 to q, (..., 3)."""
    q = np.asarray(q, float)
    q0inv = np.asarray(q0, float) * np.array([-1.0, -1.0, -1.0, 1.0])
    r = multiply(q, np.broadcast_to(q0inv, q.shape))
    r = np.where(r[..., 3:4] < 0, -r, r)  # the shorter of the two equivalent rotations
    s = np.linalg.norm(r[..., :3], axis=-1)
    ang = 2.0 * np.arctan2(s, r[..., 3])
    axis = np.divide(r[..., :3], s[..., None], out=np.zeros_like(r[..., :3]), where=s[..., None] > 0)
    return axis * ang[..., None]
