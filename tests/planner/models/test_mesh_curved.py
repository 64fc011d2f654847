"""Curved solids from meshes: a cylinder lying and standing, a capsule, a part
with a spherical cap. The facets that stand for one curved face are one pose."""

from __future__ import annotations

import math

import numpy as np
import pytest
import shapely
import trimesh
from hypothesis import given, settings
from hypothesis import strategies as st

from planner.models.mesh import MeshSlice, object_from_mesh
from planner.models.near_congruence import nearly_congruent
from planner.models.round import round_within


def capped() -> trimesh.Trimesh:
    cylinder = trimesh.creation.cylinder(radius=20, height=40, sections=64)
    cap = trimesh.creation.icosphere(subdivisions=3, radius=20)
    cap.apply_translation([0, 0, 20])
    return trimesh.convex.convex_hull(np.vstack([cylinder.vertices, cap.vertices]))


def test_a_cylinder_lies_or_stands():
    model = object_from_mesh(trimesh.creation.cylinder(radius=20, height=60, sections=64), 8.0, "c")
    lying, standing = model.stable_poses
    width, length = sorted(np.ptp(lying.outline, axis=0).tolist())
    # cut 8 above the table through a cylinder of radius 20 lying on its side
    assert length == pytest.approx(60.0) and width == pytest.approx(
        2 * math.sqrt(20**2 - 12**2), abs=0.5
    )
    assert len(standing.outline) == 64 and round_within(standing, 0.1)
    assert math.isclose(sum(p.probability for p in model.stable_poses), 1.0)
    assert lying.probability > standing.probability


def test_a_capsule_lies_on_its_side():
    model = object_from_mesh(
        trimesh.creation.capsule(height=60, radius=15, count=[32, 32]), 8.0, "k"
    )
    (pose,) = model.stable_poses
    width, length = sorted(np.ptp(pose.outline, axis=0).tolist())
    assert length > 60 and width < 30


def test_the_facets_of_one_curved_face_are_one_pose():
    model = object_from_mesh(capped(), 8.0, "capped")
    # 53 stable poses of the mesh, most of them facets of the side it lies on
    assert len(model.stable_poses) <= 8
    best = model.stable_poses[0]
    assert best.probability > 0.5 and best.normal_z is None  # stands for several facets
    standing = [p for p in model.stable_poses if round_within(p, 0.5)]
    assert len(standing) == 1  # on its flat end


def _slice(ring: np.ndarray) -> MeshSlice:
    return MeshSlice(ring, (), np.zeros(len(ring)), np.zeros(2))


@settings(max_examples=40, deadline=None, derandomize=True)
@given(st.integers(8, 120), st.floats(-math.pi, math.pi), st.floats(0.0, 0.3), st.floats(1.2, 3.0))
def test_near_congruence_is_the_hausdorff_distance_under_a_rotation(n, angle, shrink, aspect):
    t = np.linspace(0, 2 * np.pi, n, endpoint=False)
    ring = np.column_stack([aspect * 10 * np.cos(t), 10 * np.sin(t)])
    c, s = math.cos(angle), math.sin(angle)
    other = (ring * (1 - shrink / 10)) @ np.array([[c, -s], [s, c]]).T
    gap = shapely.hausdorff_distance(
        shapely.Polygon(ring).boundary, shapely.Polygon(ring * (1 - shrink / 10)).boundary
    )
    if gap <= 0.9 * 0.2:
        assert nearly_congruent(_slice(ring), _slice(other), 0.2)
    if gap > 0.2:
        assert not nearly_congruent(_slice(ring), _slice(other), 0.2)
