"""Rules across fields of the request bodies, said in JSON Schema as well as
checked by the models' validators, so that generated clients and API testers know
them: an object is an outline or stable poses, a stable pose an outline or
slices, a direction not the zero vector.

``if``/``then``/``else`` rather than ``oneOf``: client generators turn a ``oneOf``
into a union of anonymous models, and these rules constrain one model.
"""

from __future__ import annotations

from typing import Any

__all__ = ["NOT_ZERO", "ONE_POSE_FORM", "ONE_SHAPE", "only_one_shape"]

#: A vector whose items are not all zero (JSON numbers: -0.0 is 0 too).
NOT_ZERO = {"not": {"items": {"const": 0}}}


def _given(*fields: str, **forms: dict[str, Any]) -> dict[str, Any]:
    """JSON Schema: each of `fields` present, and each of `forms` present in that form."""
    return (
        {"required": [*fields, *forms], "properties": forms} if forms else {"required": [*fields]}
    )


def _none_of(*schemas: dict[str, Any]) -> dict[str, Any]:
    return {"not": {"anyOf": list(schemas)}}


_ARRAY = {"type": "array"}
# What the validators below refuse, said in the schema so that clients and testers
# see it: an object is an outline or stable poses, never both or neither (a key
# given as null counts as given), with holes and normal_z beside an outline only;
# a stable pose is an outline or slices (null counts as absent), holes and
# normal_z beside an outline only.
ONE_SHAPE = {
    "if": _given("stable_poses"),
    "then": {
        "properties": {"stable_poses": _ARRAY},
        **_none_of(*map(_given, ("outline", "holes", "normal_z"))),
    },
    "else": _given(outline=_ARRAY),
}
ONE_POSE_FORM = {
    "if": _given(slices=_ARRAY),
    "then": _none_of(
        _given(outline=_ARRAY), _given(holes={"minItems": 1}), _given(normal_z=_ARRAY)
    ),
    "else": _given(outline=_ARRAY),
}


def only_one_shape(data: Any) -> Any:
    if isinstance(data, dict):
        if ("outline" in data) == ("stable_poses" in data):
            raise ValueError("give exactly one of 'outline' or 'stable_poses'")
        if "stable_poses" in data and ("holes" in data or "normal_z" in data):
            raise ValueError("with 'stable_poses', 'holes' and 'normal_z' go in each pose")
    return data
