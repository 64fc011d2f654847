"""One-touch values of many survivor sets at once, compiled (DESIGN §4.12).

:meth:`planner.planning.search_nodes.SearchSpace.bound_one` values each set T
(a bitset of classes) by ``min_P (1 + sum_{open} w(h|T) leaf(|S_P(h) & T|)) /
(1 - w(stay | T))`` over the undominated paths P. As array passes that is an
(n, M, C, W) intersection, its popcount, and three (n, M, C) masks; here it is
one pass that keeps only the running sums of one (set, path) at a time. The paths
it runs over are the undominated ones, and its settled sets are cliques of
inseparable classes: both found here too, with early exits.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from planner.compiled import c_array

__all__ = ["cliques", "one_touch_values", "undominated"]

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
def _clique(group, apart):  # type: ignore[no-untyped-def]
    """Are the classes of `group` (W,) pairwise inseparable? `apart` (K, W): the
    classes some path tells from each class."""
    for k in range(group.shape[0]):
        word = group[k]
        for bit in range(64):
            if word == 0:
                break
            if word & np.uint64(1):
                for q in range(group.shape[0]):
                    if group[q] & apart[k * 64 + bit, q]:
                        return False
            word >>= np.uint64(1)
    return True


@numba.njit(cache=True, nogil=True)
def _cliques(groups, apart, out):  # type: ignore[no-untyped-def]
    for i in range(groups.shape[0]):
        out[i] = _clique(groups[i], apart)


def cliques(groups: np.ndarray, apart: np.ndarray) -> np.ndarray:
    """(m,) bool: are the classes of each bitset in `groups` (m, W) pairwise
    inseparable, `apart` (K, W) the classes some path tells from each class?

    >>> apart = np.array([[2], [1], [0]], dtype=np.uint64)  # classes 0 and 1 apart
    >>> cliques(np.array([[3], [5], [6], [7]], dtype=np.uint64), apart).tolist()
    [False, True, True, False]
    """
    out = np.empty(len(groups), dtype=np.bool_)
    _cliques(c_array(groups, dtype=np.uint64), c_array(apart, dtype=np.uint64), out)
    return out


@numba.njit(cache=True, nogil=True)
def _values(rows, sets, idx, w, inseparable, apart, rate, out):  # type: ignore[no-untyped-def]
    """The groups of inseparable classes and their cliques are found once per member
    and only where a child's count asks (none when `inseparable` is empty)."""
    n, m_max = idx.shape
    n_paths, n_words = rows.shape[1], rows.shape[2]
    lazy = inseparable.shape[0] > 0
    group = np.zeros(n_words, dtype=np.uint64)
    size = np.zeros(m_max, dtype=np.int64)
    clique = np.zeros(m_max, dtype=np.bool_)
    w_stay, w_open = np.zeros(n_paths), np.zeros(n_paths)
    for b in range(n):
        members = 0
        for m in range(m_max):
            g = idx[b, m]
            if g >= 0:
                members += 1
                # without inseparable classes 0: never an open child's count (>= 2)
                size[m] = _common(inseparable[g], sets[b]) if lazy else 0
                clique[m] = False
        # member by member over every path (each member's rows lie side by side),
        # each path's sums taken in member order
        w_stay[:] = 0.0
        w_open[:] = 0.0
        for m in range(m_max):
            g = idx[b, m]
            if g < 0:
                continue
            known = False
            for c in range(n_paths):
                count = _common(rows[g, c], sets[b])
                if count == members:
                    w_stay[c] += w[b, m]
                    continue
                if count <= 1:
                    continue  # settled
                if count == size[m]:
                    if not known:
                        for k in range(n_words):
                            group[k] = inseparable[g, k] & sets[b, k]
                        clique[m] = _clique(group, apart)
                        known = True
                    if clique[m]:
                        continue  # settled: exactly its pairwise inseparable group
                if rate > 0:
                    w_open[c] += w[b, m] * max(1.0, math.log(max(count, 1)) / rate)
                else:
                    w_open[c] += w[b, m]
        best = math.inf
        for c in range(n_paths):
            if w_stay[c] < 1 - 1e-12:
                value = (1.0 + w_open[c]) / (1.0 - w_stay[c])
                if value < best:
                    best = value
        out[b] = best


def one_touch_values(
    rows: np.ndarray,
    sets: np.ndarray,
    idx: np.ndarray,
    w: np.ndarray,
    rate: float | None,
    inseparable: np.ndarray | None = None,
) -> np.ndarray:
    """(n,) the best one-touch value of each set (n, W) with members idx (n, M) (-1:
    padding) weighing w (n, M): `rows` (K, C, W) the survivor sets of each class
    along each path; leaves are valued at ``max(1, log(count) / rate)`` (one touch
    when `rate` is None). A child ``S_P(h) & T`` is settled when it holds at most
    one class, or exactly the classes `inseparable` (K, W) from h (None: each class
    only from itself) when those are pairwise inseparable. inf where no path is
    informative."""
    out = np.empty(len(sets))
    if inseparable is None:
        inseparable = np.zeros((0, sets.shape[-1]), dtype=np.uint64)
    inseparable = c_array(inseparable, dtype=np.uint64)
    _values(
        c_array(rows, dtype=np.uint64),
        c_array(sets, dtype=np.uint64),
        c_array(idx, dtype=np.int64),
        c_array(w, dtype=np.float64),
        inseparable,
        ~inseparable,
        0.0 if rate is None else float(rate),
        out,
    )
    return out


@numba.njit(cache=True, nogil=True)
def _dominated(rows, out):  # type: ignore[no-untyped-def]
    """out[r]: some other row q of the distinct rows (n, L) lies within row r."""
    n, width = rows.shape
    for r in range(n):
        for q in range(n):
            if q == r:
                continue
            within = True
            for k in range(width):
                if rows[q, k] & ~rows[r, k]:
                    within = False
                    break
            if within:
                out[r] = True
                break


def undominated(bits: np.ndarray) -> np.ndarray:
    """Indices of the paths (C, K, W) that no other path dominates, the first of
    identical ones kept.

    Path Q dominates Q' when S_Q(h) is within S_Q'(h) for every class h: whatever
    the truth, Q leaves no more classes than Q' (:mod:`planner.planning.search_nodes` uses
    it for one-touch values).

    >>> from planner.planning.bitsets import pack_bits
    >>> eye, full = np.eye(2, dtype=bool), np.ones((2, 2), dtype=bool)
    >>> undominated(pack_bits(np.stack([full, eye, eye]))).tolist()
    [1]
    """
    flat = c_array(np.asarray(bits).reshape(len(bits), -1), dtype=np.uint64)
    first: dict[bytes, int] = {}
    for i, row in enumerate(flat):
        first.setdefault(row.tobytes(), i)
    kept = np.fromiter(first.values(), dtype=np.intp, count=len(first))
    dominated = np.zeros(len(kept), dtype=np.bool_)
    _dominated(flat[kept], dominated)
    return kept[~dominated]
