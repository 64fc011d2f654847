"""A pose prior (a fixture, a camera): no hypothesis outside it, the truth kept."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from hardware_sim.presets import build_arm, explicit_preset
from hardware_sim.world import random_world
from planner.errors import InvalidObservationError
from planner.planning.config import StrategyConfig
from planner.planning.plan import plan_session
from planner.recognition.config import RecognitionConfig
from planner.recognition.session import Session
from planner.types import PosePrior, SensingPath
from tests.conftest import WORKSPACE, object_set

PRESET = explicit_preset(1.0, math.radians(3))


def _touched(models, prior, seed, touches=2):
    """A world drawn anywhere, a prior around its truth (the truth uniform inside),
    and `touches` random hitting touches; the session with and without the prior."""
    rng = np.random.default_rng(seed)
    world = random_world(models, WORKSPACE, rng)
    stable = world.model.stable_poses[world.pose_index]
    cx, cy = world.pose.apply(np.asarray(stable.centroid)[None])[0]
    r = prior * math.sqrt(rng.random())
    a = rng.uniform(-math.pi, math.pi)
    shift = rng.uniform(-0.17, 0.17)
    pose_prior = PosePrior(
        (cx + r * math.cos(a), cy + r * math.sin(a)),
        prior,
        (world.pose.theta + shift - 0.17, world.pose.theta + shift + 0.17),
    )
    arm = build_arm(world, PRESET, seed)
    plain = Session(models, PRESET.bounds, WORKSPACE)
    held = Session(models, PRESET.bounds, WORKSPACE, RecognitionConfig(prior=pose_prior))
    hits = 0
    while hits < touches:
        angle = rng.uniform(-math.pi, math.pi)
        origin = np.array([math.cos(angle), math.sin(angle)]) * WORKSPACE.radius
        aim = np.array([cx, cy]) + rng.normal(0, 10, 2)
        d = (aim - origin) / np.hypot(*(aim - origin))
        obs = arm.execute(SensingPath(tuple(origin), tuple(d), 2 * WORKSPACE.radius)).observation
        if obs.contact is None:
            continue
        hits += 1
        plain, held = plain.observe(obs), held.observe(obs)
    return world, pose_prior, plain, held


@settings(max_examples=40, deadline=None)
@given(st.integers(0, 2**16), st.sampled_from(["thesis_like", "workshop"]))
def test_the_truth_survives_a_prior_and_nothing_outside_it_is_kept(seed, name):
    models = object_set(name)
    world, prior, plain, held = _touched(models, 10.0, seed)
    assert held.hypotheses, "the prior dropped the truth"
    assert len(held.hypotheses) <= len(plain.hypotheses)
    truth = [h for h in held.hypotheses if h.object == world.model.name]
    assert truth, "the true object is gone"
    for h in held.hypotheses:
        stable = next(m for m in models if m.name == h.object).stable_poses[h.stable_pose]
        cx, cy = h.pose.apply(np.asarray(stable.centroid)[None])[0]
        reach = h.error_bound.translation + h.error_bound.rotation * float(
            np.hypot(*stable.centroid)
        )
        assert math.hypot(cx - prior.center[0], cy - prior.center[1]) <= prior.radius + reach + 1e-6


def test_the_first_probe_aims_at_the_prior_region():
    models = object_set("thesis_like")
    prior = PosePrior((60.0, -40.0), 10.0)
    session = Session(models, PRESET.bounds, WORKSPACE, RecognitionConfig(prior=prior))
    probe = plan_session(session, (WORKSPACE.radius, 0.0), StrategyConfig(name="pdm")).best
    o, d = np.array(probe.path.origin), np.array(probe.path.direction)
    # the line through the origin along d passes through the centre of the region
    v = np.array(prior.center) - o
    off = d[0] * v[1] - d[1] * v[0]
    assert abs(off) < 1e-9 and probe.path.length > np.hypot(*(np.array(prior.center) - o))


@pytest.mark.parametrize(
    "bad",
    [
        {"center": (0.0, 0.0)},
        {"center": (0.0, 0.0), "radius": -1.0},
        {"theta": (1.0, 0.0)},
        {"theta": (0.0, 7.0)},
    ],
)
def test_a_malformed_prior_is_refused(bad):
    with pytest.raises(InvalidObservationError):
        PosePrior(**bad)
