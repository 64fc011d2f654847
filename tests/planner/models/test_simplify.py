"""Finely drawn outlines simplified within the sensor's bounds (planner.models.simplify).

Two laws: the worked outline strays from the given one by no more than the
deviation it reports (and that by no more than asked), and a session working
with it stays sound against the TRUE outline: contacts anywhere within the
bounds on the unsimplified outline never lose the true interpretation, whose
pose lies inside its bound.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import shapely
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from hardware_sim.world import path_towards, random_world
from planner.geometry import wrap_angle
from planner.models.library import object_from_dict
from planner.models.outlines import make_stable_pose
from planner.models.simplify import given_faces, simplify_models, simplify_pose, widened
from planner.recognition.session import Session
from planner.types import SensorBounds, Workspace

WORKSPACE = Workspace((0.0, 0.0), 200.0)


def _curve(n: int, radius: float, ripple: float, lobes: int, squash: float, flat: float):
    """A closed curve drawn with `n` vertices: an ellipse with lobes, cut by a flat."""
    t = np.linspace(0.0, 2 * math.pi, n, endpoint=False)
    r = radius * (1 + ripple * np.cos(lobes * t))
    pts = np.column_stack([r * np.cos(t), squash * r * np.sin(t)])
    pts[:, 0] = np.minimum(pts[:, 0], flat * radius)  # a flat (a D shape) when flat < 1
    keep = np.ones(n, bool)
    keep[1:] = np.any(np.abs(np.diff(pts, axis=0)) > 1e-9, axis=1)
    return pts[keep]


curves = st.builds(
    _curve,
    n=st.integers(60, 3000),
    radius=st.floats(10.0, 60.0),
    ripple=st.floats(0.0, 0.15),
    lobes=st.integers(2, 5),
    squash=st.floats(0.4, 1.0),
    flat=st.floats(0.7, 1.2),
)


@settings(max_examples=80, derandomize=True, deadline=None)
@given(
    ring=curves,
    position=st.floats(0.0, 0.5),
    normal=st.floats(0.0, 0.1),
    hole=st.booleans(),
)
def test_worked_outline_strays_no_more_than_reported(ring, position, normal, hole) -> None:
    holes = [_curve(400, 3.0, 0.0, 2, 1.0, 2.0)[::-1]] if hole else []
    pose = make_stable_pose(ring, holes)
    worked, dev = simplify_pose(pose, position, normal)
    assert dev.position <= position and dev.normal <= normal
    assert dev.kept == sum(len(r) for r in [worked.outline, *worked.holes])
    for a, b in zip([pose.outline, *pose.holes], [worked.outline, *worked.holes], strict=True):
        # a subset of the given vertices, in their order
        assert {tuple(v) for v in b.tolist()} <= {tuple(v) for v in a.tolist()}
        gap = shapely.hausdorff_distance(shapely.LinearRing(a), shapely.LinearRing(b), densify=0.05)
        assert gap <= dev.position + 1e-7
    # every given face turned within dev.normal of the face standing for it
    chord = given_faces(pose, worked)
    turn = wrap_angle(pose.faces.angle - worked.faces.angle[chord])
    assert np.all(np.abs(turn) <= dev.normal + 1e-12)


def test_exactly_drawn_parts_are_kept_as_given() -> None:
    square = object_from_dict({"name": "sq", "outline": [[0, 0], [40, 0], [40, 40], [0, 40]]})
    (kept,), dev = simplify_models([square], SensorBounds(1.0, 0.05))
    assert kept is square and dev.position == dev.normal == 0.0
    assert widened(SensorBounds(1.0, 0.05), dev) == SensorBounds(1.0, 0.05)


def test_a_finely_drawn_disc_costs_what_its_curvature_needs() -> None:
    disc = make_stable_pose(_curve(5000, 30.0, 0.0, 2, 1.0, 2.0))
    worked, dev = simplify_pose(disc, 0.25, 0.026)
    # a full turn in chords of at most 2 x 0.026 rad: about pi / 0.026 of them
    assert len(worked.outline) <= 1.1 * math.pi / 0.026
    assert 0 < dev.normal <= 0.026


CURVED = [
    object_from_dict({"name": "cam", "outline": _curve(2400, 30.0, 0.05, 3, 0.7, 0.85).tolist()}),
    object_from_dict(
        {
            "name": "d_ring",
            "outline": _curve(3000, 35.0, 0.0, 2, 1.0, 0.8).tolist(),
            "holes": [_curve(600, 8.0, 0.0, 2, 1.0, 2.0)[::-1].tolist()],
        }
    ),
]
BOUNDS = {"noisy": SensorBounds(1.0, math.radians(3.0)), "coarse": SensorBounds(2.0, 0.1)}
CASES = {"noisy": 200, "coarse": 100}


@pytest.mark.parametrize("mode", list(BOUNDS))
def test_sound_against_the_true_outline(mode: str) -> None:
    bounds = BOUNDS[mode]
    worked = {m.name: m for m in simplify_models(CURVED, bounds)[0]}

    @settings(
        max_examples=CASES[mode],
        derandomize=True,
        deadline=None,
        suppress_health_check=[HealthCheck.too_slow],
    )
    @given(seed=st.integers(0, 2**32 - 1), touches=st.integers(1, 2))
    def case(seed: int, touches: int) -> None:
        rng = np.random.default_rng(seed)
        world = random_world(CURVED, WORKSPACE, rng)  # contacts on the outline as given
        session = Session(CURVED, bounds, WORKSPACE)
        given = world.model.stable_poses[world.pose_index]
        chord = given_faces(given, worked[world.model.name].stable_poses[world.pose_index])
        faces: list[int] = []

        def truth_survives() -> bool:
            return any(
                h.object == world.model.name
                and h.stable_pose == world.pose_index
                and list(h.assignment) == faces
                and math.hypot(h.pose.x - world.pose.x, h.pose.y - world.pose.y)
                <= h.error_bound.translation + 1e-9
                and abs(float(wrap_angle(h.pose.theta - world.pose.theta)))
                <= h.error_bound.rotation + 1e-12
                for h in session.hypotheses
            )

        for _ in range(touches):
            obs, face = world.execute(world.hitting_path(rng), bounds, rng, edge_share=0.5)
            assert face is not None
            faces.append(int(chord[face]))
            session = session.observe(obs)
            assert truth_survives(), f"lost the truth after {len(faces)} touches"
        aim = np.asarray([world.pose.x, world.pose.y]) + rng.normal(0, 60, 2)
        obs, face = world.execute(
            path_towards(WORKSPACE, rng.uniform(-math.pi, math.pi), aim), bounds, rng, 0.5
        )
        if face is not None:
            faces.append(int(chord[face]))
        session = session.observe(obs)
        assert truth_survives(), "a last path lost the truth"

    case()
