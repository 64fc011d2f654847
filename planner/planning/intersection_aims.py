"""Aim points inside the intersection area (IA) of the posed outlines (DESIGN §4.10).

The posed outlines as shapely polygons, their intersection (the IA) and the
centroid of their union; :func:`intersection_aims` spreads aim points over the
IA, or over the area inside the largest weight of outlines when the IA is
empty. World frame, lengths in the object files' unit.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import numpy as np

from planner.geometry import SHARE_SLACK
from planner.planning.posed_set import CHUNK_ELEMENTS

if TYPE_CHECKING:
    from planner.planning.budget import Budget
    from planner.planning.posed_set import PosedSet

__all__ = ["intersection_aims", "union_centre"]


def _polygons(posed: PosedSet) -> np.ndarray:
    """The posed outlines (holes cut out) as shapely polygons, built in one pass."""
    import shapely

    rings = [ring for outline, holes in posed.rings for ring in (outline, *holes)]
    ring_of = np.repeat(np.arange(len(rings)), [len(r) for r in rings])
    polygon_of = np.repeat(np.arange(len(posed.rings)), [1 + len(h) for _, h in posed.rings])
    made = shapely.linearrings(np.concatenate(rings), indices=ring_of)
    return shapely.buffer(shapely.polygons(made, indices=polygon_of), 0)


def union_centre(posed: PosedSet) -> np.ndarray:
    """Area centroid of the union of the posed outlines (world frame)."""
    import shapely

    union = shapely.union_all(_polygons(posed))
    if union.is_empty:
        return np.asarray(posed.start[posed.valid].mean(axis=0))
    return np.array(union.centroid.coords[0])


def _intersection(polygons: np.ndarray, probe: int = 16) -> Any:
    """Intersection of all polygons: a few first, then, in pairs, only those that
    do not already contain the running intersection (the others leave it as is;
    one long chain of intersections also piles up slivers)."""
    import shapely

    def tree(parts: np.ndarray) -> Any:
        while len(parts) > 1:
            pairs = shapely.intersection(parts[0 : len(parts) - 1 : 2], parts[1::2])
            parts = np.concatenate([pairs, parts[len(parts) - len(parts) % 2 :]])
        return parts[0]

    step = max(1, len(polygons) // probe)
    head = tree(polygons[::step])
    if shapely.is_empty(head):
        return head
    rest = np.delete(polygons, np.arange(0, len(polygons), step))
    cutting = rest[~shapely.contains(rest, head)]
    return tree(np.concatenate([[head], cutting]))


def _grid_depth(posed: PosedSet, xs: np.ndarray, ys: np.ndarray) -> np.ndarray:
    """`contains_points` at the grid points (x, y) for y in ys, x in xs (row-major),
    as (len(ys) * len(xs), H) bool: each row of the grid crosses a face at one x.
    Rows go in chunks of at most :data:`CHUNK_ELEMENTS` row x hypothesis x face cells."""
    n_hyp, n_faces = posed.start.shape[:2]
    step = max(1, CHUNK_ELEMENTS // max(1, n_hyp * n_faces))
    parts = [_rows_inside(posed, xs, ys[i : i + step]) for i in range(0, len(ys), step)]
    inside = np.concatenate(parts) if parts else np.zeros((0, len(xs), n_hyp), dtype=bool)
    return inside.reshape(len(ys) * len(xs), -1)


def _rows_inside(posed: PosedSet, xs: np.ndarray, ys: np.ndarray) -> np.ndarray:
    y = ys[:, None, None]
    s, e = posed.start[None], posed.end[None]
    straddle = ((s[..., 1] > y) != (e[..., 1] > y)) & posed.valid[None]
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        x_cross = s[..., 0] + (y - s[..., 1]) * (e[..., 0] - s[..., 0]) / (e[..., 1] - s[..., 1])
    x_cross = np.where(straddle, x_cross, -np.inf)
    # even-odd rule: a point is inside when a ray toward +x crosses an odd number of faces
    inside = np.zeros((len(ys), len(xs), len(posed)), dtype=bool)
    for f in range(x_cross.shape[-1]):
        inside ^= xs[None, :, None] < x_cross[:, None, :, f]
    return inside


def intersection_aims(
    posed: PosedSet, count: int, grid: int, budget: Budget | None = None
) -> np.ndarray:
    """Up to `count` spread points inside the intersection area (IA).

    The first is the IA centroid when it lies inside, else the IA's
    representative point. When the IA is empty, points inside the largest
    weight of posed outlines stand in for it. With a `budget`, the grid is
    coarsened to what it has left, and the IA is skipped (no aims) when even
    the intersection would cost more; what was done is spent from it.
    """
    if count == 0:
        return np.zeros((0, 2))
    cells = posed.start.shape[0] * posed.start.shape[1]  # per grid point: hypotheses x faces
    if budget is not None:
        if budget.affordable("aim_face") < cells:
            return np.zeros((0, 2))
        budget.spend("aim_face", cells)
        affordable = math.sqrt(budget.affordable("aim_cell") / max(cells, 1))
        grid = grid if affordable >= grid else int(affordable)
        budget.spend("aim_cell", grid * grid * cells)
    aims: list[np.ndarray] = []
    ia = _intersection(_polygons(posed))
    if not ia.is_empty and ia.area > 0:
        centroid = ia.centroid
        first = centroid if ia.contains(centroid) else ia.representative_point()
        aims.append(np.array(first.coords[0]))
    if grid < 1:
        return np.array(aims).reshape(-1, 2)
    pts = posed.start[posed.valid]
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    axes = [np.linspace(lo[i], hi[i], grid + 2)[1:-1] for i in range(2)]
    samples = np.stack(np.meshgrid(*axes), axis=-1).reshape(-1, 2)
    depth = _grid_depth(posed, *axes).astype(float) @ posed.weight
    if depth.max(initial=0.0) > 0:
        inside = samples[depth >= depth.max() - SHARE_SLACK]
        chosen = list(aims) or [inside[0]]
        # farthest-point sampling spreads the remaining aims over the area
        gap = np.min([np.hypot(*(inside - a).T) for a in chosen], axis=0)
        while len(chosen) < count and gap.max(initial=0.0) > 0:
            nxt = inside[int(np.argmax(gap))]
            chosen.append(nxt)
            gap = np.minimum(gap, np.hypot(*(inside - nxt).T))
        aims = chosen
    return np.array(aims[:count]).reshape(-1, 2)
