"""Expected remaining touches E(S): depth-limited lookahead and the exact `optimal` DP.

States are sets S of equivalence classes stored as bitsets (see
:mod:`planner.planning.bitsets`); the outcome matrix is computed once and survivor sets
of a state are restrictions ``S_P(h) & S`` (DESIGN §4.12). With w(h|S) the
class weights conditioned on S::

    E(S) = 0                                   if no path can split S
                                               (one class, or all inseparable)
    E(S) = 1 + min_P sum_h w(h|S) E(S_P(h) & S)

A path that leaves S unchanged for some truths makes the right side refer to
E(S) itself; we take the fixpoint of that equation (a "stay" outcome counts as
another try), which for one path P reads::

    E_P(S) = (1 + sum_{h: S_P(h) & S != S} w(h|S) E(S_P(h) & S)) / (1 - w_stay(P|S))

Paths with w_stay = 1 (uninformative on S) are never taken.

Depth-limited search evaluates this recursion `depth` touches deep; a leaf
state that is not settled counts one more touch, which is admissible: a state
that some path can split needs at least one touch. With ``leaf="entropy"`` (the
``lookahead`` strategy's) it counts ``max(1, log |T| / rate)`` instead, `rate` the
most information (nats) one path gives at the root: with many classes two
touches deep nearly every outcome is still open at the horizon, and one touch
each would value paths alike however much they leave. The same bound orders and
prunes the paths at every node (branch and bound), and values are memoized on
(state bitset, depth); values known to be exact (depth >= classes - 1, or no
depth limit) are shared between depths. Without a depth limit the search is
the exact dynamic programme over survivor sets (`optimal`).

Two touches deep (the default lookahead) the root paths' children are valued
one touch deep in large batches instead: the children of paths whose values
lie close together are nearly all needed anyway. One-touch values take the
minimum over the paths no other path dominates
(:func:`~planner.planning.bitsets.undominated`).

This module holds the search itself (branch and bound, memo, the public entry
points); expanding a state into its children, telling settled states and the
one-touch bounds are in :mod:`planner.planning.search_nodes`.
"""

from __future__ import annotations

import bisect
from dataclasses import dataclass

import numpy as np

from planner.arrays import distinct_rows
from planner.planning.bitsets import SurvivorTable, pack_bits, popcount, unpack_bits
from planner.planning.budget import Budget, OutOfBudgetError
from planner.planning.peers import information_gain
from planner.planning.search_nodes import Node, SearchSpace

__all__ = ["LEAVES", "SearchResult", "expected_remaining", "information_rate", "state_value"]

#: How an open set at the search's horizon is valued (see the module's text).
LEAVES = ("touch", "entropy")

#: Children of one path evaluated together one touch deep, and the most words
#: (paths x members x words) one batch of them may take; children of root paths
#: valued together when the search is two touches deep.
_BATCH = 64
_BATCH_ELEMENTS = 2_000_000
_GROUP = 256
#: Root paths whose bound is within this of the cutoff are still valued: equal values
#: are ranked by P(DM), information gain and motion, not by which was valued first.
TIE = 1e-9


@dataclass(frozen=True, eq=False)
class SearchResult:
    """Expected remaining touches of each root path, this touch included.

    `value` (C,) is exact where `exact` is set and a lower bound elsewhere
    (paths pruned as outside the best `top_k`, or not reached before the
    budget); inf for paths uninformative at the root. `truncated` says the
    budget stopped the search; `states` counts the states expanded; `gain` (C,)
    is each path's expected information gain (nats) on the root state, which
    ordered the root's paths.
    """

    value: np.ndarray
    exact: np.ndarray
    truncated: bool
    states: int
    gain: np.ndarray


class _Search:
    """E(S) by branch and bound over the nodes of a :class:`SearchSpace`, memoized
    on the state (`exact`) and on (state, depth) (`limited`), stopped by
    `budget`; with `whole`, a two-deep ranking the budget cannot finish is not
    begun."""

    def __init__(
        self, table: SurvivorTable, budget: Budget, rate: float | None = None, whole: bool = False
    ) -> None:
        self.space = SearchSpace(table, rate)
        self.n = table.n_classes
        self.budget = budget
        self.whole = whole
        self.exact: dict[bytes, float] = {}
        self.limited: dict[tuple[bytes, int], float] = {}

    def value(self, state: np.ndarray, depth: int | None) -> float:
        """E(S) searched `depth` touches deep (None: exact)."""
        self.budget.check("search_node")
        key = state.tobytes()
        known = self.exact.get(key)
        if known is not None:
            return known
        if depth is not None and (key, depth) in self.limited:
            return self.limited[key, depth]
        idx = np.flatnonzero(unpack_bits(state, self.n))
        if self.space.settled(state, idx):
            self.exact[key] = 0.0
            return 0.0
        if depth == 0:
            return float(self.space.leaf_value(len(idx)))  # S can be split: >= 1 touch
        if depth == 1:
            best = float(self.space.expand(state, idx, self.space.leaf).one_deep.min())
        else:
            # E(S) = 1 + min_P sum_h w(h|S) E(S_P(h) & S), paths in order of their bound
            node = self.space.expand(state, idx)
            best = np.inf
            child_depth = None if depth is None else depth - 1
            for c in np.argsort(node.bound, kind="stable"):
                if _cannot_improve(node.bound[c], best):
                    break
                v, done = self.path_value(node, int(c), child_depth, best)
                if done and v < best:
                    best = v
        if depth is None or depth >= len(idx) - 1:
            self.exact[key] = best
        else:
            self.limited[key, depth] = best
        return best

    def path_value(
        self, node: Node, c: int, depth: int | None, cutoff: float
    ) -> tuple[float, bool]:
        """E_P(S) for path c; stops early (returning a lower bound, False) once it
        cannot get below `cutoff`."""
        ks = np.flatnonzero(node.open[c])
        denom = 1.0 - node.w_stay[c]
        rest = float(node.weight[ks].sum())
        total = 1.0
        # leaves of the children (depth 1): batches of states at once, growing from
        # one so that a path cut off early costs little
        step = 1 if depth == 1 else max(len(ks), 1)
        for lo in _batches(len(ks), step):
            part = ks[lo[0] : lo[1]]
            if depth == 1:
                values = self.values_one(node.child[c, part])
            for i, k in enumerate(part):
                value = values[i] if depth == 1 else self.value(node.child[c, k], depth)
                # E_P(S) = (1 + sum_h w(h|S) E(S_P(h) & S)) / (1 - w_stay)
                total += node.weight[k] * value
                rest -= node.weight[k]
                # the children not valued yet count one touch each: a lower bound
                bound = (total + rest) / denom
                if _reaches(bound, cutoff):
                    return bound, False
        return total / denom, True

    def values_one(self, sets: np.ndarray) -> np.ndarray:
        """E(T) searched one touch deep for each set T (n, W), memoized: the best
        bound min_P (1 + w(open | T)) / (1 - w(stay | T)), or 0 if T is settled."""
        self.budget.check("leaf_set", 0)
        out = np.empty(len(sets))
        missing: dict[bytes, list[int]] = {}  # each set not known yet, once
        for i, state in enumerate(sets):
            key = state.tobytes()
            known = self.exact.get(key, self.limited.get((key, 1)))
            if known is None:
                missing.setdefault(key, []).append(i)
            else:
                out[i] = known
        if missing:
            todo = sets[[where[0] for where in missing.values()]]
            found = np.empty(len(todo))
            size = popcount(todo)
            # similar sizes together, each batch padded to its largest set and kept
            # within _BATCH_ELEMENTS words
            order = np.argsort(size, kind="stable")
            room = max(1, _BATCH_ELEMENTS // (len(self.space.leaf) * self.space.bits.shape[-1]))
            lo = 0
            while lo < len(order):
                hi = lo + 1
                while hi < len(order) and (hi + 1 - lo) * size[order[hi]] <= room:
                    hi += 1
                pick = order[lo:hi]
                self.budget.check("leaf_set", len(pick))
                m = int(size[pick].max())
                # members of each set, padded with -1 (one row per set)
                members = np.argsort(~unpack_bits(todo[pick], self.n), axis=1, kind="stable")
                idx = np.where(np.arange(m) < size[pick][:, None], members[:, :m], -1)
                settled = self.space.settled_many(todo[pick], idx)
                found[pick] = np.where(settled, 0.0, self.space.bound_one(todo[pick], idx))
                lo = hi
            for where, v in zip(missing.values(), found, strict=True):
                out[where] = v
            for state, v, m in zip(todo, found, size, strict=True):
                # one touch deep is the exact value for sets of at most two classes
                if v == 0.0 or m <= 2:
                    self.exact[state.tobytes()] = float(v)
                else:
                    self.limited[state.tobytes(), 1] = float(v)
        return out

    def rank(
        self,
        state: np.ndarray,
        depth: int | None,
        paths: np.ndarray,
        top_k: int | None,
        extra: np.ndarray,
        gain: np.ndarray,
    ) -> SearchResult:
        """E_P(S) of the root `paths` from `state`, searched `depth` touches deep
        (None: exact), the most informative by `gain` first; with `top_k`, only the
        best `top_k` by ``E_P + extra`` are sure to be exact, the others may keep a
        lower bound."""
        n_paths = self.space.bits.shape[0]
        value = np.full(n_paths, np.inf)
        exact = np.zeros(n_paths, dtype=bool)
        idx = np.flatnonzero(unpack_bits(state, self.n))
        if self.space.settled(state, idx):
            value[paths], exact[paths] = 0.0, True
            return SearchResult(value, exact, False, self.space.states, gain)
        if depth == 1:
            # E_P(S) one touch deep: only the paths asked for
            value[paths] = self.space.expand(state, idx, paths).one_deep
            exact[paths] = True
            return SearchResult(value, exact, False, self.space.states, gain)
        node = self.space.expand(state, idx)
        value[paths] = node.bound[paths]
        uninformative = paths[~np.isfinite(node.bound[paths])]
        exact[uninformative] = True
        child_depth = None if depth is None else depth - 1
        live = paths[np.isfinite(node.bound[paths])]
        # the most informative first, then by bound: when the budget stops the search,
        # those are the paths with exact values (bounds of many classes lie close)
        order = live[np.lexsort((node.bound[live] + extra[live], -gain[live]))]
        if child_depth == 1:
            truncated = self._rank_two(node, order, top_k, extra, value, exact)
            return SearchResult(value, exact, truncated, self.space.states, gain)
        best: list[float] = []  # sorted exact objectives found so far
        truncated = False
        for c in order:
            # a path whose bound only ties the cutoff is valued too: it may tie the
            # best, and ties are decided by the keys after the value
            threshold = _kth_best(best, top_k) + TIE
            if _reaches(node.bound[c] + extra[c], threshold):
                continue
            try:
                v, done = self.path_value(node, int(c), child_depth, threshold - extra[c])
            except OutOfBudgetError:
                truncated = True
                break
            value[c] = v
            if done:
                exact[c] = True
                bisect.insort(best, v + extra[c])
        return SearchResult(value, exact, truncated, self.space.states, gain)

    def _rank_two(
        self,
        node: Node,
        order: np.ndarray,
        top_k: int | None,
        extra: np.ndarray,
        value: np.ndarray,
        exact: np.ndarray,
    ) -> bool:
        """Root paths two touches deep, in `order`, a group at a time: all children
        of a group are valued one touch deep together. (Branch and bound would value
        nearly all of them anyway: counting one touch per child the bounds of paths
        with close values prune little.) Skips the paths whose bound reaches the
        top_k-th exact objective found so far; fills `value` and `exact` of the paths
        done and returns whether the budget stopped it."""
        if self.whole:
            # every distinct child set is valued one touch deep: a search the budget
            # cannot pay for to the end is not begun (its caller would throw it away)
            children = node.child[order][node.open[order]]
            room = self.budget.affordable("leaf_set")
            if room < len(children) and room < distinct_rows(children):
                return True
        best: list[float] = []  # sorted exact objectives found so far
        lo = 0
        while lo < len(order):
            threshold = _kth_best(best, top_k) + TIE
            picked: list[int] = []
            children = 0
            while lo < len(order) and (not picked or children < _GROUP):
                c = int(order[lo])
                lo += 1
                if not _reaches(node.bound[c] + extra[c], threshold):  # else ruled out
                    picked.append(c)
                    children += int(node.open[c].sum())
            if not picked:
                return False
            group = np.array(picked)
            at, k = np.nonzero(node.open[group])
            try:
                values = self.values_one(node.child[group[at], k])
            except OutOfBudgetError:
                return True
            # E_P(S) = (1 + sum_h w(h|S) E(S_P(h) & S)) / (1 - w_stay)
            total = 1.0 + np.bincount(at, weights=node.weight[k] * values, minlength=len(group))
            value[group] = total / (1.0 - node.w_stay[group])
            exact[group] = True
            for v in value[group] + extra[group]:
                bisect.insort(best, float(v))
        return False


def _cannot_improve(bound: float, best: float) -> bool:
    """Pruning check: paths come in order of their bound, so once a bound is not
    below the best value found (by more than rounding) no later path improves it."""
    return not bound < best - 1e-12


def _reaches(bound: float, cutoff: float) -> bool:
    """Pruning check: a lower bound at or above the cutoff (the best value found,
    or the top_k-th best objective) rules the path out."""
    return bound >= cutoff


def _kth_best(best: list[float], top_k: int | None) -> float:
    """The cutoff for entering the top `top_k`: the top_k-th of the sorted exact
    objectives `best` found so far (inf until there are that many, or no top_k)."""
    return best[top_k - 1] if top_k is not None and len(best) >= top_k else np.inf


def _batches(n: int, first: int) -> list[tuple[int, int]]:
    """[lo, hi) ranges covering range(n), each twice as long as the one before
    (up to `_BATCH`)."""
    out, lo, size = [], 0, first
    while lo < n:
        out.append((lo, min(n, lo + size)))
        lo, size = lo + size, min(2 * size, max(_BATCH, first))
    return out


def _full_state(table: SurvivorTable, state: np.ndarray | None) -> np.ndarray:
    if state is None:
        return pack_bits(np.ones(table.n_classes, dtype=bool))
    state = np.asarray(state)
    return pack_bits(state) if state.dtype == bool else state.astype(np.uint64)


def expected_remaining(
    table: SurvivorTable,
    depth: int | None = 2,
    *,
    paths: np.ndarray | None = None,
    top_k: int | None = None,
    extra_cost: np.ndarray | None = None,
    budget: Budget | None = None,
    state: np.ndarray | None = None,
    leaf: str = "touch",
    whole: bool = False,
) -> SearchResult:
    """Expected remaining touches E_P(S) of each root path P (this touch included).

    `depth` touches are searched exactly (None: no limit, the exact DP; use
    only for a few classes); `paths` limits the root paths scored (inner nodes
    always use every path); with `top_k`, only the best `top_k` by
    ``E_P + extra_cost`` are guaranteed exact and the others may keep their
    lower bound; `budget` stops the search (anytime: the best found so far,
    `truncated` set); `state` is the hypothesis set S (bool over classes or a
    bitset; default all classes); `leaf` values the open sets at the horizon:
    ``"touch"`` one touch each (every value a lower bound), ``"entropy"``
    max(1, log |T| / rate) (see the module's text). With `whole`, a search two
    touches deep that the budget cannot pay for to the end (one valuation per
    distinct set the root paths leave) is not begun: `truncated`, every value a
    bound, nothing spent (for a caller that throws a cut search away).

    >>> from planner.planning.bitsets import SurvivorTable
    >>> eye = np.eye(3, dtype=bool)
    >>> pair = eye.copy(); pair[1, 2] = pair[2, 1] = True
    >>> table = SurvivorTable.from_matrix(np.stack([pair, eye]), np.ones(3) / 3)
    >>> expected_remaining(table, depth=2).value.round(3).tolist()
    [1.667, 1.0]
    """
    if depth is not None and depth < 1:
        raise ValueError("depth must be >= 1 or None")
    if leaf not in LEAVES:
        raise ValueError(f"leaf must be one of {LEAVES}")
    full = _full_state(table, state)
    gain = state_gain(table, full)
    search = _Search(table, budget or Budget(), _rate(gain) if leaf == "entropy" else None, whole)
    root_paths = np.arange(table.n_paths) if paths is None else np.asarray(paths, dtype=int)
    extra = np.zeros(table.n_paths) if extra_cost is None else np.asarray(extra_cost, float)
    return search.rank(full, depth, root_paths, top_k, extra, gain)


def state_gain(table: SurvivorTable, state: np.ndarray) -> np.ndarray:
    """(C,) each path's expected entropy reduction (nats) of the classes of the set
    `state` (W,)."""
    return information_gain(table, table.weight * unpack_bits(state, table.n_classes))


def information_rate(table: SurvivorTable, state: np.ndarray) -> float | None:
    """The most information (nats) one path gives on the set `state` (W,); None
    when none gives any."""
    return _rate(state_gain(table, state))


def _rate(gain: np.ndarray) -> float | None:
    best = float(gain.max(initial=0.0))
    return best if best > 1e-9 else None


def state_value(
    table: SurvivorTable,
    depth: int | None = None,
    *,
    state: np.ndarray | None = None,
    budget: Budget | None = None,
) -> float:
    """E(S) itself: expected touches still needed from state S under the best
    policy searched `depth` touches deep (None: exact).

    Raises TimeoutError when the budget passes first.
    """
    search = _Search(table, budget or Budget())
    try:
        return search.value(_full_state(table, state), depth)
    except OutOfBudgetError as exc:
        raise TimeoutError("search did not finish before the budget") from exc
