"""HTTP routes (DESIGN §6). Each module builds one router from the app's input models
and settings; the routes only translate between HTTP and :mod:`app.service`."""

from __future__ import annotations

from typing import Any

from fastapi import Request, Response
from pydantic import BaseModel

from app.convert import fingerprint
from app.errors import PreconditionRequiredError, Problem
from app.service import Answer

__all__ = [
    "PRECONDITION_REQUIRED",
    "PROBLEMS",
    "request_fingerprint",
    "require_precondition",
    "respond",
]

#: Error answers every route may give (their media type becomes application/problem+json).
PROBLEMS: dict[int | str, dict[str, Any]] = {
    status: {"model": Problem, "description": description}
    for status, description in [
        (400, "malformed request (e.g. not JSON)"),
        (401, "missing or wrong API key"),
        (404, "no such resource"),
        (409, "conflicts with the resource's state"),
        (412, "If-Match does not match the session's version"),
        (413, "request body too large"),
        (422, "invalid input; `errors` names each field"),
        (503, "busy (fits and plans queued) or the store unavailable: retry after Retry-After"),
    ]
}


#: The answer of undo and delete without If-Match or an Idempotency-Key.
PRECONDITION_REQUIRED: dict[int | str, dict[str, Any]] = {
    428: {
        "model": Problem,
        "description": "needs If-Match (the session's ETag) or an Idempotency-Key",
    }
}


def respond(answer: Answer, media_type: str = "application/json") -> Response:
    headers = dict(answer.headers)
    media_type = headers.pop("Content-Type", media_type)
    if answer.replayed:
        headers["Idempotent-Replayed"] = "true"
    return Response(answer.body, answer.status, headers=headers, media_type=media_type)


def require_precondition(if_match: str | None, idempotency_key: str | None, what: str) -> None:
    """Undo and delete act on "whatever is there now": without If-Match (or an
    Idempotency-Key naming this one request) a client could undo another client's
    acknowledged touch, or delete a session it has not seen. 428 names what to send."""
    if if_match is None and idempotency_key is None:
        raise PreconditionRequiredError(
            f"{what} needs If-Match with the session's ETag (its version, as answered in "
            "the ETag header) or an Idempotency-Key",
            field="If-Match",
        )


def request_fingerprint(request: Request, body: BaseModel | None) -> str:
    query = "&".join(f"{k}={v}" for k, v in sorted(request.query_params.multi_items()))
    data = None if body is None else body.model_dump(mode="json")
    return fingerprint(request.method, request.url.path, query, data)
