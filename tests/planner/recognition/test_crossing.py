"""The free-space check's segment test against the geometry library's own."""

from __future__ import annotations

import numpy as np
import shapely
from hypothesis import given, settings
from hypothesis import strategies as st

from planner.recognition.crossing import ring_edges, segments_meet
from tests.conftest import SET_NAMES, object_set

corner = st.tuples(st.integers(-20, 20), st.integers(-20, 20))
box = st.tuples(corner, st.integers(1, 25), st.integers(1, 25))


def _boxes(found: list) -> shapely.Geometry:
    return shapely.union_all([shapely.box(x, y, x + w, y + h) for (x, y), w, h in found])


@settings(max_examples=300, deadline=None, derandomize=True)
@given(
    solid=st.lists(box, min_size=1, max_size=4),
    cut=st.lists(box, max_size=3),
    ends=st.lists(st.tuples(corner, corner), min_size=1, max_size=40),
)
def test_segments_meet_as_the_geometry_library_says_on_integer_shapes(solid, cut, ends):
    """Polygons with holes, several parts, shared edges, and segments along their
    edges, through their corners, degenerate to points: on integer coordinates
    the arithmetic is exact, so the answers must be the library's exactly."""
    shape = shapely.difference(_boxes(solid), _boxes(cut)) if cut else _boxes(solid)
    segments = np.array([[*a, *b] for a, b in ends], dtype=float)
    expected = shapely.intersects(shapely.linestrings(segments.reshape(-1, 2, 2)), shape)
    assert segments_meet(segments, ring_edges(shape)).tolist() == expected.tolist()


def test_segments_meet_as_the_geometry_library_says_on_shrunk_parts():
    """Every part of every shared set, shrunk as the free-space check shrinks it,
    against random segments (long, short, inside, outside)."""
    rng = np.random.default_rng(0)
    for name in SET_NAMES:
        for model in object_set(name):
            for layer in (layer for pose in model.stable_poses for layer in pose.layers):
                for tol in (0.0, 1.0, 6.0):
                    shape = layer.shape.buffer(-tol, join_style="mitre") if tol else layer.shape
                    x0, y0, x1, y1 = layer.shape.bounds
                    mid, reach = np.array([x0 + x1, y0 + y1]) / 2, max(x1 - x0, y1 - y0)
                    starts = mid + rng.uniform(-reach, reach, (300, 2))
                    ends = starts + rng.uniform(-reach, reach, (300, 2)) * rng.uniform(
                        0, 1, (300, 1)
                    )
                    segments = np.hstack([starts, ends])
                    expected = shapely.intersects(
                        shapely.linestrings(segments.reshape(-1, 2, 2)), shape
                    )
                    found = segments_meet(segments, ring_edges(shape))
                    assert found.tolist() == expected.tolist(), (name, model.name, tol)
