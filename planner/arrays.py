"""Row-wise uniques numpy has only in a slow form.

``np.unique(a, axis=0)`` views each row as one opaque item and sorts those: on
the small integer tables of the recognition and the planner (hypotheses by
interpretation, child sets of a search) it cost several times one lexical sort
of the columns, which is what these helpers do. Both answer exactly as the
unique over rows does.

>>> a = np.array([[2, 1], [0, 5], [2, 1], [0, 3]])
>>> row_labels(a).tolist(), np.unique(a, axis=0, return_inverse=True)[1].ravel().tolist()
([2, 1, 2, 0], [2, 1, 2, 0])
>>> distinct_rows(a)
3
"""

from __future__ import annotations

import numpy as np

__all__ = ["distinct_rows", "row_labels"]


def _sorted(rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The order sorting `rows` (n, m) lexically, first column first, and where a
    row of that order differs from the one before (True for the first)."""
    order = np.lexsort(rows.T[::-1])
    ordered = rows[order]
    new = np.ones(len(rows), dtype=bool)
    new[1:] = np.any(ordered[1:] != ordered[:-1], axis=1)
    return order, new


def distinct_rows(rows: np.ndarray) -> int:
    """How many distinct rows `rows` (n, m) holds."""
    if len(rows) < 2:
        return len(rows)
    return int(_sorted(rows)[1].sum())


def row_labels(rows: np.ndarray) -> np.ndarray:
    """(n,) each row's place among the distinct rows of `rows` (n, m) sorted
    lexically: ``np.unique(rows, axis=0, return_inverse=True)[1]``."""
    if len(rows) == 0:
        return np.zeros(0, dtype=np.int64)
    order, new = _sorted(rows)
    out = np.empty(len(rows), dtype=np.int64)
    out[order] = np.cumsum(new) - 1
    return out
