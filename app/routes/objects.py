"""Objects (§8 format): register, list, fetch. Model coordinates are kept as given."""

from collections.abc import Awaitable
from typing import Annotated, Literal
from urllib.parse import quote

from fastapi import APIRouter, Path, Query, Request, Response
from pydantic import Field

from app.answers import ObjectCreated, ObjectList, ObjectOut
from app.deps import ClientDep, ServiceDep, auth_dependencies
from app.errors import (
    ConflictError,
    InvalidInputError,
    NotFoundError,
    Problem,
    UnsupportedMediaTypeError,
)
from app.routes import PROBLEMS
from app.schema_examples import BOX_OFF
from app.schemas import MESH_MEDIA_TYPES, NAME_PATTERN, InputModels
from app.settings import Settings
from app.store_types import ObjectConflictError

__all__ = ["build_router"]


def _mesh_media_type(request: Request) -> None:
    """A mesh comes with a binary or model Content-Type. A browser sends text/plain,
    form or multipart bodies to any origin without asking first; refusing them keeps
    a page elsewhere from registering objects on a service it can reach."""
    given = request.headers.get("content-type", "").split(";")[0].strip().lower()
    if given not in MESH_MEDIA_TYPES and not given.startswith("model/"):
        raise UnsupportedMediaTypeError(
            f"Content-Type {given or 'none'!r}: a mesh is sent as application/octet-stream "
            "or a model/* type",
            field="Content-Type",
        )


async def _registered(response: Response, registration: Awaitable[tuple[bool, str]]):
    """201 for a new object, 200 for the same one again, 409 for other geometry."""
    try:
        created, name = await registration
    except ObjectConflictError as exc:
        raise ConflictError(
            f"an object named {exc.args[0]!r} with other geometry is registered", field="name"
        ) from exc
    response.status_code = 201 if created else 200
    # percent-encoded: a header is Latin-1, and `?` or `#` in a name would end the path
    response.headers["Location"] = f"/v1/objects/{quote(name, safe='')}"
    return ObjectCreated(name=name)


_MESH_RESPONSES = {
    200: {"model": ObjectCreated, "description": "the same object was there"},
    415: {"model": Problem, "description": "not a binary or model/* Content-Type"},
}
_MESH_BODY = {
    "requestBody": {
        "required": True,
        "content": {
            "application/octet-stream": {
                "schema": {"type": "string", "format": "binary"},
                "example": BOX_OFF,
            }
        },
    }
}

_MeshHeight = Annotated[
    float, Query(gt=0, le=1e6, description="slice height above the table", examples=[5.0])
]
_MeshName = Annotated[
    str, Query(min_length=1, max_length=200, pattern=NAME_PATTERN, examples=["box"])
]
_MeshFileType = Annotated[Literal["stl", "obj", "ply", "off", "glb"], Query(examples=["off"])]


def build_router(inputs: InputModels, settings: Settings) -> APIRouter:
    router = APIRouter(
        prefix="/v1/objects",
        tags=["objects"],
        dependencies=auth_dependencies(settings),
        responses=PROBLEMS,
    )
    ObjectIn = inputs.ObjectIn
    ObjectName = Annotated[str, Path(min_length=1, max_length=200, pattern=NAME_PATTERN)]

    @router.post(
        "",
        status_code=201,
        response_model=ObjectCreated,
        responses={200: {"model": ObjectCreated, "description": "the same object was there"}},
    )
    async def create_object(
        body: ObjectIn,  # type: ignore[valid-type]
        service: ServiceDep,
        client: ClientDep,
        response: Response,
    ):
        """Register one object (§8 format). The same name with other geometry: 409.
        Objects are named per client: another key's objects are not seen."""
        registration = service.register_object(body.as_dict(), client)  # type: ignore[attr-defined]
        return await _registered(response, registration)

    @router.get("", response_model=ObjectList, response_model_exclude_none=True)
    async def list_objects(
        service: ServiceDep,
        client: ClientDep,
        limit: Annotated[int, Query(ge=1, le=settings.max_list_objects)] = (
            settings.max_list_objects
        ),
    ):
        """Every object this client registered, by name, as one §8 object file."""
        objects = await service.run_db(service.store.list_objects, limit, client)
        return ObjectList(objects=[ObjectOut(**o) for o in objects])

    @router.get("/{name}", response_model=ObjectOut, response_model_exclude_none=True)
    async def get_object(name: ObjectName, service: ServiceDep, client: ClientDep):
        """One registered object in the §8 format."""
        found = await service.run_db(service.store.get_objects, [name], client)
        if name not in found:
            raise NotFoundError(f"no object named {name!r}", field="name")
        return ObjectOut(**found[name])

    @router.delete("/{name}", status_code=204, response_class=Response)
    async def delete_object(name: ObjectName, service: ServiceDep, client: ClientDep):
        """Unregister an object. Sessions that use it keep their own copy (they store
        the geometry they were created with) and go on unchanged."""
        if not await service.run_db(service.store.delete_object, name, client):
            raise NotFoundError(f"no object named {name!r}", field="name")
        return Response(status_code=204)

    @router.post(
        ":import-mesh",
        status_code=201,
        response_model=ObjectCreated,
        responses=_MESH_RESPONSES,
        openapi_extra=_MESH_BODY,
    )
    async def import_mesh(
        request: Request,
        service: ServiceDep,
        client: ClientDep,
        response: Response,
        height: _MeshHeight,
        name: _MeshName,
        file_type: _MeshFileType = "stl",
        max_poses: Annotated[int | None, Query(ge=1, le=64)] = None,
        heights: Annotated[
            list[Annotated[float, Field(gt=0, le=1e6)]] | None,
            Query(
                max_length=64,
                description="more probing heights: each stable pose is also sliced there "
                "(at most max_slices heights in all, `height` included)",
            ),
        ] = None,
    ):
        """Register a 3-D part from its triangle mesh (the request body, at most the body
        limit): stable poses with their probabilities, each sliced at `height` into an
        outline (and at each of `heights`: slices at several probing heights, the
        planner then chooses the height of each path), faces carrying their out-of-plane
        normal. Same name, other geometry: 409.
        Content-Type application/octet-stream (or model/*, application/sla,
        application/vnd.ms-pki.stl); any other: 415."""
        _mesh_media_type(request)
        data = await request.body()
        if not data:
            raise InvalidInputError("the request body must hold the mesh file", field="body")
        return await _registered(
            response,
            service.import_mesh(
                data, file_type, (height, *(heights or ())), name, max_poses, client
            ),
        )

    return router
