"""Posed faces laid out for casting paths against every hypothesis at once (DESIGN §4.11).

:class:`CastFaces` holds the faces of a :class:`~planner.planning.posed_set.PosedSet`
as separate x and y arrays (H, F), with the outcome tolerances and each outline's
bounding circle; :func:`segment_distance` and :func:`angle_cone` are the
broadcast point-to-segment distance and the cone between two normals that the
casting (:mod:`planner.planning.casting`, :mod:`planner.planning.uncertain_hits`)
and the boundary aims (:mod:`planner.planning.boundary_aims`) share. World
frame, lengths in the object files' unit, angles in radians.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from planner.geometry import LENGTH_SLACK, wrap_angle
from planner.planning.posed_set import PosedSet

__all__ = ["CastFaces", "angle_cone", "segment_distance"]


def segment_distance(
    px: np.ndarray, py: np.ndarray, ax: np.ndarray, ay: np.ndarray, bx: np.ndarray, by: np.ndarray
) -> np.ndarray:
    """Distance from points p to segments [a, b], x and y given apart (broadcast);
    the same arithmetic as :func:`planner.geometry.point_segment_distance`."""
    ex, ey = bx - ax, by - ay
    sq = np.maximum(ex * ex + ey * ey, 1e-300)
    # closest point a + u (b - a), u = clip((p - a).(b - a) / |b - a|^2, 0, 1)
    u = np.clip(((px - ax) * ex + (py - ay) * ey) / sq, 0.0, 1.0)
    return np.hypot(px - (ax + u * ex), py - (ay + u * ey))


@dataclass(frozen=True, eq=False)
class CastFaces:
    """Posed faces as separate x and y arrays (H, F), the tolerances (H,), the sine
    of each pose's rotation bound (`turn_sin` (H,): a path meets a face only if
    its direction and the face's nominal normal make ``d . n < turn_sin``) and each
    outline's bounding circle (`centre_x`, `centre_y`, `radius`, (H,))."""

    sx: np.ndarray
    sy: np.ndarray
    ex: np.ndarray
    ey: np.ndarray
    nx: np.ndarray
    ny: np.ndarray
    length: np.ndarray
    prev: np.ndarray
    next: np.ndarray
    valid: np.ndarray
    geometric: np.ndarray
    vertex_tol: np.ndarray
    graze_sin: np.ndarray
    turn_sin: np.ndarray
    centre_x: np.ndarray
    centre_y: np.ndarray
    radius: np.ndarray
    margin: float

    @classmethod
    def of(cls, posed: PosedSet, tol: tuple[np.ndarray, np.ndarray, np.ndarray]) -> CastFaces:
        count = np.maximum(posed.valid.sum(axis=1), 1)
        centre = np.where(posed.valid[..., None], posed.start, 0.0).sum(axis=1) / count[:, None]
        # every point of a face lies within the largest vertex distance of the centre
        reach = np.hypot(*np.moveaxis(posed.start - centre[:, None, :], -1, 0))
        radius = np.where(posed.valid, reach, 0.0).max(axis=1)
        return cls(
            sx=np.ascontiguousarray(posed.start[..., 0]),
            sy=np.ascontiguousarray(posed.start[..., 1]),
            ex=np.ascontiguousarray(posed.end[..., 0]),
            ey=np.ascontiguousarray(posed.end[..., 1]),
            nx=np.ascontiguousarray(posed.normal[..., 0]),
            ny=np.ascontiguousarray(posed.normal[..., 1]),
            length=posed.length,
            prev=posed.prev,
            next=posed.next,
            valid=posed.valid,
            geometric=tol[0],
            vertex_tol=tol[1],
            graze_sin=tol[2],
            turn_sin=np.sin(np.minimum(posed.rotation, np.pi / 2)),
            centre_x=centre[:, 0],
            centre_y=centre[:, 1],
            radius=radius,
            margin=LENGTH_SLACK * posed.scale,
        )


def angle_cone(
    ax: np.ndarray, ay: np.ndarray, bx: np.ndarray, by: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Centre angle and half-width (radians) of the shorter arc between unit normals a, b."""
    ang_a = np.arctan2(ay, ax)
    diff = wrap_angle(np.arctan2(by, bx) - ang_a)
    return wrap_angle(ang_a + diff / 2), np.abs(diff) / 2
