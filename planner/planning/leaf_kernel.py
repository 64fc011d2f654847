"""One-touch values of many survivor sets at once, compiled (DESIGN §4.12).

:meth:`planner.planning.search_nodes.SearchSpace.bound_one` values each set T
(a bitset of classes) by ``min_P (1 + sum_{open} w(h|T) leaf(|S_P(h) & T|)) /
(1 - w(stay | T))`` over the undominated paths P. As array passes that is an
(n, M, C, W) intersection, its popcount, and three (n, M, C) masks; here it is
one pass that keeps only the running sums of one (set, path) at a time.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from planner.compiled import c_array

__all__ = ["one_touch_values"]

_M1 = np.uint64(0x5555555555555555)
_M2 = np.uint64(0x3333333333333333)
_M4 = np.uint64(0x0F0F0F0F0F0F0F0F)
_H01 = np.uint64(0x0101010101010101)


@numba.njit(cache=True, nogil=True)
def _popcount(x):  # type: ignore[no-untyped-def]
    x = x - ((x >> np.uint64(1)) & _M1)
    x = (x & _M2) + ((x >> np.uint64(2)) & _M2)
    x = (x + (x >> np.uint64(4))) & _M4
    return (x * _H01) >> np.uint64(56)


@numba.njit(cache=True, nogil=True)
def _common(a, b):  # type: ignore[no-untyped-def]
    """How many classes two bitsets (W,) share."""
    count = 0
    for k in range(a.shape[0]):
        count += int(_popcount(a[k] & b[k]))
    return count


@numba.njit(cache=True, nogil=True)
def _clique(group, near, near_apart):  # type: ignore[no-untyped-def]
    """Are the classes of `group` (W,) among a class' inseparable neighbours `near`
    (G,) pairwise inseparable? `near_apart` (G,): G-bit masks of which neighbours
    are separable from each."""
    local = np.uint64(0)
    for q in range(near.shape[0]):
        nb = near[q]
        if nb >= 0 and (group[nb // 64] >> np.uint64(nb % 64)) & np.uint64(1):
            local |= np.uint64(1) << np.uint64(q)
    for q in range(near.shape[0]):
        if (local >> np.uint64(q)) & np.uint64(1) and (near_apart[q] & local) != 0:
            return False
    return True


@numba.njit(cache=True, nogil=True)
def _values(rows, sets, idx, w, inseparable, near, near_apart, size, clique, rate, out):  # type: ignore[no-untyped-def]
    """With `near` of shape (K, G) the groups and their cliques are found here, once
    per member and only where a child's count asks; otherwise `size` and `clique`
    (n, M) are given (or zero when no classes are inseparable)."""
    n, m_max = idx.shape
    n_paths, n_words = rows.shape[1], rows.shape[2]
    lazy = near.shape[0] > 0
    group = np.zeros(n_words, dtype=np.uint64)
    for b in range(n):
        members = 0
        for m in range(m_max):
            if idx[b, m] >= 0:
                members += 1
        if lazy:
            for m in range(m_max):
                g = idx[b, m]
                if g < 0:
                    continue
                size[b, m] = _common(inseparable[g], sets[b])
                clique[b, m] = False
        known = np.zeros(m_max, dtype=np.bool_)
        best = math.inf
        for c in range(n_paths):
            w_stay = 0.0
            w_open = 0.0
            for m in range(m_max):
                g = idx[b, m]
                if g < 0:
                    continue
                count = _common(rows[g, c], sets[b])
                if count == members:
                    w_stay += w[b, m]
                    continue
                if count <= 1:
                    continue  # settled
                if count == size[b, m]:
                    if lazy and not known[m]:
                        for k in range(n_words):
                            group[k] = inseparable[g, k] & sets[b, k]
                        clique[b, m] = _clique(group, near[g], near_apart[g])
                        known[m] = True
                    if clique[b, m]:
                        continue  # settled: exactly its pairwise inseparable group
                if rate > 0:
                    w_open += w[b, m] * max(1.0, math.log(max(count, 1)) / rate)
                else:
                    w_open += w[b, m]
            if w_stay < 1 - 1e-12:
                value = (1.0 + w_open) / (1.0 - w_stay)
                if value < best:
                    best = value
        out[b] = best


def one_touch_values(
    rows: np.ndarray,
    sets: np.ndarray,
    idx: np.ndarray,
    w: np.ndarray,
    rate: float | None,
    *,
    inseparable: np.ndarray | None = None,
    near: np.ndarray | None = None,
    near_apart: np.ndarray | None = None,
    size: np.ndarray | None = None,
    clique: np.ndarray | None = None,
) -> np.ndarray:
    """(n,) the best one-touch value of each set (n, W) with members idx (n, M) (-1:
    padding) weighing w (n, M): `rows` (K, C, W) the survivor sets of each class
    along each path; leaves are valued at ``max(1, log(count) / rate)`` (one touch
    when `rate` is None). A child ``S_P(h) & T`` is settled when it holds at most
    one class, or exactly the classes inseparable from h (`inseparable` (K, W))
    when those are pairwise inseparable: found from each class' inseparable
    neighbours `near` and `near_apart` (:func:`~planner.planning.bitsets.inseparable_neighbours`),
    or given per member as the group's `size` and whether it is a `clique` (n, M).
    inf where no path is informative."""
    out = np.empty(len(sets))
    n_words = sets.shape[-1]
    if near is None or near_apart is None or inseparable is None:
        near = np.zeros((0, 1), dtype=np.int64)
        near_apart = np.zeros((0, 1), dtype=np.uint64)
        inseparable = np.zeros((0, n_words), dtype=np.uint64)
        size = np.zeros(idx.shape, dtype=np.int64) if size is None else size
        clique = np.zeros(idx.shape, dtype=bool) if clique is None else clique
    else:
        size, clique = np.zeros(idx.shape, dtype=np.int64), np.zeros(idx.shape, dtype=bool)
    _values(
        c_array(rows, dtype=np.uint64),
        c_array(sets, dtype=np.uint64),
        c_array(idx, dtype=np.int64),
        c_array(w, dtype=np.float64),
        c_array(inseparable, dtype=np.uint64),
        c_array(near, dtype=np.int64),
        c_array(near_apart, dtype=np.uint64),
        c_array(size, dtype=np.int64),
        c_array(clique, dtype=np.bool_),
        0.0 if rate is None else float(rate),
        out,
    )
    return out
