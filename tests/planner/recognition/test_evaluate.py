"""The evaluation steps one by one (DESIGN §4.4-4.7): rotation gate, pose fit,
error bounds, slide-family samples, model check, free-space check, weights."""

from __future__ import annotations

import itertools
import math
from concurrent.futures import ThreadPoolExecutor

import numpy as np
import pytest
import shapely
from hypothesis import given, settings
from hypothesis import strategies as st

from hardware_sim.world import World, random_world
from planner.geometry import LENGTH_SLACK, point_segment_distance, rotation_matrices, wrap_angle
from planner.memo import SharedCache
from planner.models.library import object_from_dict
from planner.models.outlines import make_stable_pose
from planner.recognition import tree
from planner.recognition.config import RecognitionConfig
from planner.recognition.evaluate import _similar_runs, evaluate, evaluate_groups
from planner.recognition.model_check import (
    contacts_on_faces,
    free_space_check,
    inside_workspace,
    model_check,
)
from planner.recognition.poses import (
    RowOutlines,
    RowShapes,
    fit_bounds,
    fit_poses,
    rotation_gate,
    sample_bounds,
    slide_samples,
)
from planner.recognition.tree import TreeLevel, extend, make_groups
from planner.recognition.weights import residual_fitness, weights
from planner.types import (
    Contact,
    ObjectModel,
    Observation,
    Pose,
    SensingPath,
    SensorBounds,
    Workspace,
)
from tests.conftest import ELL, SET_NAMES, SQUARE, WORKSPACE, object_set

BOUNDS = SensorBounds(1.0, math.radians(3.0))
CONFIG = RecognitionConfig()


def _slack(length_scale: float) -> float:
    return LENGTH_SLACK * length_scale * 10


def _arrays(observations):
    """Measured points, normals (s, 2), their angles (s,) and the paths' directions (s, 2)."""
    hits = [o for o in observations if o.contact is not None]
    P = np.array([o.contact.point for o in hits])
    U = np.array([o.contact.normal for o in hits])
    dirs = np.array([o.path.direction for o in hits])
    return P, U, np.arctan2(U[:, 1], U[:, 0]), dirs


def _rank2(stable, faces) -> bool:
    n = stable.faces.normal[faces]
    return np.abs(n[:, None, 0] * n[None, :, 1] - n[:, None, 1] * n[None, :, 0]).max() > 1e-6


def _touch_until_determined(world: World, bounds, rng, edge_share=1.0):
    """Hits (errors on the bounds' edges by default) until two non-parallel faces are met."""
    obs, faces = [], []
    while len(obs) < 2 or not _rank2(world.stable, faces):
        o, f = world.execute(world.hitting_path(rng), bounds, rng, edge_share=edge_share)
        obs.append(o)
        faces.append(f)
    return obs, np.array(faces)


def _posed(stable, theta, t):
    """Every sample's posed outline (N, V, 2)."""
    return np.stack([Pose(t[k, 0], t[k, 1], theta[k]).apply(stable.outline) for k in range(len(t))])


def _steps(stable, obs, faces, bounds, length_scale, config=CONFIG):
    """The pose steps (fit, bounds, samples, sample bounds) for one row of faces."""
    P, U, _, _ = _arrays(obs)
    face = np.asarray(faces)[None]
    assigned = np.ones(face.shape, bool)
    eps_d, phi = bounds.position_error, bounds.normal_error
    slack = _slack(length_scale)
    pose = fit_poses(stable, P, U, face, assigned, eps_d, phi, length_scale)
    fb = fit_bounds(pose, RowShapes.of([stable], [len(face)]), assigned, eps_d, phi, config, slack)
    samples = slide_samples(
        pose,
        stable.faces,
        face,
        assigned,
        fb.margin,
        fb.eps_t,
        config.max_family_samples,
        length_scale,
    )
    outlines = RowOutlines.of([stable], [len(face)])
    sb = sample_bounds(
        pose,
        fb,
        samples,
        outlines,
        stable.all_faces,
        P,
        U,
        face,
        assigned,
        eps_d,
        phi,
        config,
        slack,
    )
    return pose, fb, samples, sb


# -- rotation gate (§4.4) --------------------------------------------------------------
@pytest.mark.parametrize(("spread", "kept"), [(3.9, True), (4.1, False)])
def test_rotation_gate_admits_normals_within_two_phi_of_their_mean(spread, kept):
    phi = math.radians(3.0)
    face_angle = np.array([[0.0, math.pi / 2]])
    # turned by 0.3 rad, the second normal off by `spread` phi: each is spread/2 phi from the mean
    psi = np.array([0.3, math.pi / 2 + 0.3 + spread * phi])
    assert rotation_gate(psi, face_angle, np.ones((1, 2), bool), phi)[0] == kept
    # a spurious contact is not gated
    assert rotation_gate(psi, face_angle, np.array([[True, False]]), phi)[0]


# -- pose fit (§4.4) -------------------------------------------------------------------
@pytest.mark.parametrize("name", SET_NAMES)
@settings(max_examples=25, derandomize=True, deadline=None)
@given(seed=st.integers(0, 2**32 - 1))
def test_fit_recovers_the_exact_pose_from_exact_contacts(name, seed):
    rng = np.random.default_rng(seed)
    world = random_world(object_set(name), WORKSPACE, rng)
    obs, faces = _touch_until_determined(world, SensorBounds(), rng, edge_share=0.0)
    P, U, _, _ = _arrays(obs)
    face = faces[None]
    assigned = np.ones(face.shape, bool)
    pose = fit_poses(
        world.stable, P, U, face, assigned, BOUNDS.position_error, BOUNDS.normal_error, 60.0
    )
    assert pose.fit.rank2[0]
    assert abs(float(wrap_angle(pose.fit.theta[0] - world.pose.theta))) < 1e-9
    np.testing.assert_allclose(pose.fit.t[0], world.pose.translation, atol=1e-7)
    # the contacts' model points lie on their faces' lines: n_a·m = d_a
    f = world.stable.faces
    on_line = np.einsum("si,si->s", pose.model_points[0], f.normal[faces]) - f.offset[faces]
    np.testing.assert_allclose(on_line, 0.0, atol=1e-7)


# -- error bounds (§4.4) ---------------------------------------------------------------
@pytest.mark.parametrize("name", SET_NAMES)
@settings(max_examples=40, derandomize=True, deadline=None)
@given(seed=st.integers(0, 2**32 - 1))
def test_bounds_cover_the_true_pose_for_errors_on_the_bounds_edges(name, seed):
    rng = np.random.default_rng(seed)
    world = random_world(object_set(name), WORKSPACE, rng)
    obs, faces = _touch_until_determined(world, BOUNDS, rng)
    _, _, samples, sb = _steps(world.stable, obs, faces, BOUNDS, 60.0)
    assert len(samples.src) == 1 and sb.feasible[0]
    dt = math.hypot(*(samples.t[0] - world.pose.translation))
    dtheta = abs(float(wrap_angle(samples.theta[0] - world.pose.theta)))
    assert dt <= sb.d_translation[0] + 1e-9
    assert dtheta <= sb.d_theta[0] + 1e-12
    # every outline point within eps_t/2 of where the truth puts it
    truth = world.pose.apply(world.stable.outline)
    moved = np.hypot(*(_posed(world.stable, samples.theta, samples.t)[0] - truth).T)
    assert moved.max() <= sb.eps_t[0] / 2 + 1e-9
    # every point of each contact's face within the move interpolated between its ends
    f, u = world.stable.all_faces, np.linspace(0.0, 1.0, 101)[:, None]
    fitted = Pose(samples.t[0, 0], samples.t[0, 1], samples.theta[0])
    for j, a in enumerate(faces):
        along = f.start[a] + u * (f.end[a] - f.start[a])
        gap = np.hypot(*(fitted.apply(along) - world.pose.apply(along)).T)
        start, end = sb.face_move[0, j, :, 0], sb.face_move[0, j, :, 1]  # per bound
        chords = np.where(np.isfinite(start), start + u * (end - start), np.inf)
        assert np.all(gap <= chords.min(axis=1) + 1e-9)
        assert np.all(chords.min(axis=1) <= sb.eps_t[0] / 2 + 1e-9)


def test_thesis_bounds_are_the_fixed_error_disk():
    rng = np.random.default_rng(2)
    world = random_world([ELL], WORKSPACE, rng)
    obs, faces = _touch_until_determined(world, BOUNDS, rng)
    config = RecognitionConfig(bound_mode="thesis", thesis_fraction=0.2)
    _, fb, _, sb = _steps(world.stable, obs, faces, BOUNDS, 60.0, config)
    disk = 0.2 * 2 * world.stable.centroid_radius
    np.testing.assert_allclose(fb.eps_t, disk)
    np.testing.assert_allclose(sb.eps_t, disk)  # a determined pose has no cell


# -- slide-family samples (§4.6) -------------------------------------------------------
@pytest.mark.parametrize("max_samples", [1, 4, 16])
@settings(max_examples=25, derandomize=True, deadline=None)
@given(seed=st.integers(0, 2**32 - 1))
def test_family_samples_cover_the_slide_and_bound_the_truth(max_samples, seed):
    rng = np.random.default_rng(seed)
    world = random_world([ELL], WORKSPACE, rng)
    obs, face = world.execute(world.hitting_path(rng), BOUNDS, rng, edge_share=1.0)
    config = RecognitionConfig(max_family_samples=max_samples)
    pose, _, samples, sb = _steps(world.stable, [obs], [face], BOUNDS, 60.0, config)
    assert samples.family[0] and 1 <= len(samples.src) <= max_samples
    # the samples sit at cell midpoints along one line, in the slide direction
    step = np.diff(samples.t, axis=0)
    cell = samples.cell[0]
    np.testing.assert_allclose(np.hypot(*step.T), cell / pose.rho[0], rtol=1e-9)
    np.testing.assert_allclose(np.diff(samples.s), cell, rtol=1e-9)
    # the true pose is one of the family: some sample's bound holds it
    dt = np.hypot(*(samples.t - world.pose.translation).T)
    dtheta = np.abs(wrap_angle(samples.theta - world.pose.theta))
    assert np.any((dt <= sb.d_translation + 1e-9) & (dtheta <= sb.d_theta + 1e-12))
    # each sample's error disk spans its cell
    assert np.all(sb.eps_t >= cell)


def _bottom_family(xs):
    """The square's slide family of contacts at x in `xs` on its bottom face (y = -10)."""
    stable = SQUARE.stable_poses[0]
    bottom = int(np.argmin(stable.faces.normal[:, 1]))
    obs = [Observation(SensingPath((x, -100), (0, 1), 200), Contact((x, -10), (0, -1))) for x in xs]
    P, U, _, _ = _arrays(obs)
    face = np.full((1, len(xs)), bottom)
    assigned = np.ones(face.shape, bool)
    return fit_poses(stable, P, U, face, assigned, 1.0, 0.05, 10.0), stable.faces, face, assigned


def test_family_samples_are_spaced_by_eps_t_up_to_the_cap():
    pose, faces, face, assigned = _bottom_family([0.0])
    assert not pose.fit.rank2[0]
    # a 20-long face: at a spacing of 4, five cells; at a spacing of 1, capped at 16
    five = slide_samples(pose, faces, face, assigned, np.zeros((1, 1)), np.full(1, 4.0), 16, 10.0)
    assert len(five.src) == 5 and five.cell[0] == pytest.approx(4.0)
    capped = slide_samples(pose, faces, face, assigned, np.zeros((1, 1)), np.ones(1), 16, 10.0)
    assert len(capped.src) == 16 and capped.cell[0] == pytest.approx(20 / 16)


def test_a_family_gets_no_sample_when_no_slide_keeps_its_contacts_on_their_faces():
    # two contacts 40 apart on a face 20 long
    pose, faces, face, assigned = _bottom_family([-20.0, 20.0])
    none = slide_samples(pose, faces, face, assigned, np.zeros((1, 2)), np.ones(1), 16, 10.0)
    assert len(none.src) == 0
    # each end widened by 11, the face leaves a slide of 2: two cells of 1
    room = slide_samples(pose, faces, face, assigned, np.full((1, 2), 11.0), np.ones(1), 16, 10.0)
    assert len(room.src) == 2 and room.cell[0] == pytest.approx(1.0)


# -- model check (§4.5) ----------------------------------------------------------------
def _square_check(point, normal_angle, face_move=0.5, d_theta=0.01, assigned=True):
    """Model check of one contact on the square's face x = 10 at the identity pose,
    the face known to within `face_move`."""
    f = SQUARE.stable_poses[0].faces
    right = int(np.argmax(f.normal[:, 0]))
    return model_check(
        f,
        np.array([[right]]),
        np.array([[assigned]]),
        np.array([point], float),
        np.array([normal_angle]),
        np.zeros(1),
        np.zeros((1, 2)),
        np.full((1, 1, 1, 2), face_move),
        np.array([d_theta]),
        1.0,
        0.05,
        1e-9,
    )[0]


@pytest.mark.parametrize(
    ("y", "kept"),
    [(0.0, True), (10.0, True), (11.4, True), (11.6, False), (-11.6, False), (30.0, False)],
)
def test_model_check_rejects_a_contact_beyond_its_face_end(y, kept):
    # face y in [-10, 10]; allowance eps_d + face_move = 1.5 past either end
    assert _square_check((10.0, y), 0.0) == kept


@pytest.mark.parametrize(("off", "kept"), [(0.0, True), (0.059, True), (0.061, False)])
def test_model_check_rejects_a_normal_outside_its_cone(off, kept):
    # cone: phi + d_theta = 0.06 about the face normal (angle 0), either side
    assert _square_check((10.0, 0.0), off) == kept
    assert _square_check((10.0, 0.0), -off) == kept


def test_model_check_ignores_spurious_contacts():
    assert _square_check((40.0, 40.0), 1.0, assigned=False)
    assert not _square_check((40.0, 40.0), 1.0)


def test_a_face_that_moves_less_at_one_end_admits_less_there():
    # the right face runs from (10, -10) to (10, 10); its start may move 0.1, its end 2.0:
    # within eps_d = 1 plus the move interpolated along it
    def check(point):
        f = SQUARE.stable_poses[0].faces
        right = int(np.argmax(f.normal[:, 0]))
        assert np.allclose(f.start[right], [10, -10]) and np.allclose(f.end[right], [10, 10])
        return model_check(
            f, np.array([[right]]), np.array([[True]]), np.array([point], float), np.zeros(1),
            np.zeros(1), np.zeros((1, 2)), np.array([[[[0.1, 2.0]]]]), np.zeros(1), 1.0, 0.05, 0.0,
        )[0]  # fmt: skip

    assert check((10.0, -11.05)) and not check((10.0, -11.15))  # past the start: 1 + 0.1
    assert check((10.0, 12.95)) and not check((10.0, 13.05))  # past the end: 1 + 2.0
    assert check((12.0, 0.0)) and not check((12.1, 0.0))  # midway: 1 + 1.05 off the line


@settings(max_examples=300, deadline=None, derandomize=True)
@given(
    st.floats(-30, 30), st.floats(-30, 30), st.lists(st.floats(0, 5), min_size=4, max_size=4),
    st.floats(0, 2), st.floats(-math.pi, math.pi), st.booleans(),
)  # fmt: skip
def test_the_tapered_face_check_is_the_least_gap_along_the_face(x, y, m, reach, theta, one):
    """The model check admits a contact exactly when some point of its posed face
    lies within reach plus the smaller of two bounds' moves interpolated there (one
    bound unknown: inf), sampled densely along the face."""
    f = SQUARE.stable_poses[0].faces
    move = np.array([[m[0], m[1]], [np.inf, np.inf] if one else [m[2], m[3]]])
    ok = model_check(
        f, np.zeros((1, 1), np.int64), np.ones((1, 1), bool), np.array([[x, y]]),
        np.array([theta + f.angle[0]]), np.array([theta]), np.zeros((1, 2)),
        move[None, None], np.zeros(1), reach, 0.0, 0.0,
    )[0]  # fmt: skip
    R = rotation_matrices(np.array([theta]))[0]
    a, b = R @ f.start[0], R @ f.end[0]
    u = np.linspace(0.0, 1.0, 20_001)
    dist = np.hypot(*(np.array([x, y])[:, None] - (a[:, None] + u * (b - a)[:, None])))
    start, end = move[:, :1], move[:, 1:]
    chords = np.where(np.isfinite(start), start + u * (end - start), np.inf)
    least = (dist - chords.min(axis=0)).min()
    if abs(least - reach) > 1e-3:  # away from the boundary the two agree
        assert ok == (least <= reach)


def test_model_check_rejects_a_contact_off_the_face_line():
    assert _square_check((11.4, 0.0), 0.0)
    assert not _square_check((11.6, 0.0), 0.0)
    assert not _square_check((8.4, 0.0), 0.0)


def test_inside_workspace_keeps_poses_whose_outline_stays_in_the_safe_circle():
    outline = SQUARE.stable_poses[0].outline
    ws = Workspace((0.0, 0.0), 50.0)
    t = np.array([[0.0, 0.0], [38.0, 0.0], [40.0, 0.0]])  # far corners at (x + 10, ±10)
    keep = inside_workspace(outline, np.zeros(3), t, np.zeros(3), ws, 0.0)
    reach = np.hypot(t[:, 0] + 10, 10)
    assert keep.tolist() == (reach <= 50).tolist() == [True, True, False]
    # within eps_t/2 of the circle counts as inside
    assert inside_workspace(outline, np.zeros(1), t[2:], np.full(1, 2.0), ws, 0.0)[0]
    # a quarter turn of a square about its centre changes nothing
    np.testing.assert_array_equal(
        inside_workspace(outline, np.full(3, math.pi / 2), t, np.zeros(3), ws, 0.0), keep
    )


@settings(max_examples=60, derandomize=True, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), vertices=st.integers(3, 400))
def test_inside_workspace_answers_as_every_posed_vertex_does(seed, vertices):
    # poses far from the rim skip posing the vertices: the answer is the same
    rng = np.random.default_rng(seed)
    angle = np.sort(rng.uniform(0, 2 * math.pi, vertices))
    radius = rng.uniform(2, 30, vertices)
    outline = np.column_stack([radius * np.cos(angle), radius * np.sin(angle)]) + rng.uniform(
        -10, 10, 2
    )
    ws = Workspace(tuple(rng.uniform(-20, 20, 2)), float(rng.uniform(40, 120)))
    n = 300
    theta = rng.uniform(-math.pi, math.pi, n)
    t = np.asarray(ws.center) + rng.uniform(-1.2, 1.2, (n, 2)) * ws.radius
    eps_t = rng.uniform(0, 6, n) * (rng.random(n) < 0.7)
    R = rotation_matrices(theta)
    verts = np.einsum("nij,vj->nvi", R, outline) + t[:, None]
    reach = np.hypot(*(verts - np.asarray(ws.center)).transpose(2, 0, 1)).max(axis=1)
    expected = reach <= ws.radius + eps_t / 2 + 0.5
    found = inside_workspace(outline, theta, t, eps_t, ws, 0.5)
    assert np.array_equal(found, expected)
    assert 0 < expected.sum() < n  # both answers are met


# -- free-space check (§4.5) -----------------------------------------------------------
SQUARE_GROUP = make_groups([SQUARE])[0]


def _miss(y):
    """A missed horizontal path at height y across the whole safe circle."""
    return Observation(SensingPath((-200.0, y), (1.0, 0.0), 400.0), None)


def _free(observations, theta=0.0, t=(0.0, 0.0), eps_t=2.0, assigned=None):
    """Free-space check of the square at one pose (eps_d = 1)."""
    return free_space_check(
        SQUARE_GROUP,
        observations,
        np.zeros((1, 0), bool) if assigned is None else assigned,
        np.array([theta]),
        np.array([t], float),
        np.array([eps_t]),
        np.ones(1, bool),
        1.0,
        1e-6,
    )[0]


@pytest.mark.parametrize(
    ("y", "kept"),
    [(0.0, False), (8.0, False), (9.5, True), (10.5, True), (30.0, True), (-8.0, False)],
)
def test_free_space_rejects_a_missed_path_that_crosses_the_shrunk_outline(y, kept):
    # the square [-10, 10]^2 shrunk by eps_t/2 = 1 (rounded up by at most 15%): a path
    # cutting 0.5 into it is taken for error, one cutting 2 into it is not
    assert _free([_miss(y)]) == kept


def test_free_space_poses_the_outline():
    # moved up by 25, the square lets the path at y = 0 pass and blocks one at y = 25
    assert _free([_miss(0.0)], t=(0.0, 25.0))
    assert not _free([_miss(25.0)], t=(0.0, 25.0))
    # turned by 45 degrees its corner reaches y = 14.1: a path at y = 12 is blocked
    assert _free([_miss(12.0)])
    assert not _free([_miss(12.0)], theta=math.pi / 4)


def test_free_space_checks_the_path_before_each_assigned_contact():
    # a path from below: touching the bottom face is clear, "touching" the top face is not
    up = SensingPath((0.0, -200.0), (0.0, 1.0), 400.0)
    bottom = [Observation(up, Contact((0.0, -10.0), (0.0, -1.0)))]
    top = [Observation(up, Contact((0.0, 10.0), (0.0, 1.0)))]
    assigned = np.ones((1, 1), bool)
    assert _free(bottom, assigned=assigned)
    assert not _free(top, assigned=assigned)
    # a spurious contact's path is not checked
    assert _free(top, assigned=np.zeros((1, 1), bool))


def test_free_space_leaves_samples_already_out_unchecked():
    keep = np.array([True, False])
    out = free_space_check(
        SQUARE_GROUP,
        [_miss(30.0)],
        np.zeros((2, 0), bool),
        np.zeros(2),
        np.zeros((2, 2)),
        np.full(2, 2.0),
        keep,
        1.0,
        1e-6,
    )
    assert out.tolist() == [True, False]


# -- weights (§4.7) --------------------------------------------------------------------
def _twins(prior_a: float, prior_b: float):
    """Two objects of identical geometry and different priors."""
    stable = make_stable_pose(ELL.stable_poses[0].outline)
    return [
        ObjectModel("a", (stable,), prior=prior_a),
        ObjectModel("b", (stable,), prior=prior_b),
    ]


def _grown_tree(models, truths, seed, touches):
    """The tree's groups and level after `touches` random hits on a world drawn
    from `truths`, and the observations."""
    rng = np.random.default_rng(seed)
    world = random_world(truths, WORKSPACE, rng)
    groups = make_groups(models)
    level = TreeLevel(rows=tuple(np.zeros((1, 0), np.int64) for _ in groups))
    obs = []
    for _ in range(touches):
        obs.append(world.execute(world.hitting_path(rng), BOUNDS, rng)[0])
        level = extend(level, groups, [o.contact for o in obs], BOUNDS, CONFIG)
    return groups, level, obs


@pytest.mark.parametrize(("prior_a", "prior_b"), [(3.0, 1.0), (1.0, 1.0), (0.2, 0.7)])
@settings(max_examples=10, derandomize=True, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), touches=st.integers(1, 3))
def test_weights_follow_the_prior_ratio_for_otherwise_identical_interpretations(
    prior_a, prior_b, seed, touches
):
    models = _twins(prior_a, prior_b)
    groups, level, obs = _grown_tree(models, models[:1], seed, touches)
    a, b = (
        evaluate(g, groups[g], level.rows[g], obs, BOUNDS, WORKSPACE, CONFIG, 60.0)
        for g in range(2)
    )
    assert len(a.weight) > 0
    np.testing.assert_array_equal(a.t, b.t)
    np.testing.assert_array_equal(a.row, b.row)
    np.testing.assert_allclose(a.weight / b.weight, prior_a / prior_b, rtol=1e-12)


def _square_hits(tilt: float):
    """Exact hits on the square's bottom and right faces by paths tilted by `tilt`."""
    down = (math.sin(tilt), math.cos(tilt))
    left = (-math.cos(tilt), math.sin(tilt))
    return [
        Observation(
            SensingPath((-3.0 - 200 * down[0], -10.0 - 200 * down[1]), down, 400),
            Contact((-3.0, -10.0), (0.0, -1.0)),
        ),
        Observation(
            SensingPath((10.0 - 200 * left[0], 4.0 - 200 * left[1]), left, 400),
            Contact((10.0, 4.0), (1.0, 0.0)),
        ),
    ]


def _square_row(observations, config=CONFIG):
    """The square's determined interpretation (bottom, right face) of two contacts:
    its pose steps, faces, face row (1, 2) and assignment."""
    stable = SQUARE.stable_poses[0]
    f = stable.faces
    face = np.array([[int(np.argmin(f.normal[:, 1])), int(np.argmax(f.normal[:, 0]))]])
    pose, _, samples, _ = _steps(stable, observations, face[0], BOUNDS, 10.0, config)
    return pose, samples, f, face, np.ones((1, 2), bool)


def _square_fitness(observations, config=CONFIG, workspace=None):
    pose, samples, _, face, assigned = _square_row(observations, config)
    P, U, _, _ = _arrays(observations)
    eps_d, phi = BOUNDS.position_error, BOUNDS.normal_error
    ok = np.ones(len(samples.src), bool)
    parts = [(slice(0, len(face)), slice(0, len(samples.src)))]
    args = (pose, samples, P, U, face, assigned, ok, eps_d, phi, config, _slack(10.0), workspace)
    faces = SQUARE_GROUP.stable.all_faces
    return residual_fitness([SQUARE_GROUP], parts, faces, observations, *args)


def test_weights_carry_the_incidence_of_each_hit():
    obs = _square_hits(0.0)
    pose, samples, f, face, assigned = _square_row(obs)
    ones = np.ones(len(samples.src))
    square = weights(1.0, pose, samples, f, face, assigned, _arrays(obs)[3], ones, CONFIG)
    tilted = _arrays(_square_hits(1.0))[3]
    grazing = weights(1.0, pose, samples, f, face, assigned, tilted, ones, CONFIG)
    # |dir·n| per contact: 1 for square hits, cos(1) for each tilted one
    assert square[0] > 0
    np.testing.assert_allclose(grazing / square, math.cos(1.0) ** 2, rtol=1e-9)


def test_weights_multiply_the_outlier_probability_per_spurious_contact():
    obs = _square_hits(0.0)
    pose, samples, f, face, assigned = _square_row(obs)
    dirs = _arrays(obs)[3]
    ones = np.ones(len(samples.src))
    full = weights(1.0, pose, samples, f, face, assigned, dirs, ones, CONFIG)
    one_out = weights(1.0, pose, samples, f, face, np.array([[True, False]]), dirs, ones, CONFIG)
    assert full[0] > 0
    np.testing.assert_allclose(one_out / full, CONFIG.outlier_probability, rtol=1e-12)
    # a folded contact is unassigned but not spurious: it weighs as nothing, not as
    # an outlier (tree.fold_runs)
    none = np.array([[False, False]])
    folded = weights(
        1.0, pose, samples, f, face, np.array([[True, False]]), dirs, ones, CONFIG, none
    )
    np.testing.assert_allclose(folded, one_out / CONFIG.outlier_probability, rtol=1e-12)


def test_residual_fitness_is_one_for_exact_contacts_and_less_on_the_edges():
    exact = _square_hits(0.0)
    f_exact = _square_fitness(exact)
    assert f_exact.tolist() == pytest.approx([1.0])
    # normals turned by phi/2 either way: the rotations they allow overlap by half, and
    # the square's translation polygon does not change with the rotation
    half = BOUNDS.normal_error / 2
    turned = [
        Observation(o.path, Contact(o.contact.point, _turn(o.contact.normal, sign * half)))
        for o, sign in zip(exact, (1, -1), strict=True)
    ]
    f_edge = _square_fitness(turned)
    assert f_edge[0] == pytest.approx(0.5 * f_exact[0], rel=0.02)
    # thesis mode weighs no residuals
    thesis = RecognitionConfig(bound_mode="thesis")
    f_thesis = _square_fitness(turned, thesis)
    assert f_thesis.tolist() == [1.0]


def test_residual_fitness_counts_only_the_poses_inside_the_safe_circle():
    # the prior puts the part inside the safe circle: the share of the consistent
    # set outside it is impossible, and a set wholly outside keeps the floor weight
    half = BOUNDS.normal_error / 2
    turned = [
        Observation(o.path, Contact(o.contact.point, _turn(o.contact.normal, sign * half)))
        for o, sign in zip(_square_hits(0.0), (1, -1), strict=True)
    ]
    free = _square_fitness(turned)[0]
    assert 0 < free < 1
    # the square's corners lie 14.1 from the centre, its poses within about 2 of it
    shares = [
        _square_fitness(turned, workspace=Workspace((0.0, 0.0), r))[0]
        for r in (1000.0, 17.0, 16.0, 15.0, 14.5, 13.0)
    ]
    assert shares[0] == free
    assert all(a >= b for a, b in itertools.pairwise(shares))
    assert shares[-1] <= 1e-6
    assert free > shares[3] > shares[-1]  # a circle through the set keeps a part of it
    away = _square_fitness(turned, workspace=Workspace((500.0, 0.0), 100.0))[0]
    assert away <= 1e-6


def _turn(u, angle):
    c, s = math.cos(angle), math.sin(angle)
    return (c * u[0] - s * u[1], s * u[0] + c * u[1])


@settings(max_examples=25, derandomize=True, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), contacts=st.integers(1, 8), poses=st.integers(1, 6))
def test_contacts_on_faces_is_the_distance_to_each_posed_segment(seed, contacts, poses):
    # the compiled pass answers as the array formula does: every assigned contact
    # within the tolerance of its posed finite face
    rng = np.random.default_rng(seed)
    stable = make_stable_pose([[0, 0], [40, 0], [40, 12], [22, 12], [22, 30], [0, 30]])
    faces, K = stable.faces, 9
    face = rng.integers(0, len(faces), (K, contacts))
    assigned = rng.random((K, contacts)) < 0.8
    theta = rng.uniform(-math.pi, math.pi, (K, poses))
    t = rng.uniform(-5, 5, (K, poses, 2))
    points = rng.uniform(-40, 40, (contacts, 2))
    tol = rng.uniform(0, 30, (K, poses))
    R = rotation_matrices(theta)  # (K, M, 2, 2)
    start = np.einsum("kmij,ksj->kmsi", R, faces.start[face]) + t[:, :, None]
    end = np.einsum("kmij,ksj->kmsi", R, faces.end[face]) + t[:, :, None]
    dist = point_segment_distance(points[None, None], start, end)  # (K, M, s)
    expected = np.all(~assigned[:, None] | (dist <= tol[..., None]), axis=-1)
    found = contacts_on_faces(points, faces, face, assigned, theta, t, tol)
    assert np.array_equal(found, expected)
    one = float(tol[0, 0])  # one tolerance for every pose
    same = np.all(~assigned[:, None] | (dist <= one), axis=-1)
    assert np.array_equal(contacts_on_faces(points, faces, face, assigned, theta, t, one), same)


@settings(max_examples=12, derandomize=True, deadline=None)
@given(
    set_name=st.sampled_from(SET_NAMES), seed=st.integers(0, 2**32 - 1), touches=st.integers(1, 4)
)
def test_groups_evaluated_together_are_each_evaluated_alone_bit_for_bit(set_name, seed, touches):
    """The row-wise steps of every group's rows share one pass: each group still
    gets the numbers a pass over its rows alone gives (the same bits, so the same
    plans)."""
    models = object_set(set_name)
    groups, level, obs = _grown_tree(models, models, seed, touches)
    together = evaluate_groups(groups, level.rows, obs, BOUNDS, WORKSPACE, CONFIG, 60.0)
    assert sum(len(c.weight) for c in together) > 0  # the true interpretation at least
    for g, both in enumerate(together):
        alone = evaluate(g, groups[g], level.rows[g], obs, BOUNDS, WORKSPACE, CONFIG, 60.0)
        assert both.group == alone.group == g
        for name in ("row", "theta", "t", "d_translation", "d_theta", "eps_t", "cell", "weight"):
            np.testing.assert_array_equal(getattr(both, name), getattr(alone, name), err_msg=name)


def _mixed_parts():
    """A triangle, an L and a 24-gon: stable poses of 3, 6 and 24 faces (the first
    two share a pass, padded to six faces; the third has its own)."""
    ring = [[30 * math.cos(a), 30 * math.sin(a)] for a in np.arange(24) * math.pi / 12]
    return [
        object_from_dict({"name": "tri", "outline": [[0, 0], [50, 0], [10, 30]]}),
        object_from_dict(
            {"name": "ell", "outline": [[0, 0], [40, 0], [40, 12], [22, 12], [22, 30], [0, 30]]}
        ),
        object_from_dict({"name": "round", "outline": ring}),
    ]


@settings(max_examples=8, derandomize=True, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), touches=st.integers(1, 3))
def test_stable_poses_of_unlike_face_counts_are_bounded_as_each_alone(seed, touches):
    """The sample bounds run over consecutive stable poses of about as many faces
    at once (each row padded to the most faces of its pass); poses of unlike face
    counts run apart, and every group gets the numbers of a pass of its own."""
    models = _mixed_parts()
    groups, level, obs = _grown_tree(models, models, seed, touches)
    together = evaluate_groups(groups, level.rows, obs, BOUNDS, WORKSPACE, CONFIG, 60.0)
    for g, both in enumerate(together):
        alone = evaluate(g, groups[g], level.rows[g], obs, BOUNDS, WORKSPACE, CONFIG, 60.0)
        for name in ("row", "theta", "t", "d_translation", "d_theta", "eps_t", "cell", "weight"):
            np.testing.assert_array_equal(getattr(both, name), getattr(alone, name), err_msg=name)


def test_similar_runs_merge_consecutive_groups_within_the_face_ratio():
    parts = [(slice(r, r + 2), slice(2 * r, 2 * r + 3)) for r in range(0, 10, 2)]
    runs = _similar_runs(parts, [6, 8, 3, 24, 20])
    assert [(g.start, g.stop) for g, _, _ in runs] == [(0, 2), (2, 3), (3, 5)]
    assert [(r.start, r.stop) for _, r, _ in runs] == [(0, 4), (4, 6), (6, 10)]
    assert [(s.start, s.stop) for _, _, s in runs] == [(0, 7), (8, 11), (12, 19)]


def test_shrunk_outlines_are_made_once_per_part_and_tolerance_for_the_process(monkeypatch):
    fresh = SharedCache(tree.SHRUNK_EDGES, lambda s: 1)
    monkeypatch.setattr(tree, "_shrunk", fresh)
    # two sessions' copies of one part
    a, b = (make_groups(object_set("thesis_like"))[0] for _ in range(2))
    assert a.stable is not b.stable
    cx, cy = a.stable.centroid
    segments = np.array([[cx - 500, cy, cx + 500, cy], [cx - 500, cy + 900, cx, cy + 900]])
    expected = shapely.intersects(
        shapely.linestrings(segments.reshape(-1, 2, 2)),
        a.stable.shape.buffer(-1.0, join_style="mitre"),
    )
    assert expected.tolist() == [True, False]
    assert a.crossed(segments, 1.0).tolist() == expected.tolist() and len(fresh) == 1
    assert b.crossed(segments, 1.0).tolist() == expected.tolist() and len(fresh) == 1
    b.crossed(segments, 2.0)
    assert len(fresh) == 2
    monkeypatch.setattr(fresh, "limit", 1)  # past the bound the least recently used go
    b.crossed(segments, 3.0)
    assert len(fresh) == 1
    # one shrunk outline tested from several threads at once gives the same answers
    many = np.random.default_rng(0).uniform(-80, 80, (400, 4)) + np.array([cx, cy, cx, cy])
    alone = a.crossed(many, 3.0)
    with ThreadPoolExecutor(4) as pool:
        answers = list(pool.map(lambda _: a.crossed(many, 3.0), range(16)))
    assert all(np.array_equal(x, alone) for x in answers)


def test_the_outline_bound_covers_where_two_bounds_cross_along_a_face():
    # the square's corners alternately move 10 / 2 by one bound and 2 / 10 by the other:
    # at every corner the smaller is 2, but midway along each face both allow 6
    from planner.recognition.poses import _outline_move

    stable = SQUARE.stable_poses[0]
    linear = np.array([[0.0, 10.0, 2.0, 10.0, 2.0]])
    consistent = np.array([[0.0, 2.0, 10.0, 2.0, 10.0]])
    assert _outline_move(stable.face_ends, linear, consistent)[0] == pytest.approx(6.0)
    # no crossing, or one bound unknown: the larger of the smaller end values
    assert _outline_move(stable.face_ends, linear, linear + 1)[0] == pytest.approx(10.0)
    assert _outline_move(stable.face_ends, linear, np.full_like(linear, np.inf))[
        0
    ] == pytest.approx(10.0)
