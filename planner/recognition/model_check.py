"""Model check and free-space check of posed samples (DESIGN §4.5).

With the fitted pose: each contact lies on its assigned FINITE face within
``eps_d`` plus how far that face may have moved (at most ``eps_t/2``, less near
the pose's reference point) and its measured normal within ``phi + |dtheta|`` of
the face's posed normal (:func:`model_check`); the path up to each contact (less
``eps_d``), and every missed path whole, stays outside the posed outline shrunk
by ``eps_t/2`` (:func:`free_space_check`); optionally the posed outline lies
inside the safe circle (:func:`inside_workspace`).

World frame, lengths in the object files' unit, angles in radians; a pose maps
model points v to ``R(theta) v + t``.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numba
import numpy as np

from planner.compiled import c_array, segment_gap
from planner.geometry import (
    ANGLE_SLACK,
    LENGTH_SLACK,
    SHARE_SLACK,
    rotate,
    rotation_matrices,
    wrap_angle,
)
from planner.recognition.tree import Group
from planner.types import Faces, Observation, Workspace

__all__ = [
    "PathVariants",
    "clear_paths",
    "contacts_on_faces",
    "free_space_check",
    "inside_workspace",
    "model_check",
]

#: The most (pose, path) segments one pass of the free-space check holds.
CHECK_PAIRS = 200_000


def model_check(
    faces: Faces,
    face: np.ndarray,
    assigned: np.ndarray,
    points: np.ndarray,
    psi: np.ndarray,
    theta: np.ndarray,
    t: np.ndarray,
    face_move: np.ndarray,
    d_theta: np.ndarray,
    eps_d: float,
    phi: float,
    slack: float,
) -> np.ndarray:
    """(N,) does every assigned contact fit its posed face? Each contact (`points`
    (s, 2), measured normal angles `psi` (s,); or (N, s, 2) and (N, s), each
    sample's own) within ``eps_d + slack`` plus how
    far its posed FINITE face may have moved of that face (the segment, not its
    line), and its normal within ``phi + d_theta`` of the face's posed normal.

    `face`, `assigned` (N, s): each sample's face per contact and which contacts it
    assigns (spurious ones are not checked); `theta` (N,), `t` (N, 2) the poses;
    `face_move` (N, s, B, 2) how far the start and the end of each contact's posed
    face may lie from the true ones by each of B bounds (inf: not known): a point
    between them moves by at most the interpolated value of each (the bounds are
    convex along a face), so the contact must lie within ``eps_d + slack`` plus
    the smallest of those values of some point of the face. `d_theta` (N,) the
    rotation bounds.
    """
    # each contact on its finite posed face, normal within phi + dtheta
    ok = np.ones(len(theta), dtype=bool)
    posed = _compiled_inputs(points, faces, face, assigned, theta, t)
    _on_moved_faces(*posed, c_array(face_move, dtype=float), float(eps_d + slack), ok)
    ang = np.abs(wrap_angle(np.atleast_2d(psi) - theta[:, None] - faces.angle[face]))
    ok &= np.all(~assigned | (ang <= phi + d_theta[:, None] + ANGLE_SLACK), axis=1)
    return ok


@numba.njit(cache=True, nogil=True)
def _on_moved_faces(points, starts, ends, face, assigned, cos, sin, t, move, reach, out):  # type: ignore[no-untyped-def]
    """:func:`model_check`'s contacts on their faces, one pose at a time: is some
    point ``a + s e`` (0 <= s <= L) of the posed face within ``reach + m(s)`` of the
    contact, for each bound's ``m`` linear from the start's move to the end's? For
    one bound the points that are form an interval of s (``|p - a - s e| - m(s)``
    is convex in s; squared, a quadratic inequality); the bounds' intervals and
    the face must meet."""
    for n in range(cos.shape[0]):
        c, sn = cos[n], sin[n]
        tx, ty = t[n, 0], t[n, 1]
        for j in range(face.shape[1]):
            if not assigned[n, j]:
                continue
            f = face[n, j]
            ax, ay, bx, by = _posed_face(starts, ends, f, c, sn, tx, ty)
            length = math.hypot(bx - ax, by - ay)
            px, py = points[n, j, 0] - ax, points[n, j, 1] - ay
            x, y = px, py
            if length > 0.0:
                ex, ey = (bx - ax) / length, (by - ay) / length
                x, y = px * ex + py * ey, px * ey - py * ex
            lo, hi = 0.0, length
            for i in range(move.shape[2]):
                m0, m1 = move[n, j, i, 0], move[n, j, i, 1]
                if not (math.isfinite(m0) and math.isfinite(m1)):
                    continue  # this bound is not known
                k = (m1 - m0) / length if length > 0.0 else 0.0
                r0 = reach + m0
                if abs(k) >= 0.5:  # a steep taper (a tiny face): its larger end bounds it
                    k, r0 = 0.0, reach + max(m0, m1)
                # (x - s)^2 + y^2 <= (r0 + k s)^2, with r0 + k s > 0 along the face
                qa = 1.0 - k * k
                qb = -2.0 * (x + k * r0)
                qc = x * x + y * y - r0 * r0
                disc = qb * qb - 4.0 * qa * qc
                if disc < 0.0:
                    lo, hi = 1.0, 0.0
                    break
                root = math.sqrt(disc)
                lo = max(lo, (-qb - root) / (2.0 * qa))
                hi = min(hi, (-qb + root) / (2.0 * qa))
            if lo > hi + 1e-9 * (1.0 + length):
                out[n] = False
                break


def contacts_on_faces(
    points: np.ndarray,
    faces: Faces,
    face: np.ndarray,
    assigned: np.ndarray,
    theta: np.ndarray,
    t: np.ndarray,
    tol: np.ndarray | float,
) -> np.ndarray:
    """(K, M) does every assigned contact (`points` (s, 2), or (K, s, 2) per row)
    lie within `tol` (K, M)
    of its FINITE face (`face`, `assigned` (K, s)) posed at ``theta`` (K, M), ``t``
    (K, M, 2)? One pass per pose that stops at the first contact off its face,
    measuring with :func:`planner.compiled.segment_gap` (the arithmetic of
    :func:`planner.geometry.point_segment_distance`) on the faces posed as
    :func:`planner.geometry.rotate` poses them; `tol` may be one number for all."""
    out = np.ones(theta.shape, dtype=bool)
    posed = _compiled_inputs(points, faces, face, assigned, theta, t)
    _on_faces(*posed, c_array(np.broadcast_to(tol, theta.shape), dtype=float), out)
    return out


def _compiled_inputs(
    points: np.ndarray,
    faces: Faces,
    face: np.ndarray,
    assigned: np.ndarray,
    theta: np.ndarray,
    t: np.ndarray,
) -> tuple[np.ndarray, ...]:
    """The contacts (one per row: `points` (s, 2) shared or (K, s, 2) per row),
    the faces, the rows' faces and the poses (cos, sin, t) as the compiled face
    checks take them."""
    return (
        c_array(np.broadcast_to(points, (len(face), *np.shape(points)[-2:])), dtype=float),
        c_array(faces.start, dtype=float),
        c_array(faces.end, dtype=float),
        c_array(face, dtype=np.int64),
        c_array(assigned, dtype=bool),
        c_array(np.cos(theta), dtype=float),
        c_array(np.sin(theta), dtype=float),
        c_array(t, dtype=float),
    )


@numba.njit(cache=True, nogil=True)
def _on_faces(points, starts, ends, face, assigned, cos, sin, t, tol, out):  # type: ignore[no-untyped-def]
    """:func:`contacts_on_faces`, one pose at a time."""
    K, M = cos.shape
    for k in range(K):
        for m in range(M):
            c, s = cos[k, m], sin[k, m]
            tx, ty = t[k, m, 0], t[k, m, 1]
            for j in range(face.shape[1]):
                if not assigned[k, j]:
                    continue
                f = face[k, j]
                ax, ay, bx, by = _posed_face(starts, ends, f, c, s, tx, ty)
                gap_x, gap_y = segment_gap(points[k, j, 0], points[k, j, 1], ax, ay, bx, by)
                if math.hypot(gap_x, gap_y) > tol[k, m]:
                    out[k, m] = False
                    break


def inside_workspace(
    outline: np.ndarray | Sequence[np.ndarray],
    theta: np.ndarray,
    t: np.ndarray,
    eps_t: np.ndarray,
    workspace: Workspace,
    slack: float,
    which: np.ndarray | None = None,
) -> np.ndarray:
    """(N,) does the posed `outline` (model frame, (V, 2)) lie inside the safe
    circle, within ``eps_t/2 + slack``, for each pose (`theta` (N,), `t` (N, 2))?
    Given several outlines, `which` (N,) names each pose's. Only the poses whose
    disk around `t` holding the outline crosses the circle have their vertices
    posed: a finely drawn part far from the rim costs one distance."""
    outlines = [outline] if which is None else list(outline)
    which = np.zeros(len(theta), np.int64) if which is None else np.asarray(which)
    limit = np.broadcast_to(workspace.radius + eps_t / 2 + slack, np.shape(theta))
    # each outline's farthest vertex from its origin: its reach at any rotation
    far = np.array([np.hypot(*np.asarray(o, dtype=float).T).max() for o in outlines])[which]
    centre = np.hypot(*(t - np.asarray(workspace.center)).T)
    # the margin keeps rounding out of the shortcut: it answers as the vertices do
    margin = 1e-9 * (1.0 + np.abs(limit))
    out = centre + far <= limit - margin
    near = np.flatnonzero(~out & (centre - far <= limit + margin))
    for g in np.unique(which[near]):
        at = near[which[near] == g]
        verts = rotate(rotation_matrices(theta[at]), outlines[g]) + t[at, None, :]
        reach = np.hypot(*(verts - np.asarray(workspace.center)).transpose(2, 0, 1)).max(1)
        out[at] = reach <= limit[at]
    return out


def free_space_check(
    group: Group | Sequence[Group],
    observations: list[Observation],
    assigned: np.ndarray,
    theta: np.ndarray,
    t: np.ndarray,
    eps_t: np.ndarray,
    keep: np.ndarray,
    eps_d: float,
    slack: float,
    which: np.ndarray | None = None,
    variants: PathVariants | None = None,
) -> np.ndarray:
    """`keep` (N,) and, for each pose (`theta` (N,), `t` (N, 2)), every path clear
    of the posed outline shrunk by ``eps_t/2 + slack``: up to each contact the
    sample assigns (`assigned` (N, s)), less ``eps_d + slack``, and each missed path
    whole. Samples `keep` leaves out are not checked (they stay False). Given
    several groups, `which` (N,) names each pose's; given `variants`, each pose
    observes `observations` and then its variant's last path."""
    # free space: path up to each contact (less eps_d), and each missed path whole
    floor = max(slack, LENGTH_SLACK)
    shrink = eps_t / 2 + slack
    return clear_paths(
        group, observations, assigned, theta, t, shrink, keep, eps_d + slack, floor, which,
        variants,
    )  # fmt: skip


@dataclass(frozen=True, eq=False)
class PathVariants:
    """Observation lists alike but for their last observation, checked in one pass:
    `last` (B,) each list's last observation (every one a contact), `of` (N,) the
    list each checked pose observes."""

    last: Sequence[Observation]
    of: np.ndarray


def clear_paths(
    group: Group | Sequence[Group],
    observations: list[Observation],
    assigned: np.ndarray,
    theta: np.ndarray,
    t: np.ndarray,
    shrink: np.ndarray,
    keep: np.ndarray,
    back: float,
    floor: float,
    which: np.ndarray | None = None,
    variants: PathVariants | None = None,
) -> np.ndarray:
    """`keep` (N,) and, for each pose (`theta`, `t`, N rows), every path clear of
    the posed outline shrunk by `shrink`: up to each contact the row assigns
    (`assigned` (N, s)), less `back`, and each missed path whole. Given several
    groups, `which` (N,) names each row's; given `variants`, each row observes
    `observations` and then its variant's last path. Every (row, path) pair is one
    segment of a single pass per group, path height and shrink."""
    groups = [group] if which is None else list(group)  # type: ignore[arg-type]
    which = np.zeros(len(keep), np.int64) if which is None else np.asarray(which)
    keep = keep.copy()
    if not (observations or variants) or not keep.any():
        return keep
    of = np.zeros(len(keep), np.int64) if variants is None else np.asarray(variants.of)
    origin, direction, length, layer, hit = _paths(observations, groups, back, variants)
    layers = int(layer.max(initial=0)) + 1
    # which rows check which path: a missed path always, a contact's path where
    # the row assigns that contact to a face
    check = np.broadcast_to(~hit, (len(keep), len(hit))).copy()
    check[:, hit] = assigned[:, : int(hit.sum())]
    check &= keep[:, None] & (length[of] > 0)
    step = _tol_step(shrink, floor)
    steps = int(step.max(initial=0)) + 1
    rows, cols = np.nonzero(check)
    for lo in range(0, len(rows), CHECK_PAIRS):
        i, k = rows[lo : lo + CHECK_PAIRS], cols[lo : lo + CHECK_PAIRS]
        v = of[i]
        R = rotation_matrices(theta[i])
        a = np.einsum("nji,nj->ni", R, origin[v, k] - t[i])
        end = origin[v, k] + length[v, k, None] * direction[v, k]
        b = np.einsum("nji,nj->ni", R, end - t[i])
        segments = np.hstack([a, b])
        # one pass per (group, height, shrink): the segments sorted by it and split
        key = (which[i] * layers + layer[v, which[i], k]) * steps + step[i]
        kinds, inverse = np.unique(key, return_inverse=True)
        ends = np.cumsum(np.bincount(inverse, minlength=len(kinds)))[:-1]
        for kind, sel in zip(kinds, np.split(np.argsort(inverse), ends), strict=True):
            g_z, n = divmod(int(kind), steps)
            g, z = divmod(g_z, layers)
            crossed = groups[g].crossed(segments[sel], floor * _TOL_RATIO ** float(n), z)
            keep[i[sel[crossed]]] = False
    return keep


def _paths(
    observations: list[Observation],
    groups: Sequence[Group],
    back: float,
    variants: PathVariants | None = None,
) -> tuple[np.ndarray, ...]:
    """Each observation's path as the free-space check runs it, per variant (one
    without `variants`; each variant's last path after the shared ones): origin,
    direction (V, O, 2), the length checked (V, O: up to the contact less `back`,
    or whole), the layer of each group it runs at (V, G, O), and whether it met a
    contact (O,). The shared paths are read once."""
    origin = np.array([o.path.origin for o in observations], dtype=float).reshape(-1, 2)
    direction = np.array([o.path.direction for o in observations], dtype=float).reshape(-1, 2)
    hit = np.array([o.contact is not None for o in observations], dtype=bool)
    length = np.array([o.path.length for o in observations], dtype=float)
    points = np.array([o.contact.point if o.contact else (0.0, 0.0) for o in observations])
    points = points.reshape(-1, 2)
    length[hit] = np.einsum("ki,ki->k", points[hit] - origin[hit], direction[hit]) - back
    layer = np.array(
        [[g.stable.layer_index(o.path.height) for o in observations] for g in groups],
        dtype=np.int64,
    ).reshape(len(groups), -1)
    if variants is None:
        return origin[None], direction[None], length[None], layer[None], hit
    last = _paths(list(variants.last), groups, back)
    if not last[4].all():
        raise ValueError("every variant's last observation must be a contact")
    n = len(variants.last)

    def then(shared: np.ndarray, own: np.ndarray, axis: int) -> np.ndarray:
        """The shared paths' values for every variant, then the variant's own."""
        return np.concatenate([np.broadcast_to(shared, (n, *shared.shape)), own], axis)

    return (
        then(origin, last[0][0][:, None], 1),
        then(direction, last[1][0][:, None], 1),
        then(length, last[2][0][:, None], 1),
        then(layer, last[3][0].T[:, :, None], 2),
        np.append(hit, True),
    )


#: Ratio of the geometric grid the free-space shrinks are rounded onto.
_TOL_RATIO = 1.15


def _tol_step(tol: np.ndarray, floor: float) -> np.ndarray:
    """Tolerances rounded UP onto the geometric grid ``floor * _TOL_RATIO ** n``
    (sound: a larger shrink is more lenient): each one's step n (>= 0)."""
    tol = np.maximum(tol, floor)
    return np.ceil(np.log(tol / floor) / math.log(_TOL_RATIO) - SHARE_SLACK).astype(np.int64)


@numba.njit(cache=True, nogil=True)
def _posed_face(starts, ends, f, c, s, tx, ty):  # type: ignore[no-untyped-def]
    """Face f's start and end (ax, ay, bx, by) turned by (cos, sin) = (c, s) and
    moved by (tx, ty), in the arithmetic of :func:`planner.geometry.rotate`."""
    return (
        c * starts[f, 0] + -s * starts[f, 1] + tx,
        s * starts[f, 0] + c * starts[f, 1] + ty,
        c * ends[f, 0] + -s * ends[f, 1] + tx,
        s * ends[f, 0] + c * ends[f, 1] + ty,
    )
