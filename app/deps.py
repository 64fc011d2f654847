"""Dependencies of the routes, as ``Annotated`` aliases.

Settings and the service live on ``app.state`` (set by :func:`app.main.create_app`
and its lifespan); nothing here is a module-level global.
"""

from __future__ import annotations

import time
import uuid
from typing import Annotated, Any

from fastapi import Depends, Header, Path, Request
from fastapi.security import HTTPAuthorizationCredentials, HTTPBearer

from app.access import ANONYMOUS, Clients
from app.errors import InvalidInputError, NotFoundError, UnauthorizedError
from app.service import SessionService
from app.settings import Settings
from app.view_tokens import VIEWER_READS, check_token

__all__ = [
    "ClientDep",
    "ClientsDep",
    "IdempotencyKey",
    "IfMatch",
    "ServiceDep",
    "SessionId",
    "SettingsDep",
    "auth_dependencies",
    "reject_unknown_query",
    "require_api_key",
]


def get_settings(request: Request) -> Settings:
    return request.app.state.settings


def get_service(request: Request) -> SessionService:
    service: SessionService | None = getattr(request.app.state, "service", None)
    if service is None:  # only before the lifespan started or after it ended
        raise RuntimeError("the service is not running (lifespan not started)")
    return service


SettingsDep = Annotated[Settings, Depends(get_settings)]
ServiceDep = Annotated[SessionService, Depends(get_service)]

_bearer = HTTPBearer(auto_error=False, description="the API key, when the service has one")


def get_clients(request: Request) -> Clients:
    return request.app.state.clients


ClientsDep = Annotated[Clients, Depends(get_clients)]


def get_client(request: Request) -> str:
    """The client the request's key names (``''`` on an open service)."""
    return getattr(request.state, "client", ANONYMOUS)


#: The client a request speaks for (set by the access dependency of its router).
ClientDep = Annotated[str, Depends(get_client)]


async def _viewer_token_opens(
    request: Request, clients: Clients, service: SessionService, given: str
) -> bool:
    """A viewer token (:mod:`app.view_tokens`), in the header or, for the page
    itself, in its ``token`` query parameter, opens the viewer's reads of its session;
    it is signed with the key of the session's owner."""
    route = request.scope.get("route")
    if request.method != "GET" or getattr(route, "name", None) not in VIEWER_READS:
        return False
    token = given or request.query_params.get("token", "")
    session_id = str(request.path_params.get("session_id", ""))
    if not token or not session_id:
        return False
    owner = await service.owner_of(session_id)
    key = None if owner is None else clients.key_of(owner)
    return key is not None and check_token(key, token, session_id, time.time())


async def _own_session(request: Request, service: SessionService, client: str) -> None:
    """404 for a session of another client, worded as for one that does not exist."""
    session_id = request.path_params.get("session_id")
    if session_id is not None and await service.owner_of(str(session_id)) not in (None, client):
        raise NotFoundError(f"no session {session_id}", field="id")


async def require_api_key(
    request: Request,
    clients: ClientsDep,
    service: ServiceDep,
    credentials: Annotated[HTTPAuthorizationCredentials | None, Depends(_bearer)],
) -> None:
    """With API keys, every /v1 request needs ``Authorization: Bearer <key>`` (or, for
    the viewer's reads of one session, a viewer token); it then speaks for the key's
    client and reaches only what that client created."""
    given = credentials.credentials if credentials else ""
    client = clients.client_of(given)
    if client is None:
        if await _viewer_token_opens(request, clients, service, given):
            return
        raise UnauthorizedError(
            "missing or wrong API key (Authorization: Bearer <key>)",
            field="Authorization",
            headers={"WWW-Authenticate": 'Bearer realm="tactile"'},
        )
    request.state.client = client
    await _own_session(request, service, client)


async def open_access(request: Request, service: ServiceDep) -> None:
    """An open service: every request is the anonymous client, and reaches only what
    it owns (sessions a keyed run of the same database created stay closed)."""
    await _own_session(request, service, ANONYMOUS)


def auth_dependencies(settings: Settings) -> list[Any]:
    """The routers' dependencies: the API key check (and its OpenAPI security scheme)
    when the service has keys; the owner check in either case."""
    return [Depends(require_api_key if settings.keyed else open_access)]


SessionId = Annotated[uuid.UUID, Path(description="session id (a random UUID)")]
IfMatch = Annotated[
    str | None,
    Header(
        alias="If-Match",
        max_length=512,
        description='the session\'s ETag ("<version>"); a stale one is answered 412',
    ),
]
IdempotencyKey = Annotated[
    str | None,
    Header(
        alias="Idempotency-Key",
        min_length=1,
        max_length=255,
        pattern=r"^[\x21-\x7e]+$",
        description="replays the first answer to a retried request (other body: 422)",
    ),
]


async def reject_unknown_query(request: Request) -> None:
    """422 naming a query parameter the operation does not take: a misspelt ``limt=3``
    silently ignored would answer something the client did not ask for."""
    route = request.scope.get("route")
    dependant = getattr(route, "dependant", None)
    if dependant is None or not request.query_params:
        return
    known: set[str] = set()
    todo = [dependant]
    while todo:  # the operation's own parameters and those of its dependencies
        d = todo.pop()
        known.update(p.alias for p in d.query_params)
        todo.extend(d.dependencies)
    unknown = sorted(set(request.query_params) - known)
    if unknown:
        raise InvalidInputError(
            f"unknown query parameter {unknown[0]!r}; this operation takes "
            f"{sorted(known) or 'none'}",
            field=unknown[0],
        )
