"""Vector multi-interpretation image (DESIGN §4.8, thesis ch. 3).

The scene helpers here (hypotheses consistent with touches, built by hand
without the interpretation tree) are shared with test_grid.py and
test_render.py.
"""

from __future__ import annotations

import dataclasses
from functools import cache

import numpy as np
import pytest
import shapely
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from planner.errors import InvalidModelError, PlanningNotPossibleError
from planner.geometry import cast_rays, point_segment_distance, rotation_matrix, wrap_angle
from planner.image.faces import cluster_sorted, grown_faces, posed_faces, posed_polygon
from planner.image.vector import build_mii, paths_crossings
from planner.models.library import load_objects
from planner.models.outlines import make_stable_pose
from planner.types import ErrorBound, Hypothesis, ObjectModel, Pose
from tests.conftest import DATA

OBJECT_SETS = ("mcube_prisms", "symmetric", "table_poses", "thesis_like", "workshop")
PROPERTY = settings(
    max_examples=40,
    derandomize=True,
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much],
)


@cache
def object_set(name: str) -> tuple[ObjectModel, ...]:
    return tuple(load_objects(DATA / f"{name}.json"))


def consistent_hypotheses(
    models, contacts, *, eps_t: float = 0.0, rotation: float = 0.0, tol: float = 1e-7
) -> list[Hypothesis]:
    """Every (object, stable pose, face pair, pose) putting both contacts on their
    faces with matching normals; probabilities from the priors, normalized;
    hypotheses whose posed outlines coincide share an equivalence class."""
    points = np.array([c[0] for c in contacts], dtype=float)
    normals = np.array([c[1] for c in contacts], dtype=float)
    u_angle = np.arctan2(normals[:, 1], normals[:, 0])
    found = []
    for model in models:
        for k, sp in enumerate(model.stable_poses):
            f = sp.faces
            scale = float(np.ptp(sp.outline, axis=0).max())
            for a in range(len(f)):
                theta = float(wrap_angle(u_angle[0] - f.angle[a]))
                R = rotation_matrix(theta)
                for b in np.flatnonzero(np.abs(wrap_angle(u_angle[1] - f.angle - theta)) < tol):
                    M = np.stack([R @ f.normal[a], R @ f.normal[b]])
                    if abs(np.linalg.det(M)) < 1e-9:
                        continue
                    # (R n_a)·t = (R n_a)·p_j - d_a for both contacts
                    rhs = [M[0] @ points[0] - f.offset[a], M[1] @ points[1] - f.offset[b]]
                    t = np.linalg.solve(M, rhs)
                    pose = Pose(float(t[0]), float(t[1]), theta)
                    on_face = point_segment_distance(
                        pose.inverse_apply(points), f.start[[a, b]], f.end[[a, b]]
                    )
                    if on_face.max() <= tol * scale:
                        weight = (model.prior or 1.0) * sp.probability
                        found.append(
                            Hypothesis(
                                model.name, k, (a, int(b)), pose,
                                ErrorBound(0.0, rotation, eps_t), weight,
                            )
                        )  # fmt: skip
    return with_classes(found, models)


def with_classes(hypotheses, models) -> list[Hypothesis]:
    polygons = [posed_polygon(h, {m.name: m for m in models}) for h in hypotheses]
    klass = list(range(len(hypotheses)))
    for i, (h, p) in enumerate(zip(hypotheses, polygons, strict=True)):
        for j in range(i):
            same_object = hypotheses[j].object == h.object
            if same_object and p.symmetric_difference(polygons[j]).area < 1e-6 * p.area:
                klass[i] = klass[j]
                break
    total = sum(h.probability for h in hypotheses)
    return [
        dataclasses.replace(h, probability=h.probability / total, equivalence_class=c)
        for h, c in zip(hypotheses, klass, strict=True)
    ]


def random_scene(seed: int, set_name: str | None = None, eps_t: float = 0.0, rotation=0.0):
    """Two touches on a random object of a random set in a random pose, and
    every hypothesis consistent with them."""
    rng = np.random.default_rng(seed)
    set_name = set_name or OBJECT_SETS[rng.integers(len(OBJECT_SETS))]
    models = object_set(set_name)
    truth = models[rng.integers(len(models))]
    sp = truth.stable_poses[rng.integers(len(truth.stable_poses))]
    pose = Pose(*rng.uniform(-30, 30, 2), rng.uniform(-np.pi, np.pi))
    f = sp.faces
    while True:
        a, b = rng.choice(len(f), 2, replace=False)
        if abs(f.normal[a] @ f.normal[b]) < 0.99:
            break
    s = rng.uniform(0.1, 0.9, (2, 1))
    model_points = f.start[[a, b]] + s * (f.end[[a, b]] - f.start[[a, b]])
    points = pose.apply(model_points)
    normals = f.normal[[a, b]] @ pose.rotation().T
    contacts = list(zip(points, normals, strict=True))
    hypotheses = consistent_hypotheses(models, contacts, eps_t=eps_t, rotation=rotation)
    return models, hypotheses, contacts


#: bump_block touched under its bottom (normal -y) and on its right side (+x).
BUMP_CONTACTS = [((30.0, 0.0), (0.0, -1.0)), ((100.0, 30.0), (1.0, 0.0))]
#: touches on the bump's right flank and the top: the block and its offset twin.
TWIN_CONTACTS = [((55.0, 87.5), (15 / 325**0.5, 10 / 325**0.5)), ((70.0, 80.0), (0.0, 1.0))]


def bump_block_case(eps_t: float = 0.0, rotation: float = 0.0):
    """The thesis' Exp. II object after two constraining touches: four poses of
    the block (rotations by 0, 90, 180, 270 degrees) explain both touches."""
    models = tuple(m for m in object_set("thesis_like") if m.name == "bump_block")
    return models, consistent_hypotheses(models, BUMP_CONTACTS, eps_t=eps_t, rotation=rotation)


def first_hits(mii, origins, directions, lengths):
    """First hit point (H, P, 2) and face normal (H, P, 2) per hypothesis (nan on a miss)."""
    f = mii.faces
    H = len(mii.hypotheses)
    points = np.full((H, len(origins), 2), np.nan)
    normals = np.full((H, len(origins), 2), np.nan)
    for h in range(H):
        own = f.hypothesis == h
        dist, face = cast_rays(origins, directions, lengths, f.start[own][None], f.end[own][None])
        hit = face >= 0
        points[h, hit] = origins[hit] + dist[hit, None] * directions[hit]
        normals[h, hit] = f.normal[own][face[hit]]
    return points, normals


def confused_pairs(mii, points, normals, scale):
    """Per path: number of pairs of different classes with the same measurement."""
    same_point = np.hypot(*np.moveaxis(points[:, None] - points[None], -1, 0)) < 1e-6 * scale
    same_normal = np.hypot(*np.moveaxis(normals[:, None] - normals[None], -1, 0)) < 1e-6
    other_class = (mii.classes[:, None] != mii.classes[None, :])[..., None]
    return np.sum(same_point & same_normal & other_class, axis=(0, 1)) // 2


def paths_into_ia(mii, rng, n):
    """Random straight paths from a circle outside the union to points inside the IA."""
    xmin, ymin, xmax, ymax = mii.intersection.bounds
    pts = rng.uniform([xmin, ymin], [xmax, ymax], (40 * n, 2))
    pts = pts[shapely.contains_xy(mii.intersection, pts[:, 0], pts[:, 1])][:n]
    ux0, uy0, ux1, uy1 = mii.union.bounds
    centre = np.array([ux0 + ux1, uy0 + uy1]) / 2
    radius = np.hypot(ux1 - ux0, uy1 - uy0)
    phi = rng.uniform(0, 2 * np.pi, len(pts))
    origins = centre + radius * np.stack([np.cos(phi), np.sin(phi)], axis=1)
    d = pts - origins
    lengths = np.hypot(d[:, 0], d[:, 1])
    return origins, d / lengths[:, None], lengths, radius


def shifted_rectangles(shifts=(0.0, 1.0), weights=(0.5, 0.5)):
    rect = ObjectModel("rect", (make_stable_pose([[0, 0], [2, 0], [2, 1], [0, 1]]),))
    hs = [
        Hypothesis("rect", 0, (), Pose(x, 0, 0), ErrorBound(0, 0, 0), w, equivalence_class=i)
        for i, (x, w) in enumerate(zip(shifts, weights, strict=True))
    ]
    return [rect], hs


# ---------------------------------------------------------------- basics


def test_posed_faces_follow_the_pose():
    models, hs = shifted_rectangles(shifts=(3.0,), weights=(1.0,))
    faces = posed_faces(hs, models)
    assert len(faces) == 4
    np.testing.assert_allclose(faces.start, models[0].stable_poses[0].outline + np.array([3.0, 0]))
    np.testing.assert_allclose(faces.offset, np.einsum("ij,ij->i", faces.normal, faces.end))


def test_shifted_rectangles_share_top_and_bottom():
    models, hs = shifted_rectangles()
    mii = build_mii(hs, models)
    assert mii.exact and mii.intersection.area == pytest.approx(1.0)
    assert mii.union.area == pytest.approx(3.0)
    segments = sorted((b.geometry.bounds, b.degree, b.strength) for b in mii.blocking)
    assert segments == [
        ((1.0, 0.0, 2.0, 0.0), 1, pytest.approx(1.0)),
        ((1.0, 1.0, 2.0, 1.0), 1, pytest.approx(1.0)),
    ]


def test_weighted_strength_sums_probabilities_of_sharing_classes():
    # thesis §3.1.3: strength = sum of the probabilities of the sharing boundaries
    models, hs = shifted_rectangles(shifts=(0.0, 1.0, 1.5), weights=(2.0, 1.0, 1.0))
    mii = build_mii(hs, models)
    np.testing.assert_allclose(mii.weights, [0.5, 0.25, 0.25])
    bottom = sorted(
        (b.geometry.bounds[0], b.geometry.bounds[2], b.classes, b.degree, b.strength)
        for b in mii.blocking
        if b.normal[1] < -0.5
    )
    assert [s[:4] for s in bottom] == [
        (1.0, 1.5, (0, 1), 1),
        (1.5, 2.0, (0, 1, 2), 2),
        (2.0, 3.0, (1, 2), 1),
    ]
    np.testing.assert_allclose([s[4] for s in bottom], [0.75, 1.0, 0.5])


def test_equivalent_hypotheses_count_once_with_summed_weight():
    square = next(m for m in object_set("symmetric") if m.name == "square")
    plate = next(m for m in object_set("symmetric") if m.name == "plate")
    hs = [
        Hypothesis("square", 0, (), Pose(0, 0, 0), ErrorBound(0, 0, 0), 0.3, equivalence_class=0),
        Hypothesis("square", 0, (), Pose(0, 0, np.pi / 2), ErrorBound(0, 0, 0), 0.3, 0, 0),
        Hypothesis("plate", 0, (), Pose(30, 10, 0), ErrorBound(0, 0, 0), 0.4, equivalence_class=1),
    ]
    mii = build_mii(hs, [square, plate])
    np.testing.assert_allclose(mii.class_weights, [0.6, 0.4])
    # the square's faces coincide in both members: no blocking between them
    assert mii.blocking
    for b in mii.blocking:
        assert b.classes == (0, 1) and b.degree == 1
        assert b.strength == pytest.approx(1.0)
    only_square = build_mii(hs[:2], [square])
    assert only_square.blocking == ()


def test_bump_block_image():
    models, hs = bump_block_case()
    assert len(hs) == 4 and len({h.equivalence_class for h in hs}) == 4
    mii = build_mii(hs, models)
    assert mii.intersection.symmetric_difference(shapely.box(20, 0, 100, 80)).area < 1e-3
    # Observation 3: each data site lies on a blocking boundary of degree n - 1
    for point, _ in BUMP_CONTACTS:
        on = [b for b in mii.blocking if b.geometry.distance(shapely.Point(point)) < 1e-9]
        assert max(b.degree for b in on) == len(hs) - 1
        assert max(b.strength for b in on) == pytest.approx(1.0)
    # the far sides are shared pairwise: strength 1/2
    top = [b for b in mii.blocking if b.geometry.bounds[1] == pytest.approx(100.0)]
    assert [b.strength for b in top] == [pytest.approx(0.5)]
    # the bump opens the 80-high top: hypotheses 0 and 2 share it except at x in (40, 60)
    y80 = sorted(
        b.geometry.bounds[::2]
        for b in mii.blocking
        if abs(b.geometry.bounds[1] - 80) < 1e-9 and abs(b.geometry.bounds[3] - 80) < 1e-9
    )
    np.testing.assert_allclose(y80, [(0, 40), (60, 100)], atol=1e-9)


def test_error_grows_faces_into_regions():
    models, hs = bump_block_case(eps_t=6.0, rotation=0.02)
    mii = build_mii(hs, models)
    assert not mii.exact
    assert all(b.is_region and b.geometry.area > 0 for b in mii.blocking)
    # a face of length L grows into an (L + eps_t) x eps_t rectangle
    rects = grown_faces(mii.faces)
    np.testing.assert_allclose(shapely.area(rects), (mii.faces.length + 6.0) * 6.0)
    assert mii.certain_intersection.area < mii.intersection.area
    assert mii.intersection.buffer(1e-9).contains(mii.certain_intersection)
    # the data sites still lie in regions shared by all four classes
    for point, _ in BUMP_CONTACTS:
        inside = [b for b in mii.blocking if b.geometry.distance(shapely.Point(point)) < 1e-9]
        assert max(b.degree for b in inside) == 3


def test_cluster_sorted_keeps_the_seam_together():
    angles = np.array([np.pi - 0.01, -np.pi + 0.01, 0.0, 1.0])
    labels = cluster_sorted(angles, 0.05, circular=True)
    assert labels[0] == labels[1] and len(set(labels.tolist())) == 3


def test_paths_crossings_counts_each_path():
    models, hs = shifted_rectangles()
    mii = build_mii(hs, models)
    origins = np.array([[1.5, -1.0], [0.5, -1.0], [5.0, 0.5]])
    directions = np.array([[0.0, 1.0], [0.0, 1.0], [-1.0, 0.0]])
    c = paths_crossings(mii, origins, directions, np.array([3.0, 3.0, 3.5]))
    assert c.count.tolist() == [2, 0, 0]
    np.testing.assert_allclose(c.total, [2.0, 0.0, 0.0])
    np.testing.assert_allclose(c.largest, [1.0, 0.0, 0.0])


def test_bad_input_raises_planner_errors():
    models, hs = shifted_rectangles()
    with pytest.raises(PlanningNotPossibleError):
        build_mii([], models)
    with pytest.raises(InvalidModelError):
        build_mii([dataclasses.replace(hs[0], object="nope")], models)
    with pytest.raises(InvalidModelError):
        build_mii([dataclasses.replace(hs[0], stable_pose=3)], models)
    with pytest.raises(PlanningNotPossibleError):
        build_mii([dataclasses.replace(h, probability=0.0) for h in hs], models)


# ------------------------------------------------------ thesis properties


@PROPERTY
@given(seed=st.integers(0, 2**20))
def test_theorem_1_unblocked_paths_distinguish(seed):
    """Zero error: a path from outside the union into the IA that crosses no
    blocking boundary gives a measurement that only one class explains."""
    models, hs, _ = random_scene(seed)
    mii = build_mii(hs, models)
    rng = np.random.default_rng(seed)
    origins, directions, lengths, scale = paths_into_ia(mii, rng, 200)
    free = paths_crossings(mii, origins, directions, lengths).count == 0
    points, normals = first_hits(mii, origins[free], directions[free], lengths[free])
    assert not np.isnan(points).any()  # every outline is entered on the way into the IA
    assert confused_pairs(mii, points, normals, scale).sum() == 0


def test_theorem_1_is_exercised_and_blocked_paths_can_confuse():
    models = object_set("thesis_like")
    hs = consistent_hypotheses(models, TWIN_CONTACTS)
    assert len(hs) == 4 and {h.object for h in hs} == {"bump_block", "bump_block_offset"}
    mii = build_mii(hs, models)
    rng = np.random.default_rng(7)
    origins, directions, lengths, scale = paths_into_ia(mii, rng, 400)
    crossings = paths_crossings(mii, origins, directions, lengths)
    points, normals = first_hits(mii, origins, directions, lengths)
    confused = confused_pairs(mii, points, normals, scale)
    free = crossings.count == 0
    assert free.sum() > 20 and confused[free].sum() == 0
    assert confused[~free].sum() > 0  # the check itself can see confusion
    # P(DM) >= 1 - summed strength: confusion needs enough blocking on the way
    assert np.all(crossings.total[confused > 0] > 0)


@PROPERTY
@given(seed=st.integers(0, 2**20))
def test_observation_4_ia_is_not_empty_after_consistent_touches(seed):
    models, hs, contacts = random_scene(seed)
    mii = build_mii(hs, models)
    assert mii.intersection.area > 0 and len(mii.intersection_areas) >= 1
    # Observation 1: every data site is on the intersection boundary
    for point, _ in contacts:
        assert mii.intersection.boundary.distance(shapely.Point(point)) < 1e-4
