"""The set of poses consistent with the contacts (set membership, DESIGN §4.4).

A pose ``(t', theta')`` is consistent when every assigned contact's normal lies
within phi of its face's posed normal and its point within eps_d of the face's
posed line. For a fixed theta' the consistent translations form a convex
polygon (slabs); theta' runs over the interval the normals allow. From that set:
sound error bounds that need no linearization (:func:`consistent_set_bounds`),
its volume, the bounded-error likelihood of the contacts
(:func:`consistent_volume`), and poses spread over it (:func:`consistent_poses`).

World frame, lengths in the object files' unit, angles in radians.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numba
import numpy as np

from planner.compiled import c_array
from planner.geometry import (
    ANGLE_SLACK,
    LENGTH_SLACK,
    SHARE_SLACK,
    rotate,
    rotation_matrices,
    wrap_angle,
)

__all__ = [
    "MAX_FACES",
    "ConsistentSet",
    "consistent_poses",
    "consistent_set_bounds",
    "consistent_volume",
    "latest_faces",
]

#: Faces whose contacts the likelihood's polygons hold at most (the latest touched).
MAX_FACES = 8


@dataclass(frozen=True, eq=False)
class ConsistentSet:
    """What the set of poses consistent with the contacts says, per row (K,):
    `moved` (K, P) the largest displacement of each model point from the fit,
    `dtheta` the largest rotation from it (both inf where unknown), and `feasible`,
    False only where no pose at all is consistent (the interpretation is impossible
    while the errors stay within their bounds)."""

    moved: np.ndarray
    dtheta: np.ndarray
    feasible: np.ndarray


def consistent_set_bounds(
    points: np.ndarray,
    normals: np.ndarray,
    face_normals: np.ndarray,
    face_offsets: np.ndarray,
    assigned: np.ndarray,
    theta: np.ndarray,
    t: np.ndarray,
    model_points: np.ndarray,
    eps_d: float,
    phi: float,
    samples: int = 25,
    max_contacts: int = 7,
) -> ConsistentSet:
    """Largest displacement of model points over every pose CONSISTENT with the
    contacts (set membership), for determined poses; no linearization.

    A pose ``(t', theta')`` is consistent when every assigned contact's normal lies
    within phi of its face's posed normal, ``|psi_j - theta' - angle(n_a)| <= phi``
    (an interval of theta'), and its measured point lies within eps_d of the face's
    posed line, ``|n'_j·(p_j - t') - d_a| <= eps_d`` with ``n'_j = R(theta') n_a``:
    for a fixed theta' that is a polygon of t' (slabs), bounded when two faces are
    not parallel. theta' is sampled across its interval, `samples` points a step
    ``delta`` apart; every theta' lies within ``delta / 2`` of a sample, and there
    its slabs lie inside the sample's slabs widened by ``lever delta / 2``
    (``lever`` = the outline's radius about the model origin plus eps_d, the
    farthest a contact can be from t'). The displacement ``|R(theta') v + t' - (R(theta) v + t)|``
    of a model point v is convex in t', so its maximum over a widened polygon is at
    a vertex; ``|v| delta / 2`` covers the rotation between samples. Every pose
    consistent with the contacts is thereby covered: the bounds are sound, and
    when no widened polygon holds a point the interpretation is impossible. Unlike
    the estimator's worst case (:func:`planner.recognition.pose_fit.point_bounds`),
    errors do not add up: every contact shrinks the set.

    `points`, `normals` (s, 2) measured, or (K, s, 2) per row; `face_normals`
    (K, s, 2), `face_offsets` (K, s), `assigned` (K, s) as for :func:`fit_batch`;
    `theta` (K,), `t` (K, 2) the fits; `model_points` (P, 2), the outline's
    vertices among them. Rows whose latest `max_contacts` assigned contacts hold no
    two non-parallel faces are unknown (inf, feasible): the polygon is unbounded.
    """
    K, s = assigned.shape
    P = len(model_points)
    points = np.broadcast_to(points, (K, s, 2))
    normals = np.broadcast_to(normals, (K, s, 2))
    moved = np.full((K, P), np.inf)
    dth = np.full(K, np.inf)
    feasible = np.ones(K, dtype=bool)
    if K == 0 or s < 2:
        return ConsistentSet(moved, dth, feasible)
    from_end = np.cumsum(assigned[:, ::-1], axis=1)[:, ::-1]
    use = assigned & (from_end <= max_contacts)
    slack = ANGLE_SLACK  # rounding of the measured angles
    lo, hi = _theta_interval(normals, face_normals, use, theta, phi + slack)
    lever = float(np.hypot(*np.asarray(model_points, dtype=float).T).max()) + eps_d
    # a chunk's largest arrays: the crossings of the used contacts' slabs (at most
    # `max_contacts` of them) at every rotation, and the model points moved
    used = min(s, max_contacts)
    per_row = samples * (2 * used * (used - 1) + s + P)
    chunk = max(1, 2_000_000 // per_row)
    for k0 in range(0, K, chunk):
        sl = slice(k0, min(K, k0 + chunk))
        moved[sl], dth[sl], feasible[sl] = _sweep(
            points[sl],
            face_normals[sl],
            face_offsets[sl],
            use[sl],
            theta[sl],
            t[sl],
            lo[sl],
            hi[sl],
            model_points,
            eps_d,
            lever,
            samples,
        )
    return ConsistentSet(moved, dth, feasible)


def _sweep(
    points: np.ndarray,
    face_normals: np.ndarray,
    face_offsets: np.ndarray,
    use: np.ndarray,
    theta: np.ndarray,
    t: np.ndarray,
    lo: np.ndarray,
    hi: np.ndarray,
    model_points: np.ndarray,
    eps_d: float,
    lever: float,
    samples: int,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`consistent_set_bounds` on one chunk of rows."""
    empty_range = hi < lo
    span = np.where(empty_range, 0.0, hi - lo)
    delta = span / (samples - 1)  # (K,) step between samples
    d_theta = lo[:, None] + span[:, None] * np.linspace(0.0, 1.0, samples)  # offsets from the fit
    width = eps_d + lever * delta / 2  # (K,) slab half-width, widened for the step
    vx, vy, ok, bounded = _polygons(points, face_normals, face_offsets, use, theta, d_theta, width)
    bounded &= ~empty_range
    ok &= ~empty_range[:, None, None]
    # displacement of each model point: R' v + t' - (R v + t), largest over the vertices
    model_points = c_array(model_points, dtype=float)
    fit_pts = rotate(rotation_matrices(theta), model_points) + t[:, None, :]
    norm = np.full((len(theta), len(model_points)), -np.inf)
    _largest_moves(
        c_array(vx), c_array(vy), c_array(ok),
        c_array(theta[:, None] + d_theta), model_points, fit_pts, norm,
    )  # fmt: skip
    radius = np.hypot(*model_points.T)  # (P,) |v|
    moved = norm + radius[None] * delta[:, None] / 2  # (K, P)
    feasible = ok.any(axis=2)  # (K, N)
    ang = np.where(feasible, np.abs(d_theta), -np.inf).max(axis=1)
    dth = ang + delta / 2
    some = feasible.any(axis=1)
    unknown = ~bounded & ~empty_range
    moved[~some | unknown] = np.inf
    dth[~some | unknown] = np.inf
    return moved, dth, some | unknown


@numba.njit(cache=True, nogil=True)
def _largest_moves(vx, vy, ok, angle, model_points, fit_pts, out):  # type: ignore[no-untyped-def]
    """out[k, p] = the largest ``|R(angle[k, n]) v_p + (vx, vy)[k, n, i] - fit_pts[k, p]|``
    over the rotations n and the polygon vertices i that are `ok` (left as it is
    where none is): one pass, without the (K, N, V, P) array of displacements."""
    K, N, V = vx.shape
    for k in range(K):
        for n in range(N):
            c, s = math.cos(angle[k, n]), math.sin(angle[k, n])
            for i in range(V):
                if not ok[k, n, i]:
                    continue
                for p in range(model_points.shape[0]):
                    mx, my = model_points[p, 0], model_points[p, 1]
                    dx = c * mx - s * my + vx[k, n, i] - fit_pts[k, p, 0]
                    dy = s * mx + c * my + vy[k, n, i] - fit_pts[k, p, 1]
                    d = math.sqrt(dx * dx + dy * dy)
                    if d > out[k, p]:
                        out[k, p] = d


def consistent_volume(
    points: np.ndarray,
    normals: np.ndarray,
    face_normals: np.ndarray,
    face_offsets: np.ndarray,
    assigned: np.ndarray,
    theta: np.ndarray,
    eps_d: float,
    phi: float,
    samples: int = 25,
    max_faces: int = MAX_FACES,
) -> np.ndarray:
    """Volume (area x radians) of the set of poses consistent with the contacts,
    per row (K,): the bounded-error likelihood of the contacts up to a constant
    (uniform errors within eps_d and phi, uniform prior over the pose).

    theta' runs over the interval the normals allow (as in
    :func:`consistent_set_bounds`, `samples` points); at each sample the
    translations keeping every assigned contact within eps_d of its face's posed
    line form a convex polygon (slabs), whose area is the shoelace sum of its
    vertices (the slab-edge crossings inside every slab) in angular order; the
    trapezoid rule integrates over theta'. 0 where nothing is consistent or
    eps_d is 0; inf where two non-parallel faces are missing (unbounded). Only the
    contacts on the `max_faces` faces touched last count (:func:`latest_faces`)."""
    K, s = assigned.shape
    points = np.broadcast_to(points, (K, s, 2))
    normals = np.broadcast_to(normals, (K, s, 2))
    volume = np.zeros(K)
    if K == 0 or s < 2 or eps_d <= 0:
        return np.full(K, np.inf) if s < 2 else volume
    assigned = latest_faces(face_normals, face_offsets, assigned, max_faces)
    lo, hi = _theta_interval(normals, face_normals, assigned, theta, phi)
    # a chunk's largest arrays hold its contacts and the corner tests of the slabs:
    # one slab per face touched, however many contacts lie on it
    g = min(s, _distinct_faces(face_normals, face_offsets), max_faces)
    chunk = max(1, 1_000_000 // (samples * (s + 2 * g**3)))
    for k0 in range(0, K, chunk):
        sl = slice(k0, min(K, k0 + chunk))
        volume[sl] = _volume(
            points[sl], face_normals[sl], face_offsets[sl], assigned[sl],
            theta[sl], lo[sl], hi[sl], eps_d, samples,
        )  # fmt: skip
    return volume


def _distinct_faces(face_normals: np.ndarray, face_offsets: np.ndarray) -> int:
    """How many distinct faces (offset and normal) the rows hold between them: one
    sort of the flattened keys (a row-wise unique of the triples took longer)."""
    keys = (face_normals[..., 1].ravel(), face_normals[..., 0].ravel(), face_offsets.ravel())
    order = np.lexsort(keys)
    ranked = np.stack([k[order] for k in keys])
    return int(1 + np.any(ranked[:, 1:] != ranked[:, :-1], axis=0).sum()) if order.size else 0


def _theta_interval(
    normals: np.ndarray,
    face_normals: np.ndarray,
    assigned: np.ndarray,
    theta: np.ndarray,
    phi: float,
) -> tuple[np.ndarray, np.ndarray]:
    """(lo, hi) (K,): the rotations from the fit that keep every assigned measured
    normal within phi of its face's posed normal (hi < lo: none)."""
    psi = np.arctan2(normals[..., 1], normals[..., 0])
    face_angle = np.arctan2(face_normals[..., 1], face_normals[..., 0])
    r_ang = wrap_angle(psi - face_angle - theta[:, None])
    lo = np.where(assigned, r_ang - phi, -np.inf).max(axis=1)
    hi = np.where(assigned, r_ang + phi, np.inf).min(axis=1)
    return lo, hi


def _face_groups(
    face_normals: np.ndarray, face_offsets: np.ndarray, use: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Contacts of one hypothesis that lie on the same face (same posed line) give
    parallel slabs, whose intersection is one slab: their group id `gid` (K, S) and,
    per group (K, G), its face's normal and whether any contact of it is used. G is
    at most the number of faces the USED contacts touch, however many contacts
    there are (an unused contact joins group 0 and is skipped)."""
    K, S = use.shape
    big = np.inf
    keys = (
        np.where(use, face_offsets, big),
        np.where(use, face_normals[..., 1], big),
        np.where(use, face_normals[..., 0], big),
    )
    order = np.lexsort(keys, axis=-1)
    key = np.stack(keys, axis=-1)
    ranked = np.take_along_axis(key, order[..., None], axis=1)
    first = np.ones((K, S), dtype=bool)
    first[:, 1:] = np.any(ranked[:, 1:] != ranked[:, :-1], axis=-1)
    first &= np.take_along_axis(use, order, axis=1)
    gid = np.empty((K, S), dtype=np.int64)
    np.put_along_axis(gid, order, np.maximum(np.cumsum(first, axis=1) - 1, 0), axis=1)
    G = int(first.sum(axis=1).max(initial=0))
    rows = np.broadcast_to(np.arange(K)[:, None], (K, S))
    g_normals = np.zeros((K, G, 2))
    g_use = np.zeros((K, G), dtype=bool)
    if G:
        g_normals[rows[use], gid[use]] = face_normals[use]
        g_use[rows[use], gid[use]] = True
    return gid, g_normals, g_use


def latest_faces(
    face_normals: np.ndarray, face_offsets: np.ndarray, assigned: np.ndarray, limit: int
) -> np.ndarray:
    """(K, S) the assigned contacts on the `limit` faces touched most recently: the
    polygons' work grows as the cube of the faces they hold, and a contact run
    along a finely drawn curve touches a new face almost every time. Fewer slabs
    make a larger set (a superset of the consistent one): what it weighs stays a
    weight, and bounds taken over it stay sound."""
    if assigned.sum(axis=1).max(initial=0) <= limit:  # no more contacts than faces kept
        return assigned
    gid, _, g_use = _face_groups(face_normals, face_offsets, assigned)
    K, S = assigned.shape
    faces_touched = g_use.shape[1]
    if faces_touched <= limit:
        return assigned
    rows = np.broadcast_to(np.arange(K)[:, None], (K, S))
    latest = np.full((K, faces_touched), -1)
    np.maximum.at(latest, (rows[assigned], gid[assigned]), np.nonzero(assigned)[1])
    rank = np.argsort(np.argsort(-latest, axis=1, kind="stable"), axis=1)
    keep = (rank < limit) & (latest >= 0)
    return assigned & np.take_along_axis(keep, gid, axis=1)


def _polygons(
    points: np.ndarray,
    face_normals: np.ndarray,
    face_offsets: np.ndarray,
    use: np.ndarray,
    theta: np.ndarray,
    d_theta: np.ndarray,
    width: float | np.ndarray,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The consistent translations at rotations ``theta + d_theta`` (K, N): the
    convex polygon where every used contact lies within `width` (scalar or (K,))
    of its face's posed line, as its candidate vertices (slab-edge crossings)
    `vx`, `vy` (K, N, V), `ok` (K, N, V) for those inside every slab, and
    `bounded` (K,): two non-parallel faces are used.

    The contacts on one face make one slab (the intersection of theirs), so the
    work grows with the faces touched, not with the number of contacts."""
    K, N = d_theta.shape
    gid, g_normals, g_use = _face_groups(face_normals, face_offsets, use)
    G = g_use.shape[1]
    V = 4 * (G * (G - 1) // 2)
    vx, vy = np.zeros((K, N, V)), np.zeros((K, N, V))
    ok = np.zeros((K, N, V), dtype=bool)
    bounded = np.zeros(K, dtype=bool)
    w0 = np.broadcast_to(np.asarray(width, dtype=float), theta.shape)
    _polygon_vertices(
        c_array(points, dtype=float),
        c_array(face_normals, dtype=float),
        c_array(face_offsets, dtype=float),
        c_array(use),
        gid,
        g_normals,
        g_use,
        c_array(theta[:, None] + d_theta),
        c_array(w0),
        vx, vy, ok, bounded,
    )  # fmt: skip
    return vx, vy, ok, bounded


@numba.njit(cache=True, nogil=True)
def _polygon_vertices(  # type: ignore[no-untyped-def]
    points, face_normals, face_offsets, use, gid, g_normals, g_use, angle, w0, vx, vy, ok, bounded
):
    """:func:`_polygons`, one row and rotation at a time: per face group, the slab
    n . t in [centre - w, centre + w] (the intersection of its contacts' slabs, w
    < 0 when they cannot all be met), then the four crossings of the edges of each
    two non-parallel slabs, `ok` where inside every slab (within the rounding
    slack). Crossings are laid out pair by pair (i < j), four per pair."""
    K, N = angle.shape
    S = use.shape[1]
    G = g_use.shape[1]
    centre = np.zeros(G)
    half = np.zeros(G)
    tol = np.zeros(G)
    nx = np.zeros(G)
    ny = np.zeros(G)
    c_max = np.zeros(G)
    c_min = np.zeros(G)
    for k in range(K):
        for n in range(N):
            c, s = math.cos(angle[k, n]), math.sin(angle[k, n])
            for g in range(G):
                c_max[g], c_min[g] = -math.inf, math.inf
            for j in range(S):
                if not use[k, j]:
                    continue
                fx, fy = face_normals[k, j, 0], face_normals[k, j, 1]
                value = (c * fx - s * fy) * points[k, j, 0] + (s * fx + c * fy) * points[k, j, 1]
                value -= face_offsets[k, j]
                g = gid[k, j]
                c_max[g] = max(c_max[g], value)
                c_min[g] = min(c_min[g], value)
            met = True
            for g in range(G):
                if not g_use[k, g]:
                    c_max[g], c_min[g] = 0.0, 0.0
                centre[g] = (c_max[g] + c_min[g]) / 2
                half[g] = w0[k] - (c_max[g] - c_min[g]) / 2
                tol[g] = LENGTH_SLACK * (1.0 + abs(centre[g])) + 1e-12
                if g_use[k, g] and half[g] < -tol[g]:
                    met = False
                half[g] = max(half[g], 0.0)
                nx[g] = c * g_normals[k, g, 0] - s * g_normals[k, g, 1]
                ny[g] = s * g_normals[k, g, 0] + c * g_normals[k, g, 1]
            q = 0
            for i in range(G):
                for j in range(i + 1, G):
                    det = nx[i] * ny[j] - ny[i] * nx[j]
                    good = abs(det) > SHARE_SLACK and g_use[k, i] and g_use[k, j]
                    if not good:
                        det = 1.0
                    else:
                        bounded[k] = True
                    for side in range(4):
                        ci = centre[i] + half[i] * (-1.0 if side < 2 else 1.0)
                        cj = centre[j] + half[j] * (-1.0 if side % 2 == 0 else 1.0)
                        x = (ci * ny[j] - cj * ny[i]) / det
                        y = (nx[i] * cj - nx[j] * ci) / det
                        vx[k, n, q], vy[k, n, q] = x, y
                        inside = good and met
                        for g in range(G):
                            if not inside:
                                break
                            if g_use[k, g]:
                                proj = nx[g] * x + ny[g] * y
                                inside = abs(proj - centre[g]) <= half[g] + tol[g]
                        ok[k, n, q] = inside
                        q += 1


def _volume(
    points: np.ndarray,
    face_normals: np.ndarray,
    face_offsets: np.ndarray,
    use: np.ndarray,
    theta: np.ndarray,
    lo: np.ndarray,
    hi: np.ndarray,
    eps_d: float,
    samples: int,
) -> np.ndarray:
    """:func:`consistent_volume` on one chunk of rows."""
    span = np.maximum(hi - lo, 0.0)
    d_theta = lo[:, None] + span[:, None] * np.linspace(0.0, 1.0, samples)
    vx, vy, ok, bounded = _polygons(points, face_normals, face_offsets, use, theta, d_theta, eps_d)
    area = _polygon_areas(vx, vy, ok)  # (K, N)
    step = span / (samples - 1)
    volume = (area.sum(axis=1) - (area[:, 0] + area[:, -1]) / 2) * step
    return np.where(bounded, volume, np.inf)


def _polygon_areas(vx: np.ndarray, vy: np.ndarray, ok: np.ndarray) -> np.ndarray:
    """(K, N) the area of the convex polygon whose vertices are the `ok` crossings
    of row k at rotation n: in angular order about their mean, the shoelace sum
    (0 below three vertices). The mean and the angular order are numpy's (its sort
    decides between vertices that coincide, as many do at a polygon's corners),
    the shoelace is compiled and sums in numpy's order: the areas are the array
    formula's bit for bit."""
    count = ok.sum(axis=-1)
    mx = np.where(ok, vx, 0.0).sum(axis=-1) / np.maximum(count, 1)
    my = np.where(ok, vy, 0.0).sum(axis=-1) / np.maximum(count, 1)
    ang = np.where(ok, np.arctan2(vy - my[..., None], vx - mx[..., None]), np.inf)
    order = np.argsort(ang, axis=-1)
    area = np.zeros(count.shape)
    _shoelace(c_array(vx), c_array(vy), order, count, area)
    return area


@numba.njit(cache=True, nogil=True)
def _shoelace(vx, vy, order, count, out):  # type: ignore[no-untyped-def]
    """out[k, n] = |sum of x_a y_b - y_a x_b| / 2 over consecutive vertices a, b of
    `order` (the first `count` entries, closed), summed over all V slots (zeros
    past `count`) as numpy's pairwise summation adds."""
    K, N, V = vx.shape
    terms = np.empty(V)
    for k in range(K):
        for n in range(N):
            c = count[k, n]
            if c < 3:
                continue
            for i in range(V):
                terms[i] = 0.0
            for i in range(c):
                a, b = order[k, n, i], order[k, n, (i + 1) % c]
                terms[i] = vx[k, n, a] * vy[k, n, b] - vy[k, n, a] * vx[k, n, b]
            out[k, n] = abs(_pairwise_sum(terms, 0, V)) / 2


@numba.njit(cache=True, nogil=True)
def _pairwise_sum(a, lo, n):  # type: ignore[no-untyped-def]
    """sum(a[lo:lo + n]) as numpy's float reduction adds: halves (cut at a
    multiple of 8) down to blocks of at most 128 terms (:func:`_block_sum`), the
    halves' sums added as they return. Without recursion (a cached recursive
    kernel does not load back safely): the halving tree walked with a stack."""
    if n <= 128:
        return _block_sum(a, lo, n)
    # post-order walk: (lo, n, stage) frames; stage 0 = split, 1 = add the halves
    f_lo = np.empty(64, np.int64)
    f_n = np.empty(64, np.int64)
    f_stage = np.empty(64, np.int64)
    sums = np.empty(64)
    top, depth = 0, 0
    f_lo[0], f_n[0], f_stage[0] = lo, n, 0
    while top >= 0:
        m = f_n[top]
        if m <= 128:
            sums[depth] = _block_sum(a, f_lo[top], m)
            depth += 1
            top -= 1
        elif f_stage[top] == 0:
            half = m // 2
            half -= half % 8
            f_stage[top] = 1
            # the right half is walked after the left: push it first
            f_lo[top + 1], f_n[top + 1], f_stage[top + 1] = f_lo[top] + half, m - half, 0
            f_lo[top + 2], f_n[top + 2], f_stage[top + 2] = f_lo[top], half, 0
            top += 2
        else:
            depth -= 1
            sums[depth - 1] = sums[depth - 1] + sums[depth]
            top -= 1
    return sums[0]


@numba.njit(cache=True, nogil=True)
def _block_sum(a, lo, n):  # type: ignore[no-untyped-def]
    """numpy's pairwise sum of at most 128 terms: one by one below 8, else eight
    running sums added in pairs, then the rest one by one."""
    if n < 8:
        res = 0.0
        for i in range(lo, lo + n):
            res += a[i]
        return res
    r0, r1, r2, r3 = a[lo], a[lo + 1], a[lo + 2], a[lo + 3]
    r4, r5, r6, r7 = a[lo + 4], a[lo + 5], a[lo + 6], a[lo + 7]
    i = 8
    while i < n - n % 8:
        j = lo + i
        r0 += a[j]
        r1 += a[j + 1]
        r2 += a[j + 2]
        r3 += a[j + 3]
        r4 += a[j + 4]
        r5 += a[j + 5]
        r6 += a[j + 6]
        r7 += a[j + 7]
        i += 8
    res = ((r0 + r1) + (r2 + r3)) + ((r4 + r5) + (r6 + r7))
    while i < n:
        res += a[lo + i]
        i += 1
    return res


@functools.lru_cache(maxsize=32)
def _mix(vertices: int, count: int = 8) -> np.ndarray:
    """Fixed mixing weights of the consistent-set samples (recognition must be a
    function of its inputs): `count` Dirichlet(1, ..., 1) draws over `vertices`."""
    return np.random.default_rng(vertices).dirichlet(np.ones(vertices), size=count)


def consistent_poses(
    points: np.ndarray,
    normals: np.ndarray,
    face_normals: np.ndarray,
    face_offsets: np.ndarray,
    assigned: np.ndarray,
    theta: np.ndarray,
    eps_d: float,
    phi: float,
    rotations: int = 4,
    max_faces: int = MAX_FACES,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Poses spread over the set consistent with the contacts, per row: at
    `rotations` rotations across the interval the normals allow (cell midpoints),
    fixed convex mixtures of the polygon's vertices (inside it, the polygon
    being convex). Returns theta' (K, M), t' (K, M, 2) and `valid` (K, M) (False
    where the polygon is empty or unbounded). Only the contacts on the
    `max_faces` faces touched last count (:func:`latest_faces`): the poses spread
    over a superset of the consistent set."""
    K, s = assigned.shape
    points = np.broadcast_to(points, (K, s, 2))
    normals = np.broadcast_to(normals, (K, s, 2))
    assigned = latest_faces(face_normals, face_offsets, assigned, max_faces)
    lo, hi = _theta_interval(normals, face_normals, assigned, theta, phi)
    span = np.maximum(hi - lo, 0.0)
    d_theta = lo[:, None] + span[:, None] * (np.arange(rotations) + 0.5) / rotations
    vx, vy, ok, bounded = _polygons(
        points, face_normals, face_offsets, assigned, theta, d_theta, eps_d
    )
    V = vx.shape[-1]
    mix = _mix(V)[None, None] * ok[:, :, None, :]  # (K, N, S, V)
    total = mix.sum(axis=-1)
    mix = mix / np.where(total > 0, total, 1.0)[..., None]
    tx = np.einsum("knsv,knv->kns", mix, np.where(ok, vx, 0.0))
    ty = np.einsum("knsv,knv->kns", mix, np.where(ok, vy, 0.0))
    valid = (total > 0) & bounded[:, None, None] & (hi >= lo)[:, None, None]
    th = np.broadcast_to((theta[:, None] + d_theta)[:, :, None], tx.shape)
    return (
        th.reshape(K, -1),
        np.stack([tx, ty], axis=-1).reshape(K, -1, 2),
        valid.reshape(K, -1),
    )
