"""Sessions: create, read, delete (DESIGN §6)."""

from typing import Annotated

from fastapi import APIRouter, Query, Request, Response

from app.deps import ClientDep, IdempotencyKey, IfMatch, ServiceDep, SessionId, auth_dependencies
from app.routes import (
    PRECONDITION_REQUIRED,
    PROBLEMS,
    request_fingerprint,
    require_precondition,
    respond,
)
from app.schemas import InputModels, SessionOut
from app.settings import Settings

__all__ = ["HypothesisLimit", "build_router"]

HypothesisLimit = Annotated[
    int | None, Query(ge=0, le=1_000_000, description="at most this many hypotheses")
]


def build_router(inputs: InputModels, settings: Settings) -> APIRouter:
    router = APIRouter(
        prefix="/v1/sessions",
        tags=["sessions"],
        dependencies=auth_dependencies(settings),
        responses=PROBLEMS,
    )
    SessionCreate = inputs.SessionCreate

    @router.post(
        "",
        status_code=201,
        response_model=SessionOut,
        responses={201: {"headers": {"ETag": {"schema": {"type": "string"}}}}},
    )
    async def create_session(
        body: SessionCreate,  # type: ignore[valid-type]
        request: Request,
        service: ServiceDep,
        client: ClientDep,
        idempotency_key: IdempotencyKey = None,
        limit: HypothesisLimit = None,
    ):
        """Start a recognition over an object set (registered names or inline §8 objects).
        The session belongs to the client whose key created it: other keys get 404."""
        data = body.model_dump(mode="json")  # type: ignore[attr-defined]
        data["objects"] = [
            o if isinstance(o, str) else o.as_dict()
            for o in body.objects  # type: ignore[attr-defined]
        ]
        fp = request_fingerprint(request, body)
        return respond(await service.create_session(data, idempotency_key, fp, limit, client))

    @router.get("/{session_id}", response_model=SessionOut)
    async def get_session(
        session_id: SessionId, service: ServiceDep, limit: HypothesisLimit = None
    ):
        """The session: status, observations and hypotheses (most probable first)."""
        return respond(await service.get_session(str(session_id), limit))

    @router.delete(
        "/{session_id}", status_code=204, response_class=Response, responses=PRECONDITION_REQUIRED
    )
    async def delete_session(
        session_id: SessionId,
        service: ServiceDep,
        if_match: IfMatch = None,
        idempotency_key: IdempotencyKey = None,
    ):
        """Delete the session and its observations.

        Needs If-Match (the session's ETag) or an Idempotency-Key: 428 without both."""
        require_precondition(if_match, idempotency_key, "delete")
        await service.delete_session(str(session_id), if_match)
        return Response(status_code=204)

    return router
