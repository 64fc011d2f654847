"""Where a path passes near the faces it may meet, compiled (DESIGN §4.11).

A miss, or a path that may slip past its contact, may still meet the true
outline where it passes within the vertex zone of a face turned toward it
(:mod:`planner.planning.uncertain_hits`: near misses, and near passes after a
slip). For each (path, hypothesis) pair this finds, in one pass over the hypothesis'
faces, the stretch of the path within that zone of some such face, and the range
of those faces' normals. Each face's part of the path is the chord of a capsule:
the points within r of a segment form a convex set, the union of the chords
through the two end disks and through the band along the segment. A hit's path
may also pass a vertex before its contact (a close pass): :func:`closest_vertices`
finds the vertex nearest each path's run up to its contact. Where each path first
meets each hypothesis' faces, what all of this starts from, is :func:`crossings`.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from planner.compiled import SQUARE_SCREEN, c_array, segment_gap

__all__ = ["closest_vertices", "crossings", "near_stretches"]


@numba.njit(cache=True, nogil=True, inline="always")
def _disk_chord(ox, oy, dx, dy, px, py, r):  # type: ignore[no-untyped-def]
    """The interval of s where o + s d lies within `r` of p (lo > hi when empty)."""
    wx, wy = px - ox, py - oy
    centre, off = wx * dx + wy * dy, wx * dy - wy * dx
    half_sq = r * r - off * off
    if half_sq >= 0:
        half = math.sqrt(half_sq)
        return centre - half, centre + half
    return math.inf, -math.inf


@numba.njit(cache=True, nogil=True, inline="always")
def _linear_range(start, rate, low, high):  # type: ignore[no-untyped-def]
    """The interval of s where low <= start + s rate <= high (lo > hi when empty)."""
    if abs(rate) < 1e-12:
        if start >= low and start <= high:
            return -math.inf, math.inf
        return math.inf, -math.inf
    a, b = (low - start) / rate, (high - start) / rate
    return min(a, b), max(a, b)


@numba.njit(cache=True, nogil=True, inline="always")
def _capsule(ox, oy, dx, dy, ax, ay, bx, by, r):  # type: ignore[no-untyped-def]
    """Where along the line o + s d (unit d) the points lie within `r` of the
    segment [a, b]: [lo, hi] (lo > hi when empty)."""
    lo, hi = math.inf, -math.inf
    for px, py in ((ax, ay), (bx, by)):
        c_lo, c_hi = _disk_chord(ox, oy, dx, dy, px, py, r)
        if c_lo <= c_hi:
            lo, hi = min(lo, c_lo), max(hi, c_hi)
    length = math.hypot(bx - ax, by - ay)
    ux, uy = (bx - ax) / max(length, 1e-300), (by - ay) / max(length, 1e-300)
    # the band: |u x (p - a)| <= r and 0 <= (p - a) . u <= |b - a|, each linear in s
    s_lo, s_hi = _linear_range(ux * (oy - ay) - uy * (ox - ax), ux * dy - uy * dx, -r, r)
    a_lo, a_hi = _linear_range((ox - ax) * ux + (oy - ay) * uy, dx * ux + dy * uy, 0.0, length)
    b_lo, b_hi = max(s_lo, a_lo), min(s_hi, a_hi)
    if b_lo <= b_hi:
        lo, hi = min(lo, b_lo), max(hi, b_hi)
    return lo, hi


@numba.njit(cache=True, nogil=True)
def _stretches(  # type: ignore[no-untyped-def]
    sx, sy, ex, ey, nx, ny, angle, valid, tol, turn_sin,
    ox, oy, dx, dy, rows, start, end, px, py, out,
):  # fmt: skip
    """out (n, 6): flag, s_lo, s_hi, base, t_lo, t_hi of each pair; a face within
    the vertex zone of the point (px, py) does not count (NaN: no point)."""
    for i in range(len(rows)):
        row = rows[i]
        s_lo, s_hi, t_lo, t_hi = math.inf, -math.inf, math.inf, -math.inf
        base = angle[row, 0]
        first = True
        for j in range(sx.shape[1]):
            if not valid[row, j] or not dx[i] * nx[row, j] + dy[i] * ny[row, j] < turn_sin[row]:
                continue
            lo, hi = _capsule(
                ox[i], oy[i], dx[i], dy[i], sx[row, j], sy[row, j], ex[row, j], ey[row, j], tol[row]
            )
            lo, hi = max(lo, start[i]), min(hi, end[i])
            if not lo <= hi:
                continue
            if not math.isnan(px[i]):
                gx, gy = segment_gap(px[i], py[i], sx[row, j], sy[row, j], ex[row, j], ey[row, j])
                if math.hypot(gx, gy) <= tol[row]:
                    continue
            if first:
                base, first = angle[row, j], False
            turn = (angle[row, j] - base + math.pi) % (2 * math.pi) - math.pi
            s_lo, s_hi = min(s_lo, lo), max(s_hi, hi)
            t_lo, t_hi = min(t_lo, turn), max(t_hi, turn)
        if first:  # no face near: zeros keep the infinities out of the caller's sums
            s_lo = s_hi = t_lo = t_hi = 0.0
        out[i, 0] = 0.0 if first else 1.0
        out[i, 1], out[i, 2], out[i, 3], out[i, 4], out[i, 5] = s_lo, s_hi, base, t_lo, t_hi


def near_stretches(
    faces: tuple[np.ndarray, ...],
    valid: np.ndarray,
    tol: np.ndarray,
    turn_sin: np.ndarray,
    paths: tuple[np.ndarray, ...],
    rows: np.ndarray,
    span: tuple[np.ndarray, np.ndarray],
    contact: tuple[np.ndarray, np.ndarray] | None = None,
) -> np.ndarray:
    """(n, 6) for n pairs of a path (`paths`: origin x, y and unit direction x, y,
    each (n,)) and a hypothesis' faces (row `rows` (n,) of `faces`: start x, y, end
    x, y, normal x, y, each (H, F), `valid` (H, F)), between distances `span` (lo,
    hi) along the path: whether it passes within `tol` (H,) of a face turned toward
    it (``d . n < turn_sin``) and not within `tol` of the `contact` point (x, y);
    the first and last distance of that stretch, the normal angle of the first such
    face, and the least and greatest turn of those faces' normals from it."""
    sx, sy, ex, ey, nx, ny = (c_array(f, dtype=np.float64) for f in faces)
    n = len(rows)
    px, py = contact if contact is not None else (np.full(n, np.nan), np.full(n, np.nan))
    out = np.empty((n, 6))
    _stretches(
        sx, sy, ex, ey, nx, ny,
        c_array(np.arctan2(ny, nx)),
        c_array(valid, dtype=np.bool_),
        c_array(tol, dtype=np.float64),
        c_array(turn_sin, dtype=np.float64),
        *(c_array(p, dtype=np.float64) for p in paths),
        c_array(rows, dtype=np.int64),
        *(c_array(s, dtype=np.float64) for s in span),
        c_array(px, dtype=np.float64),
        c_array(py, dtype=np.float64),
        out,
    )  # fmt: skip
    return out


@numba.njit(cache=True, nogil=True)
def _closest(sx, sy, valid, tol, ox, oy, px, py, pairs, out_k, out_gap):  # type: ignore[no-untyped-def]
    for e in range(pairs.shape[0]):
        c, h = pairs[e, 0], pairs[e, 1]
        best, k = math.inf, 0
        # squared lengths screen out the clear cases; hypot decides the close ones
        zone = tol[h] * tol[h]
        for j in range(sx.shape[1]):
            if not valid[h, j]:
                continue
            vx, vy = sx[h, j] - px[c, h], sy[h, j] - py[c, h]
            sq = vx * vx + vy * vy
            if sq <= zone * (1 - SQUARE_SCREEN) or (
                sq <= zone * (1 + SQUARE_SCREEN) and math.hypot(vx, vy) <= tol[h]
            ):
                continue  # within the contact's own vertex zone
            gx, gy = segment_gap(sx[h, j], sy[h, j], ox[c], oy[c], px[c, h], py[c, h])
            if gx * gx + gy * gy > best * best * (1 + SQUARE_SCREEN):
                continue
            gap = math.hypot(gx, gy)
            if gap < best:
                best, k = gap, j
        out_k[e], out_gap[e] = k, best


def closest_vertices(
    vertices: tuple[np.ndarray, np.ndarray],
    valid: np.ndarray,
    tol: np.ndarray,
    origins: np.ndarray,
    contact: tuple[np.ndarray, np.ndarray],
    pairs: tuple[np.ndarray, np.ndarray],
) -> tuple[np.ndarray, np.ndarray]:
    """For pairs (path c, hypothesis h): the vertex of h (`vertices` x, y (H, F),
    `valid`) nearest the path's run from its origin (`origins` (C, 2)) to its
    `contact` point (x, y (C, H)), leaving out the vertices within `tol` (H,) of the
    contact, and its distance (inf, vertex 0, when none is left).

    >>> square = (np.array([[0.0, 2.0, 2.0, 0.0]]), np.array([[0.0, 0.0, 2.0, 2.0]]))
    >>> k, gap = closest_vertices(square, np.ones((1, 4), bool), np.array([0.1]),
    ...     np.array([[3.0, -1.0]]), (np.array([[1.0]]), np.array([[0.0]])),
    ...     (np.array([0]), np.array([0])))
    >>> int(k[0]), round(float(gap[0]), 3)
    (1, 0.447)
    """
    n = len(pairs[0])
    out_k, out_gap = np.zeros(n, dtype=np.int64), np.empty(n)
    _closest(
        c_array(vertices[0], dtype=np.float64),
        c_array(vertices[1], dtype=np.float64),
        c_array(valid, dtype=np.bool_),
        c_array(tol, dtype=np.float64),
        c_array(origins[:, 0], dtype=np.float64),
        c_array(origins[:, 1], dtype=np.float64),
        c_array(contact[0], dtype=np.float64),
        c_array(contact[1], dtype=np.float64),
        c_array(np.column_stack(pairs), dtype=np.int64),
        out_k,
        out_gap,
    )
    return out_k, out_gap


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _crossings(ox, oy, dx, dy, length, sx, sy, ex, ey, face_length, valid, t, u):  # type: ignore[no-untyped-def]
    for c in range(len(ox)):
        for h in range(sx.shape[0]):
            for j in range(sx.shape[1]):
                edge_x, edge_y = ex[h, j] - sx[h, j], ey[h, j] - sy[h, j]
                denom = dx[c] * edge_y - dy[c] * edge_x
                wx, wy = sx[h, j] - ox[c], sy[h, j] - oy[c]
                t_cj = (wx * edge_y - wy * edge_x) / denom
                u_cj = (wx * dy[c] - wy * dx[c]) / denom
                meets = valid[h, j] and abs(denom) > 1e-12 * face_length[h, j]
                meets = meets and t_cj >= 0 and t_cj <= length[c] and u_cj >= 0 and u_cj <= 1
                t[c, h, j] = t_cj if meets else math.inf
                u[c, h, j] = u_cj


def crossings(
    origins: np.ndarray,
    directions: np.ndarray,
    lengths: np.ndarray,
    faces: tuple[np.ndarray, ...],
    face_length: np.ndarray,
    valid: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """Where each path (origin, unit direction, length: (C, 2), (C, 2), (C,)) crosses
    the line of each face (`faces`: start x, y, end x, y, each (H, F)): `t` (C, H, F)
    the distance along the path where it meets the face within both ends (inf
    where it does not, or runs parallel), `u` the share along the face of that
    crossing (from the start; taken even where the face is not met).

    >>> t, u = crossings(np.array([[0.0, -5.0]]), np.array([[0.0, 1.0]]), np.array([10.0]),
    ...     tuple(np.array([[v]]) for v in (-1.0, 0.0, 3.0, 0.0)), np.array([[4.0]]),
    ...     np.ones((1, 1), bool))
    >>> float(t[0, 0, 0]), float(u[0, 0, 0])
    (5.0, 0.25)
    """
    shape = (len(origins), *valid.shape)
    t, u = np.empty(shape), np.empty(shape)
    _crossings(
        c_array(origins[:, 0], dtype=np.float64),
        c_array(origins[:, 1], dtype=np.float64),
        c_array(directions[:, 0], dtype=np.float64),
        c_array(directions[:, 1], dtype=np.float64),
        c_array(lengths, dtype=np.float64),
        *(c_array(f, dtype=np.float64) for f in faces),
        c_array(face_length, dtype=np.float64),
        c_array(valid, dtype=np.bool_),
        t,
        u,
    )
    return t, u
