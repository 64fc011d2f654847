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

from planner.compiled import c_array
from planner.geometry import ANGLE_SLACK, LENGTH_SLACK, SHARE_SLACK, wrap_angle
from planner.planning.bitsets import sorted_count
from planner.planning.cast_faces import segment_distance
from planner.types import SensorBounds

if TYPE_CHECKING:
    from planner.planning.budget import Budget
    from planner.planning.posed_set import PosedSet

__all__ = ["PAIR_CHUNK", "boundary_aims"]

#: The most candidate (point, face) pairs held at once.
PAIR_CHUNK = 2_000_000


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
        affordable = budget.affordable("aim_pair") / plan.per_point
        if affordable < 1:  # not even one point's pairs: none examined
            return np.zeros((0, 2)), np.zeros((0, 2))
        limit = limit if affordable >= limit else int(affordable)
    if total > limit:
        flat = np.sort(rng.choice(total, size=limit, replace=False))
    else:
        flat = np.arange(total)
    face, sample = np.divmod(flat, face_samples)
    owner, f = fh[face], ff[face]
    start = posed.start[owner, f]
    pts = start + frac[sample, None] * (posed.end[owner, f] - start)
    normals = posed.normal[owner, f]
    shared = np.zeros((len(pts), posed.n_classes), dtype=bool)
    if plan.buckets is None:
        q, h, pairs = _blocking_pairs(posed, sensor, pts, owner, normals, plan)
        shared[q, posed.cls[h]] = True
    else:
        pairs = _bucket_blocking(
            posed, sensor, pts, owner, normals, plan.face_angle, plan.buckets, shared
        )
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


def _blocking_pairs(
    posed: PosedSet,
    sensor: SensorBounds,
    pts: np.ndarray,
    owner: np.ndarray,
    normals: np.ndarray,
    plan: _PairPlan,
) -> tuple[np.ndarray, np.ndarray, int]:
    """(point, hypothesis) pairs where a face of the hypothesis blocks the point: within
    the pose/sensor tolerance of it, with the same normal; and how many candidate
    (point, face) pairs were measured.

    Faces fall into buckets of normal angle at least as wide as the widest angle
    tolerance; in a bucket they are sorted by their extent along its direction n,
    and a face within p of a point q spans some of [n.q - p, n.q + p]. Only the
    faces of a point's bucket and its two neighbours that pass this are measured.
    """
    fh, ff = np.nonzero(posed.valid)
    angle = np.arctan2(normals[:, 1], normals[:, 0])
    # points in chunks whose candidate pairs stay under PAIR_CHUNK: a round part with
    # holes, its rotation still free, pairs every point with a million faces
    step = max(1, PAIR_CHUNK // plan.per_point)
    found = [
        _pairs_in(posed, sensor, pts, owner, angle, plan.face_angle, fh, ff, plan.buckets, lo, step)
        for lo in range(0, len(pts), step)
    ]
    if not found:
        return np.zeros(0, np.int64), np.zeros(0, np.int64), 0
    pairs = sum(n for _, _, n in found)
    return (
        np.concatenate([q for q, _, _ in found]),
        np.concatenate([h for _, h, _ in found]),
        pairs,
    )


def _pairs_in(
    posed: PosedSet,
    sensor: SensorBounds,
    pts: np.ndarray,
    owner: np.ndarray,
    angle: np.ndarray,
    face_angle: np.ndarray,
    fh: np.ndarray,
    ff: np.ndarray,
    buckets: _Buckets | None,
    lo: int,
    step: int,
) -> tuple[np.ndarray, np.ndarray, int]:
    """The blocking (point, hypothesis) pairs of the points lo .. lo + step, and how
    many candidate pairs were measured."""
    part = slice(lo, lo + step)
    pts, owner, angle = pts[part], owner[part], angle[part]
    if buckets is None:  # some tolerance spans a third of the directions: every face
        q = np.repeat(np.arange(len(pts)), len(fh))
        face = np.tile(np.arange(len(fh)), len(pts))
    else:
        q, face = _bucket_pairs(posed, sensor, pts, owner, angle, buckets)
    # the normals first (one gather each), the distances of the pairs they leave
    h, g = fh[face], owner[q]
    n_tol = 2 * sensor.normal_error + posed.rotation[g] + posed.rotation[h]
    turn = np.abs(wrap_angle(face_angle[face] - angle[q]))
    keep = turn <= n_tol + ANGLE_SLACK
    measured = len(q)
    q, face, h, g = q[keep], face[keep], h[keep], g[keep]
    p_tol = 2 * sensor.position_error + (posed.eps_t[g] + posed.eps_t[h]) / 2
    s, e, p = posed.start[fh, ff][face], posed.end[fh, ff][face], pts[q]
    dist = segment_distance(p[:, 0], p[:, 1], s[:, 0], s[:, 1], e[:, 0], e[:, 1])
    ok = dist <= p_tol + LENGTH_SLACK * posed.scale
    return q[ok] + lo, h[ok], measured


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


def _bucket_pairs(
    posed: PosedSet,
    sensor: SensorBounds,
    pts: np.ndarray,
    owner: np.ndarray,
    angle: np.ndarray,
    buckets: _Buckets,
) -> tuple[np.ndarray, np.ndarray]:
    """Candidate (point, face) pairs: same or neighbouring normal-angle bucket, and
    overlapping extents along the bucket's direction (a superset of the blocking pairs)."""
    width, used, span, n_buckets = buckets.width, buckets.used, buckets.span, buckets.n_buckets
    # the point's bucket and its two neighbours, where used
    mine = np.floor((angle + np.pi) / width).astype(np.int64)
    near = (mine[:, None] + np.array([-1, 0, 1])) % n_buckets  # (Q, 3)
    slot = np.clip(np.searchsorted(used, near), 0, len(used) - 1)
    ok = used[slot] == near
    qi, k = np.nonzero(ok)
    b = slot[qi, k]
    n_dir = (used[b] + 0.5) * width - np.pi
    x = pts[qi, 0] * np.cos(n_dir) + pts[qi, 1] * np.sin(n_dir)
    # within p of the point: 2 eps_d + (eps_t(g) + eps_t(h)) / 2, at most this
    reach = 2 * sensor.position_error + (posed.eps_t[owner[qi]] + posed.eps_t.max()) / 2
    reach = reach + 2e-9 * posed.scale
    lo = sorted_count(buckets.sorted_low, b, x - reach - span[b], "left")
    hi = sorted_count(buckets.sorted_low, b, x + reach, "right")
    count = hi - lo
    q = np.repeat(qi, count)
    at = np.arange(len(q)) - np.repeat(np.cumsum(count) - count, count)
    face = buckets.order[buckets.first[np.repeat(b, count)] + np.repeat(lo, count) + at]
    return q, face


def _bucket_blocking(
    posed: PosedSet,
    sensor: SensorBounds,
    pts: np.ndarray,
    owner: np.ndarray,
    normals: np.ndarray,
    face_angle: np.ndarray,
    buckets: _Buckets,
    shared: np.ndarray,
) -> int:
    """The blocking classes of every point into `shared` (points, classes), through
    the buckets (:func:`_bucket_pairs`, then the normal and distance tests of
    :func:`_pairs_in`) in one compiled pass without the pairs' arrays; returns how
    many candidate (point, face) pairs were measured."""
    fh, ff = np.nonzero(posed.valid)
    start, end = posed.start[fh, ff], posed.end[fh, ff]
    b = buckets
    arrays = (
        c_array(pts, dtype=float),
        c_array(owner, dtype=np.int64),
        np.arctan2(normals[:, 1], normals[:, 0]),
    )
    table = (
        float(b.width),
        int(b.n_buckets),
        c_array(b.used, np.int64),
        c_array(b.span, float),
        c_array(b.order, np.int64),
        c_array(b.first, np.int64),
        c_array(b.sorted_low, float),
    )
    faces = (c_array(face_angle, float), c_array(fh, np.int64), c_array(start), c_array(end))
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
    return int(_blocking_kernel(*arrays, *table, *faces, *tolerances, shared))


@numba.njit(cache=True, nogil=True)
def _blocking_kernel(  # type: ignore[no-untyped-def]
    pts,
    owner,
    angle,
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
    measured = 0
    for q in range(pts.shape[0]):
        g = owner[q]
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
                if shared[q, cls[h]]:
                    continue  # this class is known to block the point
                n_tol = two_phi + rotation[g] + rotation[h]
                turn = abs((face_angle[face] - angle[q] + math.pi) % (2 * math.pi) - math.pi)
                if turn > n_tol + ANGLE_SLACK:
                    continue
                ax, ay, bx, by = start[face, 0], start[face, 1], end[face, 0], end[face, 1]
                ex, ey = bx - ax, by - ay
                sq = max(ex * ex + ey * ey, 1e-300)
                u = ((pts[q, 0] - ax) * ex + (pts[q, 1] - ay) * ey) / sq
                u = min(max(u, 0.0), 1.0)
                dist = math.hypot(pts[q, 0] - (ax + u * ex), pts[q, 1] - (ay + u * ey))
                if dist <= two_eps_d + (eps_t[g] + eps_t[h]) / 2 + dist_slack:
                    shared[q, cls[h]] = True
    return measured
