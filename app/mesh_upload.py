"""An uploaded triangle mesh made an object (POST /v1/objects:import-mesh)."""

from __future__ import annotations

from typing import Any

from pydantic import ValidationError

from app.errors import InvalidInputError
from app.schemas import InputModels
from app.settings import Settings
from planner.models.library import object_to_dict
from planner.models.mesh import import_mesh_bytes
from planner.models.mesh_limits import MeshLimits

__all__ = ["mesh_object"]


def mesh_object(
    data: bytes,
    file_type: str,
    heights: tuple[float, ...],
    name: str,
    max_poses: int | None,
    settings: Settings,
    inputs: InputModels,
) -> dict[str, Any]:
    """The §8 object of a mesh upload sliced at `heights` (the first the default
    height): its work bounded by the mesh limits of `settings` before it starts,
    the result held to the limits of a posted object (an InvalidInputError naming
    where it breaks one)."""
    s = settings
    if len(heights) > s.max_slices:
        raise InvalidInputError(
            f"{len(heights)} heights exceed max_slices ({s.max_slices})", field="heights"
        )
    limits = MeshLimits(s.max_mesh_triangles, s.max_hull_faces, s.max_sliced_poses)
    height, *extra = heights
    model = import_mesh_bytes(data, file_type, height, name, max_poses, limits, heights=extra)
    stored = object_to_dict(model)
    try:
        inputs.ObjectIn.model_validate(stored)
    except ValidationError as exc:
        first = exc.errors()[0]
        where = ".".join(str(p) for p in first["loc"])
        raise InvalidInputError(
            f"the imported object breaks a limit of posted objects at {where}: "
            f"{first['msg']}; give max_poses or a coarser mesh",
            field=f"mesh.{where}",
        ) from exc
    return stored
