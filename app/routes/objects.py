"""Objects (§8 format): register, list, fetch. Model coordinates are kept as given."""

from typing import Annotated

from fastapi import APIRouter, Path, Query, Response

from app.deps import ServiceDep, auth_dependencies
from app.errors import ConflictError, NotFoundError
from app.routes import PROBLEMS
from app.schemas import NAME_PATTERN, InputModels, ObjectCreated, ObjectList, ObjectOut
from app.settings import Settings
from app.store import ObjectConflictError

__all__ = ["build_router"]


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
    async def create_object(body: ObjectIn, service: ServiceDep, response: Response):  # type: ignore[valid-type]
        """Register one object (§8 format). The same name with other geometry: 409."""
        try:
            created, name = await service.register_object(body.as_dict())  # type: ignore[attr-defined]
        except ObjectConflictError as exc:
            raise ConflictError(
                f"an object named {exc.args[0]!r} with other geometry is registered",
                field="name",
            ) from exc
        response.status_code = 201 if created else 200
        response.headers["Location"] = f"/v1/objects/{name}"
        return ObjectCreated(name=name)

    @router.get("", response_model=ObjectList, response_model_exclude_none=True)
    async def list_objects(
        service: ServiceDep,
        limit: Annotated[int, Query(ge=1, le=settings.max_list_objects)] = (
            settings.max_list_objects
        ),
    ):
        """Every registered object, by name, as one §8 object file."""
        objects = await service.run_db(service.store.list_objects, limit)
        return ObjectList(objects=[ObjectOut(**o) for o in objects])

    @router.get("/{name}", response_model=ObjectOut, response_model_exclude_none=True)
    async def get_object(name: ObjectName, service: ServiceDep):
        """One registered object in the §8 format."""
        found = await service.run_db(service.store.get_objects, [name])
        if name not in found:
            raise NotFoundError(f"no object named {name!r}", field="name")
        return ObjectOut(**found[name])

    return router
