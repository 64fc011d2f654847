"""Probing heights (DESIGN §4.13): stable poses with slices at several heights.

A contact is assigned only to faces of its path's height; free space is checked
against the outline at that height; two hypotheses are one class only when their
outlines coincide at every height; the planner chooses the height with the path.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import trimesh
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from hardware_sim.world import World, random_world
from planner.errors import InvalidModelError, InvalidObservationError, ModelFileError
from planner.geometry import wrap_angle
from planner.models.heights import check_height, models_at, probing_heights
from planner.models.library import object_from_dict, object_to_dict
from planner.models.mesh import object_from_mesh
from planner.models.outlines import make_stable_pose, with_slices
from planner.planning.config import StrategyConfig
from planner.planning.plan import plan_session
from planner.recognition.session import Session
from planner.types import ObjectModel, SensingPath, SensorBounds, Workspace
from tests.conftest import WORKSPACE

BOUNDS = SensorBounds(1.0, math.radians(3.0))
TOP = 36.0


def _rect(x0: float, y0: float, x1: float, y1: float) -> list[list[float]]:
    return [[x0, y0], [x1, y0], [x1, y1], [x0, y1]]


def _layered(name: str, low, high, high_holes=()) -> ObjectModel:
    pose = with_slices(
        [(10.0, make_stable_pose(low)), (TOP, make_stable_pose(high, list(high_holes)))]
    )
    return ObjectModel(name, (pose,))


#: Solids whose outline at the default height is one 40 x 40 square (or a 60 x 30
#: bar) and which differ higher up: a chamfer, a step, a blind hole from the top.
LAYERED = [
    _layered("box", _rect(-20, -20, 20, 20), _rect(-20, -20, 20, 20)),
    _layered("chamfered", _rect(-20, -20, 20, 20), _rect(-16, -16, 16, 16)),
    _layered("stepped", _rect(-30, -15, 30, 15), _rect(0, -15, 30, 15)),
    _layered(
        "blind_hole",
        _rect(-20, -20, 20, 20),
        _rect(-20, -20, 20, 20),
        [_rect(-6, -6, 6, 6)[::-1]],
    ),
]


def test_slices_round_trip_through_the_object_format():
    data = object_to_dict(LAYERED[3])
    assert [s["height"] for s in data["stable_poses"][0]["slices"]] == [10.0, TOP]
    back = object_from_dict(data)
    assert back.same_geometry(LAYERED[3])
    assert not back.same_geometry(LAYERED[0])
    pose = back.stable_poses[0]
    assert pose.heights == (10.0, TOP) and pose.layer_index(TOP) == 1
    assert len(pose.all_faces) == 4 + 4 + 4 and pose.face_layer.tolist() == [0] * 4 + [1] * 8


@pytest.mark.parametrize(
    ("pose", "field"),
    [
        ({"slices": [{"height": 5, "outline": _rect(0, 0, 1, 1)}] * 2}, "slices[1].height"),
        ({"slices": [{"height": 5}]}, "slices[0]"),
        ({"slices": [], "probability": 1}, "slices"),
        (
            {"slices": [{"height": 5, "outline": _rect(0, 0, 1, 1)}], "outline": _rect(0, 0, 1, 1)},
            "stable_poses[0]",
        ),
    ],
)
def test_bad_slices_are_refused_naming_the_field(pose, field):
    with pytest.raises((InvalidModelError, ModelFileError)) as err:
        object_from_dict({"name": "x", "stable_poses": [pose]})
    assert field in (err.value.field or ""), err.value.field


def test_a_set_probes_at_the_heights_every_sliced_pose_has():
    flat = object_from_dict({"name": "flat", "outline": _rect(-5, -5, 5, 5)})
    assert probing_heights([flat]) == (None,)
    check_height([flat], 123.0)  # a prism is the same at every height
    assert probing_heights([*LAYERED, flat]) == (None, TOP)
    other = ObjectModel(
        "other",
        (
            with_slices(
                [
                    (10.0, make_stable_pose(_rect(-5, -5, 5, 5))),
                    (20.0, make_stable_pose(_rect(-5, -5, 5, 5))),
                ]
            ),
        ),
    )
    assert probing_heights([LAYERED[0], other]) == (None,)
    with pytest.raises(InvalidObservationError) as err:
        Session([LAYERED[0], other]).observe(_observation(SensingPath((0, -100), (0, 1), 200, TOP)))
    assert err.value.field == "path.height"


def _observation(path):
    from planner.types import Observation

    return Observation(path, None)


def _true(session, world, faces):
    return [
        h
        for h in session.hypotheses
        if h.object == world.model.name and list(h.assignment) == faces
    ]


def _inside_bound(h, world) -> bool:
    dt = math.hypot(h.pose.x - world.pose.x, h.pose.y - world.pose.y)
    dth = abs(float(wrap_angle(h.pose.theta - world.pose.theta)))
    return dt <= h.error_bound.translation + 1e-9 and dth <= h.error_bound.rotation + 1e-12


@settings(
    max_examples=300, derandomize=True, deadline=None, suppress_health_check=[HealthCheck.too_slow]
)
@given(seed=st.integers(0, 2**32 - 1), touches=st.integers(1, 4))
def test_the_true_interpretation_survives_contacts_at_every_height(seed, touches):
    """Soundness with slices: paths at random heights, contacts anywhere within the
    bounds (their edges half the time) on the TRUE outline at that height, misses
    where the path passes over; the truth survives with its pose inside its bound."""
    rng = np.random.default_rng(seed)
    world = random_world(LAYERED, WORKSPACE, rng)
    session = Session(LAYERED, BOUNDS, WORKSPACE)
    faces: list[int] = []
    for _ in range(touches):
        aimed = world.hitting_path(rng)
        height = [None, 10.0, TOP][int(rng.integers(3))]
        path = SensingPath(aimed.origin, aimed.direction, aimed.length, height)
        obs, face = world.execute(path, BOUNDS, rng, edge_share=0.5)
        if face is not None:
            faces.append(face)
        session = session.observe(obs)
        if faces:
            survivors = _true(session, world, faces)
            assert survivors, f"lost the truth after {len(session.observations)} paths"
            assert any(_inside_bound(h, world) for h in survivors)


def _boxes(heights: list[float]) -> list[ObjectModel]:
    """A 40 mm cube and the same cube with its top edges chamfered 8 mm, standing on
    their bottom faces, sliced at 10 mm and at `heights`."""
    box = trimesh.creation.box((40, 40, 40))
    corners = [(x, y, z) for x in (-20, 20) for y in (-20, 20) for z in (-20, 12)]
    top = [(x, y, 20) for x in (-12, 12) for y in (-12, 12)]
    chamfered = trimesh.convex.convex_hull(np.array(corners + top, dtype=float))
    return [
        object_from_mesh(mesh, 10.0, name, max_poses=1, heights=heights)
        for mesh, name in ((box, "box"), (chamfered, "chamfered"))
    ]


def _recognize(models, world, seed):
    rng = np.random.default_rng(seed)
    session = Session(models, BOUNDS, world.workspace)
    for _ in range(20):
        plan = plan_session(session, (world.workspace.radius, 0.0), StrategyConfig(), rng=seed)
        if plan.status == "localized" or not plan.paths:
            break
        session = session.observe(world.execute(plan.paths[0].path, BOUNDS, rng)[0])
    return session


def test_a_chamfer_higher_up_tells_two_boxes_apart_only_when_the_planner_may_choose_the_height():
    workspace = Workspace((0.0, 0.0), 100.0)
    sliced = _boxes([TOP])
    flat = models_at(sliced, None)  # the same solids and poses, the default slice only
    low = [m.stable_poses[0].shape for m in sliced]
    assert low[0].equals(low[1])  # identical at the default height
    assert (
        not sliced[0]
        .stable_poses[0]
        .layer(TOP)
        .shape.equals(sliced[1].stable_poses[0].layer(TOP).shape)
    )
    for seed in range(6):
        world = random_world(sliced, workspace, np.random.default_rng([1, seed]))
        session = _recognize(sliced, world, seed)
        assert session.status == "localized"
        assert {h.object for h in session.hypotheses} == {world.model.name}
        assert any(o.path.height == TOP for o in session.observations)
    # the same solids at the default height only: one class holds both
    world = World(
        flat[1], 0, random_world(flat, workspace, np.random.default_rng(3)).pose, workspace
    )
    session = _recognize(flat, world, 3)
    assert session.status == "localized"
    assert {h.object for h in session.hypotheses} == {"box", "chamfered"}
