"""Mesh files in (DESIGN §4.13): the only file I/O for meshes.

The geometry lives in :mod:`planner.models.mesh`; this module reads the bytes of a
mesh file (STL, OBJ, PLY, OFF, GLB, glTF; the type from the file name's
suffix) and hands them over.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path

import trimesh

from planner.errors import ModelFileError
from planner.models.mesh import object_from_mesh, parse_mesh_bytes
from planner.types import ObjectModel

__all__ = ["import_mesh_file", "load_mesh"]


def load_mesh(path: str | os.PathLike[str]) -> trimesh.Trimesh:
    """Read a triangle mesh file; its type comes from the suffix (``.stl``, ...).

    Raises :class:`~planner.errors.ModelFileError` (field ``path``) when the
    file cannot be read, has an unknown suffix or holds no triangle mesh.
    """
    target = Path(path)
    try:
        data = target.read_bytes()
    except OSError as exc:
        raise ModelFileError(f"cannot read {target}: {exc.strerror}", field="path") from exc
    try:
        return parse_mesh_bytes(data, target.suffix)
    except ModelFileError as exc:
        raise ModelFileError(f"{target}: {exc.message}", field="path") from exc


def import_mesh_file(
    path: str | os.PathLike[str],
    height: float,
    name: str | None = None,
    max_poses: int | None = None,
    heights: Sequence[float] = (),
) -> ObjectModel:
    """The object model of the solid in a mesh file, probed at `height` (mesh
    units above the table) and at each of `heights`; `name` defaults to the file
    name without suffix.

    See :func:`planner.models.mesh.object_from_mesh` for the stable poses kept and the
    errors raised on a mesh that gives no model.
    """
    mesh = load_mesh(path)
    name = Path(path).stem if name is None else name
    return object_from_mesh(mesh, height, name, max_poses, heights=heights)
