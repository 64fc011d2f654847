"""Liveness and readiness (no API key needed)."""

from fastapi import APIRouter, Request

from app.errors import Problem, problem_response
from app.schemas import Health, InputModels
from app.settings import Settings

__all__ = ["build_router"]


def build_router(inputs: InputModels, settings: Settings) -> APIRouter:
    router = APIRouter(tags=["health"])

    @router.get("/healthz", response_model=Health)
    async def healthz():
        """The process is up."""
        return Health(status="ok")

    @router.get(
        "/readyz",
        response_model=Health,
        responses={503: {"model": Problem, "description": "not ready"}},
    )
    async def readyz(request: Request):
        """Ready to serve: the lifespan finished and the database answers."""
        service = getattr(request.app.state, "service", None)
        try:
            ok = service is not None and await service.run_db(service.store.ping)
        except Exception:  # any database failure means "not ready"
            ok = False
        if not ok:
            return problem_response(request, 503, detail="database not ready", slug="not-ready")
        return Health(status="ready")

    return router
