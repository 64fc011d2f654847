"""Stored sessions -> planner sessions -> answer bytes.

The JSON forms themselves (observation, session, plan) are written by
:mod:`planner.codec`; this module rebuilds planner sessions from stored records,
checks versions (ETag, If-Match) and request identities (Idempotency-Key), and
turns a form into the bytes of an answer (:func:`to_json`).

>>> to_json({"x": 1.0, "y": float("inf")})
b'{"x":1.0,"y":null}'
"""

from __future__ import annotations

import hashlib
import json
import uuid
from collections.abc import Callable, Mapping
from typing import Any

import numpy as np
import pydantic_core

from app.errors import LimitExceededError
from app.store_types import IdempotentWrite, SessionRecord, Snapshot, StoredResponse
from planner.codec import (
    accuracy_from_dict,
    observation_from_dict,
    observation_to_dict,
    plan_to_dict,
    prior_from_dict,
    session_to_dict,
)
from planner.models.library import object_from_dict
from planner.planning.config import DEFAULT_WORK, StrategyConfig
from planner.planning.result import Plan
from planner.recognition.config import RecognitionConfig
from planner.recognition.session import Session
from planner.recognition.snapshot import code_version, restore, snapshot
from planner.types import Observation, SensorBounds, Workspace

__all__ = [
    "build_session",
    "catch_up",
    "derive",
    "draw",
    "etag",
    "extends",
    "fingerprint",
    "idempotent_write",
    "if_match_ok",
    "next_state",
    "observed",
    "plan_json",
    "plan_rng",
    "resume",
    "session_json",
    "strategy_config",
    "to_json",
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


def build_session(record: SessionRecord) -> Session:
    cfg = record.config
    models = [object_from_dict(o, field=f"objects[{i}]") for i, o in enumerate(cfg["objects"])]
    return Session(
        models,
        SensorBounds(**cfg["sensor"]),
        Workspace(tuple(cfg["workspace"]["center"]), cfg["workspace"]["radius"]),
        RecognitionConfig(
            max_outliers=cfg["max_outliers"], prior=prior_from_dict(cfg.get("prior"))
        ),
        [observation_from_dict(o) for o in record.observations],
        accuracy=accuracy_from_dict(cfg.get("accuracy")),
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
        budget_work=s.get("budget_work", DEFAULT_WORK),  # sessions stored before it existed
        max_paths=s["max_paths"],
        motion_weight=s["motion_weight"],
        grid_size=s["grid_size"],
        forecast=int(s.get("forecast", 1)),  # sessions stored before it existed: 1
        simulations=int(s.get("simulations", StrategyConfig.simulations)),
    )


def to_json(data: Any) -> bytes:
    """Compact JSON of a JSON-ready form, non-finite floats as null (what the
    response models' ``model_dump_json`` writes for the same values)."""
    return pydantic_core.to_json(data, inf_nan_mode="null")


def session_json(
    session_id: str, version: int, cfg: Mapping[str, Any], session: Session, limit: int | None
) -> bytes:
    """The session answer's bytes (:func:`planner.codec.session_to_dict`)."""
    return to_json(session_to_dict(session_id, version, cfg, session, limit))


def plan_json(result: Plan, version: int, limit: int | None) -> bytes:
    """The plan answer's bytes (:func:`planner.codec.plan_to_dict`)."""
    return to_json(plan_to_dict(result, version, limit))


def next_state(
    record: SessionRecord,
    current: Session,
    step: Callable[[SessionRecord, Session], Session],
    limit: int | None,
    keep: bool,
) -> tuple[Session, bytes, Snapshot | None]:
    """The session after `step`, derived, its JSON at the next version and, when it
    is to be kept (`keep`), its snapshot (in a thread)."""
    new = derive(step(record, current))
    body = session_json(record.id, record.version + 1, record.config, new, limit)
    return new, body, Snapshot(code_version(), snapshot(new)) if keep else None


def observed(session: Session, observation: Observation, most: int, work: int) -> Session:
    """The session after `observation`, refused (409) when checking the
    interpretations it leaves would cost more than `work` units (naming
    ``max_interpretation_work``; known before any is checked), or when it would
    leave more than `most` hypotheses (naming ``max_hypotheses``: counted from the
    tree, before the equivalence classes, whose cost grows with the hypotheses)."""
    new = session.observe(observation)
    if (cost := new.interpretation_work) > work:
        raise LimitExceededError(
            f"this observation would leave interpretations costing {cost} units to check, "
            f"over max_interpretation_work ({work}); it is not recorded. Give the session "
            "a prior (where the part lies) or fewer objects or stable poses; a part "
            "localized long ago needs no more touches",
            field="max_interpretation_work",
        )
    if (count := new.hypothesis_count) > most:
        raise LimitExceededError(
            f"this observation would leave {count} hypotheses, over max_hypotheses "
            f"({most}); it is not recorded. Give the session a prior (where the part "
            "lies) or fewer objects or stable poses",
            field="max_hypotheses",
        )
    return new


def resume(base: Session | None, stored: bytes | None, record: SessionRecord) -> Session:
    """The record's derived session from a stored snapshot newer than the in-memory
    base (when it was written by this code and its observations begin the
    record's), else from the base, extended by the rest."""
    restored = restore(stored) if stored is not None else None
    if restored is not None and extends(restored, record):
        base = restored
    return derive(catch_up(base, record))


def draw(
    session: Session, result: Plan, record: SessionRecord, kind: str, view: str, dpi: int
) -> bytes:
    """The session's picture (SVG or PNG bytes) with its plan, titled by id and version."""
    from planner.render import session_picture

    cfg = record.config
    return session_picture(
        session,
        cfg["sensor_position"],
        result,
        fmt=kind,
        view=view,
        grid_size=cfg["strategy"]["grid_size"],
        title=f"session {record.id[:8]} v{record.version}: {session.status}",
        dpi=dpi,
    )


def idempotent_write(scope: str, key: str | None, fp: str, answer: Any) -> IdempotentWrite | None:
    """What the store keeps of `answer` under an Idempotency-Key (None without a key)."""
    if key is None:
        return None
    return IdempotentWrite(
        scope, key, StoredResponse(fp, answer.status, answer.body, answer.headers)
    )
