"""Outlines of stable poses checked and oriented before the planner uses them (DESIGN §4.1).

Object files and meshes both come through :func:`make_stable_pose`: it refuses
what the geometry cannot work with and names the field at fault.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
import shapely

from planner.errors import InvalidModelError
from planner.geometry import signed_area
from planner.types import StablePose

__all__ = ["EDGE_TOLERANCE", "make_stable_pose", "with_slices"]

#: Relative tolerance (of the outline's size) below which an edge is degenerate.
EDGE_TOLERANCE = 1e-6


def _as_ring(coords: object, field: str) -> np.ndarray:
    try:
        ring = np.asarray(coords, dtype=float)
    except (TypeError, ValueError) as exc:
        raise InvalidModelError("must be a list of [x, y] pairs of numbers", field=field) from exc
    if ring.ndim != 2 or ring.shape[1] != 2:
        raise InvalidModelError("must be a list of [x, y] pairs", field=field)
    if not np.all(np.isfinite(ring)):
        raise InvalidModelError("coordinates must be finite (no NaN or infinity)", field=field)
    if len(ring) > 1 and np.allclose(ring[0], ring[-1]):
        ring = ring[:-1]  # an explicitly closed ring
    if len(ring) < 3:
        raise InvalidModelError(f"needs at least 3 vertices, got {len(ring)}", field=field)
    return ring


def _check_edges(ring: np.ndarray, scale: float, field: str) -> None:
    edge = np.roll(ring, -1, axis=0) - ring
    length = np.hypot(edge[:, 0], edge[:, 1])
    short = np.flatnonzero(length <= EDGE_TOLERANCE * scale)
    if short.size:
        raise InvalidModelError(
            f"degenerate edge {int(short[0])} (vertices {int(short[0])} and "
            f"{int((short[0] + 1) % len(ring))} coincide within {EDGE_TOLERANCE * scale:.3g})",
            field=field,
        )


def make_stable_pose(
    outline: object,
    holes: Sequence[object] = (),
    probability: float = 1.0,
    normal_z: Sequence[float] | None = None,
    *,
    field: str = "outline",
) -> StablePose:
    """Validate and orient one stable pose (DESIGN §4.1).

    Refuses fewer than 3 vertices, non-finite coordinates, self-intersection,
    zero area, degenerate edges and holes outside the outline, naming the field.
    The outline is re-oriented counter-clockwise and holes clockwise; vertex
    coordinates are kept exactly as given.

    >>> pose = make_stable_pose([[0, 0], [0, 1], [1, 1], [1, 0]])  # clockwise in
    >>> pose.outline.tolist()
    [[1.0, 0.0], [1.0, 1.0], [0.0, 1.0], [0.0, 0.0]]
    """
    ring = _as_ring(outline, field)
    hole_rings = [_as_ring(h, f"{field}.holes[{i}]") for i, h in enumerate(holes)]
    scale = float(np.ptp(ring, axis=0).max()) or 1.0
    for i, r in enumerate([ring, *hole_rings]):
        name = field if i == 0 else f"{field}.holes[{i - 1}]"
        _check_edges(r, scale, name)
        collinear = np.linalg.matrix_rank(r - r.mean(axis=0), tol=EDGE_TOLERANCE * scale) < 2
        if not collinear and not shapely.LinearRing(r).is_simple:
            raise InvalidModelError("self-intersects (bow-tie or crossing edges)", field=name)
        if abs(signed_area(r)) <= (EDGE_TOLERANCE * scale) ** 2:
            raise InvalidModelError("has zero area", field=name)
    polygon = shapely.Polygon(ring, hole_rings)
    if not polygon.is_valid:
        reason = shapely.is_valid_reason(polygon)
        raise InvalidModelError(f"holes are not inside the outline ({reason})", field=field)
    if signed_area(ring) < 0:
        ring = ring[::-1].copy()
    hole_rings = [h[::-1].copy() if signed_area(h) > 0 else h for h in hole_rings]
    if not (math.isfinite(probability) and 0 < probability <= 1):
        raise InvalidModelError("must lie in (0, 1]", field=f"{field}.probability")
    nz = None
    if normal_z is not None:
        nz = np.asarray(normal_z, dtype=float)
        n_faces = len(ring) + sum(len(h) for h in hole_rings)
        if nz.shape != (n_faces,) or not np.all(np.abs(nz) <= 1):
            raise InvalidModelError(
                f"must hold {n_faces} numbers in [-1, 1], one per face", field=f"{field}.normal_z"
            )
    return StablePose(
        outline=ring, holes=tuple(hole_rings), probability=float(probability), normal_z=nz
    )


def with_slices(layers: Sequence[tuple[float, StablePose]], *, field: str = "slices") -> StablePose:
    """One stable pose probed at several heights (DESIGN §4.13): `layers` are
    (height, outline) pairs, the first the default height's; the outlines come
    from :func:`make_stable_pose`, the first one's probability is the pose's.
    Refuses non-finite or repeated heights, naming the field."""
    if not layers:
        raise InvalidModelError("needs at least one slice", field=field)
    seen: list[float] = []
    built = []
    for k, (height, pose) in enumerate(layers):
        z = float(height)
        if not math.isfinite(z):
            raise InvalidModelError("must be a finite number", field=f"{field}[{k}].height")
        if any(abs(z - other) <= 1e-6 * max(1.0, abs(other)) for other in seen):
            raise InvalidModelError(f"height {z:g} given twice", field=f"{field}[{k}].height")
        seen.append(z)
        built.append(
            StablePose(pose.outline, pose.holes, layers[0][1].probability, pose.normal_z, z)
        )
    first = built[0]
    return StablePose(
        first.outline, first.holes, first.probability, first.normal_z, first.height,
        tuple(built[1:]),
    )  # fmt: skip
