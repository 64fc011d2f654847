"""Paths aimed where the classes differ (DESIGN §4.10, §4.15): how deep in a
feature region its aim is sought."""

from __future__ import annotations

import pytest
import shapely
from hypothesis import given, settings
from hypothesis import strategies as st
from shapely.ops import polylabel

from planner.planning.feature_aims import THICKNESS_SHARE, _aim_precision


@settings(max_examples=30, deadline=None)
@given(
    length=st.floats(5.0, 300.0),
    thickness=st.floats(0.2, 40.0),
    width=st.sampled_from([0.0, 0.5, 2.0]),
)
def test_a_feature_aim_lies_as_deep_as_the_contact_error_or_its_thickness_allows(
    length, thickness, width
):
    """The aim is the region's deepest point to within a quarter of the precision:
    the contact error, or with exact contacts a share of the mean thickness (so a
    long sliver is not searched to a thousandth of its size)."""
    region = shapely.box(0.0, 0.0, length, thickness)
    precision = _aim_precision(region, width)
    mean_thickness = 2 * region.area / region.length
    if width > 0:
        assert precision >= width
    else:
        floor = max(THICKNESS_SHARE * mean_thickness, 1e-3 * region.area**0.5)
        assert precision == pytest.approx(floor, rel=1e-12)
    aim = polylabel(region, tolerance=precision / 4)
    deepest = min(length, thickness) / 2
    assert region.contains(aim)
    assert region.exterior.distance(aim) >= deepest - precision / 4 - 1e-9
