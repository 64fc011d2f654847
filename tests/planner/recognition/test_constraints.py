"""Constraint tables (DESIGN §4.2) against brute force, and the checks' soundness."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from planner.geometry import wrap_angle
from planner.memo import SharedCache
from planner.models.outlines import make_stable_pose
from planner.recognition import constraints
from planner.recognition.constraints import (
    ConstraintTables,
    build_tables,
    extend_feasibility,
    pair_feasibility,
)
from planner.types import Contact, Faces
from tests.conftest import SET_NAMES, object_set

SAMPLES = 120


def brute_force_tables(faces: Faces) -> ConstraintTables:
    """Tables from dense sampling of face points."""
    s = np.linspace(0.0, 1.0, SAMPLES)
    pts = faces.start[:, None, :] + s[None, :, None] * (faces.end - faces.start)[:, None, :]
    gaps = pts[None, :, None, :, :] - pts[:, None, :, None, :]  # [a, b, i, j] = y_bj - x_ai
    dist = np.hypot(gaps[..., 0], gaps[..., 1])
    proj = np.einsum("ak,abijk->abij", faces.normal, gaps)
    return ConstraintTables(
        d_min=dist.min(axis=(2, 3)),
        d_max=dist.max(axis=(2, 3)),
        angle=wrap_angle(faces.angle[None, :] - faces.angle[:, None]),
        c_min=proj.min(axis=(2, 3)),
        c_max=proj.max(axis=(2, 3)),
        scale=1.0,
    )


@pytest.mark.parametrize("name", SET_NAMES)
def test_tables_match_brute_force(name):
    for model in object_set(name):
        for pose in model.stable_poses:
            exact, brute = build_tables(pose.faces), brute_force_tables(pose.faces)
            # sampling error: half the largest sample spacing on each of two faces
            step = pose.faces.length.max() / (SAMPLES - 1)
            assert np.all(exact.d_min <= brute.d_min + 1e-9)
            assert np.allclose(exact.d_min, brute.d_min, atol=step)
            assert np.allclose(exact.d_max, brute.d_max, atol=1e-9)
            assert np.allclose(exact.c_min, brute.c_min, atol=1e-9)
            assert np.allclose(exact.c_max, brute.c_max, atol=1e-9)


def test_signed_angle_rejects_the_mirror_assignment():
    # a right triangle: contacts on the legs seen in the mirrored order must be refused
    tri = make_stable_pose([[0, 0], [4, 0], [0, 3]])
    t = build_tables(tri.faces)
    bottom = Contact((2, 0), (0, -1))
    left = Contact((0, 1), (-1, 0))
    ok = pair_feasibility(t, bottom, left, 0.0, 0.0)
    assert ok[0, 2] and not ok[2, 0]
    # under an unsigned test the mirror (left face first) would pass the angle check
    assert math.isclose(abs(t.angle[0, 2]), abs(t.angle[2, 0]))


def test_error_widens_every_check():
    sq = make_stable_pose([[0, 0], [10, 0], [10, 10], [0, 10]])
    t = build_tables(sq.faces)
    a = Contact((5, 0), (0, -1))
    far = Contact((5, 11), (0, 1))  # 11 apart: too far for an exact square of side 10
    assert not pair_feasibility(t, a, far, 0.0, 0.0).any()
    assert pair_feasibility(t, a, far, 0.5, 0.0)[0, 2]
    tilted = Contact((10, 5), (math.cos(0.05), math.sin(0.05)))
    assert not pair_feasibility(t, a, tilted, 0.0, 0.0)[0, 1]
    assert pair_feasibility(t, a, tilted, 0.0, 0.03)[0, 1]


def test_tables_are_built_once_per_stable_pose_and_the_process_keeps_a_bounded_number(
    monkeypatch,
):
    fresh = SharedCache(constraints.SHARED_CELLS, lambda t: t.d_min.size)
    monkeypatch.setattr(constraints, "_shared", fresh)
    square = [[0, 0], [2, 0], [2, 2], [0, 2]]
    first = constraints.shared_tables(make_stable_pose(square).faces)
    again = constraints.shared_tables(make_stable_pose(square).faces)  # another session's part
    assert again is first
    built = build_tables(make_stable_pose(square).faces)
    for name in ("d_min", "d_max", "angle", "c_min", "c_max"):
        assert np.array_equal(getattr(first, name), getattr(built, name))
        assert not getattr(first, name).flags.writeable
    other = constraints.shared_tables(make_stable_pose([[0, 0], [3, 0], [0, 3]]).faces)
    assert other is not first and other.d_min.shape == (3, 3)
    # past the cell budget the least recently used go first
    monkeypatch.setattr(fresh, "limit", 16 + 9)
    constraints.shared_tables(make_stable_pose([[0, 0], [4, 0], [4, 1], [0, 1]]).faces)
    assert constraints.shared_tables(make_stable_pose(square).faces) is not first


@settings(max_examples=60, deadline=None, derandomize=True)
@given(
    name=st.sampled_from(SET_NAMES),
    seed=st.integers(0, 2**32 - 1),
    earlier=st.integers(0, 5),
    eps_d=st.sampled_from([0.0, 0.5, 1.0, 3.0]),
    phi=st.sampled_from([0.0, 0.02, 0.0873, 0.3]),
)
def test_extension_checks_are_the_pair_checks_bit_for_bit(name, seed, earlier, eps_d, phi):
    """The compiled extension (every earlier contact on its row's face, the newest
    on each face) answers as the pair tables do, read at the rows' faces, cell
    for cell: contacts on faces and off them, spurious assignments (-1) among
    the rows, no earlier contact at all."""
    rng = np.random.default_rng(seed)
    model = object_set(name)[rng.integers(len(object_set(name)))]
    pose = model.stable_poses[rng.integers(len(model.stable_poses))]
    faces = pose.all_faces
    tables = build_tables(faces)
    F = len(faces)
    contacts = []
    for _ in range(earlier + 1):
        f = rng.integers(F)
        at = faces.start[f] + rng.uniform(0, 1) * (faces.end[f] - faces.start[f])
        turn = rng.normal(0, 0.05)
        n = faces.normal[f]
        normal = (
            n[0] * math.cos(turn) - n[1] * math.sin(turn),
            n[0] * math.sin(turn) + n[1] * math.cos(turn),
        )
        contacts.append(Contact(tuple(at + rng.normal(0, 1.0, 2)), normal))
    rows = rng.integers(-1, F, (40, earlier))
    unary = rng.random(F) < 0.8
    expected = np.broadcast_to(unary, (len(rows), F)).copy()
    for j in range(earlier):
        table = pair_feasibility(tables, contacts[j], contacts[-1], eps_d, phi)
        col = rows[:, j]
        expected &= np.where(col[:, None] >= 0, table[np.maximum(col, 0)], True)
    found = extend_feasibility(tables, rows, contacts, unary, eps_d, phi)
    np.testing.assert_array_equal(found, expected)
