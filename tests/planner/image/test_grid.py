"""Grid multi-interpretation image and the thesis' paths (DESIGN §4.9, thesis ch. 4, App. 2, 4)."""

from __future__ import annotations

import math

import numpy as np
import pytest
import shapely
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st
from scipy import ndimage

from planner.errors import PlanningNotPossibleError
from planner.geometry import cast_rays
from planner.image.grid import GridMapping, build_grid
from planner.image.vector import build_mii
from planner.image.windows import choose, sweep_rays, thesis_paths, windows
from planner.models.outlines import make_stable_pose
from planner.types import ErrorBound, Hypothesis, ObjectModel, Pose, Workspace
from tests.planner.image.test_vector import (
    TWIN_CONTACTS,
    bump_block_case,
    confused_pairs,
    consistent_hypotheses,
    first_hits,
    object_set,
    random_scene,
    shifted_rectangles,
)

AGREEMENT = settings(
    max_examples=12,
    derandomize=True,
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much],
)
finite = st.floats(-1e3, 1e3, allow_nan=False, allow_infinity=False)


def thesis_error(models):
    """The thesis' simulations: error disk of 10% of the effective object diameter."""
    pose = models[0].stable_poses[0]
    return 0.1 * 2.0 * pose.centroid_radius


def cells_world(grid, mask):
    return grid.mapping.inverse(np.argwhere(mask) + 1.0)


def resolvable(mii, cell: float) -> bool:
    """No two parallel faces of different classes closer than 3 cells unless collinear
    and overlapping: below that the grid cannot tell them apart (it merges them)."""
    f = mii.faces
    scale = max(np.ptp(np.concatenate([f.start, f.end]), axis=0))
    same = (np.abs(f.normal @ f.normal.T - 1.0) < 1e-12) & (f.klass[:, None] != f.klass[None])
    gap_lines = np.abs(f.offset[:, None] - f.offset[None])
    t = np.stack([-f.normal[:, 1], f.normal[:, 0]], axis=1)
    s0, s1 = np.einsum("ik,ik->i", f.start, t), np.einsum("ik,ik->i", f.end, t)
    # along face i's line, the gap between the two faces' extents (< 0: overlap)
    lo_j = np.minimum(np.einsum("jk,ik->ij", f.start, t), np.einsum("jk,ik->ij", f.end, t))
    hi_j = np.maximum(np.einsum("jk,ik->ij", f.start, t), np.einsum("jk,ik->ij", f.end, t))
    gap_along = np.maximum(lo_j - np.maximum(s0, s1)[:, None], np.minimum(s0, s1)[:, None] - hi_j)
    tiny = 1e-6 * scale
    near_parallel = same & (gap_lines > tiny) & (gap_lines < 3 * cell) & (gap_along < 3 * cell)
    near_ends = same & (gap_lines <= tiny) & (gap_along > tiny) & (gap_along < 3 * cell)
    return not (near_parallel.any() or near_ends.any())


# ------------------------------------------------------------ App. 2 mapping


@given(
    points=st.lists(st.tuples(finite, finite), min_size=2, max_size=8),
    eps_t=st.floats(0.0, 50.0),
    size=st.integers(8, 400),
)
@settings(max_examples=60, derandomize=True, deadline=None)
def test_app2_mapping_round_trips(points, eps_t, size):
    pts = np.array(points)
    assume(np.ptp(pts, axis=0).max() > 1e-3)
    m = GridMapping.fit(pts, eps_t, size)
    np.testing.assert_allclose(m.inverse(m.forward(pts)), pts, atol=1e-9 * (1 + abs(pts).max()))
    np.testing.assert_allclose(m.forward_matrix() @ m.inverse_matrix(), np.eye(3), atol=1e-9)
    # the image plus its growth margin (worst case eps_t sqrt(2) / 2) fits in cells 1..B
    g = m.forward(pts)
    margin = eps_t * m.scale * math.sqrt(2) / 2
    assert g.min() - margin >= 1.0 - 1e-9 and g.max() + margin <= size + 1e-9


def test_app2_mapping_matches_the_thesis_matrices():
    m = GridMapping(x_min=-5.0, y_min=2.0, delta=20.0, eps_t=2.0, size=70)
    a = 20.0 * 68 / 24.0  # A = Delta (B - 2) / (Delta + 2 eps_t)
    s = a / 20.0
    expected = [[s, 0, s * (2.0 + 5.0) + 1], [0, s, s * (2.0 - 2.0) + 1], [0, 0, 1]]
    np.testing.assert_allclose(m.forward_matrix(), expected)
    np.testing.assert_allclose(m.inverse_matrix()[:2, 2], [-2.0 - 1 / s - 5.0, -2.0 - 1 / s + 2.0])


# ------------------------------------------------------------- MGRID, eq. 4.3


def test_eq_4_3_counts_overlaps_and_the_corner_free_variant():
    models, hs = shifted_rectangles(shifts=(0.0, 1.0, 1.5), weights=(1.0, 1.0, 1.0))
    summed = build_grid(hs, models, size=64)
    assert summed.mgrid.max() == 3  # 1 (a face) + degree 2 where all three bottoms overlap
    triple = cells_world(summed, summed.mgrid == 3)
    assert np.all((triple[:, 0] > 1.3) & (triple[:, 0] < 2.2))
    np.testing.assert_allclose(np.unique(summed.strength), [0.0, 2 / 3, 1.0])
    # blocking of different normals meeting at the corner (2, 1): eq. 4.3 adds them up
    corner = [
        Hypothesis("rect", 0, (), Pose(x, y, 0), ErrorBound(0, 0, 0), 1.0, equivalence_class=k)
        for k, (x, y) in enumerate([(0.0, 0.0), (0.5, 0.0), (0.0, 0.5)])
    ]
    with_corners = build_grid(corner, models, size=64)
    corner_free = build_grid(corner, models, size=64, corners=False)
    np.testing.assert_allclose(with_corners.strength.max(), 4 / 3)
    np.testing.assert_allclose(corner_free.strength.max(), 2 / 3)
    assert np.array_equal(with_corners.strength > 0, corner_free.strength > 0)
    assert with_corners.mgrid.max() == 3 and corner_free.mgrid.max() == 2
    zone = cells_world(with_corners, with_corners.strength > 1.0)
    assert np.all(np.hypot(*(zone - [2.0, 1.0]).T) < 3 * with_corners.cell_size)


def test_bump_block_grid_areas_and_target():
    models, hs = bump_block_case()
    grid = build_grid(hs, models, size=70)
    assert grid.n_areas == 1
    np.testing.assert_allclose(grid.world_targets()[0], (60.0, 40.0), atol=1.5 * grid.cell_size)
    assert np.array_equal(grid.labels > 0, grid.ia)


def test_several_areas_are_labelled_and_targets_lie_inside():
    # a U-channel and a slab over its prongs: two intersection areas
    u = next(m for m in object_set("workshop") if m.name == "u_channel")
    slab = ObjectModel("slab", (make_stable_pose([[0, 40], [100, 40], [100, 80], [0, 80]]),))
    hs = [
        Hypothesis("u_channel", 0, (), Pose(0, 0, 0), ErrorBound(0, 0, 0), 0.5, 0),
        Hypothesis("slab", 0, (), Pose(0, 0, 0), ErrorBound(0, 0, 0), 0.5, 1),
    ]
    grid = build_grid(hs, [u, slab], size=120)
    mii = build_mii(hs, [u, slab])
    assert len(mii.intersection_areas) == grid.n_areas == 2
    for k, (x, y) in enumerate(grid.world_targets(), start=1):
        i, j = np.floor(grid.mapping.forward([[x, y]])[0] - 0.5).astype(int)
        assert grid.labels[i, j] == k
        assert mii.intersection.contains(shapely.Point(x, y))


def test_target_falls_back_to_the_deepest_point_when_the_centroid_is_outside():
    u = next(m for m in object_set("workshop") if m.name == "u_channel")
    hs = [Hypothesis("u_channel", 0, (), Pose(0, 0, 0), ErrorBound(0, 0, 0), 1.0)]
    grid = build_grid(hs, [u], size=100)
    assert grid.n_areas == 1
    i, j = np.rint(ndimage.center_of_mass(grid.ia)).astype(int)
    assert not grid.ia[i, j]  # the U's centroid is in its slot
    depth = ndimage.distance_transform_edt(grid.ia)
    ti, tj = (grid.targets[0] - 1.0).astype(int)
    assert grid.ia[ti, tj] and depth[ti, tj] == depth.max()


# ------------------------------------------------------ grid vs. vector form


@pytest.mark.parametrize("eps_t", [0.0, 8.0])
def test_bump_block_grid_agrees_with_vector(eps_t):
    models, hs = bump_block_case(eps_t=eps_t, rotation=0.03 if eps_t else 0.0)
    check_agreement(build_mii(hs, models), build_grid(hs, models, size=200))


@AGREEMENT
@given(seed=st.integers(0, 2**20))
def test_grid_agrees_with_vector_at_size_200(seed):
    models, hs, _ = random_scene(seed)
    mii = build_mii(hs, models)
    grid = build_grid(hs, models, size=200)
    assume(resolvable(mii, grid.cell_size))
    check_agreement(mii, grid)


@AGREEMENT
@given(seed=st.integers(0, 2**20))
def test_grid_agrees_with_vector_regions_with_error(seed):
    models, hs, _ = random_scene(seed, eps_t=6.0, rotation=0.03)
    check_agreement(build_mii(hs, models), build_grid(hs, models, size=200))


def check_agreement(mii, grid):
    cell = grid.cell_size
    # IA area within 5%
    grid_area = grid.ia.sum() * cell**2
    assert grid_area == pytest.approx(mii.certain_intersection.area, rel=0.05)
    blocking = shapely.union_all([b.geometry for b in mii.blocking])
    centres = cells_world(grid, grid.strength > 0)
    if not mii.blocking:
        assert len(centres) == 0
        return
    # each grid blocking cell lies within one cell of a vector blocking boundary
    x, y = centres.T
    near = shapely.box(x - 1.5 * cell, y - 1.5 * cell, x + 1.5 * cell, y + 1.5 * cell)
    assert shapely.intersects(near, blocking).all()
    # and every exact blocking segment runs over grid blocking cells at least as strong
    strongest = ndimage.maximum_filter(grid.strength, size=3)
    for b in mii.blocking:
        if b.is_region:
            continue
        samples = shapely.line_interpolate_point(
            b.geometry, np.linspace(0.05, 0.95, 9), normalized=True
        )
        i, j = np.floor(grid.mapping.forward(shapely.get_coordinates(samples)) - 0.5).T
        assert np.all(strongest[i.astype(int), j.astype(int)] >= b.strength - 1e-9)


# ----------------------------------------------------- sweep, windows, CHOOSE


def test_windows_are_circular_runs():
    assert windows(np.array([True, False, False, True, True, False, True])) == [(3, 2), (6, 2)]
    assert windows(np.ones(5, bool)) == [(0, 5)]
    assert windows(np.zeros(5, bool)) == []


def test_sweep_counts_separate_blocking_runs():
    models, hs = bump_block_case()
    grid = build_grid(hs, models, size=70)
    target = grid.targets[0]
    up, right = sweep_rays(grid, target, np.radians([80.0, 10.0])).total
    # up crosses y = 80 (shared by two) and y = 100 (shared by two other)
    assert up == pytest.approx(1.0)
    # right crosses x = 100 where three share it (the fourth has its bump there)
    assert right == pytest.approx(0.75)
    # through the bump's gap at y = 80 only the top at y = 100 blocks
    through_gap = sweep_rays(grid, target, np.radians([100.0]))
    assert through_gap.total[0] == pytest.approx(0.5) and through_gap.runs[0] == 1


def test_paths_start_on_the_safe_circle_and_end_at_the_aim():
    models, hs = shifted_rectangles()
    ws = Workspace((1.5, 0.5), 10.0)
    paths = thesis_paths(hs, models, ws, (11.5, 0.5), size=60)
    assert paths and paths[0].family == "distinguishing"
    keys = [(p.admitted_strength, p.motion_cost) for p in paths]
    assert keys == sorted(keys)
    assert choose(paths) is paths[0]
    for p in paths:
        origin = np.asarray(p.path.origin)
        assert np.hypot(*(origin - ws.center)) == pytest.approx(ws.radius)
        np.testing.assert_allclose(p.path.end, p.aim, atol=1e-9)


def test_distinguishing_grid_paths_distinguish():
    models = object_set("thesis_like")
    hs = consistent_hypotheses(models, TWIN_CONTACTS)
    mii = build_mii(hs, models)
    paths = thesis_paths(hs, models, Workspace((50, 40), 200), (250, 40), size=100)
    best = [p for p in paths if p.family == "distinguishing"]
    assert best
    o = np.array([p.path.origin for p in best])
    d = np.array([p.path.direction for p in best])
    length = np.array([p.path.length for p in best])
    points, normals = first_hits(mii, o, d, length)
    assert not np.isnan(points).any()
    assert confused_pairs(mii, points, normals, 200.0).sum() == 0


@pytest.mark.parametrize("with_error", [False, True])
@pytest.mark.parametrize("sensor", [(250.0, 40.0), (-150.0, 40.0), (50.0, 240.0)])
def test_exp_2_the_chosen_path_hunts_the_bump(with_error, sensor):
    """Thesis Exp. II: after two constraining touches the strategy probes for the
    triangular feature: its path meets the bump in at least one hypothesis."""
    models, hs = bump_block_case()
    if with_error:
        models, hs = bump_block_case(eps_t=thesis_error(models), rotation=math.radians(3))
    chosen = choose(thesis_paths(hs, models, Workspace((50, 40), 200), sensor))
    assert chosen.family == "sub-optimal" and chosen.admitted_strength == pytest.approx(0.5)
    mii = build_mii(hs, models)
    f = models[0].stable_poses[0].faces
    bump = np.flatnonzero(np.abs(f.normal).min(axis=1) > 0.1)
    assert len(bump) == 2
    hits_bump = []
    for k in range(len(hs)):
        own = mii.faces.hypothesis == k
        _, face = cast_rays(
            np.array([chosen.path.origin]), np.array([chosen.path.direction]),
            np.array([chosen.path.length]), mii.faces.start[own][None], mii.faces.end[own][None],
        )  # fmt: skip
        hits_bump.append(int(face[0]) in bump)
    assert any(hits_bump)


def test_bad_grid_input():
    models, hs = shifted_rectangles()
    with pytest.raises(PlanningNotPossibleError):
        build_grid(hs, models, size=4)
    with pytest.raises(PlanningNotPossibleError):
        thesis_paths(hs, models, Workspace((50.0, 50.0), 1.0), (51.0, 50.0), size=32)
