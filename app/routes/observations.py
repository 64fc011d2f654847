"""Observations: append one (the planner updates the hypotheses), undo the last."""

from fastapi import APIRouter, Request

from app.deps import IdempotencyKey, IfMatch, ServiceDep, SessionId, auth_dependencies
from app.routes import (
    PRECONDITION_REQUIRED,
    PROBLEMS,
    request_fingerprint,
    require_precondition,
    respond,
)
from app.routes.sessions import HypothesisLimit
from app.schemas import InputModels, SessionOut
from app.settings import Settings

__all__ = ["build_router"]


def build_router(inputs: InputModels, settings: Settings) -> APIRouter:
    router = APIRouter(
        prefix="/v1/sessions/{session_id}/observations",
        tags=["observations"],
        dependencies=auth_dependencies(settings),
        responses=PROBLEMS,
    )
    ObservationIn = inputs.ObservationIn

    @router.post("", status_code=201, response_model=SessionOut)
    async def add_observation(
        session_id: SessionId,
        body: ObservationIn,  # type: ignore[valid-type]
        request: Request,
        service: ServiceDep,
        if_match: IfMatch = None,
        idempotency_key: IdempotencyKey = None,
        limit: HypothesisLimit = None,
    ):
        """Record one executed sensing path and its contact (null: it touched nothing).

        Answers the new session state once the observation is stored durably.
        Touches no interpretation explains give status `inconsistent` (undo recovers)."""
        fp = request_fingerprint(request, body)
        data = body.model_dump(mode="json")  # type: ignore[attr-defined]
        answer = await service.add_observation(
            str(session_id), data, idempotency_key, fp, if_match, limit
        )
        return respond(answer)

    @router.delete("/last", response_model=SessionOut, responses=PRECONDITION_REQUIRED)
    async def undo_observation(
        session_id: SessionId,
        request: Request,
        service: ServiceDep,
        if_match: IfMatch = None,
        idempotency_key: IdempotencyKey = None,
        limit: HypothesisLimit = None,
    ):
        """Undo: drop the last observation and answer the session state before it.

        Needs If-Match (the session's ETag) or an Idempotency-Key: 428 without both."""
        require_precondition(if_match, idempotency_key, "undo")
        fp = request_fingerprint(request, None)
        answer = await service.undo(str(session_id), idempotency_key, fp, if_match, limit)
        return respond(answer)

    return router
