"""HTTP errors as RFC 9457 problem details (``application/problem+json``).

The planner raises :class:`planner.errors.PlannerError` and knows nothing of
HTTP; this module is the only place where its subclasses meet status codes.
Every 4xx names the offending field when there is one::

    {"type": "urn:tactile-planner:problem:invalid-observation",
     "title": "Invalid observation", "status": 422,
     "detail": "path.direction: must not be the zero vector",
     "errors": [{"field": "path.direction", "message": "must not be the zero vector"}]}
"""

from __future__ import annotations

import http
from collections.abc import Mapping, Sequence
from typing import Any

from fastapi import FastAPI, Request
from fastapi.encoders import jsonable_encoder
from fastapi.exceptions import RequestValidationError
from fastapi.responses import JSONResponse
from pydantic import BaseModel, Field
from starlette.exceptions import HTTPException as StarletteHTTPException

from app.store_types import StoreUnavailableError
from planner.errors import (
    InvalidModelError,
    InvalidObservationError,
    ModelFileError,
    PlannerError,
    PlanningNotPossibleError,
)

__all__ = [
    "PROBLEM_MEDIA_TYPE",
    "AppError",
    "ConflictError",
    "FieldError",
    "IdempotencyInFlightError",
    "IdempotencyMismatchError",
    "InvalidInputError",
    "LimitExceededError",
    "NotFoundError",
    "PreconditionFailedError",
    "PreconditionRequiredError",
    "Problem",
    "UnauthorizedError",
    "UnavailableError",
    "UnsupportedMediaTypeError",
    "install_error_handlers",
    "problem_response",
]

PROBLEM_MEDIA_TYPE = "application/problem+json"
_TYPE_PREFIX = "urn:tactile-planner:problem:"


class FieldError(BaseModel):
    """One offending input: a dotted `field` path (``objects[0].outline``) and why."""

    field: str = Field(description="dotted path of the input, e.g. 'path.direction'")
    message: str
    location: str | None = Field(None, description="body, query, header or path")


class Problem(BaseModel):
    """RFC 9457 problem details, with the offending fields in `errors`."""

    type: str = "about:blank"
    title: str
    status: int = Field(ge=400, le=599)
    detail: str | None = None
    instance: str | None = None
    errors: list[FieldError] = Field(default_factory=list)
    request_id: str | None = None


class AppError(Exception):
    """An error the service answers on purpose (not a planner error)."""

    status = 400
    slug = "bad-request"
    title = "Bad request"

    def __init__(
        self,
        detail: str,
        *,
        field: str | None = None,
        headers: Mapping[str, str] | None = None,
    ) -> None:
        super().__init__(detail)
        self.detail = detail
        self.field = field
        self.headers = dict(headers or {})


class InvalidInputError(AppError):
    status, slug, title = 422, "invalid-input", "Invalid input"


class NotFoundError(AppError):
    status, slug, title = 404, "not-found", "Not found"


class ConflictError(AppError):
    status, slug, title = 409, "conflict", "Conflict"


class LimitExceededError(AppError):
    status, slug, title = 409, "limit-exceeded", "Limit exceeded"


class IdempotencyInFlightError(AppError):
    status, slug, title = 409, "idempotency-key-in-flight", "Request with this key in flight"


class IdempotencyMismatchError(AppError):
    status, slug, title = 422, "idempotency-key-reused", "Idempotency key reused"


class PreconditionFailedError(AppError):
    status, slug, title = 412, "precondition-failed", "Precondition failed"


class PreconditionRequiredError(AppError):
    status, slug, title = 428, "precondition-required", "Precondition required"


class UnsupportedMediaTypeError(AppError):
    status, slug, title = 415, "unsupported-media-type", "Unsupported media type"


class UnauthorizedError(AppError):
    status, slug, title = 401, "unauthorized", "Unauthorized"


class UnavailableError(AppError):
    status, slug, title = 503, "unavailable", "Service unavailable"


# planner error -> (status, slug, title); the most specific class wins
_PLANNER_ERRORS: list[tuple[type[PlannerError], int, str, str]] = [
    (InvalidObservationError, 422, "invalid-observation", "Invalid observation"),
    (InvalidModelError, 422, "invalid-object", "Invalid object"),
    (ModelFileError, 422, "invalid-object", "Invalid object"),
    (PlanningNotPossibleError, 409, "planning-not-possible", "Planning not possible"),
    (PlannerError, 422, "invalid-input", "Invalid input"),
]


def problem_response(
    request: Request,
    status: int,
    *,
    title: str | None = None,
    detail: str | None = None,
    slug: str | None = None,
    errors: Sequence[FieldError] = (),
    headers: Mapping[str, str] | None = None,
) -> JSONResponse:
    """A problem+json response; `headers` are kept (WWW-Authenticate, Retry-After, ...)."""
    phrase = _phrase(status)
    problem = Problem(
        type=_TYPE_PREFIX + slug if slug else "about:blank",
        title=title or phrase,
        status=status,
        detail=detail,
        instance=request.url.path,
        errors=list(errors),
        request_id=request.scope.get("state", {}).get("request_id"),
    )
    return JSONResponse(
        problem.model_dump(mode="json", exclude_none=True),
        status_code=status,
        headers=dict(headers or {}),
        media_type=PROBLEM_MEDIA_TYPE,
    )


def _phrase(status: int) -> str:
    try:
        return http.HTTPStatus(status).phrase
    except ValueError:
        return "Error"


def field_path(loc: Sequence[Any]) -> tuple[str, str | None]:
    """Pydantic's error location -> (dotted field path, location).

    >>> field_path(("body", "objects", 0, "outline", 3))
    ('objects[0].outline[3]', 'body')
    """
    location = None
    parts = list(loc)
    if parts and parts[0] in ("body", "query", "header", "path", "cookie"):
        location = str(parts.pop(0))
    out = ""
    for part in parts:
        if isinstance(part, int):
            out += f"[{part}]"
        elif isinstance(part, str) and (part.startswith("function-") or "[" in part):
            continue  # pydantic validator wrappers, not fields
        else:
            out += f".{part}" if out else str(part)
    return out or (location or "body"), location


def _validation_errors(exc: RequestValidationError) -> tuple[int, list[FieldError]]:
    errors = []
    status = 422
    for err in exc.errors():
        if err.get("type") == "json_invalid":
            status = 400
        field, location = field_path(err.get("loc", ()))
        if err.get("type") == "json_invalid":
            field = "body"
        message = str(err.get("msg", "invalid"))
        ctx = err.get("ctx") or {}
        if err.get("type") == "json_invalid" and ctx.get("error"):
            message = f"malformed JSON: {ctx['error']}"
        errors.append(FieldError(field=field, message=message, location=location))
    return status, errors


def _planner_mapping(exc: PlannerError) -> tuple[int, str, str]:
    for cls, status, slug, title in _PLANNER_ERRORS:
        if isinstance(exc, cls):
            return status, slug, title
    return 422, "invalid-input", "Invalid input"  # pragma: no cover - PlannerError is listed


def install_error_handlers(app: FastAPI) -> None:
    """Answer every error as problem+json; never a 5xx for a client's mistake."""

    @app.exception_handler(AppError)
    async def _app_error(request: Request, exc: AppError) -> JSONResponse:
        errors = [FieldError(field=exc.field, message=exc.detail)] if exc.field else []
        return problem_response(
            request,
            exc.status,
            title=exc.title,
            detail=exc.detail,
            slug=exc.slug,
            errors=errors,
            headers=exc.headers,
        )

    @app.exception_handler(StoreUnavailableError)
    async def _store_unavailable(request: Request, exc: StoreUnavailableError) -> JSONResponse:
        # the database is locked, busy or down: nothing was changed, the request may be retried
        error = UnavailableError(str(exc), headers={"Retry-After": "1"})
        return await _app_error(request, error)

    @app.exception_handler(MemoryError)
    async def _out_of_memory(request: Request, exc: MemoryError) -> JSONResponse:
        # an allocation passed the process's memory cap (max_memory_bytes, set by
        # `tactile serve`): that request fails, the server and its other requests go on
        error = UnavailableError(
            "the request needed more memory than the server's max_memory_bytes allows "
            "now; retry later, or with fewer objects, poses or observations",
            headers={"Retry-After": "5"},
        )
        return await _app_error(request, error)

    @app.exception_handler(PlannerError)
    async def _planner_error(request: Request, exc: PlannerError) -> JSONResponse:
        status, slug, title = _planner_mapping(exc)
        errors = [FieldError(field=exc.field, message=exc.message)] if exc.field else []
        return problem_response(
            request, status, title=title, detail=str(exc), slug=slug, errors=errors
        )

    @app.exception_handler(RequestValidationError)
    async def _validation(request: Request, exc: RequestValidationError) -> JSONResponse:
        status, errors = _validation_errors(exc)
        detail = "; ".join(f"{e.field}: {e.message}" for e in errors[:5])
        slug = "malformed-json" if status == 400 else "validation-failed"
        title = "Malformed JSON" if status == 400 else "Validation failed"
        return problem_response(
            request, status, title=title, detail=detail, slug=slug, errors=errors
        )

    @app.exception_handler(StarletteHTTPException)
    async def _http(request: Request, exc: StarletteHTTPException) -> JSONResponse:
        detail = exc.detail if isinstance(exc.detail, str) else jsonable_encoder(exc.detail)
        headers = dict(exc.headers or {})
        if exc.status_code == 405:  # every method of the path, not only the first route's
            headers["Allow"] = _allowed_methods(request)
        return problem_response(
            request,
            exc.status_code,
            detail=None if detail == _phrase(exc.status_code) else str(detail),
            headers=headers,
        )


def _allowed_methods(request: Request) -> str:
    methods: set[str] = set()
    for route in request.app.router.routes:
        regex = getattr(route, "path_regex", None)
        if regex is not None and regex.match(request.scope["path"]):
            methods |= set(getattr(route, "methods", None) or ())
    return ", ".join(sorted(methods))
