"""The JSON forms of the planner's values (DESIGN §6): observations, sessions, plans.

One place writes each form; the service, the simulated clients and the load
test all call it. Every function returns plain dicts and lists of ``str``,
``int``, ``float``, ``bool`` and ``None``, in the field order of the §6 answers,
with each number already of the type the answer schema gives it (``float``
for coordinates, lengths, angles and probabilities, ``int`` for counts and
indices), so any JSON encoder writes the bytes the service answers. Nothing
here knows HTTP. World frame, radians, lengths in the object files' unit.

Non-finite numbers: an error bound that is not finite is written 0.0; an
optional plan score that is not finite (``expected_remaining``,
``motion_cost``, ``expected_eps_t``, ``p_forecast``) is written None; the
remaining floats are passed on as they are (JSON encoders write inf and NaN
as null or refuse them).

>>> obs = observation_from_dict(
...     {"path": {"origin": [0, -10], "direction": [0, 2], "length": 20}, "contact": None})
>>> observation_to_dict(obs)
{'path': {'origin': [0.0, -10.0], 'direction': [0.0, 1.0], 'length': 20.0}, 'contact': None}
>>> observation_from_dict(observation_to_dict(obs)) == obs
True
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any, Literal

from planner.planning.config import DEFAULT_WORK
from planner.types import (
    Accuracy,
    Contact,
    Hypothesis,
    Observation,
    PosePrior,
    SensingPath,
    SensorBounds,
    Workspace,
)

if TYPE_CHECKING:
    from planner.planning.result import Plan, PlannedPath
    from planner.recognition.session import Localization, Session

__all__ = [
    "NormalZ",
    "accuracy_from_dict",
    "accuracy_to_dict",
    "contact_to_dict",
    "hypothesis_to_dict",
    "localization_to_dict",
    "observation_from_dict",
    "observation_to_dict",
    "path_to_dict",
    "plan_to_dict",
    "planned_path_to_dict",
    "prior_from_dict",
    "prior_to_dict",
    "sensor_to_dict",
    "session_to_dict",
    "strategy_to_dict",
    "workspace_to_dict",
]

#: How a contact's out-of-plane normal component is written: ``"known"`` only when
#: the contact has one (the request body and the stored form), ``"always"`` (null
#: when unknown: the session answer), ``"omit"`` never (the viewer's drawing data).
NormalZ = Literal["known", "always", "omit"]


def _vec(values: Sequence[float]) -> list[float]:
    return [float(v) for v in values]


def _bounded(x: float) -> float:
    """An error bound as answered: 0.0 where it is not finite."""
    return float(x) if math.isfinite(x) else 0.0


def _optional(x: float | None) -> float | None:
    """An optional score as answered: None where it is unknown or not finite."""
    return None if x is None or not math.isfinite(x) else float(x)


# -- observations -----------------------------------------------------------------------------
def path_to_dict(path: SensingPath, *, height: NormalZ = "known") -> dict[str, Any]:
    """``{"origin": [x, y], "direction": [dx, dy], "length": L}`` (direction a unit
    vector), with ``"height": z`` when the path has a probing height (`height`
    ``"always"``: null without one, as the answers' schema has it)."""
    out: dict[str, Any] = {
        "origin": _vec(path.origin),
        "direction": _vec(path.direction),
        "length": float(path.length),
    }
    if path.height is not None or height == "always":
        out["height"] = None if path.height is None else float(path.height)
    return out


def contact_to_dict(
    contact: Contact | None, *, normal_z: NormalZ = "known"
) -> dict[str, Any] | None:
    """``{"point": [x, y], "normal": [nx, ny], "normal_z": z}`` (see :data:`NormalZ`
    for when ``normal_z`` is written); None for a miss."""
    if contact is None:
        return None
    out: dict[str, Any] = {"point": _vec(contact.point), "normal": _vec(contact.normal)}
    z = contact.normal_z
    if normal_z == "always" or (normal_z == "known" and z is not None):
        out["normal_z"] = None if z is None else float(z)
    return out


def observation_to_dict(obs: Observation, *, normal_z: NormalZ = "known") -> dict[str, Any]:
    """``{"path": {...}, "contact": {...} | null}``: the body of ``POST
    .../observations``, and the form the service stores (`normal_z` ``"always"``:
    the answers' form, every optional field written)."""
    return {
        "path": path_to_dict(obs.path, height="always" if normal_z == "always" else "known"),
        "contact": contact_to_dict(obs.contact, normal_z=normal_z),
    }


def observation_from_dict(data: Mapping[str, Any]) -> Observation:
    """The observation of its JSON form (checked by the planner's types: finite
    numbers, non-zero vectors; direction and normal normalized). Whether the
    contact lies too far behind the path's origin depends on the sensor: the
    session checks it."""
    path = data["path"]
    contact = data.get("contact")
    return Observation(
        SensingPath(
            tuple(path["origin"]),
            tuple(path["direction"]),
            float(path["length"]),
            None if path.get("height") is None else float(path["height"]),
        ),
        None
        if contact is None
        else Contact(tuple(contact["point"]), tuple(contact["normal"]), contact.get("normal_z")),
    )


# -- sessions ---------------------------------------------------------------------------------
def sensor_to_dict(sensor: SensorBounds) -> dict[str, Any]:
    """``{"position_error": length, "normal_error": radians, "tip_radius": length}``."""
    return {
        "position_error": float(sensor.position_error),
        "normal_error": float(sensor.normal_error),
        "tip_radius": float(sensor.tip_radius),
    }


def workspace_to_dict(workspace: Workspace) -> dict[str, Any]:
    """The safe circle: ``{"center": [x, y], "radius": r}``."""
    return {"center": _vec(workspace.center), "radius": float(workspace.radius)}


def strategy_to_dict(strategy: Mapping[str, Any]) -> dict[str, Any]:
    """A session's strategy settings as answered (``forecast`` 1, ``simulations`` 1000
    and ``seed`` None when missing, as in sessions stored before they existed)."""
    seed = strategy.get("seed")
    return {
        "name": str(strategy["name"]),
        "depth": int(strategy["depth"]),
        "budget_ms": float(strategy["budget_ms"]),
        "budget_work": float(strategy.get("budget_work", DEFAULT_WORK)),
        "max_paths": int(strategy["max_paths"]),
        "motion_weight": float(strategy["motion_weight"]),
        "grid_size": int(strategy["grid_size"]),
        "forecast": int(strategy.get("forecast", 1)),
        "simulations": int(strategy.get("simulations", 1000)),
        "seed": None if seed is None else int(seed),
    }


def hypothesis_to_dict(h: Hypothesis) -> dict[str, Any]:
    """Object, stable pose, pose (model -> world), error bound, probability (clipped
    to [0, 1]), face per contact (None: spurious) and equivalence class."""
    e = h.error_bound
    return {
        "object": h.object,
        "stable_pose": int(h.stable_pose),
        "pose": {"x": float(h.pose.x), "y": float(h.pose.y), "theta": float(h.pose.theta)},
        "error_bound": {
            "translation": _bounded(e.translation),
            "rotation": _bounded(e.rotation),
            "eps_t": _bounded(e.eps_t),
        },
        "probability": min(max(float(h.probability), 0.0), 1.0),
        "assignment": [None if f is None else int(f) for f in h.assignment],
        "equivalence_class": int(h.equivalence_class),
    }


def session_to_dict(
    session_id: str,
    version: int,
    cfg: Mapping[str, Any],
    session: Session,
    limit: int | None = None,
) -> dict[str, Any]:
    """The §6 session answer: `cfg` holds the session's settings as created
    (``sensor_position``, ``strategy``, ``max_outliers``; sensor bounds and safe
    circle are the session's own); at most `limit` hypotheses, most probable first
    (None: all); ``hypothesis_count`` and ``class_count`` count them all."""
    hyps = session.hypotheses
    shown = hyps if limit is None else hyps[:limit]
    return {
        "id": session_id,
        "version": int(version),
        "status": session.status,
        "objects": [m.name for m in session.models],
        "sensor": sensor_to_dict(session.sensor),
        "workspace": workspace_to_dict(session.workspace),
        "sensor_position": _vec(cfg["sensor_position"]),
        "strategy": strategy_to_dict(cfg["strategy"]),
        "max_outliers": int(cfg["max_outliers"]),
        "observations": [
            {"index": i, **observation_to_dict(o, normal_z="always")}
            for i, o in enumerate(session.observations)
        ],
        "hypotheses": [hypothesis_to_dict(h) for h in shown],
        "hypothesis_count": len(hyps),
        "class_count": len({h.equivalence_class for h in hyps}),
        "accuracy": accuracy_to_dict(session.accuracy),
        "localization": localization_to_dict(session.localization),
        "prior": None if session.config.prior is None else prior_to_dict(session.config.prior),
    }


def accuracy_to_dict(accuracy: Accuracy) -> dict[str, Any]:
    """``{"translation": length, "rotation": radians}``: what `localized` requires."""
    return {"translation": float(accuracy.translation), "rotation": float(accuracy.rotation)}


def accuracy_from_dict(data: Mapping[str, Any] | None) -> Accuracy | None:
    """The accuracy of its JSON form (None: the session's default)."""
    if data is None:
        return None
    return Accuracy(float(data["translation"]), float(data["rotation"]))


def prior_to_dict(prior: PosePrior) -> dict[str, Any]:
    """``{"region": {"center", "radius"} | None, "theta": [lo, hi] | None}``."""
    region = None
    if prior.center is not None and prior.radius is not None:
        region = {"center": _vec(prior.center), "radius": float(prior.radius)}
    theta = None if prior.theta is None else [float(prior.theta[0]), float(prior.theta[1])]
    return {"region": region, "theta": theta}


def prior_from_dict(data: Mapping[str, Any] | None) -> PosePrior | None:
    """The pose prior of its JSON form (None, or both parts null: none)."""
    if data is None:
        return None
    region, theta = data.get("region"), data.get("theta")
    if region is None and theta is None:
        return None
    return PosePrior(
        None if region is None else tuple(region["center"]),
        None if region is None else float(region["radius"]),
        None if theta is None else (float(theta[0]), float(theta[1])),
    )


def localization_to_dict(loc: Localization) -> dict[str, Any]:
    """How far the session is from `localized`: classes left, the answer's bound
    (null without a hypothesis), what is missing (``one_class``, ``accuracy``),
    whether the rotation is free (a round outline's), how many classes the bound
    covers."""
    bound = None
    if loc.bound is not None:
        bound = {
            "translation": _bounded(loc.bound.translation),
            "rotation": _bounded(loc.bound.rotation),
            "eps_t": _bounded(loc.bound.eps_t),
        }
    return {
        "classes": int(loc.classes),
        "bound": bound,
        "missing": list(loc.missing),
        "rotation_free": bool(loc.rotation_free),
        "covered": int(loc.covered),
    }


# -- plans ------------------------------------------------------------------------------------
def planned_path_to_dict(p: PlannedPath) -> dict[str, Any]:
    """One ranked path: geometry, aim point, family and scores."""
    return {
        "origin": _vec(p.origin),
        "direction": _vec(p.direction),
        "length": float(p.length),
        "aim": _vec(p.aim),
        "family": str(p.family),
        "p_distinguishing": float(p.p_distinguishing),
        "p_informative": float(p.p_informative),
        "expected_pruning": float(p.expected_pruning),
        "expected_remaining": _optional(p.expected_remaining),
        "motion_cost": _optional(p.motion_cost),
        "source": None if p.source is None else str(p.source),
        "expected_eps_t": _optional(p.expected_eps_t),
        "p_forecast": _optional(p.p_forecast),
        "scored_by": str(p.scored_by),
        "height": _optional(p.height),
    }


def plan_to_dict(plan: Plan, version: int, limit: int | None = None) -> dict[str, Any]:
    """The §6 plan answer for session `version`: its first `limit` paths (None: all),
    best first."""
    paths = plan.paths if limit is None else plan.paths[:limit]
    return {
        "status": plan.status,
        "truncated": bool(plan.truncated),
        "elapsed_ms": float(plan.elapsed_ms),
        "paths": [planned_path_to_dict(p) for p in paths],
        "strategy": str(plan.strategy),
        "note": None if plan.note is None else str(plan.note),
        "candidates": int(plan.candidates),
        "classes": int(plan.classes),
        "work": float(plan.work),
        "stopped_by": plan.stopped_by,
        "version": int(version),
    }
