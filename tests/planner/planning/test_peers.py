"""The published peers (EC2, information gain, POMCP) against brute force and Fig. 7.1."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
from hypothesis import given, settings

from planner.planning.bitsets import SurvivorTable
from planner.planning.budget import Budget
from planner.planning.candidate_generation import CandidateConfig
from planner.planning.config import StrategyConfig
from planner.planning.peers import edge_cut, entropy, information_gain
from planner.planning.plan import plan
from planner.planning.pomcp import search
from planner.planning.strategies import rank_candidates
from tests.planner.planning.test_scoring import fig71
from tests.planner.planning.test_strategies import (
    FIG71,
    MODELS,
    PATH_A,
    PATH_B,
    SENSOR,
    WORKSPACE,
    fig71_dilemma,
    tables,
)


def brute_edge_cut(table: SurvivorTable, path: int) -> float:
    """Enumerate the edges (every pair of classes) and, per truth, those it cuts."""
    m, w = table.matrix()[path], table.weight
    total = 0.0
    for truth in range(table.n_classes):
        for a, b in itertools.combinations(range(table.n_classes), 2):
            if not (m[truth, a] and m[truth, b]):  # an end ruled out: the edge is cut
                total += w[truth] * w[a] * w[b]
    return total


def brute_information_gain(table: SurvivorTable, path: int) -> float:
    m, w = table.matrix()[path], table.weight
    h = -sum(p * math.log(p) for p in w if p > 0)
    after = 0.0
    for truth in range(table.n_classes):
        alive = [w[j] for j in range(table.n_classes) if m[truth, j]]
        total = sum(alive)
        after += w[truth] * -sum(p / total * math.log(p / total) for p in alive if p > 0)
    return h - after


@settings(max_examples=200, deadline=None)
@given(tables())
def test_edge_cut_equals_brute_force_and_ec2_takes_its_maximum(drawn):
    table, _ = drawn
    brute = np.array([brute_edge_cut(table, c) for c in range(table.n_paths)])
    np.testing.assert_allclose(edge_cut(table), brute, atol=1e-12)
    ranking = rank_candidates(table, StrategyConfig(name="ec2", budget_work=None, budget_ms=None))
    if len(ranking.order):
        assert brute[ranking.order[0]] == pytest.approx(brute.max(), abs=1e-12)


@settings(max_examples=200, deadline=None)
@given(tables())
def test_information_gain_equals_brute_force_and_infogain_takes_its_maximum(drawn):
    table, _ = drawn
    brute = np.array([brute_information_gain(table, c) for c in range(table.n_paths)])
    np.testing.assert_allclose(information_gain(table), brute, atol=1e-9)
    ranking = rank_candidates(
        table, StrategyConfig(name="infogain", budget_work=None, budget_ms=None)
    )
    if len(ranking.order):
        assert brute[ranking.order[0]] == pytest.approx(brute.max(), abs=1e-9)


def test_entropy_of_uniform_and_of_certain():
    assert entropy(np.full(4, 2.0)) == pytest.approx(math.log(4))
    assert entropy(np.array([0.0, 3.0])) == 0.0


def test_the_greedy_peers_part_on_fig71():
    # a distinguishes half and leaves three; b leaves a pair whatever happens.
    # EC2 prefers b (more edge weight cut), information gain a: E_a = 1.5 < E_b = 2
    table = fig71("one")
    config = {"budget_work": None, "budget_ms": None}
    assert rank_candidates(table, StrategyConfig(name="ec2", **config)).order[0] == 1
    assert rank_candidates(table, StrategyConfig(name="infogain", **config)).order[0] == 0
    assert rank_candidates(table, StrategyConfig(name="lookahead", **config)).order[0] == 0


@pytest.mark.parametrize("seed", range(5))
def test_pomcp_finds_the_optimal_first_path_of_the_dilemma(seed):
    # b (E = 2) beats a (E = 2.25), which a greedy P(DM) rule takes
    result = search(fig71_dilemma(), np.random.default_rng(seed), simulations=1000)
    assert result.best == 1
    assert result.value[1] == pytest.approx(2.0)
    assert result.simulations == 1000 and not result.truncated


@pytest.mark.parametrize("seed", range(3))
def test_pomcp_plans_fig71_from_the_geometry(seed):
    config = StrategyConfig(
        name="pomcp",
        simulations=1000,
        candidates=CandidateConfig(count=0, feature_paths=0),
        budget_ms=None,
        budget_work=None,
    )
    result = plan(
        FIG71,
        MODELS,
        SENSOR,
        WORKSPACE,
        (100.0, 0.0),
        config,
        rng=seed,
        extra_paths=[PATH_A, PATH_B],
    )
    first = result.paths[0]
    assert (first.origin, first.direction) == (PATH_A.origin, PATH_A.direction)
    assert first.expected_remaining == pytest.approx(1.5)


def test_pomcp_is_a_function_of_the_seed_and_stops_at_the_work_budget():
    table = fig71("two")
    runs = [search(table, np.random.default_rng(7), simulations=300) for _ in range(2)]
    np.testing.assert_array_equal(runs[0].visits, runs[1].visits)
    assert runs[0].best == runs[1].best
    budget = Budget(work=200.0)
    cut = search(table, np.random.default_rng(7), simulations=10_000, budget=budget)
    assert cut.truncated and cut.simulations < 10_000 and budget.stopped_by == "work"


def test_pomcp_on_a_settled_table_has_nothing_to_do():
    same = SurvivorTable.from_matrix(np.ones((2, 3, 3), dtype=bool), np.full(3, 1 / 3))
    result = search(same, np.random.default_rng(0))
    assert result.best == -1 and result.simulations == 0
    ranking = rank_candidates(same, StrategyConfig(name="pomcp"))
    assert not len(ranking.order) and "no informative path" in ranking.note
