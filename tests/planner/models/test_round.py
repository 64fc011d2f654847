"""Round outlines: every rotation about the centroid moves the boundary by at
most the annulus it needs, and a session reports a disc's rotation as free."""

from __future__ import annotations

import math

import numpy as np
import shapely
from hypothesis import given, settings
from hypothesis import strategies as st

from planner.models.outlines import make_stable_pose
from planner.models.round import annulus_width, round_within
from planner.recognition.session import Session
from planner.types import Contact, ObjectModel, Observation, SensingPath, SensorBounds, Workspace


def ring(n: int, r: float, c=(0.0, 0.0), wobble: float = 0.0, k: int = 5) -> np.ndarray:
    t = np.linspace(0, 2 * np.pi, n, endpoint=False)
    rho = r + wobble * np.sin(k * t)
    return np.column_stack([c[0] + rho * np.cos(t), c[1] + rho * np.sin(t)])


@settings(max_examples=80, deadline=None, derandomize=True)
@given(
    st.integers(12, 400),
    st.floats(0.0, 3.0),
    st.integers(1, 9),
    st.floats(-math.pi, math.pi),
    st.booleans(),
)
def test_a_rotation_moves_the_boundary_by_at_most_the_annulus(n, wobble, k, angle, hole):
    holes = [ring(max(12, n // 3), 10.0, wobble=wobble / 3, k=k)[::-1]] if hole else []
    pose = make_stable_pose(ring(n, 40.0, wobble=wobble, k=k), holes)
    c = np.asarray(pose.centroid)
    polygon = shapely.Polygon(pose.outline, pose.holes)
    turned = shapely.affinity.rotate(polygon, angle, origin=tuple(c), use_radians=True)
    moved = shapely.hausdorff_distance(polygon.boundary, turned.boundary, densify=0.02)
    assert moved <= annulus_width(pose) + 1e-6


def test_round_parts_and_others():
    disc = make_stable_pose(ring(2000, 40.0))
    assert round_within(disc, 0.1)
    washer = make_stable_pose(ring(200, 40.0), [ring(100, 10.0)[::-1]])
    assert round_within(washer, 2.0)
    off_centre = make_stable_pose(ring(200, 40.0), [ring(100, 10.0, (15.0, 0.0))[::-1]])
    assert not round_within(off_centre, 2.0)
    flat = disc.outline[disc.outline[:, 1] > -30.0]  # a disc with a flat
    assert not round_within(make_stable_pose(flat), 2.0)
    assert not round_within(make_stable_pose(ring(400, 40.0) * [1.0, 0.8]), 2.0)


def _touch(angle: float, r: float = 40.0) -> Observation:
    d = np.array([math.cos(angle), math.sin(angle)])
    p = r * d
    return Observation(SensingPath(tuple(p + 150 * d), tuple(-d), 300), Contact(tuple(p), tuple(d)))


def test_a_disc_is_localized_with_its_rotation_free():
    disc = ObjectModel("disc", (make_stable_pose(ring(2000, 40.0)),))
    s = Session([disc], SensorBounds(1.0, math.radians(3)), Workspace((0, 0), 200))
    s = s.observe(_touch(0.3)).observe(_touch(2.0))
    loc = s.localization
    assert s.status == "localized" and loc.classes == 1 and loc.rotation_free
    assert loc.bound.rotation == math.pi


def test_a_disc_with_a_flat_has_its_rotation_bounded():
    outline = ring(400, 40.0)
    d_shape = ObjectModel("d", (make_stable_pose(outline[outline[:, 1] > -30.0]),))
    s = Session([d_shape], SensorBounds(1.0, math.radians(3)), Workspace((0, 0), 200))
    s = s.observe(_touch(0.3)).observe(_touch(2.0))
    assert not s.localization.rotation_free
    assert s.localization.bound.rotation < math.pi
