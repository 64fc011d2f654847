"""Whether two slices of posed meshes are one 2-D model (DESIGN §4.13): stable
poses whose slices are congruent under a planar rotation are merged on import."""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np
from scipy.spatial import cKDTree

from planner.geometry import signed_area

__all__ = ["congruent", "congruent_poses", "shape_labels"]

#: Relative tolerance (of the slice's size) under which a vertex counts as lying
#: on the line through its neighbours, and under which two slices coincide.
COLLINEAR_TOLERANCE = 1e-6
#: The most rotations tried for two outlines. A shape many-fold symmetric maps
#: onto its copy at the first; past this many, two outlines count as two shapes
#: (never one that is not: the answer stays sound), so that a pair of heavy
#: outlines costs a bounded amount.
MAX_ROTATIONS = 32


def _rotation_to(a: np.ndarray, b: np.ndarray, tol: float) -> np.ndarray:
    """Angles (radians) of the best rotations about the origin taking the rows
    of a (N, 2) onto b (N, 2) cyclically shifted by k, one per plausible shift k
    (those that send a's first vertex to a vertex of b at the same radius; the
    first `MAX_ROTATIONS` of them)."""
    n = len(a)
    radius_a, radius_b = np.hypot(*a[0]), np.hypot(*b.T)
    shifts = np.flatnonzero(np.abs(radius_b - radius_a) <= tol)[:MAX_ROTATIONS]
    shifted = b[(shifts[:, None] + np.arange(n)[None, :]) % n]
    # theta_k = atan2(sum_i a_i x b_(i+k), sum_i a_i . b_(i+k))
    cross = np.sum(a[None, :, 0] * shifted[..., 1] - a[None, :, 1] * shifted[..., 0], axis=1)
    dot = np.sum(a[None, :, 0] * shifted[..., 0] + a[None, :, 1] * shifted[..., 1], axis=1)
    return np.arctan2(cross, dot)


def _matches(points: np.ndarray, targets: np.ndarray, tol: float) -> np.ndarray | None:
    """Index of the target within `tol` of each point, if that pairing is one-to-one
    (a k-d tree over the targets: memory and time grow with the vertices, not with
    their pairs)."""
    distance, nearest = cKDTree(targets).query(points, distance_upper_bound=tol)
    if not np.all(np.isfinite(distance)):
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
    origin = np.zeros(2)
    return any(
        _layer_onto(a, b, origin, origin, _turn(theta), limit, tol)
        for theta in _rotation_to(a.outline, b.outline, limit)
    )


def congruent_poses(a: Any, b: Any, tol: float = COLLINEAR_TOLERANCE) -> bool:
    """Whether two stable poses (:class:`~planner.types.StablePose`) are one shape:
    one rotation about their centroids (no mirroring) maps every layer's vertices
    and face midpoints onto the same layer of the other within `tol` times the
    size, with equal `normal_z` and probing heights. Vertices are compared as
    given: an outline drawn with an extra vertex along a face is another shape.

    >>> from planner.models.library import object_from_dict
    >>> a = object_from_dict({"name": "a", "outline": [[0, 0], [4, 0], [4, 2], [0, 2]]})
    >>> b = object_from_dict({"name": "b", "outline": [[9, 9], [9, 13], [7, 13], [7, 9]]})
    >>> c = object_from_dict({"name": "c", "outline": [[0, 0], [4, 0], [4, 2.5], [0, 2.5]]})
    >>> congruent_poses(a.stable_poses[0], b.stable_poses[0])
    True
    >>> congruent_poses(a.stable_poses[0], c.stable_poses[0])
    False
    """
    if a.heights != b.heights or len(a.layers) != len(b.layers):
        return False
    for p, q in zip(a.layers, b.layers, strict=True):
        if len(p.outline) != len(q.outline) or sorted(map(len, p.holes)) != sorted(
            map(len, q.holes)
        ):
            return False
        if (p.normal_z is None) != (q.normal_z is None):
            return False
    ca, cb = np.asarray(a.centroid, dtype=float), np.asarray(b.centroid, dtype=float)
    size = max(float(np.max(np.hypot(*(a.extent - ca).T))), 1e-300)
    limit = tol * size
    for theta in _rotation_to(a.outline - ca, b.outline - cb, limit):
        rotation = _turn(theta)
        if all(
            _layer_onto(p, q, ca, cb, rotation, limit, tol)
            for p, q in zip(a.layers, b.layers, strict=True)
        ):
            return True
    return False


def _turn(theta: float) -> np.ndarray:
    c, s = math.cos(theta), math.sin(theta)
    return np.array([[c, -s], [s, c]])


def _layer_onto(
    p: Any, q: Any, ca: np.ndarray, cb: np.ndarray, rotation: np.ndarray, limit: float, tol: float
) -> bool:
    """Does `rotation` about the centroids `ca`, `cb` map layer (or slice) p's
    vertices and face midpoints onto q's (and its faces' normal_z onto theirs)?"""
    rings_p = [r - ca for r in (p.outline, *p.holes)]
    rings_q = [r - cb for r in (q.outline, *q.holes)]
    if _matches(np.concatenate(rings_p) @ rotation.T, np.concatenate(rings_q), limit) is None:
        return False
    middle_p = np.concatenate([(r + np.roll(r, -1, axis=0)) / 2 for r in rings_p])
    middle_q = np.concatenate([(r + np.roll(r, -1, axis=0)) / 2 for r in rings_q])
    face = _matches(middle_p @ rotation.T, middle_q, limit)
    if face is None:
        return False
    if p.normal_z is None:
        return True
    return bool(np.allclose(p.normal_z, np.asarray(q.normal_z)[face], atol=tol, rtol=0))


def shape_labels(stables: Sequence[Any], tol: float = COLLINEAR_TOLERANCE) -> np.ndarray:
    """(G,) one label per stable pose, equal exactly for those that are one shape
    (:func:`congruent_poses`; each compared with one pose of every shape found
    so far). Only poses alike in what a
    rigid motion keeps (vertices per ring, area and perimeter to six digits) are
    compared: a set of distinct parts costs no pair at all."""

    def signature(p: Any) -> tuple:
        rings = [r for q in p.layers for r in (q.outline, *q.holes)]
        area = sum(abs(signed_area(r)) for r in rings)
        length = sum(float(np.hypot(*(np.roll(r, -1, axis=0) - r).T).sum()) for r in rings)
        counts = tuple((len(q.outline), tuple(sorted(map(len, q.holes)))) for q in p.layers)
        return counts, float(f"{area:.6g}"), float(f"{length:.6g}")

    by_signature: dict[tuple, list[int]] = {}
    for i, p in enumerate(stables):
        by_signature.setdefault(signature(p), []).append(i)
    label = np.arange(len(stables))
    for members in by_signature.values():
        heads: list[int] = []  # one pose of each shape found so far
        for i in members:
            head = next((h for h in heads if congruent_poses(stables[h], stables[i], tol)), None)
            if head is None:
                heads.append(i)
            else:
                label[i] = head
    return label
