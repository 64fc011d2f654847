"""The outline distance between posed outlines, compiled (DESIGN §2).

The directed distance from the points of one posed outline to the faces of
another is ``max_p min_f |p - segment f|``. Measuring every point against every
face costs points x faces per pair, and a round outline drawn with hundreds of
faces has hundreds of rotations near one another, every pair of them a
candidate. Two things make a pair cost about points + faces instead:

- **Early break** (the maximum of minima): once the largest distance so far is
  D, a point with some face within D cannot raise it, so its scan stops at that
  face; a point farther than the answer needs (`stop`) ends the pair.
- **Locality**: the points follow the faces in order along each ring, and the
  faces of two close outlines of one model correspond in order too, so each
  point's scan starts at the face the previous point ended on and goes outward
  both ways: the face that stops it is nearly always the first or second tried.

Both change only the order of the work: every distance is computed with the same
arithmetic as a point-by-face pass, and the answer is the exact maximum of
minima (or, past `stop`, some value above `stop`).
"""

from __future__ import annotations

import math

import numba
import numpy as np

from planner.compiled import c_array, outward, segment_gap

__all__ = ["nearest_face_distances", "pair_outline_distances"]


@numba.njit(cache=True, nogil=True)
def _segment_distance(px, py, ax, ay, bx, by):  # type: ignore[no-untyped-def]
    """Distance from (px, py) to the segment a -> b (the root of the squared gap,
    as the point-by-face pass measured it)."""
    gx, gy = segment_gap(px, py, ax, ay, bx, by)
    return math.sqrt(gx * gx + gy * gy)


@numba.njit(cache=True, nogil=True)
def _directed(points, R, t, i, starts, ends, floor, stop):  # type: ignore[no-untyped-def]
    """``max_p min_f`` distance from the model `points` (P, 2) posed by rotation
    R[i] and translation t[i] to the faces (F, 2 each), exact up to `stop`: once a
    point lies farther than `stop` from every face, that point's distance is
    returned. A point whose scan finds a face within ``max(floor, largest so
    far)`` stops there (it cannot raise the answer). Each point is posed as it is
    reached, ``(R00 x + R01 y) + tx``: the numbers the posed array holds."""
    n_faces = starts.shape[0]
    r00, r01, r10, r11 = R[i, 0, 0], R[i, 0, 1], R[i, 1, 0], R[i, 1, 1]
    tx, ty = t[i, 0], t[i, 1]
    largest = 0.0
    hint = 0
    for p in range(points.shape[0]):
        mx, my = points[p, 0], points[p, 1]
        px = r00 * mx + r01 * my
        py = r10 * mx + r11 * my
        px = px + tx
        py = py + ty
        enough = max(floor, largest)
        best = math.inf
        best_face = hint
        for k in range(n_faces):
            # hint, hint + 1, hint - 1, hint + 2, ... : every face once
            f = outward(hint, k, n_faces)
            d = _segment_distance(
                px, py, starts[f, 0], starts[f, 1], ends[f, 0], ends[f, 1]
            )  # fmt: skip
            if d < best:
                best, best_face = d, f
                if d <= enough:
                    break
        hint = best_face
        if best > largest:
            largest = best
            if largest > stop:
                return largest
    return largest


@numba.njit(cache=True, nogil=True)
def _pairs(
    a_points,
    a_R,
    a_t,
    a_starts,
    a_ends,
    ia,
    b_points,
    b_R,
    b_t,
    b_starts,
    b_ends,
    ib,
    floor,
    stop,
    out,
):  # type: ignore[no-untyped-def]
    for m in range(ia.shape[0]):
        i, j = ia[m], ib[m]
        there = _directed(a_points, a_R, a_t, i, b_starts[j], b_ends[j], floor, stop)
        if there > stop:
            out[m] = there
            continue
        back = _directed(b_points, b_R, b_t, j, a_starts[i], a_ends[i], floor, stop)
        out[m] = max(there, back)


def pair_outline_distances(
    a: tuple[np.ndarray, ...],
    ia: np.ndarray,
    b: tuple[np.ndarray, ...],
    ib: np.ndarray,
    limit: float | None = None,
) -> np.ndarray:
    """(M,) the larger of the two directed distances between outline ia[m] of `a`
    and outline ib[m] of `b`, each given as (model points (P, 2), rotations (N, 2,
    2), translations (N, 2), posed face starts and ends (N, F, 2 each)): exact when
    `limit` is None; otherwise exact up to `limit` and some value above it for the
    pairs farther apart (all that ``<= limit`` needs, at a fraction of the work)."""
    ia = c_array(ia, dtype=np.int64)
    ib = c_array(ib, dtype=np.int64)
    out = np.zeros(len(ia))
    if len(ia):
        floor, stop = (0.0, math.inf) if limit is None else (float(limit), float(limit))
        a_args = [c_array(x, dtype=np.float64) for x in a]
        b_args = [c_array(x, dtype=np.float64) for x in b]
        _pairs(*a_args, ia, *b_args, ib, floor, stop, out)
    return out


@numba.njit(cache=True, nogil=True)
def _nearest(points, starts, ends, out):  # type: ignore[no-untyped-def]
    for n in range(points.shape[0]):
        for j in range(points.shape[1]):
            best = math.inf
            for f in range(starts.shape[0]):
                d = _segment_distance(
                    points[n, j, 0], points[n, j, 1],
                    starts[f, 0], starts[f, 1], ends[f, 0], ends[f, 1],
                )  # fmt: skip
                best = min(best, d)
            out[n, j] = best


def nearest_face_distances(points: np.ndarray, starts: np.ndarray, ends: np.ndarray) -> np.ndarray:
    """(N, J) distance from each point (N, J, 2) to the nearest of the faces (F, 2
    each); inf without faces."""
    points = c_array(points, dtype=np.float64)
    out = np.empty(points.shape[:2])
    _nearest(
        points,
        c_array(starts, dtype=np.float64),
        c_array(ends, dtype=np.float64),
        out,
    )
    return out
