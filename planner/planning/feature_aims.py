"""Paths aimed where the classes differ: the small feature (DESIGN §4.10, §4.15).

Near twins differ only by a groove, a notch, a chamfer, a tab or a bump; the
general candidates, aimed into the intersection area and at blocking
boundaries, rarely pass through it. For the most probable classes, the regions
where one class' posed outline has material and another's has none (their
symmetric difference, opened by the contact error so that slivers too thin to
be measured drop out) are the features; each gets paths aimed at its deepest
point: straight into the walls that bound it (against the outward normals of
both outlines there) and from evenly spread directions. World frame, lengths
in the object files' unit.
"""

from __future__ import annotations

import math
from itertools import combinations

import numpy as np
import shapely
from shapely.ops import polylabel

from planner.planning.candidates import Candidates, paths_through
from planner.planning.posed_set import PosedSet
from planner.types import SensorBounds, Workspace

__all__ = ["feature_candidates"]

#: Most classes whose differences are aimed at (the most probable first).
MAX_CLASSES = 6
#: Most feature regions per pair of classes, largest first.
MAX_REGIONS = 2
#: Evenly spread approach directions per feature, besides the wall normals.
SPREAD = 6
#: With exact contacts, the share of a region's mean thickness its aim is found to.
THICKNESS_SHARE = 0.1


def _class_outlines(posed: PosedSet, limit: int) -> list[shapely.Polygon]:
    """The posed outline of each of the `limit` most probable classes' best member."""
    order = np.argsort(-posed.class_weight, kind="stable")[:limit]
    out = []
    for best in posed.best_members(order):
        outline, holes = posed.rings[best]
        out.append(shapely.buffer(shapely.Polygon(outline, holes), 0))
    return out


def _aim_precision(region: shapely.Polygon, width: float) -> float:
    """How closely a region's deepest point is sought: to the contact error
    `width`; with exact contacts (no width), to a share of the region's mean
    thickness (twice its area over its boundary's length). Finer costs time and
    gives nothing: a thin region's deepest point moves along it at no gain, and
    a search to a thousandth of its size took 5-30 ms per sliver."""
    precision = width if width > 0 else THICKNESS_SHARE * 2 * region.area / region.length
    return max(precision, 1e-3 * math.sqrt(region.area))


def _regions(a: shapely.Polygon, b: shapely.Polygon, width: float) -> list[shapely.Polygon]:
    """Where exactly one of `a`, `b` has material, opened by `width / 2` (parts
    narrower than `width` go), largest first."""
    diff = shapely.symmetric_difference(a, b)
    if width > 0:
        diff = shapely.buffer(shapely.buffer(diff, -width / 2), width / 2)
    parts = [g for g in getattr(diff, "geoms", [diff]) if not g.is_empty and g.area > 0]
    return sorted(parts, key=lambda g: -g.area)


def _wall_normal(outline: shapely.Polygon, point: shapely.Point) -> np.ndarray | None:
    """Outward unit normal of the outline's boundary nearest `point` (None when
    the point lies on it)."""
    near = shapely.ops.nearest_points(outline.exterior, point)[0]
    away = np.array([point.x - near.x, point.y - near.y])
    norm = float(np.hypot(*away))
    if norm == 0:
        return None
    inside = outline.covers(point)
    return -away / norm if inside else away / norm


def feature_candidates(
    posed: PosedSet, workspace: Workspace, sensor: SensorBounds, limit: int = 24
) -> Candidates:
    """At most `limit` paths (source ``feature``) aimed at the regions where the
    most probable classes' outlines differ by more than the contact error can hide.

    The first paths are one per region, pairs of the most probable classes first:
    straight into the material of the class that has it there (against the
    outward normal of its nearest boundary), where one class is touched and the
    other is passed through. The evenly spread approaches follow."""
    if posed.n_classes < 2 or limit < 1:
        return Candidates.empty()
    outlines = _class_outlines(posed, MAX_CLASSES)
    width = 2 * sensor.position_error
    spread = np.arange(SPREAD) * 2 * math.pi / SPREAD
    first: list[tuple[np.ndarray, np.ndarray]] = []
    rest: list[tuple[np.ndarray, np.ndarray]] = []
    for a, b in combinations(outlines, 2):
        if len(first) >= limit:  # the paths kept are the first `limit`: no region adds one
            break
        for region in _regions(a, b, width)[:MAX_REGIONS]:
            if len(first) >= limit:
                break
            target = polylabel(region, tolerance=_aim_precision(region, width) / 4)
            aim = np.array([target.x, target.y])
            solid = a if a.covers(target) else b
            n = _wall_normal(solid, target)
            if n is not None:
                first.append((aim, -n))  # straight into the material, against its normal
            rest.extend((aim, np.array([math.cos(w), math.sin(w)])) for w in spread)
    pairs = (first + rest)[:limit]
    if not pairs:
        return Candidates.empty()
    aim = np.array([p[0] for p in pairs])
    direction = np.array([p[1] for p in pairs])
    origins, _, chord = paths_through(aim, direction, workspace)
    ok = np.isfinite(chord) & (chord > 0) & np.isfinite(origins).all(axis=1)
    return Candidates(
        origins[ok],
        direction[ok],
        chord[ok],
        aim[ok],
        np.full(int(ok.sum()), "feature", dtype="<U12"),
    )
