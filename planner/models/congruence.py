"""Whether two slices of posed meshes are one 2-D model (DESIGN §4.13): stable
poses whose slices are congruent under a planar rotation are merged on import."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

__all__ = ["congruent"]

#: Relative tolerance (of the slice's size) under which a vertex counts as lying
#: on the line through its neighbours, and under which two slices coincide.
COLLINEAR_TOLERANCE = 1e-6


def _rotation_to(a: np.ndarray, b: np.ndarray, tol: float) -> np.ndarray:
    """Angles (radians) of the best rotations about the origin taking the rows
    of a (N, 2) onto b (N, 2) cyclically shifted by k, one per plausible shift k
    (those that send a's first vertex to a vertex of b at the same radius)."""
    n = len(a)
    radius_a, radius_b = np.hypot(*a[0]), np.hypot(*b.T)
    shifts = np.flatnonzero(np.abs(radius_b - radius_a) <= tol)
    shifted = b[(shifts[:, None] + np.arange(n)[None, :]) % n]
    # theta_k = atan2(sum_i a_i x b_(i+k), sum_i a_i . b_(i+k))
    cross = np.sum(a[None, :, 0] * shifted[..., 1] - a[None, :, 1] * shifted[..., 0], axis=1)
    dot = np.sum(a[None, :, 0] * shifted[..., 0] + a[None, :, 1] * shifted[..., 1], axis=1)
    return np.arctan2(cross, dot)


def _matches(points: np.ndarray, targets: np.ndarray, tol: float) -> np.ndarray | None:
    """Index of the target within `tol` of each point, if that pairing is one-to-one."""
    distance = np.hypot(*(points[:, None, :] - targets[None, :, :]).transpose(2, 0, 1))
    nearest = np.argmin(distance, axis=1)
    if np.any(distance[np.arange(len(points)), nearest] > tol):
        return None
    if len(np.unique(nearest)) != len(targets):
        return None
    return nearest


def congruent(a: Any, b: Any, tol: float = COLLINEAR_TOLERANCE) -> bool:
    """Whether two centred slices (:class:`~planner.models.mesh.MeshSlice`) are one
    2-D model: a rotation about the centroid (a planar rigid motion, no mirroring)
    maps every vertex and face of `a` onto one of `b` within `tol` times the size,
    with equal `normal_z` (within `tol`).

    >>> from planner.models.mesh import MeshSlice
    >>> square = MeshSlice(
    ...     np.array([[1.0, -1], [1, 1], [-1, 1], [-1, -1]]), (), np.zeros(4), np.zeros(2)
    ... )
    >>> turned = MeshSlice(np.roll(square.outline, 1, axis=0), (), np.zeros(4), np.zeros(2))
    >>> congruent(square, turned)
    True
    """
    if len(a.outline) != len(b.outline) or sorted(map(len, a.holes)) != sorted(map(len, b.holes)):
        return False
    size = max(float(np.max(np.hypot(*a.outline.T))), 1e-300)
    limit = tol * size
    a_vertices, b_vertices = np.concatenate(a.rings), np.concatenate(b.rings)
    a_middle = np.concatenate([(r + np.roll(r, -1, axis=0)) / 2 for r in a.rings])
    b_middle = np.concatenate([(r + np.roll(r, -1, axis=0)) / 2 for r in b.rings])
    for theta in _rotation_to(a.outline, b.outline, limit):
        c, s = math.cos(theta), math.sin(theta)
        rotation = np.array([[c, -s], [s, c]])
        if _matches(a_vertices @ rotation.T, b_vertices, limit) is None:
            continue
        face = _matches(a_middle @ rotation.T, b_middle, limit)
        if face is not None and np.allclose(a.normal_z, b.normal_z[face], atol=tol, rtol=0):
            return True
    return False
