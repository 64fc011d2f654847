"""HTTP routes (DESIGN §6). Each module builds one router from the app's input models
and settings; the routes only translate between HTTP and :mod:`app.service`."""

from __future__ import annotations

from typing import Any

from fastapi import Request, Response
from pydantic import BaseModel

from app.convert import fingerprint
from app.errors import Problem
from app.service import Answer

__all__ = ["PROBLEMS", "request_fingerprint", "respond"]

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
    ]
}


def respond(answer: Answer, media_type: str = "application/json") -> Response:
    headers = dict(answer.headers)
    media_type = headers.pop("Content-Type", media_type)
    if answer.replayed:
        headers["Idempotent-Replayed"] = "true"
    return Response(answer.body, answer.status, headers=headers, media_type=media_type)


def request_fingerprint(request: Request, body: BaseModel | None) -> str:
    query = "&".join(f"{k}={v}" for k, v in sorted(request.query_params.multi_items()))
    data = None if body is None else body.model_dump(mode="json")
    return fingerprint(request.method, request.url.path, query, data)
