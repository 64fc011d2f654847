"""The FastAPI application (DESIGN §6): ``create_app(settings)`` and the default ``app``.

``app`` is built on first access from the environment (``TACTILE_*``), so
``uvicorn app.main:app`` works and importing this module has no side effect::

    from app.main import create_app
    from app.settings import Settings
    app = create_app(Settings(db_path="/var/lib/tactile/tactile.db"))
"""

from __future__ import annotations

from collections.abc import AsyncIterator
from contextlib import asynccontextmanager
from typing import Any

import anyio
import structlog
from fastapi import Depends, FastAPI
from fastapi.routing import APIRoute

from app import migrations
from app.access import load_clients
from app.deps import reject_unknown_query
from app.errors import PROBLEM_MEDIA_TYPE, install_error_handlers
from app.observability import (
    BodyLimitMiddleware,
    RequestContextMiddleware,
    configure_logging,
    install_metrics,
)
from app.routes import health, objects, observations, pictures, plan, sessions, viewer
from app.schema_links import add_links
from app.schemas import input_models
from app.security import (
    DocumentsKeyMiddleware,
    HostAllowListMiddleware,
    SecurityHeadersMiddleware,
)
from app.service import SessionService
from app.settings import Settings
from app.store import Store
from app.store_types import StoreUnavailableError

__all__ = ["TactileAPI", "create_app"]

API_VERSION = "1.0.0"
log = structlog.get_logger("app.main")


def operation_id(route: APIRoute) -> str:
    """Stable operation ids for generated clients: the route function's name."""
    return route.name


@asynccontextmanager
async def lifespan(app: FastAPI) -> AsyncIterator[None]:
    settings: Settings = app.state.settings
    store = Store(
        settings.database,
        busy_timeout_ms=settings.busy_timeout_ms,
        synchronous=settings.sqlite_synchronous,
        pool_size=settings.db_pool_size,
    )
    service = SessionService(settings, store, app.state.inputs)
    before = await service.run_db(store.open)
    app.state.service = service
    log.info(
        "service started",
        db=store.describe(),
        schema=migrations.head(),
        migrated_from=before,
        cpu_workers=settings.cpu_workers,
    )
    async with anyio.create_task_group() as tasks:
        tasks.start_soon(_retention, service)
        tasks.start_soon(_warm_up)
        try:
            yield
        finally:
            tasks.cancel_scope.cancel()
            app.state.service = None
            await service.run_db(store.close)
        log.info("service stopped")


async def _warm_up() -> None:
    """Load the planner's compiled kernels in the background, so that the first
    session's answers do not wait for them (the service is ready meanwhile; the
    warm-up takes no CPU worker's place, so no request queues behind it)."""
    from planner.warmup import warm_up

    try:
        seconds = await anyio.to_thread.run_sync(warm_up)
    except Exception as exc:  # a failed warm-up costs the first request time, no more
        log.warning("warm-up failed", error=repr(exc))
    else:
        log.info("warmed up", seconds=round(seconds, 2))


async def _retention(service: SessionService) -> None:
    """Purge expired idempotency records and idle sessions now and on a schedule (one
    host at a time: the store skips a round another host is running)."""
    settings = service.settings
    while True:
        try:
            removed = await service.run_db(
                service.store.purge, settings.idempotency_ttl_s, settings.session_ttl_s
            )
            if removed and any(removed.values()):
                log.info("retention", **removed)
        except StoreUnavailableError as exc:
            log.warning("retention skipped", error=str(exc))
        await anyio.sleep(settings.retention_interval_s)


def _problem_media_types(schema: dict[str, Any]) -> dict[str, Any]:
    """Error answers are application/problem+json in the OpenAPI schema too."""
    for item in schema.get("paths", {}).values():
        for operation in item.values():
            for status, response in operation.get("responses", {}).items():
                content = response.get("content", {})
                if status[:1] in "45" and content and PROBLEM_MEDIA_TYPE not in content:
                    # whatever the route's own media type, errors are problem details
                    first = content.get("application/json") or next(iter(content.values()))
                    response["content"] = {PROBLEM_MEDIA_TYPE: first}
    return schema


class TactileAPI(FastAPI):
    """FastAPI whose OpenAPI schema gives error answers as application/problem+json."""

    def openapi(self) -> dict[str, Any]:
        if self.openapi_schema is None:
            self.openapi_schema = add_links(_problem_media_types(super().openapi()))
        return self.openapi_schema


def create_app(settings: Settings | None = None) -> FastAPI:
    """Build the service. `settings` default: read from the environment (``TACTILE_*``)."""
    settings = settings or Settings()
    configure_logging(settings.log_level, settings.log_json)
    app = TactileAPI(
        title="tactile-planner",
        version=API_VERSION,
        summary="Where to touch an unseen polygonal object to recognize and localize it.",
        description=(
            "Sessions are event-sourced: an object set, sensor bounds, a safe circle and "
            "the ordered observations; hypotheses and plans are derived. Angles in radians, "
            "lengths in the unit of the object files. Errors are RFC 9457 problem details. "
            f"Limits: {settings.max_outline_vertices} vertices per ring as given and "
            f"{settings.max_worked_vertices} once simplified within the sensor's bounds, "
            f"{settings.max_objects_per_session} objects and "
            f"{settings.max_observations_per_session} observations per session, "
            f"{settings.max_hypotheses} hypotheses left by an observation "
            f"(and {settings.max_interpretation_work:,} units of interpretations to check), "
            f"plan budget up to {settings.max_plan_budget_ms:g} ms, "
            f"request bodies up to {settings.max_body_bytes} bytes."
        ),
        lifespan=lifespan,
        generate_unique_id_function=operation_id,
        dependencies=[Depends(reject_unknown_query)],
    )
    app.state.settings = settings
    clients = app.state.clients = load_clients(settings)
    app.state.service = None
    install_error_handlers(app)
    inputs = app.state.inputs = input_models(settings)
    for module in (objects, sessions, observations, plan, pictures, viewer, health):
        app.include_router(module.build_router(inputs, settings))
    install_metrics(app)
    app.add_middleware(BodyLimitMiddleware, max_body_bytes=settings.max_body_bytes)
    if clients.keyed and not settings.public_docs:
        app.add_middleware(DocumentsKeyMiddleware, clients=clients)
    if settings.allowed_hosts is not None:
        app.add_middleware(HostAllowListMiddleware, allowed=settings.allowed_hosts)
    app.add_middleware(SecurityHeadersMiddleware)
    app.add_middleware(RequestContextMiddleware)  # outermost: sees every answer
    return app


_default: FastAPI | None = None


def __getattr__(name: str) -> Any:
    """``app.main:app``: the default instance, built from the environment on first use."""
    global _default
    if name == "app":
        if _default is None:
            _default = create_app()
        return _default
    raise AttributeError(name)
