"""Bounds on the work of a mesh import, checked before the work is done
(:func:`planner.models.mesh.object_from_mesh`)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import trimesh

from planner.errors import InvalidModelError

__all__ = ["MeshLimits"]


@dataclass(frozen=True)
class MeshLimits:
    """Bounds on the work of :func:`object_from_mesh`, checked before it is done:
    triangles of the upload, faces of its convex hull (each a stable pose to weigh),
    and the most probable stable poses sliced (the rest, less probable than any of
    them, are left out like poses beyond ``max_poses``). None: unbounded."""

    max_mesh_triangles: int | None = None
    max_hull_faces: int | None = None
    max_sliced_poses: int | None = None

    def check_triangles(self, mesh: trimesh.Trimesh) -> None:
        count, most = len(getattr(mesh, "faces", ())), self.max_mesh_triangles
        if most is not None and count > most:
            raise InvalidModelError(
                f"has {count} triangles, over max_mesh_triangles ({most}): "
                "export it with a coarser tessellation",
                field="mesh",
            )

    def check_hull(self, mesh: trimesh.Trimesh) -> None:
        count, most = len(mesh.convex_hull.faces), self.max_hull_faces
        if most is not None and count > most:
            raise InvalidModelError(
                f"its convex hull has {count} faces, over max_hull_faces ({most}), each a "
                "stable pose to weigh: export it with a coarser tessellation",
                field="mesh",
            )

    def sliced(self, probabilities: np.ndarray) -> np.ndarray:
        """Indices of the poses to slice, most probable first."""
        order = np.argsort(-np.asarray(probabilities), kind="stable")
        return order if self.max_sliced_poses is None else order[: self.max_sliced_poses]
