"""Sets of equivalence classes (or hypotheses) as packed bitsets (numpy uint64 words),
and interval-overlap relations answered as unions of such sets.

Class j is bit ``j % 64`` of word ``j // 64``; a set over K classes takes
``W = ceil(K / 64)`` words (at least one). Words are kept in numpy arrays so that
whole tables of sets are combined in one pass; a set's `bytes` is its memo key.
:class:`IntervalUnions` holds, per row, intervals with owners sorted by each end,
and gives the owners of the intervals overlapping a query interval.

>>> words = pack_bits(np.array([True, False, True]))
>>> int(words[0]), unpack_bits(words, 3).tolist(), int(popcount(words))
(5, [True, False, True], 2)
"""

from __future__ import annotations

from dataclasses import dataclass

import numba
import numpy as np

from planner.compiled import c_array
from planner.errors import PlannerError

__all__ = [
    "IntervalUnions",
    "SurvivorTable",
    "close_ends",
    "compact",
    "n_words",
    "one_hot",
    "pack_bits",
    "popcount",
    "prefix_or",
    "sorted_count",
    "to_int",
    "transpose_bits",
    "unpack_bits",
    "weighted_count",
]

_BYTE_COUNTS = np.array([bin(i).count("1") for i in range(256)], dtype=np.uint8)


def n_words(n_bits: int) -> int:
    """Words needed for `n_bits` bits (at least one)."""
    return max(1, -(-n_bits // 64))


def pack_bits(mask: np.ndarray) -> np.ndarray:
    """(..., K) bool -> (..., W) uint64."""
    mask = np.asarray(mask, dtype=bool)
    width = n_words(mask.shape[-1]) * 64
    padded = np.zeros((*mask.shape[:-1], width), dtype=bool)
    padded[..., : mask.shape[-1]] = mask
    packed = np.packbits(padded, axis=-1, bitorder="little")
    return np.ascontiguousarray(packed).view("<u8").astype(np.uint64)


def unpack_bits(words: np.ndarray, n_bits: int) -> np.ndarray:
    """(..., W) uint64 -> (..., n_bits) bool."""
    raw = np.ascontiguousarray(np.asarray(words, dtype="<u8")).view(np.uint8)
    return np.unpackbits(raw, axis=-1, bitorder="little")[..., :n_bits].astype(bool)


def popcount(words: np.ndarray) -> np.ndarray:
    """Number of set bits of each set: (..., W) uint64 -> (...) int32."""
    words = np.asarray(words, dtype=np.uint64)
    if hasattr(np, "bitwise_count"):
        counts = np.bitwise_count(words)
    else:
        raw = np.ascontiguousarray(words.astype("<u8")).view(np.uint8)
        counts = _BYTE_COUNTS[raw].reshape(*words.shape, 8).sum(axis=-1, dtype=np.uint8)
    # word by word: faster than a sum over the short last axis
    total = np.zeros(words.shape[:-1], dtype=np.int32)
    for k in range(words.shape[-1]):
        total += counts[..., k]
    return total


def to_int(words: np.ndarray) -> int:
    """One set (W,) as a Python int (bit j = class j)."""
    return int.from_bytes(np.asarray(words, dtype="<u8").tobytes(), "little")


def one_hot(index: np.ndarray, width: int) -> np.ndarray:
    """(...) bit indices (negative: none) -> (..., width) uint64 sets of one bit."""
    index = np.asarray(index)
    out = np.zeros((*index.shape, width), dtype=np.uint64)
    where = np.nonzero(index >= 0)
    bit = index[where]
    out[(*where, bit // 64)] = np.left_shift(np.uint64(1), (bit % 64).astype(np.uint64))
    return out


def prefix_or(sets: np.ndarray, axis: int = -2, reverse: bool = False) -> np.ndarray:
    """Running unions along `axis` with an empty set in front: (..., N, W) -> (..., N + 1, W).

    Entry k is the union of the first k sets (`reverse`: of the sets from k on,
    the empty set then standing at the end).
    """
    sets = np.asarray(sets, dtype=np.uint64)
    axis = axis % sets.ndim
    shape = list(sets.shape)
    shape[axis] += 1
    out = np.zeros(shape, dtype=np.uint64)
    inner = (slice(None),) * axis
    if reverse:
        flipped = np.flip(sets, axis)
        np.bitwise_or.accumulate(
            flipped, axis=axis, out=np.flip(out, axis)[(*inner, slice(1, None))]
        )
    else:
        np.bitwise_or.accumulate(sets, axis=axis, out=out[(*inner, slice(1, None))])
    return out


def transpose_bits(rows: np.ndarray, n_cols: int) -> np.ndarray:
    """Transpose bit matrices: (..., R, W) rows of `n_cols` bits -> (..., n_cols, W')
    rows of R bits.

    Works on 8 x 8 blocks of bits, each held in one uint64 (byte i = row i).

    >>> m = np.array([[1, 1, 0], [0, 0, 1]], dtype=bool)
    >>> unpack_bits(transpose_bits(pack_bits(m), 3), 2).astype(int).tolist()
    [[1, 0], [1, 0], [0, 1]]
    """
    rows = np.asarray(rows, dtype=np.uint64)
    *lead, n_rows, n_w = rows.shape
    r8 = -(-n_rows // 8)
    raw = np.zeros((*lead, r8 * 8, n_w * 8), dtype=np.uint8)
    raw[..., :n_rows, :] = np.ascontiguousarray(rows).view(np.uint8)
    # blocks (..., row block, column byte), 8 row bytes each: bit 8 i + j = (row i, column j)
    raw = raw.reshape(*lead, r8, 8, n_w * 8)
    x = np.ascontiguousarray(np.swapaxes(raw, -1, -2)).view(np.uint64)[..., 0]
    for shift, mask in (
        (7, 0x00AA00AA00AA00AA),
        (14, 0x0000CCCC0000CCCC),
        (28, 0x00000000F0F0F0F0),
    ):
        # swap bit (i, j) with bit (j, i) across the diagonal, in three rounds of sub-blocks
        t = (x ^ (x >> np.uint64(shift))) & np.uint64(mask)
        x = x ^ t ^ (t << np.uint64(shift))
    # block (row block b, column byte k) now holds byte j = column 8 k + j over rows 8 b..8 b+7
    out_w = n_words(n_rows)
    blocks = np.ascontiguousarray(x[..., None]).view(np.uint8)  # (..., r8, n_w * 8, 8)
    cols = np.zeros((*lead, n_w * 8, 8, out_w * 8), dtype=np.uint8)
    cols[..., :r8] = np.moveaxis(blocks, -3, -1)
    out = cols.reshape(*lead, n_w * 64, out_w * 8)[..., :n_cols, :]
    return np.ascontiguousarray(out).view(np.uint64)


def weighted_count(words: np.ndarray, weight: np.ndarray) -> np.ndarray:
    """Total weight of the members of each set: (..., W) uint64, (K,) -> (...).

    Sums per byte from a table of the 256 subsets of each byte's 8 classes.
    """
    weight = np.asarray(weight, dtype=float)
    n_bytes = -(-len(weight) // 8)
    padded = np.zeros(n_bytes * 8)
    padded[: len(weight)] = weight
    subsets = ((np.arange(256)[:, None] >> np.arange(8)) & 1).astype(float)
    # table[b, v] = sum of the weights of bits set in byte value v of byte b
    table = padded.reshape(n_bytes, 8) @ subsets.T
    raw = np.ascontiguousarray(np.asarray(words, dtype="<u8")).view(np.uint8)
    total = np.zeros(raw.shape[:-1])
    # byte by byte, in order, as `total += table[b][raw[..., b]]` adds them
    _table_sums(raw.reshape(-1, raw.shape[-1]), c_array(table, dtype=float), total.reshape(-1))
    return total


@numba.njit(cache=True, nogil=True)
def _table_sums(raw, table, out):  # type: ignore[no-untyped-def]
    """out[m] = sum over bytes b of table[b, raw[m, b]], added byte after byte."""
    for m in range(raw.shape[0]):
        total = 0.0
        for b in range(table.shape[0]):
            total += table[b, raw[m, b]]
        out[m] = total


@dataclass(frozen=True, eq=False)
class SurvivorTable:
    """Survivor sets over K equivalence classes for C paths, as bitsets.

    `bits[c, k]` (W uint64 words, bit j = class j) is S_c(k): the classes that
    survive path c when the truth is in class k. `weight` (K,) sums to 1.
    `inseparable` (K, W) marks, for each class, the classes confusable with it
    on every path (no candidate can tell them apart).
    """

    bits: np.ndarray
    weight: np.ndarray
    inseparable: np.ndarray

    @property
    def n_paths(self) -> int:
        return self.bits.shape[0]

    @property
    def n_classes(self) -> int:
        return len(self.weight)

    def matrix(self) -> np.ndarray:
        """(C, K, K) bool: class j survives path c when the truth is class k."""
        return unpack_bits(self.bits, self.n_classes)

    @classmethod
    def from_matrix(cls, confusable: np.ndarray, weight: np.ndarray) -> SurvivorTable:
        """Build from a (C, K, K) boolean matrix (made reflexive) and class weights."""
        conf = np.array(confusable, dtype=bool)
        if conf.ndim != 3 or conf.shape[1] != conf.shape[2]:
            raise PlannerError("must have shape (paths, classes, classes)", field="confusable")
        k = conf.shape[1]
        conf[:, np.arange(k), np.arange(k)] = True
        w = np.asarray(weight, dtype=float)
        if w.shape != (k,) or not np.all(w >= 0) or w.sum() <= 0:
            raise PlannerError("must be K weights >= 0 with a positive sum", field="weight")
        inseparable = np.asarray(conf.all(axis=0)) if len(conf) else np.ones((k, k), dtype=bool)
        return cls(bits=pack_bits(conf), weight=w / w.sum(), inseparable=pack_bits(inseparable))

    @classmethod
    def from_bits(cls, bits: np.ndarray, weight: np.ndarray) -> SurvivorTable:
        """Build from (C, K, W) bitsets (made reflexive) and class weights."""
        w = np.asarray(weight, dtype=float)
        k = len(w)
        bits = np.array(bits, dtype=np.uint64).reshape(-1, k, n_words(k))
        bits |= one_hot(np.arange(k), bits.shape[-1])
        if not (np.all(w >= 0) and w.sum() > 0):
            raise PlannerError("must be K weights >= 0 with a positive sum", field="weight")
        everything = pack_bits(np.ones((k, k), dtype=bool))
        # classes confusable with each class on every path (all, with no path)
        inseparable = np.bitwise_and.reduce(bits, axis=0) if len(bits) else everything
        return cls(bits=bits, weight=w / w.sum(), inseparable=inseparable & everything)


def sorted_count(sorted_rows: np.ndarray, rows: np.ndarray, x: np.ndarray, side: str) -> np.ndarray:
    """``searchsorted(sorted_rows[rows[e]], x[e], side)`` for every e, all at once
    by halving ("right": entries <= x; "left": entries < x).

    >>> sorted_count(np.array([[1.0, 2.0, 2.0], [0.0, 5.0, 9.0]]), np.array([0, 1]),
    ...              np.array([2.0, 5.0]), "right").tolist()
    [3, 2]
    """
    n = sorted_rows.shape[1]
    out = np.empty(len(x), dtype=np.int64)
    _halving_counts(
        c_array(sorted_rows.reshape(-1), dtype=np.float64),
        c_array(rows, dtype=np.int64),
        c_array(x, dtype=np.float64),
        n,
        max(1, n.bit_length()),
        side == "right",
        out,
    )
    return out


@numba.njit(cache=True, nogil=True)
def _halving_counts(flat, rows, x, n, steps, right, out):  # type: ignore[no-untyped-def]
    """:func:`sorted_count` one query at a time, `steps` halvings each (the same
    steps as an array pass would take for all, so the same counts whatever the
    rows hold)."""
    for e in range(x.shape[0]):
        lo, hi, base = 0, n, rows[e] * n
        for _ in range(steps):
            mid = (lo + hi) >> 1
            value = flat[base + min(mid, n - 1)]
            below = value <= x[e] if right else value < x[e]
            if below and mid < hi:
                lo = mid + 1
            else:
                hi = mid
        out[e] = lo


def compact(chosen: np.ndarray) -> np.ndarray:
    """(R, N) bool -> (R, n) indices of the chosen entries of each row, in order
    (-1 = padding; n = the most chosen in a row, at least 1)."""
    n = max(1, int(chosen.sum(axis=1).max(initial=0)))
    r, k = np.nonzero(chosen)
    out = np.full((len(chosen), n), -1)
    out[r, (np.cumsum(chosen, axis=1) - 1)[r, k]] = k
    return out


@dataclass(frozen=True, eq=False)
class IntervalUnions:
    """Intervals [L, R] with owners (bits), per row: `low` (rows, N) the L ends in
    ascending order and `before` (rows, N + 1, W) the union of the owners of the
    first k of them; `high` the R ends ascending and `after` the union of the
    owners from k on (+inf pads both end lists).

    >>> iv = IntervalUnions.of(np.array([[0.0, 5.0]]), np.array([[2.0, 6.0]]),
    ...                        np.array([[3, 7]]), np.array([[True, True]]), 1)
    >>> int(iv.overlapping(np.array([0]), np.array([1.0]), np.array([5.5]))[0, 0])
    136
    """

    low: np.ndarray
    high: np.ndarray
    before: np.ndarray
    after: np.ndarray

    @classmethod
    def of(
        cls,
        low: np.ndarray,
        high: np.ndarray,
        owner: np.ndarray,
        member: np.ndarray,
        width: int,
    ) -> IntervalUnions:
        """From (rows, N) ends, owner bit indices and the member entries."""
        at = compact(member)
        path = np.arange(len(at))[:, None]
        ok = at >= 0
        kept = np.maximum(at, 0)
        lists = []
        for ends, reverse in ((low, False), (high, True)):
            values = np.where(ok, ends[path, kept], np.inf)
            order = np.argsort(values, axis=1)
            sorted_owner = np.where(ok, owner[path, kept], -1)[path, order]
            lists.append((values[path, order], _running_unions(sorted_owner, width, reverse)))
        (low_sorted, before), (high_sorted, after) = lists
        return cls(low_sorted, high_sorted, before, after)

    def overlapping(self, rows: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
        """(E, W) owners on row rows[e] of intervals meeting [lo[e], hi[e]]:
        those with L <= hi and R >= lo."""
        k_low = sorted_count(self.low, rows, hi, "right")
        k_high = sorted_count(self.high, rows, lo, "left")
        return self.before[rows, k_low] & self.after[rows, k_high]


def _running_unions(owner: np.ndarray, width: int, reverse: bool) -> np.ndarray:
    """``prefix_or(one_hot(owner, width), axis=1, reverse=reverse)`` for (rows, N)
    owner bits (negative: none), built in place in the (rows, N + 1, W) result."""
    out = np.zeros((owner.shape[0], owner.shape[1] + 1, width), dtype=np.uint64)
    r, k = np.nonzero(owner >= 0)
    bit = owner[r, k]
    out[r, k if reverse else k + 1, bit // 64] = np.left_shift(
        np.uint64(1), (bit % 64).astype(np.uint64)
    )
    view = out[:, ::-1] if reverse else out
    np.bitwise_or.accumulate(view, axis=1, out=view)
    return out


def close_ends(
    low: np.ndarray, high: np.ndarray, member: np.ndarray, below: float, above: float
) -> np.ndarray:
    """(rows, N) bool: member intervals whose R end has some member's L end within
    [R + below, R + above] (ties of an interval test, and near-ties)."""
    at = compact(member)
    path = np.arange(len(at))[:, None]
    n = at.shape[1]
    values = np.concatenate([low[path, np.maximum(at, 0)], high[path, np.maximum(at, 0)]], axis=1)
    values = np.where(np.concatenate([at, at], axis=1) >= 0, values, np.inf)
    order = np.argsort(values, axis=1)
    values = np.take_along_axis(values, order, axis=1)
    is_low = order < n
    pos = np.arange(2 * n)
    # nearest L end at or before, and at or after, each sorted position
    before = np.maximum.accumulate(np.where(is_low, pos, -1), axis=1)
    after = np.minimum.accumulate(np.where(is_low, pos, 2 * n)[:, ::-1], axis=1)[:, ::-1]
    padded = np.concatenate([values, np.full((len(values), 1), np.inf)], axis=1)
    prev = np.where(before >= 0, np.take_along_axis(padded, np.maximum(before, 0), 1), -np.inf)
    nxt = np.take_along_axis(padded, after, axis=1)
    with np.errstate(invalid="ignore"):  # padding: inf - inf
        near = (values - prev <= -below) | (nxt - values <= above)
    r, p = np.nonzero(~is_low & near)
    out = np.zeros(member.shape, dtype=bool)
    slot = at[r, order[r, p] - n]
    out[r[slot >= 0], slot[slot >= 0]] = True
    return out & member
