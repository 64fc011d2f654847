"""Outlines, faces, transforms and vectorized ray casting.

All arrays are float64; points are rows ``(x, y)``. Outlines are counter-clockwise,
holes clockwise, so that every face's outward normal is its edge direction turned
by -90 degrees (pointing away from the material, into a hole for hole faces).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

__all__ = [
    "ANGLE_SLACK",
    "LENGTH_SLACK",
    "SHARE_SLACK",
    "cast_rays",
    "point_segment_distance",
    "polygon_centroid",
    "ring_faces",
    "rotate",
    "rotation_matrix",
    "segment_segment_distance",
    "signed_area",
    "vertex_turns",
    "wrap_angle",
]


#: Rounding slack of lengths, as a share of the scene's scale: a length this far
#: past a bound (times the scale) still counts as within it.
LENGTH_SLACK = 1e-9
#: Rounding slack of angles (radians).
ANGLE_SLACK = 1e-9
#: Rounding slack of dimensionless quantities: shares, probabilities, determinants.
SHARE_SLACK = 1e-9


def wrap_angle(angle: np.ndarray | float) -> np.ndarray:
    """Wrap angles (radians) into [-pi, pi)."""
    return (np.asarray(angle) + np.pi) % (2 * np.pi) - np.pi


def vertex_turns(ring: np.ndarray) -> np.ndarray:
    """(N,) how far (radians, >= 0) a closed ring (N, 2) turns at each vertex: the
    angle from the direction of face k - 1 to that of face k (face k runs from
    vertex k to k + 1).

    >>> vertex_turns(np.array([[0.0, 0], [1, 0], [1, 1], [0, 1]])).round(6).tolist()
    [1.570796, 1.570796, 1.570796, 1.570796]
    """
    edge = np.roll(ring, -1, axis=0) - ring
    heading = np.arctan2(edge[:, 1], edge[:, 0])
    return np.abs(wrap_angle(heading - np.roll(heading, 1)))


def rotation_matrix(theta: float) -> np.ndarray:
    """Counter-clockwise rotation by `theta` radians.

    >>> rotation_matrix(math.pi / 2).round(12).tolist()
    [[0.0, -1.0], [1.0, 0.0]]
    """
    c, s = math.cos(theta), math.sin(theta)
    return np.array([[c, -s], [s, c]])


def rotation_matrices(theta: np.ndarray) -> np.ndarray:
    """Stack of rotation matrices (..., 2, 2) for an array of angles."""
    theta = np.asarray(theta, dtype=float)
    out = np.empty((*theta.shape, 2, 2))
    np.cos(theta, out=out[..., 0, 0])
    np.sin(theta, out=out[..., 1, 0])
    out[..., 1, 1] = out[..., 0, 0]
    np.negative(out[..., 1, 0], out=out[..., 0, 1])
    return out


def rotate(rot: np.ndarray, points: np.ndarray) -> np.ndarray:
    """``R v`` for each rotation `rot` (N, 2, 2) and points (P, 2), the same for all,
    or (N, P, 2), one set each: (N, P, 2). Two products and a sum per coordinate,
    the numbers ``einsum("nij,npj->npi")`` gives, at a fraction of its time
    (which loops without vectorizing over so small a contraction).

    >>> rotate(rotation_matrices(np.array([0.0, math.pi / 2])), np.array([[1.0, 0.0]])).round(12)
    array([[[1., 0.]],
    <BLANKLINE>
           [[0., 1.]]])
    """
    x, y = points[..., 0], points[..., 1]
    out = np.empty((len(rot), points.shape[-2], 2))
    out[..., 0] = rot[:, 0, 0, None] * x + rot[:, 0, 1, None] * y
    out[..., 1] = rot[:, 1, 0, None] * x + rot[:, 1, 1, None] * y
    return out


def signed_area(ring: np.ndarray) -> float:
    """Shoelace area: positive for a counter-clockwise ring."""
    x, y = ring[:, 0], ring[:, 1]
    return 0.5 * float(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y))


def polygon_centroid(outline: np.ndarray, holes: Sequence[np.ndarray] = ()) -> np.ndarray:
    """Area centroid of a polygon with holes (holes clockwise subtract)."""
    total_area, moment = 0.0, np.zeros(2)
    for ring in [outline, *holes]:
        x, y = ring[:, 0], ring[:, 1]
        xn, yn = np.roll(x, -1), np.roll(y, -1)
        cross = x * yn - xn * y
        total_area += 0.5 * cross.sum()
        moment += np.array([((x + xn) * cross).sum(), ((y + yn) * cross).sum()]) / 6.0
    return moment / total_area


def ring_faces(rings: Sequence[np.ndarray]) -> dict[str, np.ndarray]:
    """Faces of oriented rings: start, end, outward normal, offset, length, angle, ring."""
    starts = np.concatenate([r for r in rings])
    ends = np.concatenate([np.roll(r, -1, axis=0) for r in rings])
    ring = np.concatenate([np.full(len(r), i) for i, r in enumerate(rings)])
    edge = ends - starts
    length = np.hypot(edge[:, 0], edge[:, 1])
    normal = np.stack([edge[:, 1], -edge[:, 0]], axis=1) / length[:, None]
    return {
        "start": starts,
        "end": ends,
        "normal": normal,
        "offset": np.einsum("ij,ij->i", normal, starts),
        "length": length,
        "angle": np.arctan2(normal[:, 1], normal[:, 0]),
        "ring": ring,
    }


def point_segment_distance(points: np.ndarray, start: np.ndarray, end: np.ndarray) -> np.ndarray:
    """Distance from points to segments, broadcast over leading axes (last axis = xy)."""
    edge = end - start
    sq = np.maximum(np.sum(edge * edge, axis=-1), 1e-300)
    u = np.clip(np.sum((points - start) * edge, axis=-1) / sq, 0.0, 1.0)
    closest = start + u[..., None] * edge
    return np.hypot(*np.moveaxis(points - closest, -1, 0))


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]


def segment_segment_distance(
    a0: np.ndarray, a1: np.ndarray, b0: np.ndarray, b1: np.ndarray
) -> np.ndarray:
    """Minimum distance between segments [a0, a1] and [b0, b1], broadcast (last axis = xy)."""
    d = np.minimum(
        np.minimum(point_segment_distance(a0, b0, b1), point_segment_distance(a1, b0, b1)),
        np.minimum(point_segment_distance(b0, a0, a1), point_segment_distance(b1, a0, a1)),
    )
    ea, eb = a1 - a0, b1 - b0
    d1, d2 = _cross(ea, b0 - a0), _cross(ea, b1 - a0)
    d3, d4 = _cross(eb, a0 - b0), _cross(eb, a1 - b0)
    crossing = (d1 * d2 <= 0) & (d3 * d4 <= 0) & ((d1 != d2) | (d1 != 0))
    return np.where(crossing, 0.0, d)


def cast_rays(
    origins: np.ndarray,
    directions: np.ndarray,
    lengths: np.ndarray,
    starts: np.ndarray,
    ends: np.ndarray,
    valid: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """First hit of each ray on a set of segments, in one numpy pass.

    `origins`, `directions` (unit) are (..., 2) and `lengths` (...); segments are
    (..., F, 2) broadcast against them (leading axes align, F is the face axis).
    A segment is hit when the ray crosses it within its length; rays that leave
    a face from behind (starting on or inside it) still report it, so callers see
    grazing and inner hits too. `valid` (..., F) masks faces out.

    Returns (distance, face): distance along the ray (inf on a miss) and the
    index of the face hit first (-1 on a miss).
    """
    o = origins[..., None, :]
    d = directions[..., None, :]
    e = ends - starts
    denom = _cross(d, e)
    w = starts - o
    with np.errstate(divide="ignore", invalid="ignore"):
        t = _cross(w, e) / denom
        u = _cross(w, d) / denom
    hit = (np.abs(denom) > 1e-15) & (t >= 0) & (u >= 0) & (u <= 1)
    hit &= t <= lengths[..., None]
    if valid is not None:
        hit &= valid
    t = np.where(hit, t, np.inf)
    face = np.argmin(t, axis=-1)
    dist = np.take_along_axis(t, face[..., None], axis=-1)[..., 0]
    return dist, np.where(np.isfinite(dist), face, -1)
