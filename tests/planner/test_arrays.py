"""The row-wise uniques answer as numpy's unique over rows."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from planner.arrays import distinct_rows, row_labels


@settings(max_examples=80, deadline=None)
@given(
    seed=st.integers(0, 2**32 - 1),
    n=st.integers(0, 60),
    m=st.integers(1, 5),
    values=st.sampled_from([2, 5, 1000]),
    dtype=st.sampled_from([np.int64, np.uint64]),
)
def test_row_labels_and_counts_are_those_of_the_unique_over_rows(seed, n, m, values, dtype):
    rng = np.random.default_rng(seed)
    rows = rng.integers(-values if dtype == np.int64 else 0, values, (n, m)).astype(dtype)
    unique, inverse = np.unique(rows, axis=0, return_inverse=True)
    assert np.array_equal(row_labels(rows), inverse.ravel())
    assert distinct_rows(rows) == len(unique)
