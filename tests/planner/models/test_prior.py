"""The prior over poses the planner assumes, and the simulator draws from (DESIGN §4.7)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import stats

from hardware_sim.world import random_world
from planner.errors import PlannerError
from planner.models.outlines import make_stable_pose
from planner.models.prior import draw_poses, draw_stable_poses
from planner.types import Pose, Workspace
from tests.conftest import SET_NAMES, WORKSPACE, object_set


@pytest.mark.parametrize("name", SET_NAMES)
def test_drawn_outlines_lie_inside_the_safe_circle(name):
    models = object_set(name)
    rng = np.random.default_rng(3)
    for i, j in draw_stable_poses(models, 20, rng):
        stable = models[i].stable_poses[j]
        theta, t = draw_poses(stable, WORKSPACE, 50, rng)
        for th, tt in zip(theta, t, strict=True):
            posed = Pose(float(tt[0]), float(tt[1]), float(th)).apply(stable.outline)
            assert np.hypot(*posed.T).max() <= WORKSPACE.radius


def test_positions_are_uniform_among_those_that_fit():
    # a 24-gon of radius 10 about its origin fits wherever |t| <= R - 10 (in every
    # orientation): |t|^2 is then uniform on [0, (R - 10)^2]
    ring = [[10 * math.cos(a), 10 * math.sin(a)] for a in np.arange(24) * 2 * math.pi / 24]
    stable = make_stable_pose(ring)
    ws = Workspace((5.0, -3.0), 60.0)
    theta, t = draw_poses(stable, ws, 4000, np.random.default_rng(0))
    r2 = np.sum((t - np.array(ws.center)) ** 2, axis=1) / (ws.radius - 10) ** 2
    assert stats.kstest(r2, "uniform").pvalue > 0.01
    assert stats.kstest((theta + math.pi) / (2 * math.pi), "uniform").pvalue > 0.01


def test_stable_poses_follow_their_probabilities():
    models = object_set("table_poses")
    draws = draw_stable_poses(models, 6000, np.random.default_rng(1))
    for i, model in enumerate(models):
        mine = [j for m, j in draws if m == i]
        assert len(mine) / len(draws) == pytest.approx(1 / len(models), abs=0.03)
        probs = np.array([p.probability for p in model.stable_poses])
        seen = np.bincount(mine, minlength=len(probs)) / len(mine)
        np.testing.assert_allclose(seen, probs / probs.sum(), atol=0.04)


def test_an_object_too_large_for_the_circle_is_refused():
    big = make_stable_pose([[-50, -50], [50, -50], [50, 50], [-50, 50]])
    with pytest.raises(PlannerError) as err:
        draw_poses(big, Workspace((0, 0), 30), 1, np.random.default_rng(0))
    assert err.value.field.startswith("workspace")


def test_the_simulator_draws_its_worlds_from_the_prior():
    models = object_set("thesis_like")
    a = random_world(models, WORKSPACE, np.random.default_rng(5))
    b = random_world(models, WORKSPACE, np.random.default_rng(5))
    assert a == b
    centred = random_world(models, WORKSPACE, np.random.default_rng(5), "centred")
    centroid = centred.pose.apply([centred.stable.centroid])[0]
    np.testing.assert_allclose(centroid, WORKSPACE.center, atol=1e-9)
    with pytest.raises(ValueError, match="placement"):
        random_world(models, WORKSPACE, np.random.default_rng(5), "nowhere")
