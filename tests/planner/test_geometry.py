"""Transforms of planner.geometry: the same numbers as their definitions."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from planner.geometry import rotate, rotation_matrices


@settings(max_examples=40, derandomize=True, deadline=None)
@given(
    n=st.integers(0, 6),
    p=st.integers(0, 9),
    seed=st.integers(0, 2**32 - 1),
    per_row=st.booleans(),
    transposed=st.booleans(),
)
def test_rotate_is_the_matrix_product_number_for_number(n, p, seed, per_row, transposed):
    # R v for each rotation, as einsum defines it, bit for bit (the recognition's
    # hypotheses must not change with the way a rotation is computed)
    rng = np.random.default_rng(seed)
    rot = rotation_matrices(rng.uniform(-np.pi, np.pi, n))
    if transposed:  # R^T, a strided view, as the model-frame transforms pass it
        rot = rot.transpose(0, 2, 1)
    points = rng.normal(scale=100.0, size=(n, p, 2) if per_row else (p, 2))
    spec = "nij,npj->npi" if per_row else "nij,pj->npi"
    expected = np.einsum(spec, rot, points)
    got = rotate(rot, points)
    assert got.shape == (n, p, 2)
    assert np.array_equal(got, expected)
