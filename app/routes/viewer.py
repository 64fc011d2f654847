"""The live viewer: the MII as JSON and an HTML page that draws it (DESIGN §6)."""

from fastapi import APIRouter
from fastapi.responses import HTMLResponse

from app.deps import ServiceDep, SessionId, auth_dependencies
from app.routes import PROBLEMS, respond
from app.schemas import InputModels
from app.settings import Settings
from app.viewer import VIEW_CSP, VIEW_HTML

__all__ = ["build_router"]


def build_router(inputs: InputModels, settings: Settings) -> APIRouter:
    router = APIRouter(
        prefix="/v1/sessions/{session_id}",
        tags=["pictures"],
        dependencies=auth_dependencies(settings),
        responses=PROBLEMS,
    )

    @router.get("/image.json")
    async def get_image_json(session_id: SessionId, service: ServiceDep):
        """World-frame geometry of the MII: posed outlines with probability and class,
        intersection area, blocking boundaries with strength and degree, observations."""
        return respond(await service.image_json(str(session_id)))

    @router.get("/view", response_class=HTMLResponse)
    async def get_view(session_id: SessionId, service: ServiceDep) -> HTMLResponse:
        """A self-contained page drawing the MII, the planned paths and the hypotheses;
        it refreshes while the session changes."""
        await service.image_json(str(session_id))  # 404 for an unknown session
        return HTMLResponse(VIEW_HTML, headers={"Content-Security-Policy": VIEW_CSP})

    return router
