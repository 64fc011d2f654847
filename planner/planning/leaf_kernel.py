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
def _values(rows, sets, idx, w, size, clique, rate, out):  # type: ignore[no-untyped-def]
    n, m_max = idx.shape
    n_paths, n_words = rows.shape[1], rows.shape[2]
    for b in range(n):
        members = 0
        for m in range(m_max):
            if idx[b, m] >= 0:
                members += 1
        best = math.inf
        for c in range(n_paths):
            w_stay = 0.0
            w_open = 0.0
            for m in range(m_max):
                g = idx[b, m]
                if g < 0:
                    continue
                count = 0
                for k in range(n_words):
                    count += _popcount(rows[g, c, k] & sets[b, k])
                if count == members:
                    w_stay += w[b, m]
                elif count <= 1 or (clique[b, m] and count == size[b, m]):
                    continue  # settled
                elif rate > 0:
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
    size: np.ndarray,
    clique: np.ndarray,
    rate: float | None,
) -> np.ndarray:
    """(n,) the best one-touch value of each set (n, W) with members idx (n, M) (-1:
    padding) weighing w (n, M): `rows` (K, C, W) the survivor sets of each class
    along each path; a child ``S_P(h) & T`` is settled when it holds at most one
    class, or exactly the `size` (n, M) classes inseparable from h when those are a
    `clique` (n, M); leaves are valued at ``max(1, log(count) / rate)`` (one touch
    when `rate` is None). inf where no path is informative."""
    out = np.empty(len(sets))
    _values(
        np.ascontiguousarray(rows, dtype=np.uint64),
        np.ascontiguousarray(sets, dtype=np.uint64),
        np.ascontiguousarray(idx, dtype=np.int64),
        np.ascontiguousarray(w, dtype=np.float64),
        np.ascontiguousarray(size, dtype=np.int64),
        np.ascontiguousarray(clique, dtype=np.bool_),
        0.0 if rate is None else float(rate),
        out,
    )
    return out
