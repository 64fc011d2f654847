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
from collections.abc import Callable
from dataclasses import dataclass

import numba
import numpy as np

from planner.compiled import c_array
from planner.geometry import (
    ANGLE_SLACK,
    rotate,
    rotation_matrices,
    wrap_angle,
)
from planner.recognition.polygons import (
    distinct_faces,
    latest_faces,
    polygon_areas,
    slab_polygons,
)

__all__ = [
    "MAX_FACES",
    "ConsistentSet",
    "consistent_poses",
    "consistent_set_bounds",
    "consistent_volume",
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
    vertices among them, or (K, P, 2) per row (rows of several outlines, each
    padded with copies of its own points). Rows whose latest `max_contacts`
    assigned contacts hold no two non-parallel faces are unknown (inf, feasible):
    the polygon is unbounded.
    """
    K, s = assigned.shape
    P = np.shape(model_points)[-2]
    points = np.broadcast_to(points, (K, s, 2))
    normals = np.broadcast_to(normals, (K, s, 2))
    model_points = np.broadcast_to(np.asarray(model_points, dtype=float), (K, P, 2))
    moved = np.full((K, P), np.inf)
    dth = np.full(K, np.inf)
    feasible = np.ones(K, dtype=bool)
    if K == 0 or s < 2:
        return ConsistentSet(moved, dth, feasible)
    from_end = np.cumsum(assigned[:, ::-1], axis=1)[:, ::-1]
    use = assigned & (from_end <= max_contacts)
    slack = ANGLE_SLACK  # rounding of the measured angles
    lo, hi = _theta_interval(normals, face_normals, use, theta, phi + slack)
    # (K,) the farthest a contact can lie from t': each row's outline radius plus eps_d
    lever = np.hypot(model_points[..., 0], model_points[..., 1]).max(axis=1) + eps_d
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
            model_points[sl],
            eps_d,
            lever[sl],
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
    lever: np.ndarray,
    samples: int,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`consistent_set_bounds` on one chunk of rows (`model_points` (K, P, 2),
    `lever` (K,) per row)."""
    empty_range = hi < lo
    span = np.where(empty_range, 0.0, hi - lo)
    delta = span / (samples - 1)  # (K,) step between samples
    d_theta = lo[:, None] + span[:, None] * np.linspace(0.0, 1.0, samples)  # offsets from the fit
    width = eps_d + lever * delta / 2  # (K,) slab half-width, widened for the step
    vx, vy, ok, bounded = slab_polygons(
        points, face_normals, face_offsets, use, theta, d_theta, width
    )
    bounded &= ~empty_range
    ok &= ~empty_range[:, None, None]
    # displacement of each model point: R' v + t' - (R v + t), largest over the vertices
    model_points = c_array(model_points, dtype=float)
    fit_pts = rotate(rotation_matrices(theta), model_points) + t[:, None, :]
    norm = np.full(model_points.shape[:2], -np.inf)
    _largest_moves(
        c_array(vx), c_array(vy), c_array(ok),
        c_array(theta[:, None] + d_theta), model_points, fit_pts, norm,
    )  # fmt: skip
    radius = np.hypot(model_points[..., 0], model_points[..., 1])  # (K, P) |v|
    moved = norm + radius * delta[:, None] / 2  # (K, P)
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
    """out[k, p] = the largest ``|R(angle[k, n]) v_kp + (vx, vy)[k, n, i] - fit_pts[k, p]|``
    over the rotations n and the polygon vertices i that are `ok` (left as it is
    where none is): one pass, without the (K, N, V, P) array of displacements.
    Each rotated point is computed once per rotation, and the squares compared
    (the root of the largest square is the largest root, to the bit)."""
    K, N, V = vx.shape
    P = model_points.shape[1]
    rx = np.empty(P)
    ry = np.empty(P)
    fx = np.empty(P)
    fy = np.empty(P)
    best = np.empty(P)
    for k in range(K):
        for p in range(P):
            best[p] = -1.0
            fx[p] = fit_pts[k, p, 0]
            fy[p] = fit_pts[k, p, 1]
        for n in range(N):
            c, s = math.cos(angle[k, n]), math.sin(angle[k, n])
            for p in range(P):
                mx, my = model_points[k, p, 0], model_points[k, p, 1]
                rx[p] = c * mx - s * my
                ry[p] = s * mx + c * my
            for i in range(V):
                if not ok[k, n, i]:
                    continue
                ux, uy = vx[k, n, i], vy[k, n, i]
                for p in range(P):
                    dx = rx[p] + ux - fx[p]
                    dy = ry[p] + uy - fy[p]
                    best[p] = max(best[p], dx * dx + dy * dy)
        for p in range(P):
            if best[p] >= 0.0:
                d = math.sqrt(best[p])
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
    g = min(s, distinct_faces(face_normals, face_offsets), max_faces)
    chunk = max(1, 1_000_000 // (samples * (s + 2 * g**3)))
    for k0 in range(0, K, chunk):
        sl = slice(k0, min(K, k0 + chunk))
        volume[sl] = _volume(
            points[sl], face_normals[sl], face_offsets[sl], assigned[sl],
            theta[sl], lo[sl], hi[sl], eps_d, samples,
        )  # fmt: skip
    return volume


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
    vx, vy, ok, bounded = slab_polygons(
        points, face_normals, face_offsets, use, theta, d_theta, eps_d
    )
    area = polygon_areas(vx, vy, ok)  # (K, N)
    step = span / (samples - 1)
    volume = (area.sum(axis=1) - (area[:, 0] + area[:, -1]) / 2) * step
    return np.where(bounded, volume, np.inf)


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
    mixing: Callable[[int], np.ndarray] | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Poses spread over the set consistent with the contacts, per row: at
    `rotations` rotations across the interval the normals allow (cell midpoints),
    fixed convex mixtures of the polygon's vertices (inside it, the polygon
    being convex): `mixing(V)` (S, V) non-negative weights over the V candidate
    vertices, renormalized over those that are vertices (default: eight
    Dirichlet draws, which gather near the polygon's middle). Returns theta'
    (K, M), t' (K, M, 2) and `valid` (K, M) (False where the polygon is empty or
    unbounded). Only the contacts on the `max_faces` faces touched last count
    (:func:`latest_faces`): the poses spread
    over a superset of the consistent set."""
    K, s = assigned.shape
    points = np.broadcast_to(points, (K, s, 2))
    normals = np.broadcast_to(normals, (K, s, 2))
    assigned = latest_faces(face_normals, face_offsets, assigned, max_faces)
    lo, hi = _theta_interval(normals, face_normals, assigned, theta, phi)
    span = np.maximum(hi - lo, 0.0)
    d_theta = lo[:, None] + span[:, None] * (np.arange(rotations) + 0.5) / rotations
    vx, vy, ok, bounded = slab_polygons(
        points, face_normals, face_offsets, assigned, theta, d_theta, eps_d
    )
    V = vx.shape[-1]
    mix = (mixing or _mix)(V)[None, None] * ok[:, :, None, :]  # (K, N, S, V)
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
