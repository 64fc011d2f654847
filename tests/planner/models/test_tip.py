"""The ball tip (DESIGN §4.14): contacts moved back to the surface within the
widened bound, the grown outline the planner casts, the exact ball the simulated
hardware casts, and a whole recognition with the centre reported."""

from __future__ import annotations

import math

import numpy as np
import pytest
import shapely
from hypothesis import given, settings
from hypothesis import strategies as st

from hardware_sim.world import World, path_towards, random_world
from planner.models.library import load_objects, object_from_dict
from planner.models.tip import (
    MITRE_LIMIT,
    cast_ball,
    grown_model,
    grown_pose,
    surface_bounds,
    surface_contact,
)
from planner.planning.config import StrategyConfig
from planner.planning.outcomes import OutcomeConfig, predict_outcomes
from planner.planning.plan import plan_session
from planner.planning.posed_set import pose_hypotheses
from planner.recognition.session import Session
from planner.render import session_picture
from planner.types import (
    Contact,
    ErrorBound,
    Hypothesis,
    Pose,
    SensingPath,
    SensorBounds,
)
from tests.conftest import SET_NAMES, WORKSPACE, object_set

angles = st.floats(-math.pi, math.pi)


def _unit(a: float) -> np.ndarray:
    return np.array([math.cos(a), math.sin(a)])


@settings(max_examples=300, deadline=None)
@given(
    r=st.floats(0.0, 20.0),
    eps_d=st.floats(0.0, 5.0),
    phi=st.floats(0.0, 0.7),
    a=angles,
    da=st.floats(-1.0, 1.0),
    e_len=st.floats(0.0, 1.0),
    e_dir=angles,
)
def test_the_surface_point_lies_within_the_widened_bound(r, eps_d, phi, a, da, e_len, e_dir):
    """|(c - r u) - s| <= eps_d + 2 r sin(phi / 2) for a centre c within eps_d of
    the true centre s + r n and u within phi of n."""
    s = np.array([3.0, -2.0])
    n = _unit(a)
    u = _unit(a + da * phi)
    c = s + r * n + e_len * eps_d * _unit(e_dir)
    bounds = surface_bounds(SensorBounds(eps_d, phi, r))
    moved = surface_contact(Contact(tuple(c), tuple(u)), r)
    assert np.hypot(*(np.asarray(moved.point) - s)) <= bounds.position_error + 1e-9
    assert moved.normal == pytest.approx(tuple(u))
    assert bounds.normal_error == phi and bounds.tip_radius == 0


def test_the_widened_bound_is_reached():
    """The bound is tight: the centre error along the chord the normal error swings."""
    r, eps_d, phi = 3.0, 1.0, 0.1
    n, u = _unit(0.0), _unit(phi)
    chord = r * (n - u)  # the surface point moves by r (n - u)
    c = r * n + eps_d * chord / np.hypot(*chord)
    moved = surface_contact(Contact(tuple(c), tuple(u)), r)
    bound = surface_bounds(SensorBounds(eps_d, phi, r)).position_error
    assert np.hypot(*moved.point) == pytest.approx(bound)


def _valid_poses():
    for name in SET_NAMES:
        for model in object_set(name):
            for k, stable in enumerate(model.stable_poses):
                yield pytest.param(stable, id=f"{name}-{model.name}-{k}")


@pytest.mark.parametrize("stable", list(_valid_poses())[::3])
@pytest.mark.parametrize("r", [0.5, 3.0])
def test_the_grown_outline_holds_every_centre_and_no_more_than_the_mitres(stable, r):
    """Every face keeps its index and normal; each face not shortened past its
    ends lies on its own line moved out by r; the grown region holds the exact
    one (outline buffered by r, where the ball's centre can be) and lies within
    the mitre limit of the outline."""
    grown = grown_pose(stable, r)
    bare, faces = stable.faces, grown.faces
    assert np.array_equal(faces.normal, bare.normal) and np.array_equal(faces.ring, bare.ring)
    forward = np.einsum("ij,ij->i", faces.end - faces.start, bare.end - bare.start) > 0
    # n.x = d + r at both ends (a capped mitre moves an end off the line; at most a few)
    on_line = np.isclose(np.einsum("ij,ij->i", bare.normal, faces.start), bare.offset + r) & (
        np.isclose(np.einsum("ij,ij->i", bare.normal, faces.end), bare.offset + r)
    )
    assert on_line[forward].mean() > 0.8
    region = shapely.Polygon(grown.outline, list(grown.holes)).buffer(0)
    exact = stable.shape.buffer(r, quad_segs=32)
    assert exact.difference(region).area <= 1e-6 * exact.area + 1e-3 * r * exact.length
    assert region.difference(stable.shape.buffer(MITRE_LIMIT * r * 1.001)).area <= 1e-9


@settings(max_examples=150, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), r=st.floats(0.2, 10.0), name=st.sampled_from(SET_NAMES))
def test_the_ball_stops_where_it_first_comes_within_its_radius(seed, r, name):
    """cast_ball's centre lies r from the outline, and the path before it farther."""
    rng = np.random.default_rng(seed)
    world = random_world(object_set(name), WORKSPACE, rng)
    path = world.hitting_path(rng) if rng.random() < 0.8 else path_towards(
        WORKSPACE, rng.uniform(-math.pi, math.pi), rng.normal(0, 80, 2)
    )  # fmt: skip
    shape = world.polygon()
    start, end, normal = world.posed_faces()
    hit = cast_ball(path.origin, path.direction, path.length, start, end, normal, r)
    line = shapely.LineString([path.origin, path.end])
    if hit is None:
        assert line.distance(shape) >= r * (1 - 1e-9)
        return
    t, face, vertex = hit
    centre = np.asarray(path.origin) + t * np.asarray(path.direction)
    assert shapely.Point(centre).distance(shape) == pytest.approx(r, rel=1e-6, abs=1e-7)
    before = np.asarray(path.origin) + max(t - 1e-6 * r, 0.0) * np.asarray(path.direction)
    assert shapely.LineString([path.origin, before]).distance(shape) >= r * (1 - 1e-6)
    if vertex >= 0:
        assert np.allclose(end[face], start[vertex])


def test_the_plan_predicts_where_the_ball_stops():
    """The planner casts the grown outline: for the true pose its predicted contact
    is the simulated ball's centre with the face's normal."""
    model = load_objects("workshop")[0]
    world = World(model, 0, Pose(10.0, -5.0, 0.7), WORKSPACE)
    r = 3.0
    rng = np.random.default_rng(1)
    truth = Hypothesis(model.name, 0, (), world.pose, ErrorBound(0, 0, 0), 1.0)
    posed = pose_hypotheses([truth], {model.name: grown_model(model, r)})
    checked = 0
    for _ in range(40):
        path = world.hitting_path(rng)
        stop = world.ball_contact(path, r)
        out = predict_outcomes(
            posed,
            np.array([path.origin]),
            np.array([path.direction]),
            np.array([path.length]),
            SensorBounds(1.0, 0.05),
            OutcomeConfig(),
        )
        centre, _, face = stop
        (dx, dy), (wx, wy) = path.direction, centre - np.asarray(path.origin)
        off_path = dx * wy - dy * wx
        if not out.hit[0, 0] or abs(off_path) > 1e-9:
            continue  # the ball met a vertex and rolled off the path onto a face
        assert out.point[0, 0] == pytest.approx(centre, abs=1e-6)
        assert int(out.face[0, 0]) == face
        checked += 1
    assert checked >= 30


@pytest.mark.parametrize("r", [0.0, 3.0])
def test_a_recognition_with_the_centre_reported_localizes_the_truth(r):
    """Lookahead sessions told the radius, contacts at the ball's centre within the
    bounds: the right object and pose, inside the reported bound."""
    models = object_set("workshop")
    bounds = SensorBounds(1.0, math.radians(3), r)
    for seed in range(4):
        rng = np.random.default_rng(seed)
        world = random_world(models, WORKSPACE, rng)
        session = Session(models, bounds, WORKSPACE)
        for _ in range(12):
            plan = plan_session(session, (200.0, 0.0), StrategyConfig(name="lookahead"), rng=seed)
            obs, _ = world.execute(plan.paths[0].path, bounds, rng, edge_share=0.5)
            session = session.observe(obs)
            if session.status != "ambiguous" and session.contacts:
                break
        assert session.status == "localized"
        best = session.hypotheses[0]
        assert (best.object, best.stable_pose) == (world.model.name, world.pose_index)
        gap = math.hypot(best.pose.x - world.pose.x, best.pose.y - world.pose.y)
        assert gap <= best.error_bound.translation + 1e-9


def test_the_picture_draws_the_ball_and_the_grown_outline():
    models = object_set("thesis_like")
    bounds = SensorBounds(1.0, 0.05, 4.0)
    world = World(models[0], 0, Pose(0.0, 0.0, 0.3), WORKSPACE)
    obs, _ = world.execute(world.hitting_path(np.random.default_rng(0)), bounds)
    svg = session_picture(Session(models, bounds, WORKSPACE).observe(obs), (200, 0), fmt="svg")
    assert b'id="ball-0"' in svg and b'id="grown-0"' in svg
    plain = Session(models, SensorBounds(1.0, 0.05), WORKSPACE).observe(obs)
    assert b'id="ball-0"' not in session_picture(plain, (200, 0), fmt="svg")


def test_a_path_passing_within_the_radius_stops_on_the_ball():
    """A path 1 above a square's top face misses it bare and with a 0.5 mm ball; a
    3 mm ball meets the corner and rolls onto the side face; straight down, the
    centre stops r above the face."""
    square = object_from_dict(
        {"name": "sq", "outline": [[-10, -10], [10, -10], [10, 10], [-10, 10]]}
    )
    world = World(square, 0, Pose(0.0, 0.0, 0.0), WORKSPACE)
    path = SensingPath((-150.0, 11.0), (1.0, 0.0), 300.0)
    assert world.first_contact(path) is None
    assert world.ball_contact(path, 0.5) is None
    # it meets the corner's arc, and rolls onto the face the path pushes against
    centre, surface, face = world.ball_contact(path, 3.0)
    assert centre == pytest.approx([-13.0, 10.0]) and surface == pytest.approx([-10.0, 10.0])
    assert square.stable_poses[0].faces.normal[face] == pytest.approx([-1.0, 0.0])
    centre, surface, face = world.ball_contact(SensingPath((0.0, 150.0), (0.0, -1.0), 300.0), 3.0)
    assert centre == pytest.approx([0.0, 13.0]) and surface == pytest.approx([0.0, 10.0])
