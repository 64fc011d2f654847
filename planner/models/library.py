"""Object files in and out (DESIGN §8): the only file I/O in the planner.

Format: ``{"objects": [{"name": ..., "stable_poses": [{"outline": [[x, y], ...],
"holes": [[[x, y], ...]], "probability": p, "normal_z": [...]}], "prior": w}]}``;
an object with a plain ``"outline"`` (and optional ``"holes"``) is shorthand for
one stable pose of probability 1. A stable pose probed at several heights gives
``"slices": [{"height": z, "outline": ..., "holes": ..., "normal_z": ...}, ...]``
instead of its outline, the first slice at the default height (DESIGN §4.13).
Coordinates are kept exactly as given.
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Iterable, Mapping
from importlib import resources
from pathlib import Path
from typing import Any

from planner.errors import InvalidModelError, ModelFileError
from planner.models.outlines import make_stable_pose, with_slices
from planner.types import ObjectModel, StablePose

__all__ = [
    "dump_objects",
    "embedded_sets",
    "load_objects",
    "object_file",
    "object_from_dict",
    "object_to_dict",
    "parse_objects",
]

_OBJECT_KEYS = {"name", "outline", "holes", "stable_poses", "prior", "normal_z", "probability"}
_POSE_KEYS = {"outline", "holes", "probability", "normal_z", "slices"}
_SLICE_KEYS = {"height", "outline", "holes", "normal_z"}


def object_from_dict(data: Any, *, field: str = "object") -> ObjectModel:
    """Build and validate one object from its §8 dictionary.

    >>> obj = object_from_dict({"name": "tri", "outline": [[0, 0], [1, 0], [0, 1]]})
    >>> obj.name, len(obj.stable_poses), obj.stable_poses[0].probability
    ('tri', 1, 1.0)
    """
    if not isinstance(data, Mapping):
        raise ModelFileError("must be a JSON object", field=field)
    unknown = set(data) - _OBJECT_KEYS
    if unknown:
        raise ModelFileError(f"unknown keys {sorted(unknown)}", field=field)
    name = data.get("name")
    if not isinstance(name, str) or not name.strip() or len(name) > 200:
        raise ModelFileError(
            "must be a non-empty string of at most 200 characters", field=f"{field}.name"
        )
    if ("outline" in data) == ("stable_poses" in data):
        raise ModelFileError("give exactly one of 'outline' or 'stable_poses'", field=field)
    if "outline" in data:
        poses_data: list[Any] = [
            {k: data[k] for k in ("outline", "holes", "normal_z") if k in data}
        ]
        pose_field = [field]
    else:
        poses_data = data["stable_poses"]
        if not isinstance(poses_data, list) or not poses_data:
            raise ModelFileError("must be a non-empty list", field=f"{field}.stable_poses")
        pose_field = [f"{field}.stable_poses[{i}]" for i in range(len(poses_data))]
    poses = []
    for pose_data, pf in zip(poses_data, pose_field, strict=True):
        if not isinstance(pose_data, Mapping) or ("outline" in pose_data) == (
            "slices" in pose_data
        ):
            raise ModelFileError(
                "must be an object with exactly one of 'outline' and 'slices'", field=pf
            )
        unknown = set(pose_data) - _POSE_KEYS
        if unknown:
            raise ModelFileError(f"unknown keys {sorted(unknown)}", field=pf)
        probability = pose_data.get("probability", 1.0)
        if isinstance(probability, bool) or not isinstance(probability, int | float):
            raise ModelFileError("must be a number", field=f"{pf}.probability")
        if "outline" in pose_data:
            poses.append(_outline(pose_data, float(probability), pf))
            continue
        slices = pose_data["slices"]
        if not isinstance(slices, list) or not slices:
            raise ModelFileError("must be a non-empty list", field=f"{pf}.slices")
        layers = []
        for k, sl in enumerate(slices):
            sf = f"{pf}.slices[{k}]"
            if not isinstance(sl, Mapping) or not {"height", "outline"} <= set(sl):
                raise ModelFileError("must be an object with 'height' and 'outline'", field=sf)
            if set(sl) - _SLICE_KEYS:
                raise ModelFileError(f"unknown keys {sorted(set(sl) - _SLICE_KEYS)}", field=sf)
            z = sl["height"]
            if isinstance(z, bool) or not isinstance(z, int | float):
                raise ModelFileError("must be a number", field=f"{sf}.height")
            layers.append((float(z), _outline(sl, float(probability), sf)))
        poses.append(with_slices(layers, field=f"{pf}.slices"))
    total = sum(p.probability for p in poses)
    if total > 1 + 1e-6:
        raise InvalidModelError(
            f"stable pose probabilities sum to {total:.4g} > 1", field=f"{field}.stable_poses"
        )
    prior = data.get("prior")
    if prior is not None and (
        isinstance(prior, bool)
        or not isinstance(prior, int | float)
        or not math.isfinite(prior)
        or prior <= 0
    ):
        raise ModelFileError("must be a finite number > 0", field=f"{field}.prior")
    return ObjectModel(
        name=name, stable_poses=tuple(poses), prior=None if prior is None else float(prior)
    )


def _outline(data: Mapping[str, Any], probability: float, field: str) -> StablePose:
    holes = data.get("holes", [])
    if not isinstance(holes, list):
        raise ModelFileError("must be a list of rings", field=f"{field}.holes")
    return make_stable_pose(
        data["outline"], holes, probability, data.get("normal_z"), field=f"{field}.outline"
    )


def _rings(pose: StablePose) -> dict[str, Any]:
    entry: dict[str, Any] = {"outline": pose.outline.tolist()}
    if pose.holes:
        entry["holes"] = [h.tolist() for h in pose.holes]
    if pose.normal_z is not None:
        entry["normal_z"] = pose.normal_z.tolist()
    return entry


def object_to_dict(obj: ObjectModel) -> dict[str, Any]:
    """The §8 dictionary of one object (always in the `stable_poses` form)."""
    poses = []
    for pose in obj.stable_poses:
        if pose.height is None:
            entry = _rings(pose)
        else:
            entry = {"slices": [{"height": p.height, **_rings(p)} for p in pose.layers]}
        poses.append({**entry, "probability": pose.probability})
    out: dict[str, Any] = {"name": obj.name, "stable_poses": poses}
    if obj.prior is not None:
        out["prior"] = obj.prior
    return out


def parse_objects(data: Any) -> list[ObjectModel]:
    """Validate a whole §8 document (already decoded JSON)."""
    if not isinstance(data, Mapping) or not isinstance(data.get("objects"), list):
        raise ModelFileError("must be a JSON object with an 'objects' list", field="objects")
    objects = [object_from_dict(o, field=f"objects[{i}]") for i, o in enumerate(data["objects"])]
    if not objects:
        raise ModelFileError("must hold at least one object", field="objects")
    names = [o.name for o in objects]
    duplicate = next((n for n in names if names.count(n) > 1), None)
    if duplicate is not None:
        raise ModelFileError(f"name {duplicate!r} appears twice", field="objects")
    return objects


def embedded_sets() -> list[str]:
    """Names of the object sets shipped with the package (``planner/data``)."""
    data = resources.files("planner") / "data"
    return sorted(p.name.removesuffix(".json") for p in data.iterdir() if p.name.endswith(".json"))


def object_file(value: str | os.PathLike[str]) -> Path:
    """The object file `value` names: a path, or the name of an embedded set.

    >>> object_file("thesis_like").name
    'thesis_like.json'
    """
    path = Path(value)
    if path.exists() or path.suffix == ".json" or len(path.parts) > 1:
        return path
    if str(value) not in embedded_sets():
        raise ModelFileError(
            f"no file {str(value)!r} and no embedded set of that name; sets: {embedded_sets()}",
            field="path",
        )
    return Path(str(resources.files("planner") / "data" / f"{value}.json"))


def load_objects(path: str | os.PathLike[str]) -> list[ObjectModel]:
    """Read and validate an object file (a path, or an embedded set's name)."""
    path = object_file(path)
    try:
        text = Path(path).read_text(encoding="utf-8")
    except OSError as exc:
        raise ModelFileError(f"cannot read {path}: {exc.strerror}", field="path") from exc
    try:
        data = json.loads(text)
    except json.JSONDecodeError as exc:
        raise ModelFileError(f"not valid JSON: {exc}", field="path") from exc
    return parse_objects(data)


def dump_objects(objects: Iterable[ObjectModel], path: str | os.PathLike[str]) -> None:
    """Write objects as a §8 file atomically (a reader never sees half a file)."""
    target = Path(path)
    tmp = target.with_name(f".{target.name}.tmp")
    tmp.write_text(
        json.dumps({"objects": [object_to_dict(o) for o in objects]}, indent=1), encoding="utf-8"
    )
    os.replace(tmp, target)
