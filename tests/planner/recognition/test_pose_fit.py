"""Pose fit (DESIGN §4.4): exact recovery, bounds that hold, batch = Kalman."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from hardware_sim.world import random_world
from planner.geometry import rotation_matrices
from planner.recognition.consistent import (
    consistent_poses,
    consistent_set_bounds,
    consistent_volume,
)
from planner.recognition.polygons import latest_faces
from planner.recognition.pose_fit import PoseFilter, fit_batch, noise_scales, point_bounds
from planner.types import Pose, SensorBounds
from tests.conftest import SET_NAMES, WORKSPACE, object_set


def _touches(world, bounds, rng, count):
    """`count` contacts with their true faces, until two non-parallel faces are among them."""
    obs, faces = [], []
    while len(obs) < count or not _rank2(world, faces):
        o, f = world.execute(world.hitting_path(rng), bounds, rng, edge_share=0.5)
        obs.append(o)
        faces.append(f)
    return obs, faces


def _rank2(world, faces) -> bool:
    n = world.stable.faces.normal[faces]
    return (
        len(faces) > 1
        and np.abs(n[:, None, 0] * n[None, :, 1] - n[:, None, 1] * n[None, :, 0]).max() > 1e-6
    )


def _arrays(world, obs, faces):
    """Measured points and normals (s, 2), and the faces' normals and offsets (1, s)."""
    stable = world.stable
    P = np.array([o.contact.point for o in obs])
    U = np.array([o.contact.normal for o in obs])
    return P, U, stable.faces.normal[faces][None], stable.faces.offset[faces][None]


def _fit(world, obs, faces, bounds, per_row=False):
    stable = world.stable
    P, U, fn, fo = _arrays(world, obs, faces)
    if per_row:
        P, U = P[None], U[None]
    sd, sp = noise_scales(bounds.position_error, bounds.normal_error, stable.centroid_radius)
    return fit_batch(P, U, fn, fo, np.ones((1, len(obs)), bool), stable.centroid[None], sd, sp)


@pytest.mark.parametrize("name", SET_NAMES)
@settings(max_examples=40, derandomize=True, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), count=st.integers(2, 5))
def test_exact_contacts_recover_the_pose(name, seed, count):
    rng = np.random.default_rng(seed)
    world = random_world(object_set(name), WORKSPACE, rng)
    obs, faces = _touches(world, SensorBounds(), rng, count)
    fit = _fit(world, obs, faces, SensorBounds())
    assert fit.rank2[0]
    scale = max(1.0, math.hypot(world.pose.x, world.pose.y))
    assert abs(fit.t[0, 0] - world.pose.x) <= 1e-9 * scale
    assert abs(fit.t[0, 1] - world.pose.y) <= 1e-9 * scale
    assert abs(math.remainder(fit.theta[0] - world.pose.theta, 2 * math.pi)) <= 1e-9


@pytest.mark.parametrize("name", SET_NAMES)
@settings(max_examples=40, derandomize=True, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), count=st.integers(2, 6))
def test_batch_fit_and_kalman_updates_agree(name, seed, count):
    bounds = SensorBounds(1.0, math.radians(3))
    rng = np.random.default_rng(seed)
    world = random_world(object_set(name), WORKSPACE, rng)
    obs, faces = _touches(world, bounds, rng, count)
    fit = _fit(world, obs, faces, bounds)
    sd, sp = noise_scales(bounds.position_error, bounds.normal_error, world.stable.centroid_radius)
    kf = PoseFilter(sd, sp)
    for o, f in zip(obs, faces, strict=True):
        kf.update(
            o.contact.point,
            o.contact.normal,
            world.stable.faces.normal[f],
            world.stable.faces.offset[f],
        )
    assert kf.ready
    x, y, theta = kf.pose
    assert np.allclose(kf.state, fit.z[0], rtol=0, atol=1e-6 * np.abs(fit.z[0]).max())
    assert abs(x - fit.t[0, 0]) <= 1e-6 and abs(y - fit.t[0, 1]) <= 1e-6
    assert abs(math.remainder(theta - fit.theta[0], 2 * math.pi)) <= 1e-6


def test_filter_reports_undetermined_pose_until_two_faces():
    kf = PoseFilter(1.0, 0.05)
    kf.update((1, 0), (1, 0), (1, 0), 1.0)
    assert not kf.ready
    with pytest.raises(ValueError, match="not determined"):
        _ = kf.pose


@pytest.mark.parametrize("name", ["thesis_like", "workshop"])
@settings(max_examples=20, derandomize=True, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), count=st.integers(2, 4))
def test_per_row_contacts_give_the_shared_fit(name, seed, count):
    bounds = SensorBounds(1.0, math.radians(5))
    rng = np.random.default_rng(seed)
    world = random_world(object_set(name), WORKSPACE, rng)
    obs, faces = _touches(world, bounds, rng, count)
    shared = _fit(world, obs, faces, bounds)
    rows = _fit(world, obs, faces, bounds, per_row=True)
    np.testing.assert_allclose(rows.z, shared.z, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(rows.sens, shared.sens, rtol=1e-9, atol=1e-12)
    P, U, fn, fo = _arrays(world, obs, faces)
    assigned = np.ones((1, len(obs)), bool)
    args = (fn, fo, assigned, shared.theta, shared.t, world.stable.outline, 1.0, math.radians(5))
    a = consistent_set_bounds(P, U, *args)
    b = consistent_set_bounds(P[None], U[None], *args)
    np.testing.assert_allclose(a.moved, b.moved)
    np.testing.assert_allclose(a.dtheta, b.dtheta)
    assert a.feasible.tolist() == b.feasible.tolist() == [True]


@pytest.mark.parametrize("name", SET_NAMES)
@settings(max_examples=30, derandomize=True, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), count=st.integers(2, 5))
def test_consistent_set_bound_covers_the_true_pose(name, seed, count):
    # set membership: the true pose keeps every contact within its bounds, so every
    # model point moves from the fit to the truth by no more than the bound
    bounds = SensorBounds(1.0, math.radians(5))
    rng = np.random.default_rng(seed)
    world = random_world(object_set(name), WORKSPACE, rng)
    obs, faces = _touches(world, bounds, rng, count)
    fit = _fit(world, obs, faces, bounds)
    stable = world.stable
    found = consistent_set_bounds(
        *_arrays(world, obs, faces),
        np.ones((1, len(obs)), bool),
        fit.theta,
        fit.t,
        stable.outline,
        bounds.position_error,
        bounds.normal_error,
    )
    fitted = Pose(float(fit.t[0, 0]), float(fit.t[0, 1]), float(fit.theta[0]))
    true_move = np.hypot(*(world.pose.apply(stable.outline) - fitted.apply(stable.outline)).T)
    assert found.feasible[0]
    assert np.all(true_move <= found.moved[0] + 1e-6)
    assert abs(math.remainder(world.pose.theta - fit.theta[0], 2 * math.pi)) <= found.dtheta[0]


def test_consistent_volume_of_two_square_touches():
    # contacts on perpendicular faces x = 0 and y = 0: at every rotation the
    # translations form a 2 eps_d square, over a rotation interval of 2 phi
    normals = np.array([[[-1.0, 0.0], [0.0, -1.0]]])
    points = np.array([[[0.0, 0.5], [0.5, 0.0]]])
    eps_d, phi = 0.1, 0.05
    volume = consistent_volume(
        points, normals, normals, np.zeros((1, 2)), np.ones((1, 2), bool), np.zeros(1), eps_d, phi
    )
    np.testing.assert_allclose(volume, 4 * eps_d**2 * 2 * phi, rtol=1e-9)
    # a normal off by phi / 2 narrows the rotation interval to 1.5 phi
    off = normals.copy()
    off[0, 0] = [-math.cos(phi / 2), -math.sin(phi / 2)]
    narrowed = consistent_volume(
        points, off, normals, np.zeros((1, 2)), np.ones((1, 2), bool), np.zeros(1), eps_d, phi
    )
    np.testing.assert_allclose(narrowed, 4 * eps_d**2 * 1.5 * phi, rtol=1e-9)
    parallel = np.array([[[-1.0, 0.0], [-1.0, 0.0]]])
    unbounded = consistent_volume(
        points, parallel, parallel, np.zeros((1, 2)), np.ones((1, 2), bool), np.zeros(1), eps_d, phi
    )
    assert np.isinf(unbounded).all()


@pytest.mark.parametrize("name", ["thesis_like", "workshop"])
@settings(max_examples=15, derandomize=True, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), count=st.integers(2, 5))
def test_consistent_poses_keep_every_contact_within_its_bounds(name, seed, count):
    # errors of at most half the bounds: the consistent set has room inside
    bounds, noise = SensorBounds(1.0, math.radians(5)), SensorBounds(0.5, math.radians(2.5))
    rng = np.random.default_rng(seed)
    world = random_world(object_set(name), WORKSPACE, rng)
    obs, faces = _touches(world, noise, rng, count)
    fit = _fit(world, obs, faces, bounds)
    points, normals, face_normals, face_offsets = _arrays(world, obs, faces)
    assigned = np.ones((1, len(obs)), bool)
    eps_d, phi = bounds.position_error, bounds.normal_error
    theta, t, valid = consistent_poses(
        points, normals, face_normals, face_offsets, assigned, fit.theta, eps_d, phi
    )
    assert valid.any()
    R = rotation_matrices(theta[valid])  # (M, 2, 2)
    n = np.einsum("mij,sj->msi", R, face_normals[0])
    gap = np.einsum("msi,si->ms", n, points) - np.einsum("msi,mi->ms", n, t[valid])
    assert np.all(np.abs(gap - face_offsets[0]) <= eps_d + 1e-9)
    ang = np.arctan2(normals[:, 1], normals[:, 0]) - np.arctan2(n[..., 1], n[..., 0])
    assert np.all(np.abs(np.remainder(ang + math.pi, 2 * math.pi) - math.pi) <= phi + 1e-9)


def _polygon_touches(seed, sides, count):
    """`count` exact contacts on random faces of a regular `sides`-gon of radius 50
    posed at a random rotation: points, normals (s, 2), face normals, offsets (1, s)."""
    rng = np.random.default_rng(seed)
    ang = np.arange(sides) * 2 * math.pi / sides
    normal = np.column_stack([np.cos(ang), np.sin(ang)])
    offset = np.full(sides, 50.0)
    faces = rng.integers(0, sides, count)
    theta = rng.uniform(-math.pi, math.pi)
    R = rotation_matrices(np.array([theta]))[0]
    tangent = normal[faces] @ np.array([[0.0, 1.0], [-1.0, 0.0]])
    along = rng.uniform(-10, 10, count)[:, None] * tangent
    points = (normal[faces] * offset[faces, None] + along) @ R.T
    normals = normal[faces] @ R.T
    return points, normals, normal[faces][None], offset[faces][None], np.array([theta])


@settings(max_examples=30, derandomize=True, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), count=st.integers(1, 16), limit=st.integers(2, 8))
def test_the_likelihood_keeps_the_contacts_on_the_faces_touched_last(seed, count, limit):
    _, _, face_normals, face_offsets, _ = _polygon_touches(seed, 24, count)
    assigned = np.random.default_rng(seed).random((1, count)) < 0.9
    kept = latest_faces(face_normals, face_offsets, assigned, limit)
    key = [tuple(face_normals[0, j].round(12)) for j in range(count)]
    touched = {key[j] for j in np.flatnonzero(assigned[0])}
    chosen = {key[j] for j in np.flatnonzero(kept[0])}
    assert not np.any(kept & ~assigned)
    if len(touched) <= limit:
        assert np.array_equal(kept, assigned)
    else:
        assert len(chosen) == limit
        # every contact on a kept face counts; no dropped face was touched after a kept one
        assert all(kept[0, j] for j in np.flatnonzero(assigned[0]) if key[j] in chosen)
        last_use = {k: max(j for j in np.flatnonzero(assigned[0]) if key[j] == k) for k in touched}
        assert min(last_use[k] for k in chosen) > max(
            (last_use[k] for k in touched - chosen), default=-1
        )


@settings(max_examples=20, derandomize=True, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), count=st.integers(3, 14), limit=st.integers(2, 8))
def test_fewer_faces_make_a_consistent_set_no_smaller(seed, count, limit):
    points, normals, face_normals, face_offsets, theta = _polygon_touches(seed, 24, count)
    assigned = np.ones((1, count), bool)
    eps_d, phi = 1.0, math.radians(3)
    args = (points, normals, face_normals, face_offsets, assigned, theta, eps_d, phi)
    whole = consistent_volume(*args, max_faces=count)
    fewer = consistent_volume(*args, max_faces=limit)
    assert np.all(fewer >= whole * (1 - 1e-9))


@settings(max_examples=20, derandomize=True, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), contacts=st.integers(1, 12), vertices=st.integers(1, 40))
def test_point_bounds_add_each_contacts_worst_case(seed, contacts, vertices):
    # the compiled sum equals the array formula: S_v = S_t + (R J v) S_theta per
    # contact, eps_d ||S_v[:2, :2]||_2 + phi |S_v[:, 2]|, over the assigned contacts
    rng = np.random.default_rng(seed)
    K = 7
    fit = type("Fit", (), {})()
    fit.theta = rng.uniform(-math.pi, math.pi, K)
    fit.sens = rng.normal(size=(K, contacts, 3, 3))
    fit.sens_origin = rng.normal(size=(K, contacts, 2, 3))
    points = rng.normal(size=(vertices, 2)) * 40
    assigned = rng.random((K, contacts)) < 0.8
    eps_d, phi = 1.0, 0.05
    arm = np.einsum("kij,pj->kpi", rotation_matrices(fit.theta) @ [[0, -1], [1, 0]], points)
    s_v = fit.sens_origin[:, :, None] + arm[:, None, :, :, None] * fit.sens[:, :, None, None, 2, :]
    each = eps_d * np.linalg.norm(s_v[..., :2], ord=2, axis=(-2, -1)) + phi * np.hypot(
        s_v[..., 0, 2], s_v[..., 1, 2]
    )
    expected = (each * assigned[:, :, None]).sum(axis=1)
    np.testing.assert_allclose(
        point_bounds(fit, points, assigned, eps_d, phi), expected, rtol=1e-9, atol=1e-12
    )
