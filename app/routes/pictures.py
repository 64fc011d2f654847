"""Pictures of the multi-interpretation image (the planner's `render`), and the
session's report (the planner's `report`)."""

from typing import Annotated, Literal

from fastapi import APIRouter, Query, Response

from app.answers import ReportOut
from app.deps import ServiceDep, SessionId, auth_dependencies
from app.routes import PROBLEMS, respond
from app.schemas import InputModels
from app.settings import Settings

__all__ = ["build_router"]

View = Annotated[
    Literal["vector", "grid", "both"], Query(description="vector MII, grid MII, or both")
]


def build_router(inputs: InputModels, settings: Settings) -> APIRouter:
    router = APIRouter(
        prefix="/v1/sessions/{session_id}",
        tags=["pictures"],
        dependencies=auth_dependencies(settings),
        responses=PROBLEMS,
    )

    @router.get(
        "/image.svg",
        response_class=Response,
        responses={200: {"content": {"image/svg+xml": {}}, "description": "SVG picture"}},
    )
    async def get_image_svg(session_id: SessionId, service: ServiceDep, view: View = "vector"):
        """The MII: posed outlines, IA, blocking boundaries shaded by strength, contacts with
        normals, ranked paths. 409 while there is no hypothesis to draw."""
        return respond(await service.picture(str(session_id), "svg", view, 100))

    @router.get(
        "/image.png",
        response_class=Response,
        responses={200: {"content": {"image/png": {}}, "description": "PNG picture"}},
    )
    async def get_image_png(
        session_id: SessionId,
        service: ServiceDep,
        view: View = "vector",
        dpi: Annotated[int, Query(ge=30, le=settings.max_image_dpi)] = 100,
    ):
        """The same picture as image.svg, as PNG."""
        return respond(await service.picture(str(session_id), "png", view, dpi))

    @router.get("/report.json", response_model=ReportOut, tags=["reports"])
    async def get_report_json(session_id: SessionId, service: ServiceDep):
        """The report: each touch with its residuals against the most probable
        hypothesis, and that hypothesis with its bound, probability and status."""
        return respond(await service.report(str(session_id), "json"))

    @router.get(
        "/report.csv",
        response_class=Response,
        tags=["reports"],
        responses={200: {"content": {"text/csv": {}}, "description": "the report as CSV"}},
    )
    async def get_report_csv(session_id: SessionId, service: ServiceDep):
        """The same report as CSV: a row per touch (`row` touch), then the answer
        (`row` result); empty cells where a column does not apply."""
        return respond(await service.report(str(session_id), "csv"))

    return router
