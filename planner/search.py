"""Expected remaining touches E(S): depth-limited lookahead and the exact `optimal` DP.

States are sets S of equivalence classes stored as bitsets (see
:mod:`planner.bitsets`); the outcome matrix is computed once and survivor sets
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
that some path can split needs at least one touch. The same bound orders and
prunes the paths at every node (branch and bound), and values are memoized on
(state bitset, depth); values known to be exact (depth >= classes - 1, or no
depth limit) are shared between depths. Without a depth limit the search is
the exact dynamic programme over survivor sets (`optimal`).
"""

from __future__ import annotations

import bisect
import time
from dataclasses import dataclass
from typing import Any

import numpy as np

from planner.bitsets import pack_bits, popcount, unpack_bits
from planner.outcomes import SurvivorTable

__all__ = ["Deadline", "SearchResult", "expected_remaining", "state_value"]


class _OutOfTimeError(Exception):
    """Raised inside the search when the deadline passes."""


@dataclass(frozen=True)
class Deadline:
    """A point in `time.perf_counter()` seconds after which search stops (inf: never)."""

    end: float = float("inf")

    @classmethod
    def after_ms(cls, budget_ms: float | None) -> Deadline:
        if budget_ms is None:
            return cls()
        return cls(time.perf_counter() + budget_ms / 1000.0)

    def expired(self) -> bool:
        return time.perf_counter() > self.end

    def check(self) -> None:
        if time.perf_counter() > self.end:
            raise _OutOfTimeError


@dataclass(frozen=True, eq=False)
class SearchResult:
    """Expected remaining touches of each root path, this touch included.

    `value` (C,) is exact where `exact` is set and a lower bound elsewhere
    (paths pruned as outside the best `top_k`, or not reached before the
    deadline); inf for paths uninformative at the root. `truncated` says the
    deadline stopped the search; `states` counts the states expanded.
    """

    value: np.ndarray
    exact: np.ndarray
    truncated: bool
    states: int


@dataclass(frozen=True, eq=False)
class _Node:
    child: np.ndarray  # (C, m, W) survivor sets S_P(h) & S
    weight: np.ndarray  # (m,) w(h|S)
    w_stay: np.ndarray  # (C,) weight of truths that leave S unchanged
    open: np.ndarray  # (C, m) children that are neither S nor settled
    bound: np.ndarray  # (C,) admissible lower bound of E_P(S); inf when uninformative


class _Search:
    def __init__(self, table: SurvivorTable, deadline: Deadline) -> None:
        self.bits = table.bits
        self.weight = table.weight
        self.n = table.n_classes
        self.inseparable = table.inseparable
        self.separable = ~unpack_bits(table.inseparable, self.n)
        self.any_inseparable = bool((~self.separable & ~np.eye(self.n, dtype=bool)).any())
        self.one_word = self.bits.shape[-1] == 1
        self.bits1 = self.bits[..., 0]  # the only word when one_word
        self.deadline = deadline
        self.exact: dict[bytes, float] = {}
        self.limited: dict[tuple[bytes, int], float] = {}
        self.states = 0

    def settled(self, sets: np.ndarray, idx: np.ndarray, truth: np.ndarray | None = None) -> Any:
        """(...) bool: which sets (..., W) within the classes idx no path can split.

        `truth` (..., class index) names a member of each set: a settled set lies
        within that member's inseparable classes, a cheap first filter.
        """
        if sets.ndim == 1:
            one = None if truth is None else np.asarray(truth)[None]
            return bool(self.settled(sets[None], idx, one)[0])
        single = popcount(sets) <= 1
        if not self.any_inseparable:
            return single
        maybe = ~single
        if truth is not None:
            outside = sets & ~self.inseparable[truth]
            maybe &= ~np.any(outside != 0, axis=-1)
        out = single.copy()
        if maybe.any():
            member = unpack_bits(sets[maybe], self.n)[..., idx].astype(np.float32)
            apart = self.separable[np.ix_(idx, idx)].astype(np.float32)
            # settled iff no two members j, l are separable: m^T A m == 0
            out[maybe] = np.einsum("...j,...j->...", member @ apart, member) == 0
        return out

    def expand(self, state: np.ndarray, idx: np.ndarray) -> _Node:
        self.states += 1
        w = self.weight[idx]
        w = w / w.sum() if w.sum() > 0 else np.full(len(idx), 1.0 / len(idx))
        if self.one_word and not self.any_inseparable:
            # fast path: one word per set; a set x is a single class iff x & (x - 1) == 0
            word = self.bits1[:, idx] & state[0]
            stay = word == state[0]
            open_ = ~stay & ((word & (word - np.uint64(1))) != 0)
            child = word[..., None]
        else:
            child = self.bits[:, idx, :] & state
            stay = np.all(child == state, axis=-1)
            truth = np.broadcast_to(idx, stay.shape)
            open_ = ~stay & ~self.settled(child, idx, truth)
        w_stay = stay.astype(float) @ w
        informative = w_stay < 1 - 1e-12
        bound = np.full(len(child), np.inf)
        # E_P(S) >= (1 + sum_{open children} w(h|S) * 1) / (1 - w_stay)
        bound[informative] = (1.0 + open_[informative].astype(float) @ w) / (
            1.0 - w_stay[informative]
        )
        return _Node(child, w, w_stay, open_, bound)

    def value(self, state: np.ndarray, depth: int | None) -> float:
        """E(S) searched `depth` touches deep (None: exact)."""
        self.deadline.check()
        key = state.tobytes()
        known = self.exact.get(key)
        if known is not None:
            return known
        if depth is not None and (key, depth) in self.limited:
            return self.limited[key, depth]
        idx = np.flatnonzero(unpack_bits(state, self.n))
        if len(idx) <= 1 or self.settled(state, idx):
            self.exact[key] = 0.0
            return 0.0
        if depth == 0:
            return 1.0  # admissible leaf bound: S can be split, so at least one touch
        node = self.expand(state, idx)
        if depth == 1:
            best = float(node.bound.min())  # children are leaves worth 0 or 1: exact
        else:
            # E(S) = 1 + min_P sum_h w(h|S) E(S_P(h) & S), paths in order of their bound
            best = np.inf
            child_depth = None if depth is None else depth - 1
            for c in np.argsort(node.bound, kind="stable"):
                if not node.bound[c] < best - 1e-12:
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
        self, node: _Node, c: int, depth: int | None, cutoff: float
    ) -> tuple[float, bool]:
        """E_P(S) for path c; stops early (returning a lower bound, False) once it
        cannot get below `cutoff`."""
        ks = np.flatnonzero(node.open[c])
        denom = 1.0 - node.w_stay[c]
        rest = float(node.weight[ks].sum())
        total = 1.0
        for k in ks:
            # E_P(S) = (1 + sum_h w(h|S) E(S_P(h) & S)) / (1 - w_stay)
            total += node.weight[k] * self.value(node.child[c, k], depth)
            rest -= node.weight[k]
            if (total + rest) / denom >= cutoff:
                return (total + rest) / denom, False
        return total / denom, True

    def rank(
        self,
        state: np.ndarray,
        depth: int | None,
        paths: np.ndarray,
        top_k: int | None,
        extra: np.ndarray,
    ) -> SearchResult:
        n_paths = self.bits.shape[0]
        value = np.full(n_paths, np.inf)
        exact = np.zeros(n_paths, dtype=bool)
        idx = np.flatnonzero(unpack_bits(state, self.n))
        if len(idx) <= 1 or self.settled(state, idx):
            value[paths], exact[paths] = 0.0, True
            return SearchResult(value, exact, False, self.states)
        node = self.expand(state, idx)
        value[paths] = node.bound[paths]
        uninformative = paths[~np.isfinite(node.bound[paths])]
        exact[uninformative] = True
        if depth == 1:
            exact[paths] = True
            return SearchResult(value, exact, False, self.states)
        child_depth = None if depth is None else depth - 1
        live = paths[np.isfinite(node.bound[paths])]
        order = live[np.argsort(node.bound[live] + extra[live], kind="stable")]
        best: list[float] = []  # sorted exact objectives found so far
        truncated = False
        for c in order:
            threshold = best[top_k - 1] if top_k is not None and len(best) >= top_k else np.inf
            if node.bound[c] + extra[c] >= threshold:
                break
            try:
                v, done = self.path_value(node, int(c), child_depth, threshold - extra[c])
            except _OutOfTimeError:
                truncated = True
                break
            value[c] = v
            if done:
                exact[c] = True
                bisect.insort(best, v + extra[c])
        return SearchResult(value, exact, truncated, self.states)


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
    deadline: Deadline | None = None,
    state: np.ndarray | None = None,
) -> SearchResult:
    """Expected remaining touches E_P(S) of each root path P (this touch included).

    `depth` touches are searched exactly (None: no limit, the exact DP; use
    only for a few classes); `paths` limits the root paths scored (inner nodes
    always use every path); with `top_k`, only the best `top_k` by
    ``E_P + extra_cost`` are guaranteed exact and the others may keep their
    lower bound; `deadline` stops the search (anytime: the best found so far,
    `truncated` set); `state` is the hypothesis set S (bool over classes or a
    bitset; default all classes).

    >>> from planner.outcomes import SurvivorTable
    >>> eye = np.eye(3, dtype=bool)
    >>> pair = eye.copy(); pair[1, 2] = pair[2, 1] = True
    >>> table = SurvivorTable.from_matrix(np.stack([pair, eye]), np.ones(3) / 3)
    >>> expected_remaining(table, depth=2).value.round(3).tolist()
    [1.667, 1.0]
    """
    if depth is not None and depth < 1:
        raise ValueError("depth must be >= 1 or None")
    search = _Search(table, deadline or Deadline())
    root_paths = np.arange(table.n_paths) if paths is None else np.asarray(paths, dtype=int)
    extra = np.zeros(table.n_paths) if extra_cost is None else np.asarray(extra_cost, float)
    return search.rank(_full_state(table, state), depth, root_paths, top_k, extra)


def state_value(
    table: SurvivorTable,
    depth: int | None = None,
    *,
    state: np.ndarray | None = None,
    deadline: Deadline | None = None,
) -> float:
    """E(S) itself: expected touches still needed from state S under the best
    policy searched `depth` touches deep (None: exact).

    Raises TimeoutError when the deadline passes first.
    """
    search = _Search(table, deadline or Deadline())
    try:
        return search.value(_full_state(table, state), depth)
    except _OutOfTimeError as exc:
        raise TimeoutError("search did not finish before the deadline") from exc
