"""The schema says what the validators check: for every combination of given, null
and absent fields, the JSON Schema of a request body accepts exactly what the
request model accepts (so a schema-driven client or tester never sends a
schema-valid body the service refuses for its form), and a direction the schema
admits is one the planner can normalize."""

from __future__ import annotations

import math

import jsonschema
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from pydantic import BaseModel, ValidationError

from app.schemas import input_models
from app.settings import Settings
from planner.errors import InvalidObservationError, PlannerError
from planner.models.library import object_from_dict
from planner.types import SensingPath

SQUARE = [[0, 0], [40, 0], [40, 40], [0, 40]]
HOLE = [[10, 10], [20, 10], [20, 20]]
NORMAL_Z = "one per vertex"
SLICES = [{"height": 5, "outline": SQUARE}]
ABSENT = object()
MODELS = input_models(Settings(db_path="rules.db"))


def _body(fields: dict[str, object]) -> dict[str, object]:
    """The fields given; a given normal_z has one value per vertex, holes included."""
    body = {k: v for k, v in fields.items() if v is not ABSENT}
    if body.get("normal_z") == NORMAL_Z:
        holes = body.get("holes") if isinstance(body.get("holes"), list) else []
        body["normal_z"] = [0.0] * (len(SQUARE) + sum(map(len, holes)))
    return body


def _agree(model: type[BaseModel], body: dict[str, object]) -> None:
    """The schema admits `body` exactly when the service would register it (the
    model's validation, then the planner's reading of the object)."""
    schema_ok = jsonschema.Draft202012Validator(model.model_json_schema()).is_valid(body)
    try:
        object_from_dict(model.model_validate(body).as_dict())  # type: ignore[attr-defined]
        service_ok = True
    except (ValidationError, PlannerError):
        service_ok = False
    assert schema_ok == service_ok, body


def _choice(*values: object) -> st.SearchStrategy[object]:
    return st.sampled_from([ABSENT, None, *values])


POSE = st.fixed_dictionaries(
    {
        "outline": _choice(SQUARE),
        "slices": _choice(SLICES),
        "holes": _choice([], [HOLE]),
        "normal_z": _choice(NORMAL_Z),
    }
).map(_body)


@settings(max_examples=300, derandomize=True, database=None)
@given(
    st.fixed_dictionaries(
        {
            "outline": _choice(SQUARE),
            "stable_poses": _choice([{"outline": SQUARE}], [{"slices": SLICES}]),
            "holes": _choice([], [HOLE]),
            "normal_z": _choice(NORMAL_Z),
        }
    ).map(_body)
)
def test_an_object_s_schema_admits_exactly_its_one_shape(fields):
    _agree(MODELS.ObjectIn, {"name": "part", **fields})


@settings(max_examples=200, derandomize=True, database=None)
@given(POSE)
def test_a_stable_pose_s_schema_admits_exactly_its_one_form(pose):
    _agree(MODELS.ObjectIn, {"name": "part", "stable_poses": [pose]})


VECTOR_ITEM = st.sampled_from([0.0, -0.0, 5e-324, -5e-324, 1e-300, 1.0, -3.5, 1e6])


@settings(max_examples=200, derandomize=True, database=None)
@given(st.lists(VECTOR_ITEM, min_size=2, max_size=2))
def test_the_schema_admits_the_directions_the_planner_normalizes(vector):
    body = {"path": {"origin": [0, -10], "direction": vector, "length": 20}}
    schema = MODELS.ObservationIn.model_json_schema()
    admitted = jsonschema.Draft202012Validator(schema).is_valid(body)
    try:
        unit = SensingPath((0.0, -10.0), tuple(vector), 20.0).direction
    except InvalidObservationError:
        unit = None
    assert admitted == (unit is not None) == any(vector)
    if unit is not None:
        assert math.hypot(*unit) == pytest.approx(1.0)
        signs = [
            (math.copysign(1, u), math.copysign(1, v))
            for u, v in zip(unit, vector, strict=True)
            if v
        ]
        assert all(a == b for a, b in signs)
