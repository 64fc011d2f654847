"""Scores, families, expected remaining touches and the exact DP (DESIGN §4.12).

Synthetic outcome matrices are (paths, classes, classes) booleans: entry
[c, k, j] says class j survives path c when the truth is class k.
"""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
import shapely
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from planner.models.outlines import make_stable_pose
from planner.planning.bitsets import SurvivorTable, pack_bits
from planner.planning.budget import UNIT_US, Budget
from planner.planning.confusability import confusability, survivor_table
from planner.planning.leaf_kernel import cliques, undominated
from planner.planning.outcomes import predict_outcomes
from planner.planning.peers import information_gain
from planner.planning.posed_set import pose_hypotheses
from planner.planning.scoring import (
    FAMILIES,
    combined_objective,
    family_codes,
    information_scores,
    motion_cost,
)
from planner.planning.search import expected_remaining, information_rate, state_value
from planner.types import ErrorBound, Hypothesis, ObjectModel, Pose, SensorBounds, Workspace


def partition(k: int, *groups: tuple[int, ...]) -> np.ndarray:
    """Confusability of one path whose outcomes split the classes into `groups`
    (classes not named are told apart from everything)."""
    m = np.eye(k, dtype=bool)
    for g in groups:
        m[np.ix_(g, g)] = True
    return m


def only_separates(k: int, *pairs: tuple[int, int]) -> np.ndarray:
    """A path on which every pair of classes is confusable except the given ones."""
    m = np.ones((k, k), dtype=bool)
    for a, b in pairs:
        m[a, b] = m[b, a] = False
    return m


UNIFORM6 = np.full(6, 1 / 6)
# Fig. 7.1: a distinguishes 0, 1, 2 and leaves {3, 4, 5}; b leaves a pair whatever happens
PATH_A = partition(6, (3, 4, 5))
PATH_B = partition(6, (0, 1), (2, 3), (4, 5))


def fig71(case: str) -> SurvivorTable:
    """Paths a, b and a follow-up that is useless as a first touch (0, 1, 2 confusable
    with everything on it): case `one` splits {3, 4, 5} at once, case `two` only 4 from 5."""
    if case == "one":
        follow = only_separates(6, (3, 4), (3, 5), (4, 5))
    else:
        follow = only_separates(6, (4, 5))
    return SurvivorTable.from_matrix(np.stack([PATH_A, PATH_B, follow]), UNIFORM6)


def test_fig71_information_scores():
    s = information_scores(fig71("one"))
    np.testing.assert_allclose(s.p_distinguishing[:2], [0.5, 0.0])
    np.testing.assert_allclose(s.p_informative[:2], [1.0, 1.0])
    # a: 3/6 (1 - 1/6) + 3/6 (1 - 3/6); b: 1 - 2/6
    np.testing.assert_allclose(s.expected_pruning[:2], [2 / 3, 2 / 3])
    assert [FAMILIES[f] for f in s.family] == ["informative", "informative", "partial"]


@pytest.mark.parametrize(
    ("case", "e_three", "e_a"),
    [
        # the 3 left after a are resolved in one touch: E_a = 1 + 0.5 * 1
        ("one", 1.0, 1.5),
        # they are not: b splits 3 | {4, 5}, then the follow-up: E(3) = 1 + 2/3 * 1
        ("two", 5 / 3, 1 + 0.5 * 5 / 3),
    ],
)
def test_fig71_expected_remaining(case, e_three, e_a):
    table = fig71(case)
    three = np.array([False, False, False, True, True, True])
    assert state_value(table, None, state=three) == pytest.approx(e_three)
    # E_b = 1 + (E{0,1} + E{2,3} + E{4,5}) / 3 = 1 + 1
    for depth in (2, 3, None):
        result = expected_remaining(table, depth, paths=np.array([0, 1]))
        assert result.value[0] == pytest.approx(e_a)
        assert result.value[1] == pytest.approx(2.0)
        assert result.exact[[0, 1]].all()
    # either way the lower expected count is a's: lookahead agrees with P(DM) here
    assert state_value(table, None) == pytest.approx(min(e_a, 2.0))


def test_fig71_b_wins_when_the_leftovers_are_costly():
    # the thesis' dilemma in four classes: a distinguishes 0 (P(DM) = 1/4) but leaves
    # {1, 2, 3}, which take 5/3 more touches; b surely leaves a pair, each split in one
    a = partition(4, (1, 2, 3))
    b = partition(4, (0, 1), (2, 3))
    follow = only_separates(4, (2, 3))
    table = SurvivorTable.from_matrix(np.stack([a, b, follow]), np.full(4, 0.25))
    info = information_scores(table)
    assert info.p_distinguishing[0] > info.p_distinguishing[1]
    result = expected_remaining(table, 2)
    # E_a = 1 + 3/4 * (1 + 2/3); E_b = 1 + 1/2 + 1/2
    np.testing.assert_allclose(result.value[:2], [2.25, 2.0])
    assert int(np.argmin(result.value)) == 1


def random_tables(max_classes=4, max_paths=3):
    @st.composite
    def build(draw):
        k = draw(st.integers(2, max_classes))
        c = draw(st.integers(1, max_paths if k <= 3 else 2))
        upper = draw(st.lists(st.booleans(), min_size=c * k * k, max_size=c * k * k))
        conf = np.array(upper, dtype=bool).reshape(c, k, k)
        conf = conf | conf.transpose(0, 2, 1)  # confusability is symmetric
        weight = np.array(draw(st.lists(st.floats(0.05, 1.0), min_size=k, max_size=k)))
        return SurvivorTable.from_matrix(conf, weight)

    return build()


def brute_force(table: SurvivorTable, first: int | None = None) -> float:
    """min over every deterministic policy (state -> path) of its expected touches,
    evaluated by plain recursion; a stay outcome counts as another try."""
    conf, w = table.matrix(), table.weight
    n_paths, k = conf.shape[0], conf.shape[1]

    def child(s, c, h):
        return frozenset(j for j in s if conf[c, h, j])

    def informative(s, c):
        return any(child(s, c, h) != s for h in s)

    full = frozenset(range(k))
    reach, todo = set(), [full]
    while todo:
        s = todo.pop()
        if s in reach:
            continue
        reach.add(s)
        for c in range(n_paths):
            if informative(s, c):
                todo.extend(child(s, c, h) for h in s)
    decisions = sorted(
        (s for s in reach if any(informative(s, c) for c in range(n_paths))), key=sorted
    )
    options = [
        [c for c in range(n_paths) if informative(s, c) and (s != full or first in (None, c))]
        for s in decisions
    ]
    best = math.inf
    for choice in itertools.product(*options):
        policy = dict(zip(decisions, choice, strict=True))

        def value(s, policy=policy):
            if s not in policy:
                return 0.0  # no path splits s: nothing more to learn
            c, total = policy[s], sum(w[h] for h in s)
            stay = sum(w[h] for h in s if child(s, c, h) == s) / total
            rest = sum(w[h] / total * value(child(s, c, h)) for h in s if child(s, c, h) != s)
            return (1 + rest) / (1 - stay)

        best = min(best, value(full))
    return best


@settings(max_examples=60, deadline=None)
@given(random_tables())
def test_optimal_equals_brute_force(table):
    assume(table.n_classes <= 3 or table.n_paths <= 2)
    exact = expected_remaining(table, None)
    root = state_value(table, None)
    assert root == pytest.approx(brute_force(table))
    for c in range(table.n_paths):
        expected = brute_force(table, first=c)
        if math.isinf(expected):
            assert math.isinf(exact.value[c])
        else:
            assert exact.value[c] == pytest.approx(expected)
    finite = exact.value[np.isfinite(exact.value)]
    assert root == pytest.approx(finite.min() if len(finite) else 0.0)


@settings(max_examples=60, deadline=None)
@given(random_tables(max_classes=6, max_paths=5))
def test_deep_lookahead_equals_optimal_and_shallow_bounds_it(table):
    exact = expected_remaining(table, None).value
    deep = expected_remaining(table, table.n_classes).value
    np.testing.assert_allclose(deep, exact)
    previous = np.zeros_like(exact)
    for depth in range(1, table.n_classes):
        bound = expected_remaining(table, depth).value
        assert np.all(bound <= exact + 1e-9)  # the leaf bound is admissible
        assert np.all(bound >= previous - 1e-9)  # and deeper search only tightens it
        previous = bound


@settings(max_examples=40, deadline=None)
@given(random_tables(max_classes=6, max_paths=6), st.integers(1, 3))
def test_top_k_search_keeps_the_best_exact(table, top_k):
    full = expected_remaining(table, 2)
    pruned = expected_remaining(table, 2, top_k=top_k)
    order = np.lexsort((~pruned.exact, pruned.value))[:top_k]
    best = np.sort(full.value)[:top_k]
    np.testing.assert_allclose(np.sort(pruned.value[order]), best)
    assert np.all(pruned.value <= full.value + 1e-9)  # the rest keep lower bounds


@settings(max_examples=40, deadline=None)
@given(random_tables(max_classes=6, max_paths=6), st.integers(1, 3), st.sampled_from([2, None]))
def test_top_k_search_values_every_path_that_ties_the_cutoff(table, top_k, depth):
    # a path whose value equals the top_k-th best is valued exactly, not left at a
    # bound that ties: equal values are ranked by P(DM), gain and motion, not by
    # which path the search happened to value first. Every path twice: ties forced
    table = SurvivorTable.from_matrix(np.concatenate([table.matrix()] * 2), table.weight)
    full = expected_remaining(table, depth)
    pruned = expected_remaining(table, depth, top_k=top_k)
    finite = np.sort(full.value[np.isfinite(full.value)])
    assume(len(finite) > 0)
    cutoff = finite[min(top_k, len(finite)) - 1]
    tied = full.value <= cutoff + 1e-12
    assert np.all(pruned.exact[tied])
    np.testing.assert_allclose(pruned.value[tied], full.value[tied])


def test_equal_paths_are_all_valued_under_top_k():
    # five paths that each tell three classes apart: all worth one touch, all exact
    # with top_k = 1 (the first valued used to keep the others at their bound)
    table = SurvivorTable.from_matrix(np.stack([np.eye(3, dtype=bool)] * 5), np.ones(3) / 3)
    for depth in (2, None):
        found = expected_remaining(table, depth, top_k=1)
        assert found.exact.all()
        np.testing.assert_allclose(found.value, 1.0)


def test_inseparable_classes_end_the_search():
    # classes 1 and 2 are confusable on every path: once they are what is left,
    # no touch can help, and the remaining count is 0, not infinity
    a = partition(3, (1, 2))
    table = SurvivorTable.from_matrix(np.stack([a, a]), np.ones(3) / 3)
    assert state_value(table, None) == pytest.approx(1.0)
    assert state_value(table, None, state=np.array([False, True, True])) == 0.0


@pytest.mark.parametrize("depth", [None, 2])
def test_the_budget_stops_the_search(depth):
    rng = np.random.default_rng(0)
    conf = rng.random((30, 12, 12)) < 0.4
    table = SurvivorTable.from_matrix(conf | conf.transpose(0, 2, 1), np.ones(12))
    for budget in (lambda: Budget(work=0.0), lambda: Budget(cap_ms=0.0)):
        result = expected_remaining(table, depth, budget=budget())
        assert result.truncated
        assert not result.exact[np.isfinite(result.value)].any()
        with pytest.raises(TimeoutError):
            state_value(table, None, budget=budget())


@pytest.mark.parametrize(
    ("p_dm", "p_inf", "family"),
    [
        (1.0, 1.0, "distinguishing"),
        (0.4, 1.0, "informative"),
        (0.0, 0.3, "partial"),
        (0.0, 0.0, "uninformative"),
    ],
)
def test_families(p_dm, p_inf, family):
    assert FAMILIES[int(family_codes(np.array([p_dm]), np.array([p_inf]))[0])] == family


def test_motion_cost_is_arc_plus_approach():
    ws = Workspace((10.0, 0.0), 50.0)
    origins = np.array([[60.0, 0.0], [10.0, 50.0], [-40.0, 0.0]])
    cost = motion_cost(origins, np.array([5.0, 5.0, 5.0]), ws, (80.0, 0.0))
    np.testing.assert_allclose(cost, [5.0, 50 * math.pi / 2 + 5, 50 * math.pi + 5])
    np.testing.assert_allclose(combined_objective([1.0, 2.0], [10.0, 0.0], 0.5), [6.0, 2.0])


SQUARE = ObjectModel("square", (make_stable_pose([[-20, -20], [20, -20], [20, 20], [-20, 20]]),))
FRAME = ObjectModel(
    "frame",
    (
        make_stable_pose(
            [[-20, -20], [20, -20], [20, 20], [-20, 20]],
            [[[-10, -10], [-10, 10], [10, 10], [10, -10]]],
        ),
    ),
)
MODELS = {"square": SQUARE, "frame": FRAME}
DOWN = (np.array([[0.0, 100.0]]), np.array([[0.0, -1.0]]), np.array([130.0]))


def scores_down(hyps):
    sensor = SensorBounds(0.2, 0.02)
    posed = pose_hypotheses(hyps, MODELS)
    out = predict_outcomes(posed, *DOWN, sensor)
    table = survivor_table(posed, confusability(posed, out, sensor))
    return posed, out, information_scores(table)


def square(x, y, cls, name="square", eps_t=0.5):
    return Hypothesis(name, 0, (), Pose(x, y, 0.0), ErrorBound(0.0, 0.0, eps_t), 1.0, cls)


def test_theorem2_single_blocking_boundary():
    # n = 5 equally likely; the path crosses one blocking boundary of degree m = 2
    # (three top faces on y = 20, at x offsets that do not matter on this path)
    hyps = [square(0, 0, 0), square(3, 0, 1), square(-3, 0, 2), square(0, 5, 3), square(0, 10, 4)]
    _, out, info = scores_down(hyps)
    assert not out.uncertain.any()
    n, m = 5, 2
    assert info.p_distinguishing[0] == pytest.approx((n - m - 1) / n)


def test_theorem2_agrees_with_the_blocking_strength_of_the_vector_mii():
    # exact outlines: the MII's blocking boundaries are segments; the path runs from
    # outside the union into the IA and crosses the one shared top face
    from planner.image.vector import build_mii, paths_crossings

    offsets = [(0, 0), (3, 0), (-3, 0), (0, 5), (0, 10)]
    hyps = [square(x, y, i, eps_t=0.0) for i, (x, y) in enumerate(offsets)]
    into_ia = (DOWN[0], DOWN[1], np.array([100.0]))  # ends at (0, 0), inside every outline
    mii = build_mii(hyps, MODELS)
    assert mii.intersection.contains(shapely.Point(0.0, 0.0))
    crossed = paths_crossings(mii, *into_ia)
    assert crossed.count[0] == 1
    sensor = SensorBounds(0.2, 0.02)
    posed = pose_hypotheses(hyps, MODELS)
    out = predict_outcomes(posed, *into_ia, sensor)
    info = information_scores(survivor_table(posed, confusability(posed, out, sensor)))
    assert info.p_distinguishing[0] == pytest.approx(1.0 - crossed.total[0])


def test_fig72_blocking_boundary_crossed_yet_distinguishing():
    # thesis Fig. 7.2 asks whether a path can cross a blocking boundary and still be
    # sure to distinguish: yes. The frame's hole face on y = -10 (normal +y) and the
    # low square's top face share a blocking boundary the path crosses, but the
    # frame is touched first on its own top face.
    hyps = [
        square(0, 0, 0, name="frame"),
        square(0, -30, 1),
        square(0, 8, 2),
        square(0, -5, 3),
    ]
    posed, out, info = scores_down(hyps)
    hole_face = [
        f
        for f in range(posed.valid.shape[1])
        if posed.valid[0, f]
        and np.allclose(posed.start[0, f, 1], -10)
        and posed.normal[0, f, 1] > 0.99
    ]
    assert hole_face, "the frame has a hole face on y = -10 facing up"
    assert np.allclose(out.point[0, 1], [0, -10]) and np.allclose(out.normal[0, 1], [0, 1])
    assert np.allclose(out.point[0, 0], [0, 20])
    assert info.p_distinguishing[0] == pytest.approx(1.0)
    assert FAMILIES[int(info.family[0])] == "distinguishing"


def dense_scores(conf: np.ndarray, weight: np.ndarray, state: np.ndarray) -> tuple:
    """P(DM), P(informative) and expected pruning from the (C, K, K) class matrix."""
    conf = conf[:, state][:, :, state]
    w = weight[state] / weight[state].sum()
    surviving = conf.astype(float) @ w
    p_dm = (conf.sum(axis=-1) == 1).astype(float) @ w
    p_inf = (~conf.all(axis=-1)).astype(float) @ w
    return p_dm, p_inf, (1.0 - surviving) @ w


@settings(max_examples=40, deadline=None)
@given(st.integers(2, 140), st.integers(1, 6), st.integers(0, 2**31))
def test_information_scores_agree_with_the_class_matrix(k, n_paths, seed):
    rng = np.random.default_rng(seed)
    conf = rng.random((n_paths, k, k)) < rng.uniform(0.05, 0.9)
    table = SurvivorTable.from_matrix(conf | conf.transpose(0, 2, 1), rng.uniform(0.1, 1, k))
    for state in (None, rng.random(k) < 0.6):
        if state is not None and not state.any():
            continue
        s = information_scores(table, state)
        inside = np.ones(k, bool) if state is None else state
        p_dm, p_inf, pruning = dense_scores(table.matrix(), table.weight, inside)
        np.testing.assert_allclose(s.p_distinguishing, p_dm, atol=1e-12)
        np.testing.assert_allclose(s.p_informative, p_inf, atol=1e-12)
        np.testing.assert_allclose(s.expected_pruning, np.clip(pruning, 0, 1), atol=1e-12)


def lookahead_reference(
    table: SurvivorTable, depth: int, rate: float | None = None, leaf_paths=None
) -> np.ndarray:
    """E_P(S) of every path, `depth` touches deep, by plain recursion over sets; an
    open set s at the horizon counts 1 touch, or max(1, log |s| / rate) given a
    `rate`; sets one touch from the horizon choose among `leaf_paths` (default all)."""
    conf, weight = table.matrix(), table.weight
    together = conf.all(axis=0)
    last = range(len(conf)) if leaf_paths is None else leaf_paths

    def settled(s):
        return all(together[a, b] for a in s for b in s)

    def path(s, c, d):
        w = {h: weight[h] / sum(weight[j] for j in s) for h in s}
        kids = {h: frozenset(j for j in s if conf[c, h, j]) for h in s}
        stay = sum(w[h] for h in s if kids[h] == s)
        if stay >= 1 - 1e-12:
            return math.inf
        rest = sum(w[h] * value(kids[h], d - 1) for h in s if kids[h] != s)
        return (1 + rest) / (1 - stay)

    def value(s, d):
        if settled(s):
            return 0.0
        if d == 0:
            return 1.0 if rate is None else max(1.0, math.log(len(s)) / rate)
        return min(path(s, c, d) for c in (last if d == 1 else range(len(conf))))

    full = frozenset(range(table.n_classes))
    return np.array([path(full, c, depth) if not settled(full) else 0.0 for c in range(len(conf))])


@settings(max_examples=30, deadline=None)
@given(st.integers(3, 12), st.integers(1, 6), st.integers(0, 2**31))
def test_lookahead_agrees_with_plain_recursion(k, n_paths, seed):
    # inseparable pairs make settled leaves; the one-touch leaves run in batches
    rng = np.random.default_rng(seed)
    conf = rng.random((n_paths, k, k)) < rng.uniform(0.1, 0.7)
    pairs = rng.integers(0, k, (rng.integers(0, 4), 2))
    conf[:, pairs[:, 0], pairs[:, 1]] = True
    table = SurvivorTable.from_matrix(conf | conf.transpose(0, 2, 1), rng.uniform(0.1, 1, k))
    for depth in (1, 2, 3):
        found = expected_remaining(table, depth)
        np.testing.assert_allclose(found.value, lookahead_reference(table, depth), rtol=1e-9)
        assert found.exact.all()


@settings(max_examples=40, deadline=None)
@given(st.integers(2, 150), st.integers(1, 8), st.integers(0, 2**31))
def test_cliques_agree_with_pairwise_checks(k, n_groups, seed):
    # groups wider than one word of classes, and classes with more than 64
    # inseparable neighbours, are checked alike
    rng = np.random.default_rng(seed)
    together = rng.random((k, k)) < rng.uniform(0.5, 1.0)
    together = together & together.T
    np.fill_diagonal(together, True)
    members = rng.random((n_groups, k)) < rng.uniform(0.02, 0.5)
    expected = [not np.any(~together[np.ix_(m, m)]) for m in members]
    found = cliques(pack_bits(members), ~pack_bits(together))
    assert found.tolist() == expected


@settings(max_examples=40, deadline=None)
@given(st.integers(3, 12), st.integers(1, 6), st.integers(0, 2**31))
def test_entropy_leaves_agree_with_plain_recursion(k, n_paths, seed):
    # an open set at the horizon counts max(1, log |T| / rate), rate the most
    # information one path gives at the root
    rng = np.random.default_rng(seed)
    conf = rng.random((n_paths, k, k)) < rng.uniform(0.1, 0.7)
    conf[:, np.arange(k), np.arange(k)] = True  # a truth never rules itself out
    table = SurvivorTable.from_matrix(conf | conf.transpose(0, 2, 1), rng.uniform(0.1, 1, k))
    rate = information_rate(table, pack_bits(np.ones(k, dtype=bool)))
    gain = information_gain(table).max()
    assert rate == pytest.approx(gain) if gain > 1e-9 else rate is None
    for depth in (1, 2):
        found = expected_remaining(table, depth, leaf="entropy")
        expected = lookahead_reference(table, depth, rate, undominated(table.bits))
        np.testing.assert_allclose(found.value, expected, rtol=1e-9)
        # never below the one-touch leaves' value, which is a lower bound
        assert np.all(found.value >= expected_remaining(table, depth).value - 1e-9)
    # as deep as the classes, no set is left open at the horizon: the exact values
    deep = expected_remaining(table, k, leaf="entropy").value
    np.testing.assert_allclose(deep, expected_remaining(table, None).value)


def test_entropy_leaves_prefer_halving_to_peeling_one_class_off():
    # 32 equal classes, five binary tests (bit j of the class) and one that tells
    # class 0 from the rest. Two touches deep no truth is settled after halving,
    # while peeling settles 1/32: one touch per open set prefers the peel (2.94
    # against 2.97), though it leaves 31 classes where halving leaves 8
    k = 32
    bits = (np.arange(k)[:, None] >> np.arange(5)) & 1
    halving = [bits[:, j][:, None] == bits[:, j][None, :] for j in range(5)]
    peel = np.ones((k, k), dtype=bool)
    peel[0, 1:] = peel[1:, 0] = False
    table = SurvivorTable.from_matrix(np.stack([*halving, peel]), np.ones(k) / k)
    touch = expected_remaining(table, 2).value
    entropy = expected_remaining(table, 2, leaf="entropy").value
    assert np.argmin(touch) == 5 and touch[5] < touch[0]
    assert np.argmin(entropy) < 5 and entropy[5] > entropy[0] + 0.5


def test_under_a_budget_the_most_informative_paths_get_exact_values():
    # many paths with close bounds; the budget lets only the first group be valued:
    # those are the most informative ones, not the ones first by bound
    rng = np.random.default_rng(3)
    k, n_paths = 40, 400
    conf = rng.random((n_paths, k, k)) < rng.uniform(0.05, 0.6, (n_paths, 1, 1))
    table = SurvivorTable.from_matrix(conf | conf.transpose(0, 2, 1), np.ones(k) / k)
    gain = information_gain(table)
    found = expected_remaining(table, 2, budget=Budget(work=200_000.0))
    assert found.truncated and found.exact.any() and not found.exact.all()
    valued = np.flatnonzero(found.exact)
    assert gain[valued].min() >= np.sort(gain)[::-1][len(valued) - 1] - 1e-12


@settings(max_examples=30, deadline=None)
@given(st.integers(3, 10), st.integers(1, 4), st.integers(0, 2**31))
def test_dominated_paths_leave_the_lookahead_unchanged(k, n_paths, seed):
    # copies of paths, and copies that confuse more: the one-touch leaves use only
    # the paths nothing dominates, the values stay those of the plain recursion
    rng = np.random.default_rng(seed)
    conf = rng.random((n_paths, k, k)) < rng.uniform(0.1, 0.6)
    conf = conf | conf.transpose(0, 2, 1)
    worse = conf[rng.integers(0, n_paths, 3)] | (rng.random((3, k, k)) < 0.2)
    same = conf[rng.integers(0, n_paths, 2)]
    paths = np.concatenate([worse | worse.transpose(0, 2, 1), conf, same])
    table = SurvivorTable.from_matrix(paths[rng.permutation(len(paths))], rng.uniform(0.1, 1, k))
    kept = undominated(table.bits)
    assert len(kept) <= n_paths
    matrix = table.matrix()
    for q in range(len(paths)):  # every path is within reach of a kept one
        assert any((matrix[p] <= matrix[q]).all() for p in kept)
    for depth in (1, 2, 3):
        found = expected_remaining(table, depth)
        np.testing.assert_allclose(found.value, lookahead_reference(table, depth), rtol=1e-9)


def test_a_whole_search_the_budget_cannot_finish_is_not_begun():
    # a plan ranks a search the budget stops by information gain, so the work of
    # the cut search is lost: asked for whole, it is not begun and nothing is spent
    rng = np.random.default_rng(3)
    k, n_paths = 40, 400
    conf = rng.random((n_paths, k, k)) < rng.uniform(0.05, 0.6, (n_paths, 1, 1))
    table = SurvivorTable.from_matrix(conf | conf.transpose(0, 2, 1), np.ones(k) / k)
    free = Budget()
    full = expected_remaining(table, 2, budget=free, whole=True)
    assert not full.truncated and full.exact.all()
    needed = free.spent["leaf_set"]
    short = Budget(work=(needed - 1) * UNIT_US["leaf_set"])
    cut = expected_remaining(table, 2, budget=short, whole=True)
    assert cut.truncated and not cut.exact[np.isfinite(cut.value)].any()
    assert short.spent["leaf_set"] == 0 and not short.exhausted()
    # every value a lower bound of the searched one
    assert (cut.value <= full.value + 1e-12).all()
    # with the work it needs, the same values as without a budget
    enough = expected_remaining(
        table, 2, budget=Budget(work=needed * UNIT_US["leaf_set"]), whole=True
    )
    np.testing.assert_array_equal(enough.value, full.value)
