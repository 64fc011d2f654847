"""The consistent translations: one slab per touched face equals one slab per contact."""

from __future__ import annotations

import math

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial import ConvexHull, QhullError

from planner.geometry import rotation_matrices
from planner.recognition.polygons import pairwise_sum, polygon_areas, slab_polygons


def _slow_polygons(points, face_normals, face_offsets, use, theta, d_theta, width):
    """The reference: every pair of contacts' slab edges crossed, checked against every
    contact (cubic in the contacts)."""
    s = use.shape[1]
    pairs = np.array(np.triu_indices(s, 1)).T
    sides = np.array([[-1.0, -1.0], [-1.0, 1.0], [1.0, -1.0], [1.0, 1.0]])
    R = rotation_matrices(theta[:, None] + d_theta)
    n = np.einsum("knij,ksj->knsi", R, face_normals)
    centre = np.einsum("knsi,ksi->kns", n, points) - face_offsets[:, None, :]
    i, j = pairs[:, 0], pairs[:, 1]
    a, b = n[:, :, i], n[:, :, j]
    det = a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]
    good = (np.abs(det) > 1e-9) & use[:, None, i] & use[:, None, j]
    det = np.where(good, det, 1.0)
    w = np.broadcast_to(np.asarray(width, dtype=float), theta.shape)[:, None, None, None]
    ci = centre[:, :, i, None] + w * sides[:, 0]
    cj = centre[:, :, j, None] + w * sides[:, 1]
    shape = (*det.shape[:2], -1)
    vx = ((ci * b[..., 1, None] - cj * a[..., 1, None]) / det[..., None]).reshape(shape)
    vy = ((a[..., 0, None] * cj - b[..., 0, None] * ci) / det[..., None]).reshape(shape)
    proj = n[..., None, :, 0] * vx[..., None] + n[..., None, :, 1] * vy[..., None]
    inside = np.abs(proj - centre[:, :, None, :]) <= w + 1e-9 * (1 + np.abs(centre[:, :, None]))
    ok = np.repeat(good, 4, axis=-1) & np.all(inside | ~use[:, None, None, :], axis=-1)
    return vx, vy, ok


def _area(x, y) -> float:
    pts = np.unique(np.round(np.stack([x, y], axis=-1), 9), axis=0)
    if len(pts) < 3:
        return 0.0
    try:
        return float(ConvexHull(pts).volume)
    except QhullError:  # collinear
        return 0.0


@settings(max_examples=150, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), contacts=st.integers(2, 12), faces=st.integers(2, 5))
def test_one_slab_per_face_gives_the_polygon_of_one_slab_per_contact(seed, contacts, faces):
    rng = np.random.default_rng(seed)
    K, N = 3, 4
    angles = rng.uniform(-np.pi, np.pi, (K, faces))
    normals = np.stack([np.cos(angles), np.sin(angles)], axis=-1)  # (K, F, 2)
    offsets = rng.uniform(2, 8, (K, faces))
    face = rng.integers(0, faces, (K, contacts))  # several contacts on one face
    rows = np.arange(K)[:, None]
    fn, fo = normals[rows, face], offsets[rows, face]
    # contacts near their face's line (in the model frame), spread along it
    along = np.stack([-fn[..., 1], fn[..., 0]], axis=-1) * rng.uniform(-5, 5, (K, contacts, 1))
    points = fn * (fo + rng.uniform(-0.3, 0.3, (K, contacts)))[..., None] + along
    use = rng.random((K, contacts)) < 0.85
    theta = rng.uniform(-0.05, 0.05, K)
    d_theta = rng.uniform(-0.02, 0.02, (K, N))
    width = rng.uniform(0.2, 0.6, K)
    vx, vy, ok, _ = slab_polygons(points, fn, fo, use, theta, d_theta, width)
    rx, ry, rok = _slow_polygons(points, fn, fo, use, theta, d_theta, width)
    for k in range(K):
        for m in range(N):
            assert ok[k, m].any() == rok[k, m].any(), (k, m)
            fast = _area(vx[k, m][ok[k, m]], vy[k, m][ok[k, m]])
            slow = _area(rx[k, m][rok[k, m]], ry[k, m][rok[k, m]])
            assert abs(fast - slow) <= 1e-6 * max(1.0, slow), (k, m, fast, slow)


@settings(max_examples=30, derandomize=True, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), n=st.integers(1, 700))
def test_the_compiled_sum_adds_as_numpy_does(seed, n):
    rng = np.random.default_rng(seed)
    a = rng.normal(size=n) * 10.0 ** rng.uniform(-5, 5, n)  # magnitudes that round
    assert pairwise_sum(a, 0, n) == a.sum()


def _areas_by_arrays(vx, vy, ok):
    """The polygon areas as array passes: angular order about the mean, shoelace."""
    count = ok.sum(axis=-1)
    mx = np.where(ok, vx, 0.0).sum(axis=-1) / np.maximum(count, 1)
    my = np.where(ok, vy, 0.0).sum(axis=-1) / np.maximum(count, 1)
    ang = np.where(ok, np.arctan2(vy - my[..., None], vx - mx[..., None]), np.inf)
    order = np.argsort(ang, axis=-1)
    sx = np.take_along_axis(np.where(ok, vx, np.nan), order, axis=-1)
    sy = np.take_along_axis(np.where(ok, vy, np.nan), order, axis=-1)
    idx = np.arange(sx.shape[-1])
    wrap = idx == np.maximum(count - 1, 0)[..., None]
    nx = np.where(wrap, sx[..., :1], np.roll(sx, -1, axis=-1))
    ny = np.where(wrap, sy[..., :1], np.roll(sy, -1, axis=-1))
    cross = np.where(idx < count[..., None], sx * ny - sy * nx, 0.0)
    return np.where(count >= 3, np.abs(np.nansum(cross, axis=-1)) / 2, 0.0)


@settings(max_examples=30, derandomize=True, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), slots=st.sampled_from([4, 12, 24, 60, 112, 180]))
def test_polygon_areas_are_the_array_formulas_bit_for_bit(seed, slots):
    # convex polygons (points of an ellipse), some corners repeated, others not kept
    rng = np.random.default_rng(seed)
    t = rng.uniform(0, 2 * np.pi, (6, 4, slots))
    vx = 20 * np.cos(t) + rng.normal() * 50
    vy = 7 * np.sin(t) + rng.normal() * 50
    vx[..., 1::2], vy[..., 1::2] = vx[..., ::2][..., : slots // 2], vy[..., ::2][..., : slots // 2]
    ok = rng.random(vx.shape) < rng.uniform(0.05, 1.0)
    found = polygon_areas(vx, vy, ok)
    assert np.array_equal(found, _areas_by_arrays(vx, vy, ok))
    corners = np.array([[[[0.0, 2, 2, 0]]], [[[0.0, 0, 2, 2]]]])  # a 2 x 2 square
    assert polygon_areas(*corners, np.ones((1, 1, 4), bool))[0, 0] == 4.0


@settings(max_examples=60, deadline=None)
@given(st.integers(0, 2**31), st.integers(1, 6), st.integers(1, 8))
def test_face_groups_number_the_distinct_faces_in_sorted_order(seed, rows, contacts):
    # contacts on a few faces (repeated keys), some unused: a group per distinct
    # (normal, offset) of the used ones, numbered in sorted order
    from planner.recognition.polygons import face_groups

    rng = np.random.default_rng(seed)
    angle = rng.integers(0, 4, (rows, contacts)) * math.pi / 2
    normals = np.stack([np.cos(angle), np.sin(angle)], axis=-1)
    offsets = rng.integers(0, 3, (rows, contacts)).astype(float)
    use = rng.random((rows, contacts)) < 0.7
    gid, g_normals, g_use = face_groups(normals, offsets, use)
    for k in range(rows):
        keys = sorted({(*normals[k, s], offsets[k, s]) for s in range(contacts) if use[k, s]})
        for s in np.flatnonzero(use[k]):
            g = keys.index((*normals[k, s], offsets[k, s]))
            assert gid[k, s] == g and g_use[k, g]
            np.testing.assert_array_equal(g_normals[k, g], normals[k, s])
        assert g_use[k].sum() == len(keys)
