"""Aim points on faces where the hypotheses' boundaries differ (DESIGN §4.10, §4.8).

A point on a posed face is blocked by every hypothesis with a face through it
(within the pose and sensor tolerance, with the same normal); its blocking
strength is the weight of those classes. :func:`boundary_aims` samples the faces
and keeps the points of low strength, weakest first, one per cell of a spacing
grid; the (point, face) pairs are found through buckets of normal angle. World
frame, lengths in the object files' unit, angles in radians.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numba
import numpy as np

from planner.compiled import c_array, segment_gap
from planner.geometry import ANGLE_SLACK, LENGTH_SLACK, SHARE_SLACK
from planner.types import SensorBounds

if TYPE_CHECKING:
    from planner.planning.budget import Budget
    from planner.planning.posed_set import PosedSet

__all__ = ["boundary_aims"]


def boundary_aims(
    posed: PosedSet,
    sensor: SensorBounds,
    count: int,
    face_samples: int,
    rng: np.random.Generator,
    budget: Budget | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Up to `count` points on posed faces where the classes' boundaries differ,
    weakest blocking first, from `face_samples` points examined per face.

    With a `budget`, fewer points are examined when their (point, face) pairs would
    cost more than it has left (sized in advance, so the same on any machine); the
    pairs examined are spent from it.

    Returns (points (N, 2), outward normals (N, 2)).
    """
    if count == 0 or face_samples == 0:
        return np.zeros((0, 2)), np.zeros((0, 2))
    frac = (np.arange(face_samples) + 0.5) / face_samples
    # the sample points (valid face x sample, in that order) are drawn before any is
    # made: hundreds of hypotheses of a round part with holes hold a million faces
    fh, ff = np.nonzero(posed.valid)
    plan = _PairPlan.of(posed, sensor)
    total, limit = len(fh) * face_samples, 8 * count
    if budget is not None:
        if budget.at_most("aim_pair", 1, plan.per_point) < 1:  # not one point's pairs
            return np.zeros((0, 2)), np.zeros((0, 2))
        limit = budget.at_most("aim_pair", limit, plan.per_point)
    if total > limit:
        flat = np.sort(rng.choice(total, size=limit, replace=False))
    else:
        flat = np.arange(total)
    face, sample = np.divmod(flat, face_samples)
    owner, f = fh[face], ff[face]
    start = posed.start[owner, f]
    pts = start + frac[sample, None] * (posed.end[owner, f] - start)
    normals = posed.normal[owner, f]
    shared, pairs = _blocking_classes(posed, sensor, pts, owner, normals, plan)
    if budget is not None:
        budget.spend("aim_pair", pairs)
    strength = np.empty(len(pts))
    chunk = max(1, 1_000_000 // max(1, posed.valid.size))
    for lo in range(0, len(pts), chunk):
        # blocking strength: weight of the classes with a face there
        strength[lo : lo + chunk] = shared[lo : lo + chunk] @ posed.class_weight
    differs = strength < 1 - SHARE_SLACK
    pts, normals, strength = pts[differs], normals[differs], strength[differs]
    order = rng.permutation(len(pts))
    order = order[np.argsort(strength[order], kind="stable")]
    # one aim per cell of a spacing grid, weakest blocking first
    spacing = max(float(np.median(posed.length[posed.valid])) / 4, 1e-6 * posed.scale)
    cells = np.floor(pts[order] / spacing).astype(np.int64)
    _, first = np.unique(cells, axis=0, return_index=True)
    chosen = order[np.sort(first)][:count]
    return pts[chosen], normals[chosen]


@dataclass(frozen=True)
class _PairPlan:
    """How points are paired with faces: the valid faces' normal angles, their
    buckets (None: every face is a candidate) and the candidate pairs per point."""

    face_angle: np.ndarray
    buckets: _Buckets | None
    per_point: int

    @classmethod
    def of(cls, posed: PosedSet, sensor: SensorBounds) -> _PairPlan:
        fh, ff = np.nonzero(posed.valid)
        face_angle = np.arctan2(posed.normal[fh, ff, 1], posed.normal[fh, ff, 0])
        # turn <= n_tol + ANGLE_SLACK with n_tol = 2 phi + dtheta(h) + dtheta(g) <= widest
        widest = 2 * sensor.normal_error + 2 * posed.rotation.max() + 2e-9
        n_buckets = int(min(1024, 2 * np.pi // max(widest * (1 + SHARE_SLACK), 1e-12)))
        buckets = None if n_buckets < 3 else _Buckets.of(posed, face_angle, n_buckets)
        per_point = len(fh) if buckets is None else 3 * buckets.sorted_low.shape[1]
        return cls(face_angle, buckets, max(1, per_point))


@dataclass(frozen=True)
class _Buckets:
    """The valid faces in buckets of normal angle, each sorted by its low extent
    along the bucket's direction (built once, queried per chunk of points)."""

    n_buckets: int
    width: float
    used: np.ndarray
    span: np.ndarray
    order: np.ndarray
    first: np.ndarray
    sorted_low: np.ndarray

    @classmethod
    def none(cls) -> _Buckets:
        """No buckets: every face is a candidate."""
        empty = np.zeros(0, dtype=np.int64)
        return cls(1, 2 * np.pi, empty, np.zeros(0), empty, empty, np.zeros((0, 0)))

    @classmethod
    def of(cls, posed: PosedSet, face_angle: np.ndarray, n_buckets: int) -> _Buckets:
        fh, ff = np.nonzero(posed.valid)
        width = 2 * np.pi / n_buckets
        bucket = np.floor((face_angle + np.pi) / width).astype(np.int64) % n_buckets
        centre = (bucket + 0.5) * width - np.pi
        s, e = posed.start[fh, ff], posed.end[fh, ff]
        # extent of each face along its bucket's direction n
        along_s = s[:, 0] * np.cos(centre) + s[:, 1] * np.sin(centre)
        along_e = e[:, 0] * np.cos(centre) + e[:, 1] * np.sin(centre)
        low, high = np.minimum(along_s, along_e), np.maximum(along_s, along_e)
        used, row = np.unique(bucket, return_inverse=True)
        span = np.zeros(len(used))
        np.maximum.at(span, row, high - low)
        order = np.lexsort((low, row))
        size = np.bincount(row, minlength=len(used))
        first = np.cumsum(size) - size
        sorted_low = np.full((len(used), int(size.max())), np.inf)
        rank = np.arange(len(order)) - first[row[order]]
        sorted_low[row[order], rank] = low[order]
        return cls(n_buckets, width, used, span, order, first, sorted_low)


def _blocking_classes(
    posed: PosedSet,
    sensor: SensorBounds,
    pts: np.ndarray,
    owner: np.ndarray,
    normals: np.ndarray,
    plan: _PairPlan,
) -> tuple[np.ndarray, int]:
    """(points, classes) bool: the classes with a face blocking each point, within the
    pose/sensor tolerance of it and with the same normal; and how many candidate
    (point, face) pairs were measured.

    Faces fall into buckets of normal angle at least as wide as the widest angle
    tolerance; in a bucket they are sorted by their extent along its direction n,
    and a face within p of a point q spans some of [n.q - p, n.q + p]. Only the
    faces of a point's bucket and its two neighbours that pass this are measured
    (every face when some tolerance spans a third of the directions). One compiled
    pass, which holds no pairs: a round part with holes, its rotation still free,
    pairs every point with a million faces."""
    fh, ff = np.nonzero(posed.valid)
    start, end = posed.start[fh, ff], posed.end[fh, ff]
    b = plan.buckets or _Buckets.none()
    arrays = (
        c_array(pts, dtype=float),
        c_array(owner, dtype=np.int64),
        np.arctan2(normals[:, 1], normals[:, 0]),
    )
    table = (
        plan.buckets is None,
        float(b.width),
        int(b.n_buckets),
        c_array(b.used, np.int64),
        c_array(b.span, float),
        c_array(b.order, np.int64),
        c_array(b.first, np.int64),
        c_array(b.sorted_low, float),
    )
    faces = (c_array(plan.face_angle, float), c_array(fh, np.int64), c_array(start), c_array(end))
    tolerances = (
        c_array(posed.rotation, float),
        c_array(posed.eps_t, float),
        c_array(posed.cls, dtype=np.int64),
        2 * sensor.normal_error,
        2 * sensor.position_error,
        float(posed.eps_t.max()),
        2e-9 * posed.scale,
        LENGTH_SLACK * posed.scale,
    )
    shared = np.zeros((len(pts), posed.n_classes), dtype=bool)
    return shared, int(_blocking_kernel(*arrays, *table, *faces, *tolerances, shared))


@numba.njit(cache=True, nogil=True)
def _blocks(q, face, g, pts, angle, face_angle, start, end, h, rotation, eps_t, tol):  # type: ignore[no-untyped-def]
    """Does `face` (of hypothesis h) block point q (of hypothesis g)? Its normal
    within the angle tolerance of the point's, and the point within the position
    tolerance of it; `tol` = (2 phi, 2 eps_d, the distance's rounding slack)."""
    two_phi, two_eps_d, dist_slack = tol
    n_tol = two_phi + rotation[g] + rotation[h]
    turn = abs((face_angle[face] - angle[q] + math.pi) % (2 * math.pi) - math.pi)
    if turn > n_tol + ANGLE_SLACK:
        return False
    gap = segment_gap(
        pts[q, 0], pts[q, 1], start[face, 0], start[face, 1], end[face, 0], end[face, 1]
    )
    return math.hypot(*gap) <= two_eps_d + (eps_t[g] + eps_t[h]) / 2 + dist_slack


@numba.njit(cache=True, nogil=True)
def _blocking_kernel(  # type: ignore[no-untyped-def]
    pts,
    owner,
    angle,
    every_face,
    width,
    n_buckets,
    used,
    span,
    order,
    first,
    sorted_low,
    face_angle,
    fh,
    start,
    end,
    rotation,
    eps_t,
    cls,
    two_phi,
    two_eps_d,
    eps_t_max,
    reach_slack,
    dist_slack,
    shared,
):
    """:func:`_blocking_classes`' pass: `shared` filled, the pairs measured returned.
    A class already found blocking a point is not measured again."""
    tol = (two_phi, two_eps_d, dist_slack)
    measured = 0
    for q in range(pts.shape[0]):
        g = owner[q]
        if every_face:
            measured += fh.shape[0]
            for face in range(fh.shape[0]):
                h = fh[face]
                if not shared[q, cls[h]] and _blocks(
                    q, face, g, pts, angle, face_angle, start, end, h, rotation, eps_t, tol
                ):
                    shared[q, cls[h]] = True
            continue
        mine = math.floor((angle[q] + math.pi) / width)
        reach = two_eps_d + (eps_t[g] + eps_t_max) / 2 + reach_slack
        for d in (-1, 0, 1):
            near = (mine + d) % n_buckets
            slot = min(max(np.searchsorted(used, near), 0), len(used) - 1)
            if used[slot] != near:
                continue
            n_dir = (used[slot] + 0.5) * width - math.pi
            x = pts[q, 0] * math.cos(n_dir) + pts[q, 1] * math.sin(n_dir)
            row = sorted_low[slot]
            lo = np.searchsorted(row, x - reach - span[slot], side="left")
            hi = np.searchsorted(row, x + reach, side="right")
            measured += hi - lo
            for r in range(lo, hi):
                face = order[first[slot] + r]
                h = fh[face]
                if not shared[q, cls[h]] and _blocks(
                    q, face, g, pts, angle, face_angle, start, end, h, rotation, eps_t, tol
                ):
                    shared[q, cls[h]] = True
    return measured
