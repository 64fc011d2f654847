"""Equivalence is true symmetry only, and `localized` is never wrong (DESIGN §2).

A class never holds two posed outlines farther apart than the symmetry tolerance
(no chains), never two objects that are not congruent, and a continuous symmetry
is one class. Whenever a session says `localized`, the true object is named and
the true outline lies within the reported bound.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import shapely
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial import cKDTree

from hardware_sim.world import random_world
from planner.geometry import wrap_angle
from planner.models.library import object_from_dict
from planner.recognition.equivalence import (
    EDGE_SAMPLES,
    PosedRings,
    equivalence_classes,
    outline_distance,
    within,
)
from planner.recognition.outline_kernel import nearest_face_distances
from planner.recognition.session import Session
from planner.types import Accuracy, ObjectModel, SensorBounds
from tests.conftest import SET_NAMES, WORKSPACE, object_set

BOUNDS = SensorBounds(1.0, math.radians(3))
#: Every shared set: the five of the first round, the near twins and the curved
#: parts (the cam, over 500 vertices, is refused by the service and left out).
ALL_SETS = [*SET_NAMES, "twins", "curved"]


def models_of(name: str) -> list[ObjectModel]:
    return [m for m in object_set(name) if m.name != "cam"]


def posed(session: Session, h) -> shapely.Polygon:
    stable = session.models_by_name[h.object].stable_poses[h.stable_pose]
    return shapely.Polygon(h.pose.apply(stable.outline), [h.pose.apply(r) for r in stable.holes])


def outline_gap(a: shapely.Polygon, b: shapely.Polygon) -> float:
    """Hausdorff distance between the boundaries, densified (independent of the
    vertex-based measure the classes are built with)."""
    return float(shapely.hausdorff_distance(a.boundary, b.boundary, densify=0.05))


def touched(models, seed: int, touches: int, bounds: SensorBounds = BOUNDS):
    rng = np.random.default_rng(seed)
    world = random_world(models, WORKSPACE, rng)
    session = Session(models, bounds, WORKSPACE)
    for _ in range(touches):
        session = session.observe(world.execute(world.hitting_path(rng), bounds, rng)[0])
    return world, session


@pytest.mark.parametrize("name", ALL_SETS)
@pytest.mark.parametrize("seed", range(3))
def test_a_class_never_holds_outlines_farther_apart_than_its_tolerance(name, seed):
    _, session = touched(models_of(name), seed, 2)
    tau = session.symmetry_tolerance
    by_class: dict[int, list] = {}
    for h in session.hypotheses:
        by_class.setdefault(h.equivalence_class, []).append(posed(session, h))
    for members in by_class.values():
        for i, a in enumerate(members):
            for b in members[i + 1 :]:
                # the vertex-based measure and a densified boundary one agree to 2%
                assert outline_gap(a, b) <= tau * 1.02 + 1e-9


@pytest.mark.parametrize("seed", range(6))
def test_near_twins_never_share_a_class(seed):
    _, session = touched(models_of("twins"), seed, 3)
    objects: dict[int, set[str]] = {}
    for h in session.hypotheses:
        objects.setdefault(h.equivalence_class, set()).add(h.object)
    assert all(len(names) == 1 for names in objects.values())


@pytest.mark.parametrize("seed", range(8))
def test_objects_within_the_tolerance_but_not_congruent_never_share_a_class(seed):
    # 60 x 35 and 60 x 40: centred, 2.5 apart, within tau = 4 of a 2 mm sensor
    a = object_from_dict(
        {"name": "a", "outline": [[-30, -17.5], [30, -17.5], [30, 17.5], [-30, 17.5]]}
    )
    b = object_from_dict({"name": "b", "outline": [[-30, -20], [30, -20], [30, 20], [-30, 20]]})
    world, session = touched([a, b], seed, 5, SensorBounds(2.0, 0.1))
    objects: dict[int, set[str]] = {}
    for h in session.hypotheses:
        objects.setdefault(h.equivalence_class, set()).add(h.object)
    assert all(len(names) == 1 for names in objects.values())
    if session.status == "localized":
        assert session.hypotheses[0].object == world.model.name


def test_congruent_objects_in_one_place_are_one_class():
    square = {"outline": [[-10, -10], [10, -10], [10, 10], [-10, 10]]}
    a = object_from_dict({"name": "a", **square})
    b = object_from_dict({"name": "b", **square})
    _, session = touched([a, b], 3, 3, SensorBounds())
    assert session.hypotheses and session.status == "localized"
    assert {h.object for h in session.hypotheses} == {"a", "b"}


def test_a_disc_is_one_class_whatever_its_rotation():
    ring = [[30 * math.cos(k * math.pi / 32), 30 * math.sin(k * math.pi / 32)] for k in range(64)]
    disc = object_from_dict({"name": "disc", "outline": ring})
    _, session = touched([disc], 1, 3, SensorBounds())
    thetas = {round(h.pose.theta, 6) for h in session.hypotheses}
    assert len(thetas) > 1  # the rotations the contacts cannot fix
    assert len({h.equivalence_class for h in session.hypotheses}) == 1


def test_outline_distance_is_the_same_in_chunks_of_any_size(monkeypatch):
    # rows go in chunks so that a round outline's rotations never fill the memory
    ring = [[30 * math.cos(k * math.pi / 24), 20 * math.sin(k * math.pi / 24)] for k in range(48)]
    stable = object_from_dict({"name": "ellipse", "outline": ring}).stable_poses[0]
    theta = np.linspace(0, 0.3, 9)
    rings = PosedRings.of(stable, theta, np.column_stack([theta * 3, np.zeros(9)]))
    whole = outline_distance(rings, 0, rings, np.arange(9))
    monkeypatch.setattr("planner.recognition.equivalence.CHUNK_ELEMENTS", 1)
    np.testing.assert_array_equal(outline_distance(rings, 0, rings, np.arange(9)), whole)
    assert whole[0] < 1e-9 and np.all(np.diff(whole) > 0)


@settings(max_examples=60, deadline=None)
@given(st.integers(0, 2**16), st.sampled_from([3, 7, 60, 500]), st.floats(0.0, 4.0))
def test_every_boundary_point_lies_near_a_measured_one(seed, n, spacing):
    # short faces hold fewer points, never so few that a stretch of boundary goes
    # unmeasured: every point of a face lies within max(spacing, gap) / 2 of one
    rng = np.random.default_rng(seed)
    a = np.sort(rng.uniform(0, 2 * np.pi, n)) if n > 3 else np.array([0.0, 2.0, 4.0])
    r = 30 * (1 + 0.5 * rng.random(n))
    ring = np.column_stack([r * np.cos(a), r * np.sin(a)])
    stable = object_from_dict({"name": "p", "outline": ring.tolist()}).stable_poses[0]
    theta, t = rng.normal(0, 1, 2), rng.normal(0, 5, (2, 2))
    rings = PosedRings.of(stable, theta, t, spacing)
    full = PosedRings.of(stable, theta, t)
    assert full.points.shape[1] == len(stable.faces.start) * (EDGE_SAMPLES + 1)
    assert rings.points.shape[1] <= full.points.shape[1]
    assert rings.gap <= max(spacing, full.gap) + 1e-12
    # dense points along every face of the first pose, against the measured ones
    u = np.linspace(0, 1, 41)[:, None, None]
    dense = rings.starts[0] + u * (rings.ends[0] - rings.starts[0])
    gaps, _ = cKDTree(rings.points[0]).query(dense.reshape(-1, 2))
    assert gaps.max() <= max(spacing, full.gap) / 2 + 1e-9


def brute_force_distance(rings: PosedRings, i: int, rows: np.ndarray) -> np.ndarray:
    """The outline distance by its definition: every point against every face,
    both ways (the law the compiled early-break scan must keep)."""

    def directed(points: np.ndarray, starts: np.ndarray, ends: np.ndarray) -> float:
        p, a, e = points[:, None, :], starts[None], ends[None] - starts[None]
        sq = np.maximum(np.einsum("...i,...i", e, e), 1e-300)
        u = np.clip(np.einsum("...i,...i", p - a, e) / sq, 0.0, 1.0)
        gap = p - (a + u[..., None] * e)
        return float(np.sqrt(np.einsum("...i,...i", gap, gap).min(axis=1)).max())

    return np.array(
        [
            max(
                directed(rings.points[i], rings.starts[j], rings.ends[j]),
                directed(rings.points[j], rings.starts[i], rings.ends[i]),
            )
            for j in rows
        ]
    )


@settings(max_examples=60, deadline=None)
@given(st.integers(0, 2**16), st.floats(0.02, 3.0), st.sampled_from([3, 5, 48, 200]))
def test_within_answers_as_the_exact_distance(seed, scale, n):
    # the scan breaks early and starts where the last point ended; the distance and
    # every threshold's answer must equal measuring every point against every face
    rng = np.random.default_rng(seed)
    k = np.arange(n)
    radius = 30 * (1 + 0.3 * rng.random(n)) if n < 48 else 30 * np.ones(n)
    ring = np.column_stack([radius * np.cos(2 * np.pi * k / n), radius * np.sin(2 * np.pi * k / n)])
    stable = object_from_dict({"name": "p", "outline": ring.tolist()}).stable_poses[0]
    theta = rng.normal(0, 0.05 * scale, 12)
    theta[-1] += np.pi / 2  # a far turn: its nearest faces lie away from the first tried
    t = rng.normal(0, scale, (12, 2))
    rings = PosedRings.of(stable, theta, t)
    exact = outline_distance(rings, 0, rings, np.arange(12))
    np.testing.assert_array_equal(exact, brute_force_distance(rings, 0, np.arange(12)))
    near = (exact[3] * (1 + 1e-9), exact[3] * (1 - 1e-9), exact[3])
    for limit in (*np.quantile(exact, [0.2, 0.5, 0.8]), *near, 0.0):
        got = within(rings, 0, rings, np.arange(12), float(limit))
        np.testing.assert_array_equal(got, exact <= limit)


def test_classes_do_not_chain():
    # outlines 0.6 tau apart in a row: a chain links them all, classes must not
    square = object_from_dict({"name": "sq", "outline": [[-5, -5], [5, -5], [5, 5], [-5, 5]]})
    stable = square.stable_poses[0]
    tau = 1.0
    xs = np.arange(6) * 0.3 * tau  # neighbours 0.3 tau apart: within tau/2 of each other
    rings = [PosedRings.of(stable, np.zeros(len(xs)), np.column_stack([xs, np.zeros(len(xs))]))]
    label = equivalence_classes(rings, np.arange(len(xs)), np.arange(len(xs)), tau)
    for k in np.unique(label):
        members = xs[label == k]
        assert np.ptp(members) <= tau
    assert len(np.unique(label)) > 1


@pytest.mark.parametrize("name", ALL_SETS)
def test_localized_names_the_true_object_and_bounds_the_true_outline(name):
    """200 worlds drawn from the prior per set, four random hitting touches each at
    1 mm / 3 degrees: whenever the session says localized, it is right."""
    models = models_of(name)
    localized = singles = 0
    for seed in range(200):
        world, session = touched(models, 1000 + seed, 4)
        if session.status != "localized":
            continue
        localized += 1
        best = session.hypotheses[0]
        true_poly = world.polygon()
        named = session.models_by_name[best.object]
        assert best.object == world.model.name or named.same_geometry(world.model)
        bound = session.localization.bound
        assert outline_gap(posed(session, best), true_poly) <= bound.eps_t / 2 + 1e-6
        assert Accuracy.admits(session.accuracy, bound)
        # a class of one reports its leader's own bound: the truth's pose lies in it
        alone = sum(h.equivalence_class == best.equivalence_class for h in session.hypotheses)
        if alone == 1 and (best.object, best.stable_pose) == (world.model.name, world.pose_index):
            moved = math.hypot(best.pose.x - world.pose.x, best.pose.y - world.pose.y)
            assert moved <= bound.translation + 1e-6
            assert abs(wrap_angle(best.pose.theta - world.pose.theta)) <= bound.rotation + 1e-9
            singles += 1
    assert localized > 0
    assert singles > 0 or name == "symmetric"  # every part of that set has a symmetry


def _classes_without_filter(rings, order, family, tau):
    """The greedy classes with every unclassed hypothesis measured (no candidate tree)."""
    sizes = [len(r) for r in rings]
    offsets = np.concatenate([[0], np.cumsum(sizes)])
    group = np.repeat(np.arange(len(rings)), sizes)
    local = np.arange(offsets[-1]) - offsets[group]
    label = np.full(offsets[-1], -1)
    classes = 0
    for leader in order:
        if label[leader] >= 0:
            continue
        label[leader] = classes
        open_ = np.flatnonzero((label < 0) & (family != family[leader]))
        for h in np.unique(group[open_]):
            mine = open_[group[open_] == h]
            close = within(rings[group[leader]], local[leader], rings[h], local[mine], tau / 2)
            label[mine[close]] = classes
        classes += 1
    return label


@settings(max_examples=40, deadline=None)
@given(
    st.integers(0, 2**16),
    st.sampled_from([6, 24, 80]),
    st.booleans(),
    st.floats(0.1, 4.0),
    st.sampled_from([4, 15]),
)
def test_the_candidate_filter_drops_no_pair_that_is_within(seed, n, hole, spread, m):
    """Round outlines with an off-centre hole turned a little: the support values see
    nothing, the probe distances tell them apart; the classes must be those of
    measuring every pair (with `m` = 4 per outline, few enough that every pair is
    measured without the filter; with 15, filtered)."""
    rng = np.random.default_rng(seed)
    ring = [
        [30 * math.cos(2 * math.pi * k / n), 30 * math.sin(2 * math.pi * k / n)] for k in range(n)
    ]
    holes = [[[12 + 2 * math.cos(-a), 8 + 2 * math.sin(-a)] for a in np.linspace(0, 6, 7)]]
    shapes = [{"name": "a", "outline": ring, **({"holes": holes} if hole else {})},
              {"name": "b", "outline": [[x * 1.01, y] for x, y in ring]}]  # fmt: skip
    tau = 1.0
    rings = []
    for shape in shapes:
        stable = object_from_dict(shape).stable_poses[0]
        theta = rng.normal(0, 0.02 * spread, m) + rng.integers(0, n, m) * 2 * math.pi / n
        rings.append(PosedRings.of(stable, theta, rng.normal(0, 0.3 * spread, (m, 2))))
    total = sum(len(r) for r in rings)
    order = rng.permutation(total)
    # some hypotheses samples of one slide family (they never share a class)
    family = rng.integers(0, total, total) if hole else np.arange(total)
    got = equivalence_classes(rings, order, family, tau)
    np.testing.assert_array_equal(got, _classes_without_filter(rings, order, family, tau))


@settings(max_examples=40, deadline=None)
@given(st.integers(0, 2**16), st.integers(1, 40))
def test_probe_distances_are_the_distances_to_the_nearest_face(seed, n_faces):
    # the compiled probe distances against shapely's, on a random ring's faces
    rng = np.random.default_rng(seed)
    starts = rng.normal(0, 20, (n_faces, 2))
    ends = np.roll(starts, -1, axis=0)
    points = rng.normal(0, 30, (3, 5, 2))
    got = nearest_face_distances(points, starts, ends)
    faces = shapely.multilinestrings(np.stack([starts, ends], axis=1))
    want = shapely.distance(shapely.points(points), faces)
    np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-12)


def test_none_can_share_only_outlines_whose_support_values_lie_apart():
    """Two squares 0.9 tau apart may share a class (a join takes them in): the
    screen says so; 1.1 tau apart (their support values differ by that much) they
    cannot, nor can two of one slide family or of two shapes."""
    from planner.recognition.equivalence import none_can_share

    square = object_from_dict({"name": "sq", "outline": [[-5, -5], [5, -5], [5, 5], [-5, 5]]})
    stable, tau = square.stable_poses[0], 1.0

    def apart(dx, family=(0, 1), shapes=(0, 0)):
        return none_can_share(
            [stable, stable], [np.zeros(1), np.zeros(1)], [np.zeros((1, 2)), np.array([[dx, 0.0]])],
            np.array(family), np.array(shapes), tau,
        )  # fmt: skip

    assert not apart(0.9 * tau) and not apart(0.0)
    assert apart(1.1 * tau)
    assert apart(0.0, family=(3, 3)) and apart(0.0, shapes=(0, 1))
