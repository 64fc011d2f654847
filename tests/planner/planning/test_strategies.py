"""Strategies and the planner's entry point (DESIGN §4.12, §6)."""

from __future__ import annotations

import dataclasses
import math
import time
from unittest import mock

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from planner.errors import PlannerError
from planner.models.outlines import make_stable_pose
from planner.planning import budget as budget_module
from planner.planning.analysis import analyse
from planner.planning.bitsets import SurvivorTable
from planner.planning.candidate_generation import CandidateConfig
from planner.planning.config import STRATEGIES, StrategyConfig
from planner.planning.plan import plan
from planner.planning.scoring import UNINFORMATIVE
from planner.planning.search import expected_remaining
from planner.planning.strategies import rank_candidates
from planner.types import (
    Contact,
    ErrorBound,
    Hypothesis,
    ObjectModel,
    Observation,
    Pose,
    SensingPath,
    SensorBounds,
    Workspace,
)

SQUARE = ObjectModel("square", (make_stable_pose([[-20, -20], [20, -20], [20, 20], [-20, 20]]),))
ELL = ObjectModel(
    "ell", (make_stable_pose([[0, 0], [40, 0], [40, 12], [12, 12], [12, 30], [0, 30]]),)
)
TRIANGLE = ObjectModel("triangle", (make_stable_pose([[30, 0], [-15, 26], [-15, -26]]),))
MODELS = {m.name: m for m in (SQUARE, ELL, TRIANGLE)}
WORKSPACE = Workspace((0.0, 0.0), 100.0)
SENSOR = SensorBounds(0.5, 0.02)
FAST = {"candidates": CandidateConfig(count=64), "budget_ms": None, "budget_work": None}


def hyp(name, x, y, theta=0.0, cls=0, p=1.0, eps_t=1.0):
    return Hypothesis(name, 0, (), Pose(x, y, theta), ErrorBound(0.2, 0.0, eps_t), p, cls)


# Fig. 7.1 as geometry: six squares. Path a comes down x = 0 and meets the tops of
# 0, 1, 2 at distinct heights and those of 3, 4, 5 on one line (P(DM) = 0.5, else 3
# left); path b comes in along y = 0 and meets the right faces in pairs (0, 3), (1, 4),
# (2, 5) (surely 2 left). Each path resolves what the other leaves.
FIG71 = [
    hyp("square", x, y, cls=i, p=1 / 6)
    for i, (x, y) in enumerate([(0, 12), (5, 6), (-5, -6), (0, 0), (5, 0), (-5, 0)])
]
PATH_A = SensingPath((0.0, 100.0), (0.0, -1.0), 100.0)
PATH_B = SensingPath((100.0, 0.0), (-1.0, 0.0), 100.0)


@pytest.mark.parametrize("name", ["pdm", "lookahead", "optimal"])
def test_fig71_geometric(name):
    config = StrategyConfig(
        name=name,
        candidates=CandidateConfig(count=0, feature_paths=0),
        budget_ms=None,
        budget_work=None,
    )
    result = plan(
        FIG71, MODELS, SENSOR, WORKSPACE, (100.0, 0.0), config, extra_paths=[PATH_A, PATH_B]
    )
    assert result.status == "ambiguous" and result.candidates == 2 and not result.truncated
    a, b = result.paths
    assert (a.origin, a.direction) == (PATH_A.origin, PATH_A.direction)
    assert a.p_distinguishing == pytest.approx(0.5) and b.p_distinguishing == 0.0
    assert a.family == b.family == "informative"
    # E_a = 1 + 0.5 * 1 (b then splits the three); E_b = 1 + 1 (a then splits each pair)
    assert a.expected_remaining == pytest.approx(1.5)
    assert b.expected_remaining == pytest.approx(2.0)


def fig71_dilemma() -> SurvivorTable:
    """Four classes: a distinguishes 0 and leaves {1, 2, 3} (5/3 more touches),
    b leaves a pair either way; the third path only splits 2 from 3."""
    a = np.eye(4, dtype=bool)
    a[1:, 1:] = True
    b = np.eye(4, dtype=bool)
    b[:2, :2] = b[2:, 2:] = True
    follow = np.ones((4, 4), dtype=bool)
    follow[2, 3] = follow[3, 2] = False
    return SurvivorTable.from_matrix(np.stack([a, b, follow]), np.full(4, 0.25))


@pytest.mark.parametrize(
    ("name", "best"), [("pdm", 0), ("pruning", 1), ("lookahead", 1), ("optimal", 1)]
)
def test_lookahead_weighs_what_is_left(name, best):
    ranking = rank_candidates(
        fig71_dilemma(), StrategyConfig(name=name, budget_ms=None, budget_work=None)
    )
    assert ranking.order[0] == best
    # E_a = 1 + 3/4 (1 + 2/3) = 2.25, E_b = 2
    np.testing.assert_allclose(ranking.expected_remaining[[0, 1]], [2.25, 2.0])


@st.composite
def tables(draw):
    k = draw(st.integers(2, 6))
    c = draw(st.integers(1, 8))
    bits = draw(st.lists(st.booleans(), min_size=c * k * k, max_size=c * k * k))
    conf = np.array(bits).reshape(c, k, k)
    if draw(st.booleans()):  # sometimes mostly confusable: uninformative paths abound
        conf |= np.array(draw(st.lists(st.booleans(), min_size=c, max_size=c)))[:, None, None]
    conf = conf | conf.transpose(0, 2, 1)
    weight = np.array(draw(st.lists(st.floats(0.01, 1.0), min_size=k, max_size=k)))
    source = np.array(
        draw(st.lists(st.sampled_from(["", "random", "window", "probe"]), min_size=c, max_size=c))
    )
    return SurvivorTable.from_matrix(conf, weight), source


@settings(max_examples=150, deadline=None)
@given(tables(), st.sampled_from(STRATEGIES), st.integers(0, 2**16))
def test_never_uninformative_while_informative_exists(table_source, name, seed):
    table, source = table_source
    config = StrategyConfig(name=name, budget_ms=None, budget_work=None, optimal_max_classes=4)
    ranking = rank_candidates(table, config, source=source, rng=seed)
    conf = table.matrix()
    informative = ~conf.all(axis=-1).all(axis=-1)  # some truth learns something
    assert not np.isin(ranking.order, np.flatnonzero(~informative)).any()
    assert (len(ranking.order) > 0) == informative.any()


@st.composite
def scenes(draw):
    n = draw(st.integers(2, 5))
    names = st.sampled_from(sorted(MODELS))
    coord = st.floats(-8, 8)
    return [
        hyp(draw(names), draw(coord), draw(coord), draw(st.floats(-math.pi, math.pi)), i, 1 / n)
        for i in range(n)
    ]


@settings(max_examples=12, deadline=None)
@given(scenes(), st.sampled_from(STRATEGIES), st.integers(0, 2**16))
def test_plans_never_hold_uninformative_paths(hyps, name, seed):
    config = StrategyConfig(name=name, grid_size=30, **FAST)
    found = analyse(hyps, MODELS, SENSOR, WORKSPACE, (100.0, 0.0), config, seed)
    result = plan(hyps, MODELS, SENSOR, WORKSPACE, (100.0, 0.0), config, seed)
    assert result.candidates == len(found.candidates)
    assert all(p.family != "uninformative" for p in result.paths)
    assert bool(result.paths) == bool((found.info.family != UNINFORMATIVE).any())
    for p in result.paths:
        assert math.hypot(*p.origin) == pytest.approx(WORKSPACE.radius)
        assert p.expected_remaining is not None and p.expected_remaining >= 1.0


def test_opening_probe_before_any_contact():
    result = plan([], MODELS, SENSOR, WORKSPACE, (150.0, 0.0), StrategyConfig(name="lookahead"))
    assert result.status == "awaiting_contact"
    (probe,) = result.paths
    assert probe.origin == pytest.approx((100.0, 0.0)) and probe.direction == pytest.approx(
        (-1.0, 0.0)
    )
    assert probe.length == pytest.approx(200.0) and probe.aim == (0.0, 0.0)
    # after a miss the next opening turns about the centre
    missed = [Observation(probe.path)]
    again = plan([], MODELS, SENSOR, WORKSPACE, (150.0, 0.0), observations=missed).paths[0]
    assert math.hypot(*again.origin) == pytest.approx(100.0) and again.origin != probe.origin


def test_random_opening_aims_at_the_centre():
    config = StrategyConfig(name="random")
    first = plan([], MODELS, SENSOR, WORKSPACE, (100.0, 0.0), config, rng=1).paths[0]
    other = plan([], MODELS, SENSOR, WORKSPACE, (100.0, 0.0), config, rng=2).paths[0]
    assert first.origin != other.origin
    for p in (first, other):
        end = np.add(p.origin, np.multiply(p.direction, p.length / 2))
        np.testing.assert_allclose(end, (0.0, 0.0), atol=1e-9)


def test_random_aims_at_the_union_centre():
    hyps = [hyp("square", 10, 0, cls=0, p=0.5), hyp("square", 10, 6, cls=1, p=0.5)]
    result = plan(
        hyps, MODELS, SENSOR, WORKSPACE, (100.0, 0.0), StrategyConfig(name="random", **FAST)
    )
    assert result.paths and result.paths[0].source == "random"
    np.testing.assert_allclose(result.paths[0].aim, (10.0, 3.0), atol=1e-6)


def test_status_localized_and_inconsistent():
    one = [hyp("square", 0, 0, cls=3, p=0.5), hyp("square", 0, 0, math.pi / 2, cls=3, p=0.5)]
    assert plan(one, MODELS, SENSOR, WORKSPACE, (100.0, 0.0)).status == "localized"
    touched = [Observation(PATH_A, Contact((0.0, 20.0), (0.0, 1.0)))]
    gone = plan([], MODELS, SENSOR, WORKSPACE, (100.0, 0.0), observations=touched)
    assert gone.status == "inconsistent" and not gone.paths


def test_thesis_second_probe_is_orthogonal_to_the_first_normal():
    # one contact on a top face (normal +y): interpretations slide along x
    hyps = [hyp("square", x, 0, cls=i, p=1 / 5) for i, x in enumerate([-8, -4, 0, 4, 8])]
    touched = [Observation(PATH_A, Contact((0.0, 20.0), (0.0, 1.0)))]
    config = StrategyConfig(name="thesis", **FAST)
    result = plan(hyps, MODELS, SENSOR, WORKSPACE, (0.0, 100.0), config, observations=touched)
    probe = result.paths[0]
    assert probe.source == "probe"
    assert abs(probe.direction[1]) == pytest.approx(0.0, abs=1e-9)
    assert probe.aim[1] < 20.0  # it crosses the body below the contact


def test_thesis_windows_after_two_contacts():
    hyps = [hyp("square", 0, 0, cls=0, p=0.5), hyp("ell", -20, -20, cls=1, p=0.5)]
    touched = [
        Observation(PATH_A, Contact((0.0, 20.0), (0.0, 1.0))),
        Observation(PATH_B, Contact((20.0, 0.0), (1.0, 0.0))),
    ]
    config = StrategyConfig(name="thesis", grid_size=40, **FAST)
    result = plan(hyps, MODELS, SENSOR, WORKSPACE, (100.0, 0.0), config, observations=touched)
    assert result.paths
    assert result.paths[0].source == "window"  # in CHOOSE order, informative ones only


def test_thesis_choice_picks_within_the_lowest_level_of_windows():
    # four classes; every path tells one class from the rest, so all are informative
    conf = np.ones((5, 4, 4), dtype=bool)
    for c in range(4):
        conf[c, c, :] = conf[c, :, c] = False
        conf[c, c, c] = True
    conf[4] = conf[0]
    table = SurvivorTable.from_matrix(conf, np.full(4, 0.25))
    source = np.array(["window"] * 4 + ["boundary"])
    tier = np.array([0, 0, 0, 1, 0])  # windows in CHOOSE order: three at the lowest level
    chosen = rank_candidates(table, StrategyConfig(name="thesis"), source=source, tier=tier, rng=0)
    np.testing.assert_array_equal(chosen.order, [0, 1, 2, 3])
    firsts = set()
    for seed in range(20):
        config = StrategyConfig(name="thesis", thesis_choice="random")
        order = rank_candidates(table, config, source=source, tier=tier, rng=seed).order
        assert sorted(order[:3]) == [0, 1, 2] and order[3] == 3
        firsts.add(int(order[0]))
    assert firsts == {0, 1, 2}
    with pytest.raises(PlannerError, match="thesis_choice"):
        StrategyConfig(name="thesis", thesis_choice="nearest")


def test_optimal_says_when_it_plays_lookahead():
    hyps = [hyp("triangle", 3 * i, 0, 0.2 * i, cls=i, p=1 / 5) for i in range(5)]
    config = StrategyConfig(name="optimal", optimal_max_classes=3, **FAST)
    result = plan(hyps, MODELS, SENSOR, WORKSPACE, (100.0, 0.0), config)
    assert "optimal played lookahead" in result.note
    exact = plan(
        hyps, MODELS, SENSOR, WORKSPACE, (100.0, 0.0), StrategyConfig(name="optimal", **FAST)
    )
    assert exact.note is None and exact.paths[0].expected_remaining >= 1.0


@pytest.mark.parametrize(
    ("limits", "stopped_by"),
    [({"budget_ms": 1e-3, "budget_work": None}, "time"), ({"budget_work": 1.0}, "work")],
)
def test_budget_stops_with_the_best_so_far(limits, stopped_by):
    # neighbours within the tolerance of each other: no path settles everything at once,
    # so the search must look deeper and the (tiny) budget stops it
    hyps = [hyp("square", 1.5 * i, 0.8 * i, cls=i, p=1 / 8) for i in range(8)]
    config = StrategyConfig(
        name="lookahead", depth=3, candidates=CandidateConfig(count=64), **limits
    )
    result = plan(hyps, MODELS, SENSOR, WORKSPACE, (100.0, 0.0), config)
    assert result.truncated and "budget" in result.note
    assert result.stopped_by == stopped_by and result.work > 0
    assert result.paths and all(p.family != "uninformative" for p in result.paths)


def test_a_search_the_budget_stopped_ranks_by_information_gain():
    """The budget stops the depth-3 search part way: the paths are ranked as
    ``infogain`` ranks them (a stopped search would prefer the paths it valued
    first); with the budget to finish, the search's own ranking."""
    hyps = [hyp("square", 1.5 * i, 0.8 * i, cls=i, p=1 / 8) for i in range(8)]
    config = StrategyConfig(
        name="lookahead", depth=3, candidates=CandidateConfig(count=64), budget_work=20_000.0
    )
    stopped = plan(hyps, MODELS, SENSOR, WORKSPACE, (100.0, 0.0), config)
    assert stopped.truncated and "ranked by information gain" in stopped.note
    peer = plan(
        hyps, MODELS, SENSOR, WORKSPACE, (100.0, 0.0), dataclasses.replace(config, name="infogain")
    )
    assert [p.path for p in stopped.paths] == [p.path for p in peer.paths]
    whole = plan(
        hyps, MODELS, SENSOR, WORKSPACE, (100.0, 0.0), dataclasses.replace(config, budget_work=None)
    )
    assert not whole.truncated and "information gain" not in (whole.note or "")


def test_a_work_budget_gives_the_same_plan_however_slow_the_machine():
    """The same plan, also when the clock runs 50 times slower (a loaded machine)."""
    hyps = [hyp("square", 1.5 * i, 0.8 * i, cls=i, p=1 / 8) for i in range(8)]
    config = StrategyConfig(
        name="lookahead",
        depth=3,
        candidates=CandidateConfig(count=64),
        budget_work=1_000,
        budget_ms=None,
    )
    first = plan(hyps, MODELS, SENSOR, WORKSPACE, (100.0, 0.0), config, 3)
    real = time.perf_counter
    start = real()
    with mock.patch.object(
        budget_module.time, "perf_counter", lambda: start + 50 * (real() - start)
    ):
        slow = plan(hyps, MODELS, SENSOR, WORKSPACE, (100.0, 0.0), config, 3)
    assert first.stopped_by == slow.stopped_by == "work"
    assert [p.path for p in first.paths] == [p.path for p in slow.paths]
    assert [p.expected_remaining for p in first.paths] == [p.expected_remaining for p in slow.paths]
    assert first.work == slow.work


def test_motion_weight_prefers_near_origins():
    hyps = [hyp("ell", 2 * i, -i, 0.1 * i, cls=i, p=1 / 6) for i in range(6)]
    near = StrategyConfig(name="pdm", motion_weight=10.0, **FAST)
    free = StrategyConfig(name="pdm", motion_weight=0.0, **FAST)
    heavy = plan(hyps, MODELS, SENSOR, WORKSPACE, (100.0, 0.0), near).paths[0]
    light = plan(hyps, MODELS, SENSOR, WORKSPACE, (100.0, 0.0), free).paths[0]
    assert heavy.motion_cost <= light.motion_cost
    assert light.p_distinguishing >= heavy.p_distinguishing


def test_plans_are_deterministic_for_a_seed():
    hyps = [hyp("triangle", 3 * i, 0, 0.3 * i, cls=i, p=1 / 4) for i in range(4)]
    config = StrategyConfig(name="random", **FAST)
    one = plan(hyps, MODELS, SENSOR, WORKSPACE, (100.0, 0.0), config, rng=7)
    two = plan(hyps, MODELS, SENSOR, WORKSPACE, (100.0, 0.0), config, rng=7)
    assert [p.origin for p in one.paths] == [p.origin for p in two.paths]


def test_config_from_the_session_json():
    config = StrategyConfig.from_dict({"name": "lookahead", "depth": 3, "budget_ms": 250})
    assert (config.name, config.depth, config.budget_ms) == ("lookahead", 3, 250)
    with pytest.raises(PlannerError, match=r"strategy\.name"):
        StrategyConfig(name="clairvoyant")
    with pytest.raises(PlannerError, match="unknown keys"):
        StrategyConfig.from_dict({"name": "pdm", "colour": "red"})
    with pytest.raises(PlannerError, match=r"strategy\.depth"):
        StrategyConfig(depth=0)
    with pytest.raises(PlannerError, match="invalid strategy settings"):
        StrategyConfig.from_dict({"depth": "deep"})
    nested = StrategyConfig.from_dict(
        {"candidates": {"count": 32}, "outcome": {"grazing_angle": 0.2}}
    )
    assert nested.candidates.count == 32 and nested.outcome.grazing_angle == 0.2


# fourteen squares in a row, each its own class: more than optimal_max_classes
ROW = [hyp("square", 7 * i - 45, 0.5 * i, cls=i, p=1 / 14) for i in range(14)]


@pytest.mark.parametrize("name", ["pdm", "pruning"])
def test_strategies_that_do_not_search_score_one_touch_deep_on_large_sets(name):
    config = StrategyConfig(name=name, **FAST)
    result = plan(ROW, MODELS, SENSOR, WORKSPACE, (100.0, 0.0), config)
    found = analyse(ROW, MODELS, SENSOR, WORKSPACE, (100.0, 0.0), config)
    assert found.table.n_classes > config.optimal_max_classes
    paths = [found.candidates.path(i) for i in range(len(found.candidates))]
    rows = {p.origin + p.direction: i for i, p in enumerate(paths)}
    chosen = np.array([rows[p.origin + p.direction] for p in result.paths])
    one = expected_remaining(found.table, 1, paths=chosen).value[chosen]
    two = expected_remaining(found.table, 2, paths=chosen).value[chosen]
    np.testing.assert_allclose([p.expected_remaining for p in result.paths], one)
    assert np.all(one <= two + 1e-9)  # the one-touch bound is a lower bound
    # on a small set they are searched as deep as lookahead does
    small = StrategyConfig(name=name, optimal_max_classes=20, **FAST)
    deep = plan(ROW, MODELS, SENSOR, WORKSPACE, (100.0, 0.0), small).paths
    np.testing.assert_allclose([p.expected_remaining for p in deep], two)


def test_budget_covers_the_outcome_model():
    # 72 classes x 256 candidates come in blocks; the budget is spent after the first
    many = [hyp("square", 2 * (i % 12) - 11, 2 * (i // 12) - 5, cls=i, p=1 / 72) for i in range(72)]
    config = StrategyConfig(name="pdm", budget_work=1.0, candidates=CandidateConfig(count=256))
    result = plan(many, MODELS, SENSOR, WORKSPACE, (100.0, 0.0), config)
    unlimited = dataclasses.replace(config, budget_ms=None, budget_work=None)
    full = plan(many, MODELS, SENSOR, WORKSPACE, (100.0, 0.0), unlimited)
    assert result.truncated and "budget" in result.note and result.stopped_by == "work"
    assert 0 < result.candidates < full.candidates and not full.truncated
    assert result.paths and all(p.family != "uninformative" for p in result.paths)


@pytest.mark.parametrize("name", ["pdm", "lookahead", "optimal"])
def test_no_candidate_at_all(name):
    none = CandidateConfig(count=0, boundary_aims=0, intersection_aims=0, feature_paths=0)
    result = plan(
        FIG71, MODELS, SENSOR, WORKSPACE, (100.0, 0.0), StrategyConfig(name=name, candidates=none)
    )
    assert result.status == "ambiguous" and result.candidates == 0 and not result.paths
    assert "no informative path" in result.note


def _slide_family(family_ids):
    # one contact on the square's top face (face 2, normal +y): samples slide along x,
    # 4 apart, each disk (6) wider than the spacing
    return [
        Hypothesis("square", 0, (2,), Pose(x, 0, 0), ErrorBound(3.0, 0.0, 6.0), 0.2, i, f)
        for i, (x, f) in enumerate(zip([-8, -4, 0, 4, 8], family_ids, strict=True))
    ]


def test_a_path_across_a_slide_family_pins_it():
    touched = [Observation(PATH_A, Contact((0.0, 20.0), (0.0, 1.0)))]
    side = SensingPath((100.0, 10.0), (-1.0, 0.0), 200.0)  # meets the right faces
    down = SensingPath((10.0, 100.0), (0.0, -1.0), 200.0)  # meets the top face again
    found = {}
    for name, ids in (("family", [7] * 5), ("unrelated", range(5))):
        found[name] = analyse(
            _slide_family(ids),
            MODELS,
            SENSOR,
            WORKSPACE,
            (100.0, 0.0),
            StrategyConfig(**FAST),
            observations=touched,
            extra_paths=[side, down],
        )
    for name, f in found.items():
        i_side, i_down = np.flatnonzero(f.candidates.source == "extra")[:2]
        p_side = f.info.p_distinguishing[i_side]
        if name == "family":  # the side contact fixes the slide: one pose is left
            assert p_side == pytest.approx(1.0)
        else:  # separate interpretations 4 apart with 6-wide disks stay confusable
            assert p_side < 1.0
        # a touch parallel to the one made pins nothing
        assert f.info.p_distinguishing[i_down] < 1.0


@pytest.mark.parametrize("name", ["workshop", "curved"])
def test_the_buckets_find_every_face_that_blocks_an_aim(name, monkeypatch):
    """Buckets of normal angle and extents only skip faces that cannot block a point:
    the aims must be those found by measuring every face."""
    from planner.planning import boundary_aims as module
    from planner.planning.posed_set import pose_hypotheses
    from planner.recognition.session import Session
    from tests.conftest import WORKSPACE, object_set

    models = [m for m in object_set(name) if m.name != "cam"]
    session = Session(models, SensorBounds(1, 0.05), WORKSPACE).observe(
        Observation(SensingPath((0, -200), (0, 1), 400), Contact((0, -30), (0, -1)))
    )
    posed = pose_hypotheses(session.hypotheses, session.models_by_name)
    bucketed = module._PairPlan.of(posed, session.bounds)
    assert bucketed.buckets is not None
    found = module.boundary_aims(posed, session.bounds, 40, 6, np.random.default_rng(3))
    every = module._PairPlan(bucketed.face_angle, None, int(posed.valid.sum()))
    monkeypatch.setattr(module._PairPlan, "of", classmethod(lambda cls, *_: every))
    measured = module.boundary_aims(posed, session.bounds, 40, 6, np.random.default_rng(3))
    assert len(found[0]) > 0
    np.testing.assert_array_equal(found[0], measured[0])
    np.testing.assert_array_equal(found[1], measured[1])


def _pin_families_one_by_one(hypotheses, posed, outcomes, bits, sensor):
    """The law family by family and pair by pair: on path c, sample a of a slide
    family (one interpretation, every touched face parallel, each sample a class of
    its own) no longer survives with sample b where the path surely meets both on
    one face not parallel to the family's."""
    tol = math.sin(2 * sensor.normal_error + 1e-6)
    n = np.nan_to_num(posed.touched)
    assigned = np.array([[-1 if a is None else a for a in h.assignment] for h in hypotheses])
    members = np.bincount(posed.cls, minlength=posed.n_classes)
    families: dict[tuple, list[int]] = {}
    for i, h in enumerate(hypotheses):
        on = assigned[i] >= 0
        u = n[i, np.argmax(on)]
        cross = np.abs(n[i, :, 0] * u[1] - n[i, :, 1] * u[0])
        if on.any() and np.all(~on | (cross <= tol)) and members[posed.cls[i]] == 1:
            key = (h.interpretation, h.object, h.stable_pose, tuple(assigned[i]))
            families.setdefault(key, []).append(i)
    out = bits.copy()
    sure = outcomes.hit & ~outcomes.uncertain
    for hs in families.values():
        u = n[hs[0], np.argmax(assigned[hs[0]] >= 0)]

        def pins(c: int, h: int, u: np.ndarray = u) -> bool:
            hit_n = outcomes.normal[c, h]
            return bool(sure[c, h] and abs(hit_n[0] * u[1] - hit_n[1] * u[0]) > tol)

        for a, b in ((a, b) for a in hs for b in hs if a != b):
            for c in range(len(outcomes.hit)):
                if outcomes.face[c, a] == outcomes.face[c, b] and pins(c, a) and pins(c, b):
                    kb = int(posed.cls[b])
                    out[c, posed.cls[a], kb // 64] &= ~np.uint64(1 << (kb % 64))
    return out


def test_slide_families_are_pinned_as_one_family_at_a_time_would_be(monkeypatch):
    """All families' pins in one pass clear the bits the law clears family by
    family, on the first plan of a set whose first touch leaves slide families."""
    from planner.planning import analysis
    from planner.planning.plan import plan_session
    from planner.recognition.session import Session
    from tests.conftest import WORKSPACE, object_set

    cleared = []
    real = analysis.pin_families

    def check(hypotheses, posed, outcomes, bits, sensor):
        got = real(hypotheses, posed, outcomes, bits, sensor)
        want = _pin_families_one_by_one(hypotheses, posed, outcomes, bits, sensor)
        np.testing.assert_array_equal(got, want)
        cleared.append(int((got != bits).sum()))
        return got

    monkeypatch.setattr(analysis, "pin_families", check)
    session = Session(object_set("workshop"), SensorBounds(1, 0.05), WORKSPACE).observe(
        Observation(SensingPath((0, -200), (0, 1), 400), Contact((0, -30), (0, -1)))
    )
    plan_session(session, (200.0, 0.0), StrategyConfig(name="pdm", budget_work=None), 0)
    assert cleared and max(cleared) > 0, "no family was pinned: the check saw nothing"
