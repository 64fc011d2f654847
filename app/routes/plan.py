"""The next sensing paths, ranked by the session's strategy (the planner's `plan`)."""

from typing import Annotated

from fastapi import APIRouter, Query

from app.deps import ServiceDep, SessionId, auth_dependencies
from app.routes import PROBLEMS, respond
from app.schemas import InputModels, PlanOut
from app.settings import Settings

__all__ = ["build_router"]


def build_router(inputs: InputModels, settings: Settings) -> APIRouter:
    router = APIRouter(
        prefix="/v1/sessions/{session_id}",
        tags=["plan"],
        dependencies=auth_dependencies(settings),
        responses=PROBLEMS,
    )

    @router.get("/plan", response_model=PlanOut)
    async def get_plan(
        session_id: SessionId,
        service: ServiceDep,
        limit: Annotated[int, Query(ge=1, le=settings.max_plan_paths)] = 5,
    ):
        """Ranked sensing paths, best first, within the session's `budget_ms`
        (`truncated` says the search stopped early). With no contact yet: the opening probe."""
        return respond(await service.get_plan(str(session_id), limit))

    return router
