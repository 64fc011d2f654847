"""The polygons of the consistent set (DESIGN §4.4): at a fixed rotation the
translations that keep every used contact within a width of its face's posed line
form a convex polygon, the intersection of one slab per face touched
(:func:`slab_polygons`: its vertices among the crossings of the slabs' edges), and
its area (:func:`polygon_areas`) is what the likelihood integrates. The contacts a
polygon holds (:func:`latest_faces`) and its work (:func:`distinct_faces`) are
chosen here too. The loops over rows and rotations are compiled (numba, cached).

World frame, lengths in the object files' unit, angles in radians.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from planner.compiled import c_array
from planner.geometry import LENGTH_SLACK, SHARE_SLACK

__all__ = [
    "distinct_faces",
    "face_groups",
    "latest_faces",
    "pairwise_sum",
    "polygon_areas",
    "slab_polygons",
]


def distinct_faces(face_normals: np.ndarray, face_offsets: np.ndarray) -> int:
    """How many distinct faces (offset and normal) the rows hold between them: one
    sort of the flattened keys (a row-wise unique of the triples took longer)."""
    keys = (face_normals[..., 1].ravel(), face_normals[..., 0].ravel(), face_offsets.ravel())
    order = np.lexsort(keys)
    ranked = np.stack([k[order] for k in keys])
    return int(1 + np.any(ranked[:, 1:] != ranked[:, :-1], axis=0).sum()) if order.size else 0


def face_groups(
    face_normals: np.ndarray, face_offsets: np.ndarray, use: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Contacts of one hypothesis that lie on the same face (same posed line) give
    parallel slabs, whose intersection is one slab: their group id `gid` (K, S) and,
    per group (K, G), its face's normal and whether any contact of it is used. G is
    at most the number of faces the USED contacts touch, however many contacts
    there are. Groups are numbered in the order of their (normal x, normal y,
    offset); an unused contact takes the last group's number (0 when none) and is
    skipped.

    >>> n = np.array([[[0.0, 1.0], [1.0, 0.0], [0.0, 1.0]]])
    >>> gid, g_n, g_use = face_groups(n, np.array([[2.0, 0.0, 2.0]]), np.ones((1, 3), bool))
    >>> gid.tolist(), g_n.tolist(), g_use.tolist()
    ([[0, 1, 0]], [[[0.0, 1.0], [1.0, 0.0]]], [[True, True]])
    """
    K, S = use.shape
    gid = np.zeros((K, S), dtype=np.int64)
    count = np.zeros(K, dtype=np.int64)
    normals = c_array(face_normals, dtype=np.float64)
    _face_groups(normals, c_array(face_offsets, dtype=np.float64), c_array(use), gid, count)
    G = int(count.max(initial=0))
    g_normals = np.zeros((K, G, 2))
    g_use = np.zeros((K, G), dtype=bool)
    if G:
        rows = np.broadcast_to(np.arange(K)[:, None], (K, S))
        g_normals[rows[use], gid[use]] = normals[use]
        g_use[rows[use], gid[use]] = True
    return gid, g_normals, g_use


@numba.njit(cache=True, nogil=True)
def _face_groups(normals, offsets, use, gid, count):  # type: ignore[no-untyped-def]
    """Per row: the used contacts sorted (stably) by normal x, normal y, offset, a
    new group at each change of the three."""
    K, S = use.shape
    order = np.empty(S, dtype=np.int64)
    for k in range(K):
        m = 0
        for s in range(S):
            if use[k, s]:
                # insertion sort: S is the number of contacts
                q = m
                while q > 0 and _key_less(normals[k], offsets[k], s, order[q - 1]):
                    order[q] = order[q - 1]
                    q -= 1
                order[q] = s
                m += 1
        g = -1
        for p in range(m):
            s = order[p]
            if p == 0 or _key_less(normals[k], offsets[k], order[p - 1], s):
                g += 1
            gid[k, s] = g
        for s in range(S):
            if not use[k, s]:
                gid[k, s] = max(g, 0)
        count[k] = g + 1


@numba.njit(cache=True, nogil=True, inline="always")
def _key_less(normals, offsets, a, b):  # type: ignore[no-untyped-def]
    """Is contact a's (normal x, normal y, offset) before contact b's?"""
    for i in range(3):
        x = normals[a, i] if i < 2 else offsets[a]
        y = normals[b, i] if i < 2 else offsets[b]
        if x < y:
            return True
        if x > y:
            return False
    return False


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
    gid, _, g_use = face_groups(face_normals, face_offsets, assigned)
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


def slab_polygons(
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
    gid, g_normals, g_use = face_groups(face_normals, face_offsets, use)
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
    """:func:`slab_polygons`, one row and rotation at a time: per face group, the slab
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


def polygon_areas(vx: np.ndarray, vy: np.ndarray, ok: np.ndarray) -> np.ndarray:
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
            out[k, n] = abs(pairwise_sum(terms, 0, V)) / 2


@numba.njit(cache=True, nogil=True)
def pairwise_sum(a, lo, n):  # type: ignore[no-untyped-def]
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
