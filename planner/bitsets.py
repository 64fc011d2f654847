"""Sets of equivalence classes as packed bitsets (numpy uint64 words).

Class j is bit ``j % 64`` of word ``j // 64``; a set over K classes takes
``W = ceil(K / 64)`` words (at least one). Words are kept in numpy arrays so that
whole tables of sets are combined in one pass; a set's `bytes` is its memo key.

>>> words = pack_bits(np.array([True, False, True]))
>>> int(words[0]), unpack_bits(words, 3).tolist(), int(popcount(words))
(5, [True, False, True], 2)
"""

from __future__ import annotations

import numpy as np

__all__ = ["n_words", "pack_bits", "popcount", "to_int", "unpack_bits"]

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
    """Number of set bits of each set: (..., W) uint64 -> (...) int."""
    words = np.asarray(words, dtype=np.uint64)
    if hasattr(np, "bitwise_count"):
        return np.bitwise_count(words).sum(axis=-1, dtype=np.int64)
    raw = np.ascontiguousarray(words.astype("<u8")).view(np.uint8)
    return _BYTE_COUNTS[raw].sum(axis=-1, dtype=np.int64)


def to_int(words: np.ndarray) -> int:
    """One set (W,) as a Python int (bit j = class j)."""
    return int.from_bytes(np.asarray(words, dtype="<u8").tobytes(), "little")
