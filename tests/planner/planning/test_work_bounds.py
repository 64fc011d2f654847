"""Candidate generation and casting keep to the work budget (DESIGN §4.12).

A plan is sized by work counted in advance, never by the clock: the aims examine
what the budget can pay for, the casting's first block is as many paths as it has
left (at least one), and a cell costs more on parts with many faces.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from planner.models.library import parse_objects
from planner.planning.analysis import analyse
from planner.planning.boundary_aims import boundary_aims
from planner.planning.budget import UNIT_US, Budget
from planner.planning.config import StrategyConfig
from planner.planning.intersection_aims import intersection_aims
from planner.planning.posed_set import pose_hypotheses
from planner.recognition.session import Session
from planner.types import Contact, Observation, SensingPath, SensorBounds, Workspace
from tests.conftest import object_set


def gon(n: int, r: float, c: tuple[float, float] = (0.0, 0.0)) -> list[list[float]]:
    t = np.linspace(0, 2 * np.pi, n, endpoint=False)
    return [[c[0] + r * math.cos(a), c[1] + r * math.sin(a)] for a in t]


@pytest.fixture(scope="module")
def holey():
    """A round part with holes touched once: many hypotheses of many faces."""
    holes = [gon(40, 4, (-30 + 20 * (i % 4), -30 + 20 * (i // 4)))[::-1] for i in range(16)]
    models = parse_objects(
        {"objects": [{"name": "holey", "outline": gon(160, 60), "holes": holes}]}
    )
    session = Session(models, SensorBounds(1.0, math.radians(3)), Workspace((0, 0), 200))
    session = session.observe(
        Observation(SensingPath((0, -200), (0, 1), 400), Contact((0, -60), (0, -1)))
    )
    return session, pose_hypotheses(session.hypotheses, session.models_by_name)


def test_boundary_aims_examine_only_what_the_budget_pays_for(holey):
    session, posed = holey
    free = boundary_aims(posed, session.bounds, 40, 6, np.random.default_rng(3))
    unlimited = Budget()
    same = boundary_aims(posed, session.bounds, 40, 6, np.random.default_rng(3), unlimited)
    np.testing.assert_array_equal(free[0], same[0])
    full = unlimited.spent["aim_pair"]
    assert full > 0
    small = Budget(work=full * UNIT_US["aim_pair"] / 10)
    few = boundary_aims(posed, session.bounds, 40, 6, np.random.default_rng(3), small)
    assert 0 < small.spent["aim_pair"] <= full / 10
    assert len(few[0]) <= len(free[0])


def test_intersection_aims_coarsen_then_give_up_with_the_budget(holey):
    _, posed = holey
    cells = posed.start.shape[0] * posed.start.shape[1]
    assert len(intersection_aims(posed, 8, 24, Budget(work=cells * UNIT_US["aim_face"] / 2))) == 0
    tight = Budget(work=cells * (UNIT_US["aim_face"] + 4 * UNIT_US["aim_cell"]))
    aims = intersection_aims(posed, 8, 24, tight)
    assert tight.spent["aim_cell"] <= 4 * cells and len(aims) >= 1
    assert len(intersection_aims(posed, 8, 24)) >= len(aims)


def _analysed(session: Session, budget: Budget):
    """The plan's analysis of `session` from (200, 0) at default settings."""
    return analyse(
        session.hypotheses,
        session.models,
        session.bounds,
        session.workspace,
        (200, 0),
        StrategyConfig(),
        0,
        observations=session.observations,
        budget=budget,
    )


def _per_path(posed) -> float:
    """What casting one path against `posed` costs (units)."""
    return len(posed) * max(1.0, posed.valid.sum() / len(posed) / 12) * UNIT_US["outcome_cell"]


@pytest.mark.parametrize("work", [20_000.0, 200_000.0, 600_000.0])
def test_a_plan_on_many_faces_spends_at_most_one_cast_path_beyond_its_budget(holey, work):
    session, posed = holey
    budget = Budget(work=work)
    found = _analysed(session, budget)
    assert len(found.candidates) >= 1
    per_path = _per_path(posed)
    # each stage is sized before it starts: past the budget only by the first path cast
    assert budget.units <= work + per_path
    # the count is the work: the same request spends the same units again
    again = Budget(work=work)
    _analysed(session, again)
    assert again.spent == budget.spent


@pytest.mark.parametrize("work", [40_000.0, 60_000.0, 120_000.0])
def test_no_block_of_paths_starts_past_what_the_budget_can_pay_for(work):
    # the first block is sized to the budget; a later one started while anything
    # was left, and a block of 78 paths overshot 60,000 units by 49,000
    session = Session(
        object_set("thesis_like"), SensorBounds(1.0, math.radians(3)), Workspace((0, 0), 200)
    )
    session = session.observe(
        Observation(SensingPath((0, -200), (0, 1), 400), Contact((0, -20), (0, -1)))
    )
    posed = pose_hypotheses(session.hypotheses, session.models_by_name)
    budget = Budget(work=work)
    found = _analysed(session, budget)
    per_path = _per_path(posed)
    assert found.truncated and len(found.candidates) > 16  # several blocks, cut
    assert budget.units <= work + per_path


def test_a_wall_clock_cap_without_a_work_budget_analyses_every_path():
    # `tactile simulate --budget-work 0` (no work limit) kept the default wall-clock
    # cap; the blocks after the first were sized by the infinite work left
    session = Session(
        object_set("thesis_like"), SensorBounds(1.0, math.radians(3)), Workspace((0, 0), 200)
    )
    session = session.observe(
        Observation(SensingPath((0, -200), (0, 1), 400), Contact((0, -20), (0, -1)))
    )
    budget = Budget(work=None, cap_ms=3_600_000.0)
    assert not budget.unlimited
    found = _analysed(session, budget)
    assert not found.truncated
    assert len(found.candidates) == len(_analysed(session, Budget()).candidates)
