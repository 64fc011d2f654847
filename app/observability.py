"""Logs, request ids, the body size limit and metrics.

- Logs are JSON lines from structlog (stdlib loggers such as uvicorn's go
  through the same renderer); every line logged while a request is handled
  carries its ``request_id`` (taken from ``X-Request-ID`` when the client sent
  a sane one, else a new UUID, and echoed in the response).
- Bodies over ``max_body_bytes`` are refused with 413 problem+json, by the
  declared Content-Length before reading, or while streaming a chunked body.
- ``/metrics`` comes from prometheus-fastapi-instrumentator, with its own
  registry per app (several apps can live in one test process); with
  ``PROMETHEUS_MULTIPROC_DIR`` set (several workers) it aggregates the workers.
"""

from __future__ import annotations

import logging
import re
import sys
import time
import uuid
from typing import Any

import structlog
from fastapi import FastAPI
from starlette.exceptions import HTTPException
from starlette.requests import Request
from starlette.types import ASGIApp, Message, Receive, Scope, Send

from app.errors import problem_response

__all__ = [
    "BodyLimitMiddleware",
    "RequestContextMiddleware",
    "configure_logging",
    "install_metrics",
]

_REQUEST_ID = re.compile(r"^[A-Za-z0-9._:-]{1,128}$")
log = structlog.get_logger("app.access")


def configure_logging(level: str = "info", json_lines: bool = True) -> None:
    """Route structlog and stdlib logging to stderr as JSON lines (idempotent)."""
    shared: list[Any] = [
        structlog.contextvars.merge_contextvars,
        structlog.stdlib.add_logger_name,
        structlog.stdlib.add_log_level,
        structlog.processors.TimeStamper(fmt="iso", utc=True),
        structlog.processors.format_exc_info,
    ]
    structlog.configure(
        processors=[*shared, structlog.stdlib.ProcessorFormatter.wrap_for_formatter],
        logger_factory=structlog.stdlib.LoggerFactory(),
        wrapper_class=structlog.stdlib.BoundLogger,
        cache_logger_on_first_use=False,
    )
    renderer = (
        structlog.processors.JSONRenderer() if json_lines else structlog.dev.ConsoleRenderer()
    )
    formatter = structlog.stdlib.ProcessorFormatter(
        foreign_pre_chain=shared,
        processors=[structlog.stdlib.ProcessorFormatter.remove_processors_meta, renderer],
    )
    handler = logging.StreamHandler(sys.stderr)
    handler.setFormatter(formatter)
    handler.set_name("tactile")
    root = logging.getLogger()
    root.handlers = [h for h in root.handlers if h.get_name() != "tactile"] + [handler]
    root.setLevel(level.upper())
    for name in ("uvicorn", "uvicorn.error"):
        logging.getLogger(name).handlers = []
        logging.getLogger(name).propagate = True
    # the access line comes from RequestContextMiddleware, with the request id
    logging.getLogger("uvicorn.access").handlers = []
    logging.getLogger("uvicorn.access").propagate = False


class RequestContextMiddleware:
    """Request id in and out, one access log line per request, and a 500 problem
    (with the request id) for anything unexpected."""

    def __init__(self, app: ASGIApp) -> None:
        self.app = app

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        given = dict(scope.get("headers") or []).get(b"x-request-id", b"").decode("latin-1")
        request_id = given if _REQUEST_ID.match(given) else uuid.uuid4().hex
        scope.setdefault("state", {})["request_id"] = request_id
        structlog.contextvars.clear_contextvars()
        structlog.contextvars.bind_contextvars(request_id=request_id)
        start = time.perf_counter()
        status = 500
        started = False

        async def send_with_id(message: Message) -> None:
            nonlocal status, started
            if message["type"] == "http.response.start":
                started = True
                status = message["status"]
                headers = list(message.get("headers", []))
                headers.append((b"x-request-id", request_id.encode()))
                message = {**message, "headers": headers}
            await send(message)

        try:
            await self.app(scope, receive, send_with_id)
        except Exception:
            log.exception("unhandled error", method=scope["method"], path=scope["path"])
            if started:
                raise
            response = problem_response(
                Request(scope), 500, detail="internal error; see the server log"
            )
            await response(scope, receive, send_with_id)
        finally:
            log.info(
                "request",
                method=scope["method"],
                path=scope["path"],
                status=status,
                duration_ms=round((time.perf_counter() - start) * 1000, 3),
            )
            structlog.contextvars.clear_contextvars()


class BodyLimitMiddleware:
    """Refuse request bodies over `max_body_bytes` with 413 problem+json.

    FastAPI's own ``max_body_size`` answers a too-large declared Content-Length
    with a text/plain 413, so this small middleware does the same job in the
    service's problem format."""

    def __init__(self, app: ASGIApp, max_body_bytes: int) -> None:
        self.app = app
        self.max_body_bytes = max_body_bytes

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        limit = self.max_body_bytes
        declared = dict(scope.get("headers") or []).get(b"content-length")
        if declared is not None:
            try:
                too_big = int(declared) > limit
            except ValueError:
                too_big = False
            if too_big:
                await self._refuse(scope, receive, send)
                return
        received = 0

        async def limited() -> Message:
            nonlocal received
            message = await receive()
            if message["type"] == "http.request":
                received += len(message.get("body", b""))
                if received > limit:
                    raise HTTPException(413, f"request body over {limit} bytes")
            return message

        await self.app(scope, limited, send)

    async def _refuse(self, scope: Scope, receive: Receive, send: Send) -> None:
        response = problem_response(
            Request(scope),
            413,
            title="Content too large",
            slug="body-too-large",
            detail=f"request body over {self.max_body_bytes} bytes",
            headers={"Connection": "close"},
        )
        await response(scope, receive, send)


def install_metrics(app: FastAPI) -> None:
    """``/metrics`` (Prometheus text format), not in the OpenAPI schema."""
    from prometheus_client import CollectorRegistry
    from prometheus_fastapi_instrumentator import Instrumentator

    Instrumentator(
        should_group_status_codes=False,
        excluded_handlers=["/metrics"],
        registry=CollectorRegistry(auto_describe=True),
    ).instrument(app).expose(app, endpoint="/metrics", include_in_schema=False)
