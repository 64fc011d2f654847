"""The next sensing paths, ranked by the session's strategy (the planner's `plan`)."""

from typing import Annotated

from fastapi import APIRouter, Query

from app.answers import PlanOut
from app.deps import ServiceDep, SessionId, auth_dependencies
from app.routes import PROBLEMS, respond
from app.schemas import InputModels
from app.settings import Settings

__all__ = ["build_router"]


def build_router(inputs: InputModels, settings: Settings) -> APIRouter:
    router = APIRouter(
        prefix="/v1/sessions/{session_id}",
        tags=["plan"],
        dependencies=auth_dependencies(settings),
        responses=PROBLEMS,
    )
    big = settings.max_coordinate
    Coordinate = Annotated[
        float | None,
        Query(
            ge=-big,
            le=big,
            allow_inf_nan=False,
            description="the sensor's current place (world frame); a coordinate not "
            "given is the session's sensor_position's",
        ),
    ]

    @router.get("/plan", response_model=PlanOut)
    async def get_plan(
        session_id: SessionId,
        service: ServiceDep,
        limit: Annotated[int, Query(ge=1, le=settings.max_plan_paths)] = 5,
        sensor_x: Coordinate = None,
        sensor_y: Coordinate = None,
    ):
        """Ranked sensing paths, best first, within the session's `budget_ms`
        (`truncated` says the search stopped early). With no contact yet: the opening probe.
        `sensor_x`, `sensor_y`: plan from where the sensor is now (motion costs and the
        opening probe start there); one alone moves the session's sensor_position along
        that axis."""
        position = None if sensor_x is None and sensor_y is None else (sensor_x, sensor_y)
        return respond(await service.get_plan(str(session_id), limit, position))

    return router
