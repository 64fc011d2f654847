"""A plan on a finely drawn part works on one hypothesis per class, whose error
disk covers every member's: conservative, never over-confident."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from hardware_sim.world import random_world
from planner.planning import plan as plan_module
from planner.planning import representatives as reps
from planner.planning.config import StrategyConfig
from planner.planning.plan import plan_session
from planner.recognition.equivalence import PosedRings, pair_distances
from planner.recognition.session import Session
from planner.types import ErrorBound, Hypothesis, Pose, SensorBounds
from tests.conftest import WORKSPACE, object_set

BOUNDS = SensorBounds(1.0, math.radians(3))


def touched(seed: int, touches: int) -> Session:
    models = [m for m in object_set("curved") if m.name == "ellipse_60x35"]
    rng = np.random.default_rng(seed)
    world = random_world(models, WORKSPACE, rng)
    session = Session(models, BOUNDS, WORKSPACE)
    for _ in range(touches):
        session = session.observe(world.execute(world.hitting_path(rng), BOUNDS, rng)[0])
    return session


@pytest.mark.parametrize("seed", range(4))
def test_a_representative_covers_every_member_of_its_class(seed):
    session = touched(seed, 2)
    hyps = session.hypotheses
    out = reps.representatives(hyps, session.symmetry_tolerance, session.joined_classes, 10**9)
    assert len(out) == len({h.equivalence_class for h in hyps}) < len(hyps)
    assert math.isclose(sum(r.probability for r in out), 1.0)
    stable = session.models[0].stable_poses[0]
    for r in out:
        members = [h for h in hyps if h.equivalence_class == r.equivalence_class]
        poses = [r, *members]
        rings = PosedRings.of(
            stable,
            np.array([h.pose.theta for h in poses]),
            np.array([[h.pose.x, h.pose.y] for h in poses]),
        )
        gap = pair_distances(rings, np.zeros(len(members), int), rings, np.arange(1, len(poses)))
        # every member's error region lies inside the representative's
        for h, d in zip(members, gap, strict=True):
            assert d + h.error_bound.eps_t / 2 <= r.error_bound.eps_t / 2 + 1e-9
            assert r.error_bound.translation >= h.error_bound.translation


def test_few_posed_faces_plan_on_every_hypothesis(monkeypatch):
    session = touched(0, 2)
    hyps = session.hypotheses
    assert reps.representatives(hyps, 1.0, frozenset(), 1) == hyps
    monkeypatch.setattr(reps, "PLAN_FACES", 0)
    assert len(reps.representatives(hyps, 1.0, frozenset(), 1)) < len(hyps)


def test_a_plan_on_representatives_is_seeded_and_offers_paths(monkeypatch):
    monkeypatch.setattr(reps, "PLAN_FACES", 0)
    session = touched(1, 2)
    config = StrategyConfig(budget_ms=None)
    a = plan_session(session, (200.0, 0.0), config, 3)
    b = plan_session(session, (200.0, 0.0), config, 3)
    assert a.paths and [p.path for p in a.paths] == [p.path for p in b.paths]


@settings(max_examples=200, deadline=None)
@given(
    st.lists(
        st.tuples(st.floats(1e-6, 1.0), st.integers(0, 5), st.integers(1, 30)),
        min_size=1,
        max_size=60,
    ),
    st.integers(1, 400),
)
def test_a_weighted_sample_keeps_the_likely_hypotheses_and_two_classes(rows, limit):
    total = sum(p for p, _, _ in rows)
    hyps = [
        Hypothesis("a", 0, (k,), Pose(k, 0, 0), ErrorBound(1, 0.1, 2), p / total, c)
        for k, (p, c, _) in enumerate(rows)
    ]
    faces = [f for _, _, f in rows]
    out = reps.weighted_sample(hyps, faces, limit)
    if sum(faces) <= limit:
        assert out == hyps
        return
    # most probable first, as given; each drawn once
    index = [h.assignment[0] for h in out]
    assert index == sorted(set(index))
    draws = max(2, int(len(hyps) * limit / sum(faces)))
    for h in hyps:  # a hypothesis likelier than one draw is always drawn
        if h.probability >= 1 / draws:
            assert h.assignment[0] in index
    classes = {h.equivalence_class for h in hyps}
    assert len({h.equivalence_class for h in out}) >= min(2, len(classes))
    assert len(out) <= draws + 1


def test_a_plan_on_a_sample_claims_no_sure_touch(monkeypatch):
    monkeypatch.setattr(reps, "PLAN_FACES", 0)
    monkeypatch.setattr(reps, "SAMPLE_FACES", 200)
    session = touched(1, 1)
    planned = []
    real = plan_module.plan
    monkeypatch.setattr(
        plan_module, "plan", lambda hyps, *a, **k: planned.append(len(hyps)) or real(hyps, *a, **k)
    )
    result = plan_session(session, (200.0, 0.0), StrategyConfig(budget_ms=None), 3)
    faces = len(session.models[0].stable_poses[0].all_faces.start)
    assert planned[0] <= 200 // faces + 2 < len({h.equivalence_class for h in session.hypotheses})
    assert result.paths and result.truncated and "weighted sample" in result.note
    assert all(p.p_distinguishing == 0 and p.p_forecast is None for p in result.paths)
    assert all(p.family != "distinguishing" for p in result.paths)
