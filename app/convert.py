"""JSON (DESIGN §6) <-> planner objects: observations, stored sessions, answers.

>>> obs = observation_from_dict(
...     {"path": {"origin": [0, -10], "direction": [0, 2], "length": 20}, "contact": None})
>>> observation_to_dict(obs)["path"]["direction"]
[0.0, 1.0]
"""

from __future__ import annotations

import hashlib
import json
import math
import uuid
from collections.abc import Mapping
from typing import Any

import numpy as np
import pydantic_core

from app.schemas import (
    ErrorBoundOut,
    HypothesisOut,
    ObservationOut,
    PlannedPathOut,
    PlanOut,
    PoseOut,
    SensorOut,
    SessionOut,
    StrategyOut,
    WorkspaceOut,
)
from app.store import SessionRecord
from planner.models.library import object_from_dict
from planner.planning.config import StrategyConfig
from planner.planning.result import Plan
from planner.recognition.interpretation import RecognitionConfig
from planner.recognition.session import Session
from planner.types import Contact, Observation, SensingPath, SensorBounds, Workspace

__all__ = [
    "build_session",
    "catch_up",
    "derive",
    "etag",
    "extends",
    "fingerprint",
    "if_match_ok",
    "observation_from_dict",
    "observation_to_dict",
    "plan_out",
    "plan_rng",
    "session_json",
    "session_out",
    "strategy_config",
]


def etag(version: int) -> str:
    return f'"{version}"'


def if_match_ok(header: str | None, version: int) -> bool:
    """RFC 9110 If-Match against the session's strong ETag (`*` matches any version)."""
    if header is None:
        return True
    tags = [t.strip() for t in header.split(",")]
    return any(t == "*" or t.removeprefix("W/") == etag(version) for t in tags)


def fingerprint(method: str, path: str, query: str, body: Any) -> str:
    """A request's identity for Idempotency-Key: route, query and canonical JSON body."""
    text = json.dumps([method, path, query, body], sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()


def observation_from_dict(data: Mapping[str, Any]) -> Observation:
    """The planner's observation from its §6 JSON (validated, direction normalized)."""
    path = data["path"]
    contact = data.get("contact")
    return Observation(
        SensingPath(tuple(path["origin"]), tuple(path["direction"]), float(path["length"])),
        None
        if contact is None
        else Contact(tuple(contact["point"]), tuple(contact["normal"]), contact.get("normal_z")),
    )


def observation_to_dict(obs: Observation) -> dict[str, Any]:
    p = obs.path
    out: dict[str, Any] = {
        "path": {"origin": list(p.origin), "direction": list(p.direction), "length": p.length},
        "contact": None,
    }
    if obs.contact is not None:
        c = obs.contact
        out["contact"] = {"point": list(c.point), "normal": list(c.normal)}
        if c.normal_z is not None:
            out["contact"]["normal_z"] = c.normal_z
    return out


def build_session(record: SessionRecord) -> Session:
    cfg = record.config
    models = [object_from_dict(o, field=f"objects[{i}]") for i, o in enumerate(cfg["objects"])]
    return Session(
        models,
        SensorBounds(**cfg["sensor"]),
        Workspace(tuple(cfg["workspace"]["center"]), cfg["workspace"]["radius"]),
        RecognitionConfig(max_outliers=cfg["max_outliers"]),
        [observation_from_dict(o) for o in record.observations],
    )


def extends(session: Session, record: SessionRecord) -> bool:
    """True when `session`'s observations are the first ones of `record` (as stored:
    the comparison is exact, on the JSON form the store keeps)."""
    n = len(session.observations)
    return n <= len(record.observations) and all(
        observation_to_dict(mine) == stored
        for mine, stored in zip(session.observations, record.observations[:n], strict=True)
    )


def catch_up(base: Session | None, record: SessionRecord) -> Session:
    """The record's session from `base`, a derived session of the same session id whose
    observations are a prefix of the record's (see :func:`extends`): the remaining
    observations extend its interpretation tree one by one, as if this process had
    seen them arrive. Without a base, the session is rebuilt from all observations."""
    if base is None:
        return build_session(record)
    session = base
    for stored in record.observations[len(base.observations) :]:
        session = session.observe(observation_from_dict(stored))
    return session


def derive(session: Session) -> Session:
    session.hypotheses  # noqa: B018 - compute (and cache) the derived state here, in a thread
    return session


def plan_rng(session_id: str, version: int, seed: int | None) -> np.random.Generator:
    """The random stream of the plan at `version`: ``default_rng([seed, version])`` with
    the session's strategy seed, else seeded from the session id (so every worker
    process makes the same plan for the same version)."""
    if seed is None:
        seed = uuid.UUID(session_id).int % (2**63)
    return np.random.default_rng([seed, version])


def strategy_config(cfg: Mapping[str, Any]) -> StrategyConfig:
    s = cfg["strategy"]
    return StrategyConfig(
        name=s["name"],
        depth=s["depth"],
        budget_ms=s["budget_ms"],
        max_paths=s["max_paths"],
        motion_weight=s["motion_weight"],
        grid_size=s["grid_size"],
        forecast=int(s.get("forecast", 1)),  # sessions stored before it existed: 1
    )


def _finite(x: float) -> float:
    return float(x) if math.isfinite(x) else 0.0


def session_out(
    session_id: str, version: int, cfg: Mapping[str, Any], session: Session, limit: int | None
) -> SessionOut:
    hyps = session.hypotheses
    shown = hyps if limit is None else hyps[:limit]
    return SessionOut(
        id=session_id,
        version=version,
        status=session.status,
        objects=[m.name for m in session.models],
        sensor=SensorOut(**cfg["sensor"]),
        workspace=WorkspaceOut(**cfg["workspace"]),
        sensor_position=cfg["sensor_position"],
        strategy=StrategyOut(**cfg["strategy"]),
        max_outliers=cfg["max_outliers"],
        observations=[
            ObservationOut(index=i, **observation_to_dict(o))
            for i, o in enumerate(session.observations)
        ],
        hypotheses=[
            HypothesisOut(
                object=h.object,
                stable_pose=h.stable_pose,
                pose=PoseOut(x=h.pose.x, y=h.pose.y, theta=h.pose.theta),
                error_bound=ErrorBoundOut(
                    translation=_finite(h.error_bound.translation),
                    rotation=_finite(h.error_bound.rotation),
                    eps_t=_finite(h.error_bound.eps_t),
                ),
                probability=min(max(h.probability, 0.0), 1.0),
                assignment=list(h.assignment),
                equivalence_class=h.equivalence_class,
            )
            for h in shown
        ],
        hypothesis_count=len(hyps),
        class_count=len({h.equivalence_class for h in hyps}),
    )


def _floats(values: Any) -> list[float]:
    return [float(v) for v in values]


def session_json(
    session_id: str, version: int, cfg: Mapping[str, Any], session: Session, limit: int | None
) -> bytes:
    """``session_out(...).model_dump_json()``, byte for byte, without building and
    validating one pydantic model per hypothesis and observation (the answer to
    every observation; a test holds the two equal)."""
    hyps = session.hypotheses
    shown = hyps if limit is None else hyps[:limit]
    s, ws, st = cfg["sensor"], cfg["workspace"], cfg["strategy"]
    observations = []
    for i, o in enumerate(session.observations):
        p, c = o.path, o.contact
        contact = None
        if c is not None:
            z = None if c.normal_z is None else float(c.normal_z)
            contact = {"point": _floats(c.point), "normal": _floats(c.normal), "normal_z": z}
        path = {"origin": _floats(p.origin), "direction": _floats(p.direction)}
        observations.append(
            {"index": i, "path": {**path, "length": float(p.length)}, "contact": contact}
        )
    data = {
        "id": session_id,
        "version": int(version),
        "status": session.status,
        "objects": [m.name for m in session.models],
        "sensor": {
            "position_error": float(s["position_error"]),
            "normal_error": float(s["normal_error"]),
        },
        "workspace": {"center": _floats(ws["center"]), "radius": float(ws["radius"])},
        "sensor_position": _floats(cfg["sensor_position"]),
        "strategy": {
            "name": str(st["name"]),
            "depth": int(st["depth"]),
            "budget_ms": float(st["budget_ms"]),
            "max_paths": int(st["max_paths"]),
            "motion_weight": float(st["motion_weight"]),
            "grid_size": int(st["grid_size"]),
            "forecast": int(st.get("forecast", 1)),
            "seed": None if st.get("seed") is None else int(st["seed"]),
        },
        "max_outliers": int(cfg["max_outliers"]),
        "observations": observations,
        "hypotheses": [
            {
                "object": h.object,
                "stable_pose": int(h.stable_pose),
                "pose": {"x": float(h.pose.x), "y": float(h.pose.y), "theta": float(h.pose.theta)},
                "error_bound": {
                    "translation": _finite(h.error_bound.translation),
                    "rotation": _finite(h.error_bound.rotation),
                    "eps_t": _finite(h.error_bound.eps_t),
                },
                "probability": min(max(float(h.probability), 0.0), 1.0),
                "assignment": [None if f is None else int(f) for f in h.assignment],
                "equivalence_class": int(h.equivalence_class),
            }
            for h in shown
        ],
        "hypothesis_count": len(hyps),
        "class_count": len({h.equivalence_class for h in hyps}),
    }
    # inf/nan as null: what pydantic's model_dump_json writes
    return pydantic_core.to_json(data, inf_nan_mode="null")


def plan_out(result: Plan, version: int, limit: int) -> PlanOut:
    data = result.as_dict(limit=limit)
    return PlanOut(
        status=data["status"],
        truncated=data["truncated"],
        elapsed_ms=data["elapsed_ms"],
        paths=[PlannedPathOut(**p) for p in data["paths"]],
        strategy=data.get("strategy", ""),
        note=data.get("note"),
        candidates=data.get("candidates", 0),
        classes=data.get("classes", 0),
        version=version,
    )
