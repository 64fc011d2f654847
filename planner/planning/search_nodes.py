"""Nodes of the search over survivor sets (DESIGN §4.12): expansion, settled states, bounds.

A state is a set S of equivalence classes stored as a bitset (see
:mod:`planner.planning.bitsets`). Expanding S gives, for every path P and truth
h in S, the child ``S_P(h) & S`` (a restriction of the survivor table computed
once), the weights w(h|S), the weight of truths that leave S unchanged, and the
admissible one-touch bound on the expected remaining touches::

    E_P(S) >= (1 + sum_{open children} w(h|S)) / (1 - w_stay(P|S))

where a child is open when it is neither S itself nor settled. A state is
settled when no path can split it: it holds one class, or only classes that are
pairwise inseparable. The search that walks these nodes is in
:mod:`planner.planning.search`.

An open set at the search's horizon (a leaf) is valued at one touch, which keeps
every value a lower bound, or, given the information `rate` (nats) of the best
path at the root, at ``max(1, log |T| / rate)``: a large set left at the horizon
costs the touches it would take at that rate. `one_deep` and `bound_one` value
leaves so; `bound` always counts one touch (it prunes).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from typing import Any

import numpy as np

from planner.planning.bitsets import (
    SurvivorTable,
    popcount,
    unpack_bits,
)
from planner.planning.leaf_kernel import cliques, one_touch_values, undominated

__all__ = ["Node", "SearchSpace"]


@dataclass(frozen=True, eq=False)
class Node:
    """A state S expanded over C paths; S has m member classes."""

    child: np.ndarray  # (C, m, W) survivor sets S_P(h) & S
    weight: np.ndarray  # (m,) w(h|S)
    w_stay: np.ndarray  # (C,) weight of truths that leave S unchanged
    open: np.ndarray  # (C, m) children that are neither S nor settled
    bound: np.ndarray  # (C,) admissible lower bound of E_P(S); inf when uninformative
    one_deep: np.ndarray  # (C,) E_P(S) one touch deep, open children at their leaf value


class SearchSpace:
    """The survivor table as the search reads it: the survivor bitsets `bits`
    (C, K, W) and by class (K, C, W), the class weights, which classes no path
    tells apart, the information `rate` leaves are valued at (None: one touch);
    `states` counts the states expanded (one-touch bounds included).

    >>> from planner.planning.bitsets import SurvivorTable, pack_bits
    >>> eye = np.eye(3, dtype=bool)
    >>> space = SearchSpace(SurvivorTable.from_matrix(eye[None], np.ones(3) / 3))
    >>> space.expand(pack_bits(np.ones(3, dtype=bool)), np.arange(3)).bound.tolist()
    [1.0]
    """

    def __init__(self, table: SurvivorTable, rate: float | None = None) -> None:
        self.rate = rate
        self.bits = table.bits
        self.weight = table.weight
        self.n = table.n_classes
        self.inseparable = table.inseparable
        self.separable = ~unpack_bits(table.inseparable, self.n)
        self.apart = ~table.inseparable  # (K, W): classes some path tells from each class
        self.by_class = np.ascontiguousarray(np.swapaxes(self.bits, 0, 1))  # (K, C, W)
        self.any_inseparable = bool((~self.separable & ~np.eye(self.n, dtype=bool)).any())
        self.one_word = self.bits.shape[-1] == 1
        self.states = 0

    def leaf_value(self, count: np.ndarray | int) -> np.ndarray:
        """Touches an open leaf set of `count` classes is valued at: 1 without a
        `rate`, else max(1, log(count) / rate)."""
        count = np.asarray(count, dtype=float)
        if self.rate is None:
            return np.ones_like(count)
        return np.maximum(1.0, np.log(np.maximum(count, 1.0)) / self.rate)

    @cached_property
    def leaf(self) -> np.ndarray:
        """The paths one touch deep values need: no other path dominates them.

        If S_Q(h) is within S_Q'(h) for every h, then in any state T every member
        Q' leaves settled Q does too and every member Q leaves with T Q' does too;
        (1 + o) / (1 - s) grows with s and with o + s, so Q's one-touch bound
        ``(1 + w(open | T)) / (1 - w(stay | T))`` is never above Q''s. (Deeper
        values need not follow: E is not monotone in the set. With leaves valued
        above one touch, a path can beat one that dominates it only through a stay
        worth less than a leaf; one-touch values still take these paths only.)"""
        return undominated(self.bits)

    @cached_property
    def leaf_by_class(self) -> np.ndarray:
        """(K, leaf paths, W): `by_class` on the `leaf` paths."""
        return np.ascontiguousarray(self.by_class[:, self.leaf])

    def settled(self, state: np.ndarray, idx: np.ndarray) -> bool:
        """Can no path split the set `state` (W,) of the classes `idx`?"""
        if len(idx) <= 1:
            return True
        if not self.any_inseparable or np.any(state & self.apart[idx[0]] != 0):
            return False
        return bool(cliques(state[None], self.apart)[0])

    def settled_many(self, sets: np.ndarray, idx: np.ndarray) -> np.ndarray:
        """(n,) bool: which sets (n, W) with members idx (n, M) no path can split."""
        single = popcount(sets) <= 1
        if not self.any_inseparable:
            return single
        first = np.maximum(idx[:, 0], 0)
        inside = ~np.any(sets & self.apart[first] != 0, axis=-1) & ~single
        return single | self._cliques(sets, np.where(inside, 2, 0))

    def _cliques(self, group: np.ndarray, size: np.ndarray) -> np.ndarray:
        """Are the classes of each group (..., W) pairwise inseparable? False where
        its `size` (...) is under two (a group of one is settled anyway)."""
        out = np.zeros(size.shape, dtype=bool)
        pick = np.nonzero(size >= 2)
        if len(pick[0]):
            out[pick] = cliques(group[pick], self.apart)
        return out

    def expand(self, state: np.ndarray, idx: np.ndarray, paths: Any = slice(None)) -> Node:
        """The node of state S (classes idx): its children over `paths` (default all)."""
        self.states += 1
        w = self.weight[idx]
        w = w / w.sum() if w.sum() > 0 else np.full(len(idx), 1.0 / len(idx))
        bits = self.bits[paths]
        if self.one_word and not self.any_inseparable:
            # fast path: one word per set; a set x is a single class iff x & (x - 1) == 0
            word = bits[:, idx, 0] & state[0]
            stay = word == state[0]
            open_ = ~stay & ((word & (word - np.uint64(1))) != 0)
            child = word[..., None]
            count = popcount(child)
        else:
            child = bits[:, idx, :] & state
            # S_P(h) & S lies within S: it is S when it has as many members
            count = popcount(child)
            stay = count == len(idx)
            settled = count <= 1
            if self.any_inseparable:
                # S_P(h) & S always holds the classes inseparable from h; it is settled
                # when it holds no more (as many members) and those are pairwise inseparable
                group = self.inseparable[idx] & state
                size = popcount(group)
                settled |= (count == size) & self._cliques(group, size)
            open_ = ~stay & ~settled
        w_stay = stay.astype(float) @ w
        informative = w_stay < 1 - 1e-12
        bound = np.full(len(child), np.inf)
        # E_P(S) >= (1 + sum_{open children} w(h|S) * 1) / (1 - w_stay)
        bound[informative] = (1.0 + open_[informative].astype(float) @ w) / (
            1.0 - w_stay[informative]
        )
        one_deep = bound.copy()
        if self.rate is not None:
            # E_P(S) one touch deep: (1 + sum_{open} w(h|S) leaf(|S_P(h) & S|)) / (1 - w_stay)
            leaf = np.where(open_, self.leaf_value(count), 0.0)
            one_deep[informative] = (1.0 + leaf[informative] @ w) / (1.0 - w_stay[informative])
        return Node(child, w, w_stay, open_, bound, one_deep)

    def bound_one(self, sets: np.ndarray, idx: np.ndarray) -> np.ndarray:
        """(n,) min over paths of the one-touch value of each set T (n, W) with
        members idx (n, M) (-1 = padding): `expand(T).one_deep.min()` for a batch."""
        self.states += len(sets)
        real = idx >= 0
        g = np.maximum(idx, 0)
        w = np.where(real, self.weight[g], 0.0)
        total = w.sum(axis=1, keepdims=True)
        # w(h|T), uniform when T weighs nothing
        w = np.where(total > 0, w / np.where(total > 0, total, 1.0), real / real.sum(1)[:, None])
        # a child holding exactly the classes inseparable from h is settled when they
        # are a clique (a group of one is settled by the count already)
        inseparable = self.inseparable if self.any_inseparable else None
        return one_touch_values(self.leaf_by_class, sets, idx, w, self.rate, inseparable)
