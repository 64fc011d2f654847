"""The search chord after misses: exact extents, shared draws, bounded work (DESIGN §4.12)."""

from __future__ import annotations

import math
import tracemalloc

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from planner.geometry import rotate, rotation_matrices, segment_segment_distance
from planner.models.library import object_from_dict
from planner.planning.probes import (
    SEARCH_BATCHES,
    _prior_draws,
    _prior_extents,
    _support,
    search_chord,
)
from planner.types import SensingPath, Workspace

WORKSPACE = Workspace((10.0, -5.0), 150.0)
NORMAL = np.array([[1.0, 0.0], [0.0, 1.0]])
ELL = [[0, 0], [40, 0], [40, 12], [12, 12], [12, 30], [0, 30]]


def _ellipse(vertices: int, a: float = 40.0, b: float = 25.0) -> list[list[float]]:
    angle = np.linspace(0.0, 2 * math.pi, vertices, endpoint=False)
    return np.column_stack([a * np.cos(angle), b * np.sin(angle)]).tolist()


@settings(max_examples=200, deadline=None)
@given(
    st.lists(
        st.tuples(st.floats(-50, 50), st.floats(-50, 50)), min_size=3, max_size=40, unique=True
    ),
    st.lists(st.floats(-10.0, 10.0), min_size=1, max_size=20),
)
def test_support_is_the_greatest_vertex_projection(points, angles):
    outline = np.array(points, dtype=float)
    span = np.ptp(outline, axis=0)
    if min(span) < 1e-3 or abs(np.linalg.det(np.cov(outline.T))) < 1e-6:
        return  # no hull with an area
    phi = np.array(angles)
    unit = np.stack([np.cos(phi), np.sin(phi)], axis=1)
    brute = (unit @ outline.T).max(axis=1)
    assert np.allclose(_support(outline, phi), brute, atol=1e-9)


def test_extents_are_those_of_every_posed_draw_no_missed_path_meets():
    models = {"ell": object_from_dict({"name": "ell", "outline": ELL})}
    missed = [
        SensingPath((160.0, -5.0), (-1.0, 0.0), 300.0),
        SensingPath((10.0, 145.0), (0.0, -1.0), 150.0),
    ]
    alpha = np.arange(12) * math.pi / 12
    normal = np.stack([np.cos(alpha), np.sin(alpha)], axis=1)
    lo, hi = _prior_extents(models, WORKSPACE, missed, normal, 512)
    # the reference: pose every draw, drop those a missed path comes to within
    # rounding of, project every vertex
    want_lo, want_hi = _survivors(models, missed, normal, 512, 0)
    assert len(lo) == len(want_lo) < 512  # some draws were ruled out
    assert np.allclose(lo, want_lo, atol=1e-9)
    assert np.allclose(hi, want_hi, atol=1e-9)


def _survivors(models, missed, normal, samples, batch):
    """Extents of the draws of one batch that no missed path comes near, by posing them."""
    draws = _prior_draws(models, WORKSPACE, samples, normal, batch)[0]
    stable, theta, t = models["ell"].stable_poses[0], draws.theta, draws.t
    posed = rotate(rotation_matrices(theta), stable.outline) + t[:, None]
    start, end = posed, np.roll(posed, -1, axis=1)
    met = np.zeros(len(theta), dtype=bool)
    for p in missed:
        a = np.array(p.origin)
        b = a + p.length * np.array(p.direction)
        met |= (segment_segment_distance(start, end, a, b) < 1e-9).any(axis=1)
    proj = (posed[~met] - np.array(WORKSPACE.center)) @ normal.T
    return proj.min(axis=1), proj.max(axis=1)


def test_after_many_misses_the_search_draws_again_until_enough_survive():
    # seven parallel misses 40 apart leave few of one batch's draws: the chord would
    # be chosen on a handful; further fixed batches are drawn until a quarter survives
    models = {"ell": object_from_dict({"name": "ell", "outline": ELL})}
    cx, cy = WORKSPACE.center
    missed = [
        SensingPath((cx - 150.0, cy + y), (1.0, 0.0), 300.0) for y in np.arange(-120, 121, 40)
    ]
    lo, hi = _prior_extents(models, WORKSPACE, missed, NORMAL, 256)
    want = []
    while sum(len(w[0]) for w in want) < 256 // 4:
        want.append(_survivors(models, missed, NORMAL, 256, len(want)))
    assert 1 < len(want) <= SEARCH_BATCHES and len(want[0][0]) < 256 // 4
    assert np.allclose(lo, np.concatenate([w[0] for w in want]), atol=1e-9)
    assert np.allclose(hi, np.concatenate([w[1] for w in want]), atol=1e-9)


def test_sessions_on_rebuilt_parts_share_the_prior_draws():
    # a service builds the parts again for every session: the draws are the same
    first = {"ell": object_from_dict({"name": "ell", "outline": ELL})}
    again = {"ell": object_from_dict({"name": "ell", "outline": ELL})}
    assert _prior_draws(first, WORKSPACE, 256, NORMAL) is _prior_draws(
        again, WORKSPACE, 256, NORMAL
    )
    moved = Workspace((11.0, -5.0), 150.0)
    assert _prior_draws(first, moved, 256, NORMAL) is not _prior_draws(
        first, WORKSPACE, 256, NORMAL
    )


def test_a_finely_drawn_part_searches_within_bounded_memory():
    # 5,000 vertices as given (a session simplifies them first; the library's own
    # callers need not): posing every draw's outline took about 2.6 GB
    fine = {"disc": object_from_dict({"name": "disc", "outline": _ellipse(5000)})}
    missed = [SensingPath((160.0, -5.0), (-1.0, 0.0), 300.0)]
    tracemalloc.start()
    try:
        _, aim = search_chord(fine, WORKSPACE, missed, (160.0, -5.0))
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < 64 * 2**20
    # the chord met the most draws: off the band the miss swept
    coarse = {"disc": object_from_dict({"name": "disc", "outline": _ellipse(64)})}
    _, coarse_aim = search_chord(coarse, WORKSPACE, missed, (160.0, -5.0))
    assert abs(aim[1] - WORKSPACE.center[1]) > 25.0
    assert np.allclose(aim, coarse_aim, atol=15.0)
