"""The compiled kernels of the planner against plain references."""

from __future__ import annotations

import math

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from planner.geometry import point_segment_distance
from planner.planning.match_kernel import pair_rows, window_pairs
from planner.planning.matching import Slots, slots_match
from planner.planning.near_kernel import near_stretches


@settings(max_examples=120, deadline=None)
@given(st.integers(0, 2**31))
def test_near_stretch_is_where_the_path_passes_within_reach_of_a_face(seed):
    # one face turned toward the path; the stretch is the set of distances along
    # it (within the span) whose point lies within `tol` of the segment
    rng = np.random.default_rng(seed)
    a, b = rng.uniform(-10, 10, (2, 2))
    tol = float(rng.uniform(0.1, 4.0))
    origin = rng.uniform(-20, 20, 2)
    heading = rng.uniform(-math.pi, math.pi)
    d = np.array([math.cos(heading), math.sin(heading)])
    normal = -d  # facing the path
    faces = tuple(np.array([[v]]) for v in (*a, *b, *normal))
    span = (np.array([rng.uniform(0, 10)]), np.array([rng.uniform(20, 60)]))
    found = near_stretches(
        faces, np.ones((1, 1), bool), np.array([tol]), np.array([0.5]),
        tuple(np.array([v]) for v in (*origin, *d)), np.array([0]), span,
    )[0]  # fmt: skip
    s = np.linspace(span[0][0], span[1][0], 4001)
    within = np.array([point_segment_distance(origin + t * d, a, b) <= tol for t in s])
    inside = (s > found[1] + 1e-6) & (s < found[2] - 1e-6)
    outside = (s < found[1] - 1e-6) | (s > found[2] + 1e-6)
    if found[0]:
        assert within[inside].all() and not within[outside].any()
    else:
        assert not within.any()


@settings(max_examples=60, deadline=None)
@given(st.integers(0, 2**31), st.integers(1, 40))
def test_the_sweep_sets_exactly_the_matching_pairs(seed, n_items):
    # items on the path's line (and some with no distance along it) against the
    # pairwise reference
    rng = np.random.default_rng(seed)
    n_hyp = max(1, n_items // 2)
    hit = rng.random((2, n_items)) < 0.8
    d = rng.uniform(0, 20, (2, n_items))
    d[rng.random(d.shape) < 0.1] = np.inf
    angle = rng.uniform(-math.pi, math.pi, d.shape)
    reach = rng.uniform(0.1, 3.0, d.shape)
    alpha = rng.uniform(0.0, 1.0, d.shape)
    x = np.where(np.isfinite(d), d, rng.uniform(0, 20, d.shape))
    y = np.where(np.isfinite(d), 0.0, rng.uniform(-1, 1, d.shape))
    slots = Slots(
        hit, hit, x, y, np.cos(angle), np.sin(angle), reach, alpha, np.cos(alpha), np.sin(alpha)
    )
    owner = np.arange(n_items) % n_hyp
    rows = np.zeros((2, n_hyp, 1), dtype=np.uint64)
    columns = (x, y, slots.cos, slots.sin, reach, alpha, slots.cos_alpha, slots.sin_alpha)
    pair_rows(hit, d, columns, owner, 1e-9, rows)
    expected = np.zeros((2, n_hyp, n_hyp), dtype=bool)
    for c in range(2):
        row = Slots(*(np.asarray(f)[c] for f in slots.__dict__.values()))
        mine = Slots(*(f[:, None] for f in row.__dict__.values()))
        theirs = Slots(*(f[None, :] for f in row.__dict__.values()))
        match = slots_match(mine, theirs) & hit[c][:, None] & hit[c][None, :]
        i, j = np.nonzero(match)
        expected[c, owner[i], owner[j]] = True
    found = (rows[..., 0][..., None] >> np.arange(n_hyp, dtype=np.uint64)) & np.uint64(1)
    np.testing.assert_array_equal(found.astype(bool), expected)
    # the pairs the sweep tests: each slot along the path with those ahead of it
    # within twice the path's largest reach, the others with every hit slot
    count = 0
    for c in range(2):
        on = np.flatnonzero(hit[c] & np.isfinite(d[c]))
        off = int((hit[c] & ~np.isfinite(d[c])).sum())
        top = reach[c, on].max(initial=0.0)
        for i in on:
            ahead = (d[c, on] > d[c, i]) | ((d[c, on] == d[c, i]) & (on > i))
            count += int((ahead & (d[c, on] <= d[c, i] + 2 * top + 1e-9)).sum())
        count += off * (len(on) + off)
    assert window_pairs(hit, d, reach, 1e-9) == count
