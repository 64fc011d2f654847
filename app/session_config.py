"""The stored configuration of a new session (DESIGN §6 ``POST /v1/sessions``).

The create body, validated by its schema, with its object references resolved
(registered names or inline §8 objects) into planner models, then written in the
form the store keeps and :func:`app.convert.build_session` reads back: the
objects as §8 dictionaries, sensor bounds, safe circle, the sensor's place on
it (default: the circle's +x point), strategy settings and allowed outliers.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

from app.convert import strategy_config
from app.errors import InvalidInputError
from planner.codec import (
    accuracy_from_dict,
    accuracy_to_dict,
    prior_from_dict,
    prior_to_dict,
    sensor_to_dict,
    workspace_to_dict,
)
from planner.models.library import object_from_dict, object_to_dict
from planner.models.simplify import simplify_models
from planner.types import ObjectModel, SensorBounds, Workspace

__all__ = ["check_worked_size", "resolve_models", "session_config"]


def resolve_models(
    refs: Sequence[str | Mapping[str, Any]], stored: Mapping[str, Any]
) -> list[ObjectModel]:
    """The models of a session's `refs`: a name is looked up in `stored` (the
    registered objects by name), a dictionary is read as an inline object; each
    object once. Errors name the offending ``objects[i]``."""
    models = []
    for i, ref in enumerate(refs):
        if isinstance(ref, str):
            if ref not in stored:
                raise InvalidInputError(
                    f"no registered object named {ref!r}; register it with "
                    "POST /v1/objects or give it inline",
                    field=f"objects[{i}]",
                )
            models.append(object_from_dict(stored[ref], field=f"objects[{i}]"))
        else:
            models.append(object_from_dict(ref, field=f"objects[{i}]"))
    seen: dict[str, int] = {}
    for i, m in enumerate(models):
        if m.name in seen:
            raise InvalidInputError(
                f"object {m.name!r} appears twice (also objects[{seen[m.name]}])",
                field=f"objects[{i}]",
            )
        seen[m.name] = i
    return models


def check_worked_size(models: Sequence[ObjectModel], sensor: SensorBounds, limit: int) -> None:
    """Refuses an object whose outline, simplified within the `sensor`'s bounds
    (:func:`~planner.models.simplify.simplify_models`), still has a ring of more
    than `limit` vertices: the size the session's work grows with."""
    worked, _ = simplify_models(models, sensor)
    for i, (given, m) in enumerate(zip(models, worked, strict=True)):
        for k, (g, p) in enumerate(zip(given.stable_poses, m.stable_poses, strict=True)):
            for layer, given_layer in zip(p.layers, g.layers, strict=True):
                rings = [(len(a), len(b)) for a, b in zip(
                    [layer.outline, *layer.holes],
                    [given_layer.outline, *given_layer.holes],
                    strict=True,
                )]  # fmt: skip
                kept, drawn = max(rings)
                if kept > limit:
                    raise InvalidInputError(
                        f"a ring of {drawn} vertices keeps {kept} after simplification "
                        f"within the sensor's bounds; at most {limit} "
                        "(max_worked_vertices): draw the part more coarsely or give "
                        "larger sensor bounds",
                        field=f"objects[{i}].stable_poses[{k}]",
                    )


def session_config(
    body: Mapping[str, Any], models: Sequence[ObjectModel], max_worked: int | None = None
) -> dict[str, Any]:
    """The stored configuration of a session created with `body` over `models`
    (checked by the planner: sensor bounds, safe circle, strategy; and, given
    `max_worked`, :func:`check_worked_size`)."""
    ws = body["workspace"]
    workspace = Workspace(tuple(ws["center"]), ws["radius"])
    sensor = SensorBounds(**body["sensor"])
    if max_worked is not None:
        check_worked_size(models, sensor, max_worked)
    position = body.get("sensor_position") or [
        workspace.center[0] + workspace.radius,
        workspace.center[1],
    ]
    cfg = {
        "objects": [object_to_dict(m) for m in models],
        "sensor": sensor_to_dict(sensor),
        "workspace": workspace_to_dict(workspace),
        "sensor_position": [float(v) for v in position],
        "strategy": dict(body["strategy"]),
        "max_outliers": body["max_outliers"],
    }
    accuracy = accuracy_from_dict(body.get("accuracy"))  # the planner's own checks
    if accuracy is not None:
        cfg["accuracy"] = accuracy_to_dict(accuracy)
    prior = prior_from_dict(body.get("prior"))  # the planner's own checks
    if prior is not None:
        cfg["prior"] = prior_to_dict(prior)
    strategy_config(cfg)  # the planner's own checks
    return cfg
