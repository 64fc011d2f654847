"""Slices of one solid's stable poses that are the same up to its tessellation.

A curved solid exported as triangles rests on any of the many facets that stand
for one curved face: a cylinder with 64 sides lies on each of them, a part with
a spherical cap on dozens of its facets. Each is a stable pose of the mesh, and
their slices differ by a fraction of the tessellation, far below what a sensor
can tell: they are one pose of the real part. :func:`nearly_congruent` says when
two slices coincide within a length `tolerance` under a planar rotation about
their centroids (no mirroring): the Hausdorff distance between their boundaries
(holes included) at most `tolerance`, and the out-of-plane normals of the faces
nearest each other within :data:`NORMAL_Z_TOLERANCE` (the facets of one
tessellated sphere differ by about that much; a caller merging such poses must
not then hold contacts to one variant's out-of-plane normals).

The rotation is found from each slice's polar signature (its farthest boundary
point from the centroid in each of :data:`SIGNATURE_BINS` directions): the few
circular shifts that match the signatures best (one FFT correlation) are each
checked exactly. A pair no shift matches is kept apart: more poses, never a
wrong merge.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import shapely
from scipy.spatial import cKDTree

__all__ = ["NORMAL_Z_TOLERANCE", "SIGNATURE_BINS", "nearly_congruent"]

#: Directions of the polar signature.
SIGNATURE_BINS = 720
#: Shifts of the signature checked exactly, best matches first.
SHIFTS_CHECKED = 4
#: How far the out-of-plane normals of matched faces may differ.
NORMAL_Z_TOLERANCE = 0.1


def _boundary_points(rings: list[np.ndarray], step: float) -> tuple[np.ndarray, np.ndarray]:
    """Points along every ring at most `step` apart, and the face each lies on
    (faces numbered ring after ring)."""
    pts, face, first = [], [], 0
    for r in rings:
        a, b = r, np.roll(r, -1, axis=0)
        n = np.maximum(1, np.ceil(np.hypot(*(b - a).T) / step)).astype(np.int64)
        f = np.repeat(np.arange(len(r)), n)
        share = (np.arange(len(f)) - np.repeat(np.cumsum(n) - n, n)) / n[f]
        pts.append(a[f] + share[:, None] * (b - a)[f])
        face.append(first + f)
        first += len(r)
    return np.concatenate(pts), np.concatenate(face)


def _signature(points: np.ndarray) -> np.ndarray:
    """(SIGNATURE_BINS,) farthest distance from the origin per direction bin."""
    angle = np.arctan2(points[:, 1], points[:, 0])
    k = ((angle + math.pi) / (2 * math.pi) * SIGNATURE_BINS).astype(np.int64) % SIGNATURE_BINS
    out = np.zeros(SIGNATURE_BINS)
    np.maximum.at(out, k, np.hypot(points[:, 0], points[:, 1]))
    full = np.flatnonzero(out > 0)
    if 0 < len(full) < SIGNATURE_BINS:  # a direction the outline does not cross
        out = np.interp(np.arange(SIGNATURE_BINS), full, out[full], period=SIGNATURE_BINS)
    return out


def _polygon(rings: list[np.ndarray]) -> shapely.Polygon:
    return shapely.Polygon(rings[0], rings[1:])


def nearly_congruent(a: Any, b: Any, tolerance: float) -> bool:
    """Whether two centred slices (:class:`~planner.models.mesh.MeshSlice`) coincide
    within `tolerance` (length) under a rotation about their centroids (see the
    module's note).

    >>> from planner.models.mesh import MeshSlice
    >>> t = np.linspace(0, 2 * np.pi, 64, endpoint=False)
    >>> ring = np.column_stack([20 * np.cos(t), 10 * np.sin(t)])
    >>> slice_ = lambda r: MeshSlice(r, (), np.zeros(len(r)), np.zeros(2))
    >>> turned = ring @ np.array([[0.0, -1.0], [1.0, 0.0]]).T  # a quarter turn
    >>> nearly_congruent(slice_(ring), slice_(turned * 1.001), 0.1)
    True
    >>> nearly_congruent(slice_(ring), slice_(turned * 1.05), 0.1)
    False
    """
    if len(a.holes) != len(b.holes) or not tolerance > 0:
        return False
    pa_, pb_ = _polygon(a.rings), _polygon(b.rings)
    # boundaries within t of each other enclose areas within about t x perimeter
    if abs(pa_.area - pb_.area) > 2 * tolerance * max(pa_.length, pb_.length):
        return False
    ra = float(np.hypot(*np.concatenate(a.rings).T).max())
    rb = float(np.hypot(*np.concatenate(b.rings).T).max())
    # samples close enough that no direction bin goes empty along the outline
    step = min(tolerance / 2, math.pi * min(ra, rb) / SIGNATURE_BINS / 2)
    pa, fa = _boundary_points(a.rings, step)
    pb, fb = _boundary_points(b.rings, step)
    if abs(ra - rb) > 2 * tolerance:  # centroids move by less than the boundaries do
        return False
    sa, sb = _signature(pa), _signature(pb)
    # sum_k sa[k] sb[k + s] for every circular shift s, in one FFT
    corr = np.fft.irfft(np.conj(np.fft.rfft(sa)) * np.fft.rfft(sb), n=SIGNATURE_BINS)
    cost = (sa @ sa + sb @ sb - 2 * corr) / SIGNATURE_BINS
    boundary_b = pb_.boundary
    nz_a, nz_b = np.asarray(a.normal_z), np.asarray(b.normal_z)
    best = np.argsort(cost, kind="stable")[:SHIFTS_CHECKED]
    # each best shift and its neighbours (a bin is half a degree wide)
    shifts = dict.fromkeys((best[:, None] + np.array([0, -1, 1])[None, :]).ravel().tolist())
    for shift in shifts:
        theta = 2 * math.pi * shift / SIGNATURE_BINS
        c, s = math.cos(theta), math.sin(theta)
        rotation = np.array([[c, -s], [s, c]])
        turned = [r @ rotation.T for r in a.rings]
        gap = shapely.hausdorff_distance(_polygon(turned).boundary, boundary_b, densify=0.25)
        if gap > tolerance:
            continue
        # each face, at its middle, meets a face of the other within `tolerance`
        # whose out-of-plane normal agrees, both ways
        if _normals_agree(turned, nz_a, pb, fb, nz_b, tolerance) and _normals_agree(
            b.rings, nz_b, pa @ rotation.T, fa, nz_a, tolerance
        ):
            return True
    return False


def _normals_agree(
    rings: list[np.ndarray],
    normal_z: np.ndarray,
    points: np.ndarray,
    face: np.ndarray,
    other_z: np.ndarray,
    tolerance: float,
) -> bool:
    """Does the middle of every face of `rings` lie within `tolerance` of a sample
    (`points`, on faces `face`) of the other slice whose face's out-of-plane normal
    (`other_z`) is within NORMAL_Z_TOLERANCE of its own (`normal_z`)?"""
    middle = np.concatenate([(r + np.roll(r, -1, axis=0)) / 2 for r in rings])
    near = cKDTree(points).query_ball_point(middle, r=tolerance)
    return all(
        len(n) and np.min(np.abs(other_z[face[n]] - z)) <= NORMAL_Z_TOLERANCE
        for n, z in zip(near, normal_z, strict=True)
    )
