"""Object models (DESIGN §4.1, §8): validation, orientation, file round trip."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from planner.errors import InvalidModelError, ModelFileError, PlannerError
from planner.models.library import dump_objects, load_objects, object_from_dict, parse_objects
from tests.conftest import DATA, SET_NAMES

SQUARE = [[0, 0], [10, 0], [10, 10], [0, 10]]


@pytest.mark.parametrize(
    ("data", "field", "words"),
    [
        (
            {"name": "bow", "outline": [[0, 0], [10, 10], [10, 0], [0, 10]]},
            "object.outline",
            "self-intersects",
        ),
        ({"name": "two", "outline": [[0, 0], [1, 0]]}, "object.outline", "at least 3 vertices"),
        ({"name": "flat", "outline": [[0, 0], [1, 0], [2, 0]]}, "object.outline", "zero area"),
        ({"name": "nan", "outline": [[0, 0], [1, math.nan], [0, 1]]}, "object.outline", "finite"),
        ({"name": "inf", "outline": [[0, 0], [math.inf, 0], [0, 1]]}, "object.outline", "finite"),
        (
            {"name": "dup", "outline": [[0, 0], [1, 0], [1, 0], [0, 1]]},
            "object.outline",
            "degenerate edge 1",
        ),
        ({"name": "txt", "outline": "square"}, "object.outline", "pairs"),
        ({"name": "", "outline": SQUARE}, "object.name", "non-empty"),
        ({"name": "both", "outline": SQUARE, "stable_poses": []}, "object", "exactly one"),
        (
            {"name": "p", "stable_poses": [{"outline": SQUARE, "probability": 1.5}]},
            "probability",
            "(0, 1]",
        ),
        (
            {
                "name": "p2",
                "stable_poses": [
                    {"outline": SQUARE, "probability": 0.7},
                    {"outline": SQUARE, "probability": 0.6},
                ],
            },
            "stable_poses",
            "sum to",
        ),
        (
            {"name": "h", "outline": SQUARE, "holes": [[[20, 20], [21, 20], [21, 21]]]},
            "object.outline",
            "not inside",
        ),
        ({"name": "k", "outline": SQUARE, "colour": "red"}, "object", "unknown keys"),
        ({"name": "pr", "outline": SQUARE, "prior": -1}, "object.prior", "> 0"),
        ({"name": "nz", "outline": SQUARE, "normal_z": [0, 0]}, "normal_z", "4 numbers"),
    ],
)
def test_bad_models_are_refused_naming_the_problem(data, field, words):
    with pytest.raises(PlannerError) as info:
        object_from_dict(data)
    assert isinstance(info.value, InvalidModelError | ModelFileError)
    assert field in (info.value.field or "")
    assert words in info.value.message


def test_outline_is_oriented_ccw_and_holes_cw_coordinates_kept():
    obj = object_from_dict(
        {"name": "frame", "outline": SQUARE[::-1], "holes": [[[2, 2], [8, 2], [8, 8], [2, 8]]]}
    )
    pose = obj.stable_poses[0]
    assert sorted(map(tuple, pose.outline.tolist())) == sorted(
        map(tuple, np.asarray(SQUARE, float).tolist())
    )
    faces = pose.faces
    assert len(faces) == 8
    # hole faces point into the hole: the hole's centre lies on their outward side
    hole = faces.ring == 1
    centre = np.array([5.0, 5.0])
    assert np.all(np.einsum("ij,ij->i", faces.normal[hole], centre - faces.start[hole]) > 0)
    outer = faces.ring == 0
    assert np.all(np.einsum("ij,ij->i", faces.normal[outer], centre - faces.start[outer]) < 0)


def test_shorthand_and_stable_poses_forms_are_equivalent():
    a = object_from_dict({"name": "a", "outline": SQUARE})
    b = object_from_dict({"name": "a", "stable_poses": [{"outline": SQUARE, "probability": 1.0}]})
    assert a.same_geometry(b)


@pytest.mark.parametrize("name", SET_NAMES)
def test_files_round_trip_exactly(name, tmp_path):
    objects = load_objects(DATA / f"{name}.json")
    out = tmp_path / "out.json"
    dump_objects(objects, out)
    again = load_objects(out)
    assert all(a.same_geometry(b) for a, b in zip(objects, again, strict=True))
    raw = json.loads((DATA / f"{name}.json").read_text())["objects"]
    for obj, data in zip(objects, raw, strict=True):
        given = data.get("outline") or data["stable_poses"][0]["outline"]
        assert {tuple(v) for v in given} == {tuple(v) for v in obj.stable_poses[0].outline.tolist()}


def test_bad_files_name_the_problem(tmp_path):
    with pytest.raises(ModelFileError, match="cannot read"):
        load_objects(tmp_path / "missing.json")
    bad = tmp_path / "bad.json"
    bad.write_text("{not json")
    with pytest.raises(ModelFileError, match="not valid JSON"):
        load_objects(bad)
    with pytest.raises(ModelFileError, match="appears twice"):
        parse_objects(
            {"objects": [{"name": "a", "outline": SQUARE}, {"name": "a", "outline": SQUARE}]}
        )


@pytest.mark.parametrize("name", SET_NAMES)
def test_each_face_ends_where_the_face_it_names_starts(name):
    # holes, and the slices of posed solids, included
    holed = object_from_dict(
        {"name": "h", "outline": SQUARE, "holes": [[[4, 4], [4, 6], [6, 6], [6, 4]]]}
    )
    for obj in [*load_objects(DATA / f"{name}.json"), holed]:
        for stable in obj.stable_poses:
            faces = stable.all_faces
            assert np.array_equal(faces.end, faces.start[stable.face_ends])
            assert np.array_equal(faces.ring, faces.ring[stable.face_ends])


def test_shape_labels_join_congruent_poses_and_nothing_else():
    from planner.models.congruence import shape_labels

    ell = np.array([[0, 0], [30, 0], [30, 10], [10, 10], [10, 20], [0, 20]], float)
    c, s = math.cos(1.1), math.sin(1.1)
    turned = np.roll(ell @ np.array([[c, -s], [s, c]]).T + [50.0, -7.0], 2, axis=0)
    mirrored = (ell * [-1.0, 1.0])[::-1]  # the same edges, mirrored: not congruent
    wider = ell * [1.01, 1.0]
    outlines = [ell, turned, mirrored, wider, ell + 3.0]
    objects = [
        object_from_dict({"name": f"o{k}", "outline": o.tolist()}) for k, o in enumerate(outlines)
    ]
    labels = shape_labels([o.stable_poses[0] for o in objects])
    assert labels[0] == labels[1] == labels[4]
    assert len({labels[0], labels[2], labels[3]}) == 3
