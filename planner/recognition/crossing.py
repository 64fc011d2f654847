"""Does a segment meet a polygon? The free-space check's test, compiled (DESIGN §4.5).

A missed path, or the path up to a contact, must stay outside the posed outline
shrunk by the pose's error bound. The check poses each path into the model frame
and asks whether the segment meets the shrunk outline (touching counts): it
meets it when it crosses or touches one of the outline's edges (outer ring and
holes alike) or, crossing none, lies inside; then its start is inside, which
the even-odd rule over every ring decides. One pass over the edges per segment,
with a bounding-box screen before each edge: a shrunk outline has tens of edges
(it is made from the simplified outline), a check thousands of segments, and a
library call per batch cost more in building line objects than in testing them.

Arithmetic is plain double precision: a segment that only grazes the outline
within rounding may be answered either way, and the shrink the check tests
against already carries a slack of that order (:data:`planner.geometry.LENGTH_SLACK`).

>>> square = ring_edges(shapely.box(0.0, 0.0, 10.0, 10.0))
>>> segments = np.array([[-5, 5, 15, 5], [2, 2, 3, 3], [-5, -5, -1, 20], [-5, 0, 0, 0]])
>>> segments_meet(segments.astype(float), square).tolist()
[True, True, False, True]
>>> segments_meet(segments.astype(float), ring_edges(shapely.Polygon())).tolist()
[False, False, False, False]
"""

from __future__ import annotations

import numba
import numpy as np
import shapely

from planner.compiled import c_array

__all__ = ["ring_edges", "segments_meet"]


def ring_edges(shape: shapely.Geometry) -> np.ndarray:
    """(E, 4) every edge ``(x0, y0, x1, y1)`` of every ring (outer and holes) of
    every polygon of `shape` (a polygon, a multipolygon or empty)."""
    rings = shapely.get_rings(shapely.get_parts(shape))
    edges = [np.hstack([c[:-1], c[1:]]) for c in map(shapely.get_coordinates, rings)]
    edges = [e for e in edges if len(e)]
    return np.concatenate(edges) if edges else np.zeros((0, 4))


def segments_meet(segments: np.ndarray, edges: np.ndarray) -> np.ndarray:
    """(N,) does each segment ``(x0, y0, x1, y1)`` of `segments` (N, 4) meet the
    polygon whose ring edges are `edges` (E, 4, from :func:`ring_edges`): cross
    or touch an edge, or lie inside?"""
    out = np.zeros(len(segments), dtype=bool)
    if len(edges):
        _meet(c_array(segments, dtype=float), c_array(edges, dtype=float), out)
    return out


@numba.njit(cache=True, nogil=True)
def _orient(ax, ay, bx, by, cx, cy):  # type: ignore[no-untyped-def]
    """Sign of the turn a -> b -> c: 1 left, -1 right, 0 collinear."""
    d = (bx - ax) * (cy - ay) - (by - ay) * (cx - ax)
    return (d > 0.0) - (d < 0.0)


@numba.njit(cache=True, nogil=True)
def _meet(segments, edges, out):  # type: ignore[no-untyped-def]
    """:func:`segments_meet` into `out`, each segment first screened against the
    box of all the edges."""
    x0 = min(edges[:, 0].min(), edges[:, 2].min())
    y0 = min(edges[:, 1].min(), edges[:, 3].min())
    x1 = max(edges[:, 0].max(), edges[:, 2].max())
    y1 = max(edges[:, 1].max(), edges[:, 3].max())
    for n in range(segments.shape[0]):
        ax, ay, bx, by = segments[n, 0], segments[n, 1], segments[n, 2], segments[n, 3]
        lox, hix = min(ax, bx), max(ax, bx)
        loy, hiy = min(ay, by), max(ay, by)
        if hix < x0 or lox > x1 or hiy < y0 or loy > y1:
            continue
        inside = False
        met = False
        for e in range(edges.shape[0]):
            cx, cy, dx, dy = edges[e, 0], edges[e, 1], edges[e, 2], edges[e, 3]
            # even-odd: does the ray from a towards +x cross this edge?
            if (cy > ay) != (dy > ay) and ax < cx + (ay - cy) * (dx - cx) / (dy - cy):
                inside = not inside
            if max(cx, dx) < lox or min(cx, dx) > hix or max(cy, dy) < loy or min(cy, dy) > hiy:
                continue
            o1 = _orient(ax, ay, bx, by, cx, cy)
            o2 = _orient(ax, ay, bx, by, dx, dy)
            if o1 == 0 and o2 == 0:  # collinear, boxes overlap: they share a point
                met = True
                break
            if (
                o1 * o2 <= 0
                and _orient(cx, cy, dx, dy, ax, ay) * _orient(cx, cy, dx, dy, bx, by) <= 0
            ):
                met = True
                break
        out[n] = met or inside
