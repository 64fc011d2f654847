"""The simulated arm: exact ideal contacts, compliance, backlash, thermal drift,
vertex slides, travel accounting, and the Probe boundary."""

from __future__ import annotations

import math

import numpy as np
import pytest

from hardware_sim.arm import ArmParams, SimulatedArm, slide_off_vertex
from hardware_sim.presets import build_arm, explicit_preset
from hardware_sim.sensor import ExactSensor
from hardware_sim.world import World, random_world
from planner.models.library import object_from_dict
from planner.types import Pose, SensingPath, Workspace
from tests.conftest import SET_NAMES, WORKSPACE, object_set

SQUARE = object_from_dict({"name": "sq", "outline": [[-20, -20], [20, -20], [20, 20], [-20, 20]]})
WS = Workspace((0.0, 0.0), 100.0)


def square_world(theta: float = 0.0) -> World:
    return World(SQUARE, 0, Pose(0.0, 0.0, theta), WS)


def exact_arm(world: World, seed: int = 0, **params: float) -> SimulatedArm:
    return SimulatedArm(world, ArmParams(**params), ExactSensor(), np.random.default_rng(seed))


@pytest.mark.parametrize("set_name", SET_NAMES)
def test_ideal_gives_exact_contacts(set_name):
    models = object_set(set_name)
    rng = np.random.default_rng(7)
    for trial in range(8):
        world = random_world(models, WORKSPACE, rng)
        arm = build_arm(world, "ideal", trial)
        _, _, normals = world.posed_faces()
        for _ in range(5):
            path = world.hitting_path(rng)
            point, face = world.first_contact(path)
            result = arm.execute(path)
            c = result.observation.contact
            np.testing.assert_allclose(c.point, point, rtol=0, atol=1e-12)
            np.testing.assert_allclose(c.normal, normals[face], rtol=0, atol=1e-12)
            assert result.true_point == pytest.approx(tuple(point), abs=0)


def test_a_miss_is_a_miss_and_ends_on_the_far_side():
    arm = build_arm(square_world(), "ideal")
    path = SensingPath((0.0, 100.0), (1.0, 0.0), 50.0)  # tangent: never meets the square
    assert arm.world.first_contact(path) is None
    result = arm.execute(path)
    assert result.observation.contact is None and not result.hit
    # the chord through the centre ends on the circle: the sensor stays there
    h = math.sqrt(100**2 - 50**2)
    chord = SensingPath((-50.0, h), (0.0, -1.0), 2 * h)
    arm = build_arm(square_world(), "ideal")
    result = arm.execute(chord)
    assert not result.hit
    assert arm.position == pytest.approx((-50.0, -h), abs=1e-9)


def test_travel_distance_and_time():
    arm = exact_arm(square_world(), speed=100.0, approach_speed=20.0)
    path = SensingPath((0.0, 100.0), (0.0, -1.0), 200.0)  # from 90 degrees, down
    result = arm.execute(path)
    arc = 100.0 * math.pi / 2
    approach = 80.0  # to the top face at y = 20
    assert result.distance == pytest.approx(arc + 2 * approach)
    assert result.time == pytest.approx(arc / 100.0 + 2 * approach / 20.0)
    assert arm.position == pytest.approx((0.0, 100.0))


def test_compliance_pushes_the_reading_past_the_surface():
    arm = exact_arm(square_world(), threshold=3.0, stiffness=0.5)
    path = SensingPath((100.0, 5.0), (-1.0, 0.0), 200.0)
    c = arm.execute(path).observation.contact
    # hand deflection F / k = 6 along the path: the reading lies inside the object
    assert c.point == pytest.approx((20.0 - 6.0, 5.0))
    assert c.normal == pytest.approx((1.0, 0.0))


def test_backlash_turns_the_normal_within_half_the_play():
    play = math.radians(8.0)
    arm = exact_arm(square_world(), seed=3, backlash=play)
    errors = []
    for y in np.linspace(-15, 15, 40):
        c = arm.execute(SensingPath((100.0, float(y)), (-1.0, 0.0), 200.0)).observation.contact
        errors.append(math.atan2(c.normal[1], c.normal[0]))
    errors = np.abs(errors)
    assert errors.max() <= play / 2 + 1e-12
    assert errors.max() > play / 4


def test_thermal_drift_grows_with_use_and_cool_down_resets_it():
    arm = exact_arm(square_world(), seed=1, thermal_position=5.0, heat_time=60.0, cooldown_at=0.9)
    path = SensingPath((100.0, 0.0), (-1.0, 0.0), 200.0)
    errors = []
    for _ in range(6):
        c = arm.execute(path).observation.contact
        errors.append(math.dist(c.point, (20.0, 0.0)))
    assert errors[0] < errors[-1] <= 5.0
    assert np.all(np.diff(errors) > 0)
    pause = arm.cool_down()
    assert pause > 0 and arm.heat == pytest.approx(arm.params.cooldown_to)
    assert np.hypot(*arm.thermal_error()[0]) == pytest.approx(0.1 * 5.0)


def test_hot_arm_pauses_to_cool_before_probing():
    arm = exact_arm(square_world(), thermal_position=5.0, cooldown_at=0.5, cooldown_to=0.1)
    arm.heat = 0.7
    result = arm.execute(SensingPath((100.0, 0.0), (-1.0, 0.0), 200.0))
    # the pause (cool_time ln(0.7 / 0.1)) is booked in the probe's time
    assert result.time > arm.params.cool_time * math.log(7.0)
    assert arm.heat < 0.5


def test_tip_slides_off_a_protruding_vertex_onto_one_face():
    world = square_world()
    start, _end, normals = world.posed_faces()
    faces = set()
    for seed in range(40):
        rng = np.random.default_rng(seed)
        # straight at the corner (20, 20) along the diagonal
        d = np.array([-1.0, -1.0]) / math.sqrt(2)
        point = np.array([20.0, 20.0 - 1e-3])
        face = int(np.argmax(normals @ np.array([1.0, 0.0])))  # the right face x = 20
        rest, new_face = slide_off_vertex(world, point, face, d, 1.0, rng)
        faces.add(new_face)
        # it rests on the face it names, within the zone of the corner
        n = normals[new_face]
        assert abs(n @ rest - n @ start[new_face]) < 1e-9
        assert math.dist(rest, (20.0, 20.0)) <= 1.0 + 1e-9
    assert len(faces) == 2
    # far from a vertex nothing moves
    rest, same = slide_off_vertex(world, np.array([20.0, 0.0]), face, d, 1.0, rng)
    assert same == face and rest == pytest.approx((20.0, 0.0))


def test_no_slide_into_a_concave_corner():
    ell = object_from_dict(
        {"name": "ell", "outline": [[0, 0], [40, 0], [40, 15], [15, 15], [15, 30], [0, 30]]}
    )
    world = World(ell, 0, Pose(0.0, 0.0, 0.0), WS)
    _, _, normals = world.posed_faces()
    top_of_foot = int(np.argmin(np.hypot(*(normals - [0.0, 1.0]).T)))
    point = np.array([15.2, 15.0])  # next to the concave corner (15, 15)
    d = np.array([0.0, -1.0])
    for seed in range(10):
        rest, face = slide_off_vertex(
            world, point, top_of_foot, d, 1.0, np.random.default_rng(seed)
        )
        assert face == top_of_foot and rest == pytest.approx(point)


def test_explicit_bounds_are_respected():
    preset = explicit_preset(2.0, math.radians(4.0))
    models = object_set("workshop")
    rng = np.random.default_rng(0)
    for trial in range(6):
        world = random_world(models, WORKSPACE, rng)
        arm = build_arm(world, preset, trial)
        for _ in range(10):
            r = arm.execute(world.hitting_path(rng))
            if not r.hit:
                continue
            c = r.observation.contact
            assert math.dist(c.point, r.true_point) <= 2.0 + 1e-9
            err = math.atan2(c.normal[1], c.normal[0]) - math.atan2(*r.true_normal[::-1])
            assert abs((err + math.pi) % (2 * math.pi) - math.pi) <= math.radians(4.0) + 1e-9


def test_same_seed_same_probe_results():
    models = object_set("thesis_like")
    world = random_world(models, WORKSPACE, np.random.default_rng(2))
    paths = [world.hitting_path(np.random.default_rng(k)) for k in range(5)]
    a, b = build_arm(world, "e2_arm", 9), build_arm(world, "e2_arm", 9)
    for p in paths:
        assert a.execute(p) == b.execute(p)
