"""The live viewer: the MII as JSON and an HTML page that draws it (DESIGN §6)."""

import time
from typing import Annotated
from urllib.parse import quote

from fastapi import APIRouter, Query
from fastapi.responses import HTMLResponse

from app.answers import ViewLinkOut
from app.deps import ClientDep, ClientsDep, ServiceDep, SessionId, auth_dependencies
from app.errors import ConflictError
from app.routes import PROBLEMS, respond
from app.schemas import InputModels
from app.settings import Settings
from app.view_tokens import make_token
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
    async def get_view(
        session_id: SessionId,
        service: ServiceDep,
        token: Annotated[
            str | None,
            Query(max_length=200, description="a viewer link's token (with an API key)"),
        ] = None,
    ) -> HTMLResponse:
        """A self-contained page drawing the MII, the planned paths and the hypotheses;
        it refreshes while the session changes. With an API key, open it through a
        viewer link (POST .../view-link)."""
        await service.record(str(session_id))  # 404 for an unknown session
        return HTMLResponse(VIEW_HTML, headers={"Content-Security-Policy": VIEW_CSP})

    @router.post("/view-link", response_model=ViewLinkOut)
    async def create_view_link(
        session_id: SessionId, service: ServiceDep, clients: ClientsDep, client: ClientDep
    ):
        """A link to this session's viewer for a browser, which cannot send the API key:
        its token opens the page and the page's reads of this session only, for
        `view_link_ttl_s`. Without an API key the page needs no link: 409."""
        key = clients.key_of(client)
        if key is None:
            raise ConflictError("the service has no API key: open .../view directly", field="id")
        await service.record(str(session_id))  # 404 for an unknown session
        expires = int(time.time() + service.settings.view_link_ttl_s)
        token = make_token(key, str(session_id), expires)
        url = f"/v1/sessions/{session_id}/view?token={quote(token, safe='')}"
        return ViewLinkOut(url=url, token=token, expires_at=float(expires))

    return router
