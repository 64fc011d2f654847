"""Vector multi-interpretation image and paths' crossings (DESIGN §4.8; thesis ch. 3 and §4.2).

The MII overlays the posed outlines of every hypothesis: union area,
intersection area (IA, inside every posed outline, maybe several components)
and blocking boundaries, stretches of boundary shared with the same outward
normal by two or more equivalence classes ``K``: degree ``|K| - 1``, weighted
strength ``sum_{k in K} w(k)`` with ``w(k)`` the summed normalized probability
of the class' hypotheses (equivalent hypotheses count once, thesis §3.1.3).

With zero pose error the blocking boundaries are exact segments. With error
each posed face becomes its grown rectangle (thesis §4.2.3: widened by
``eps_t``, lengthened by ``eps_t / 2`` at each end, i.e. a square-capped buffer
of ``eps_t / 2``) and blocking boundaries become regions where grown faces of
similar normal from two or more classes overlap.

The posed faces and their normal groups are in :mod:`planner.image.faces`,
the blocking boundaries in :mod:`planner.image.blocking`; here they are
assembled into the :class:`VectorMII`, and :func:`paths_crossings` tells which
blocking boundaries straight paths meet (Theorems 1 and 2).

All coordinates are world-frame lengths in the unit of the object files;
angles are radians, counter-clockwise positive.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from functools import partial, reduce

import numpy as np
import shapely

from planner.image.blocking import BlockingBoundary, blocking_boundaries
from planner.image.faces import (
    EXACT_TOLERANCE,
    PosedFaces,
    grown_faces,
    hypothesis_weights,
    model_map,
    posed_faces,
    posed_polygon,
)
from planner.memo import cached_property
from planner.types import Hypothesis, ObjectModel

__all__ = ["DRAWN_FACES", "Crossings", "VectorMII", "build_mii", "drawable", "paths_crossings"]

#: Most posed faces a picture of the MII draws: the overlay of the blocking regions
#: grows faster than the faces (one touch on a round part with a hole: 202
#: hypotheses of 210 faces took a minute; on a ring with 16 holes, worked as 863
#: faces, two hypotheses took 3.5 s and four 19.5 s, at the service's 20 s limit).
DRAWN_FACES = 2_000


@dataclass(frozen=True, eq=False)
class VectorMII:
    """The vector multi-interpretation image of a hypothesis set (world frame).

    `weights` are the normalized hypothesis probabilities, `classes` the class
    index of each hypothesis (0..C-1, from `equivalence_class`), `class_weights`
    the summed weight per class. `intersection` is the nominal IA (inside every
    posed outline); `certain_intersection` also removes the grown faces (equal to
    `intersection` with zero error). `exact` tells whether blocking boundaries
    are segments (all error bounds zero) or regions.
    """

    hypotheses: tuple[Hypothesis, ...]
    weights: np.ndarray
    classes: np.ndarray
    class_weights: np.ndarray
    outlines: tuple[shapely.Polygon, ...]
    union: shapely.Geometry
    intersection: shapely.Geometry
    certain_intersection: shapely.Geometry
    faces: PosedFaces
    grown: np.ndarray | None
    blocking: tuple[BlockingBoundary, ...]
    exact: bool
    angle_tolerance: float
    position_tolerance: float

    @cached_property
    def intersection_areas(self) -> tuple[shapely.Polygon, ...]:
        """Connected components of the IA (largest first)."""
        parts = [p for p in shapely.get_parts(self.intersection) if p.area > 0]
        return tuple(sorted(parts, key=lambda p: -p.area))

    @property
    def bounds(self) -> tuple[float, float, float, float]:
        """(xmin, ymin, xmax, ymax) of every posed outline."""
        return tuple(float(v) for v in self.union.bounds)  # type: ignore[return-value]

    @cached_property
    def _tree(self) -> shapely.STRtree:
        return shapely.STRtree([b.geometry for b in self.blocking])


def _polygonal(geometry: shapely.Geometry) -> shapely.Geometry:
    """The polygons of an overlay result (drops stray points and lines)."""
    parts = [p for p in shapely.get_parts(geometry) if p.geom_type == "Polygon" and p.area > 0]
    if len(parts) == 1:
        return parts[0]
    return shapely.MultiPolygon(parts) if parts else shapely.Polygon()


def drawable(
    hypotheses: Sequence[Hypothesis],
    models: Mapping[str, ObjectModel] | Iterable[ObjectModel],
    max_faces: int = DRAWN_FACES,
) -> tuple[Hypothesis, ...]:
    """The most probable of `hypotheses` (given most probable first) whose posed faces
    number at most `max_faces`, and at least one: what a picture of the MII draws
    in bounded time. Fewer outlines meet in a larger intersection area, so a
    picture of a prefix says how many it drew.

    >>> from planner.models.outlines import make_stable_pose
    >>> from planner.types import ErrorBound, Pose
    >>> sq = ObjectModel("sq", (make_stable_pose([[0, 0], [2, 0], [2, 1], [0, 1]]),))
    >>> hs = [Hypothesis("sq", 0, (), Pose(x, 0, 0), ErrorBound(0, 0, 0), 0.5) for x in (0, 1)]
    >>> len(drawable(hs, [sq], max_faces=4)), len(drawable(hs, [sq], max_faces=8))
    (1, 2)
    """
    models = model_map(models)
    # faces per stable pose: one per vertex of its outline and holes
    per_pose = {
        (m.name, k): len(p.outline) + sum(len(r) for r in p.holes)
        for m in models.values()
        for k, p in enumerate(m.stable_poses)
    }
    faces = np.array([per_pose[h.object, h.stable_pose] for h in hypotheses], dtype=np.int64)
    fit = int(np.searchsorted(np.cumsum(faces), max_faces, side="right"))
    return tuple(hypotheses[: max(fit, min(1, len(hypotheses)))])


def build_mii(
    hypotheses: Sequence[Hypothesis],
    models: Mapping[str, ObjectModel] | Iterable[ObjectModel],
    *,
    angle_tolerance: float | None = None,
    position_tolerance: float | None = None,
) -> VectorMII:
    """Build the vector MII: outlines, union, IA, blocking boundaries.

    Tolerances default to ``1e-7`` (relative to the image's extent) plus, for
    normals, twice the largest rotation error bound of the hypotheses. Blocking
    boundaries are exact segments when every ``eps_t`` is zero, else regions.

    >>> from planner.models.outlines import make_stable_pose
    >>> from planner.types import ErrorBound, Pose
    >>> sq = ObjectModel("sq", (make_stable_pose([[0, 0], [2, 0], [2, 1], [0, 1]]),))
    >>> hs = [Hypothesis("sq", 0, (), Pose(x, 0, 0), ErrorBound(0, 0, 0), 0.5,
    ...                  equivalence_class=i) for i, x in enumerate([0.0, 1.0])]
    >>> mii = build_mii(hs, [sq])
    >>> mii.intersection.area, [(b.geometry.length, b.strength) for b in mii.blocking]
    (1.0, [(1.0, 1.0), (1.0, 1.0)])
    """
    models = model_map(models)
    hypotheses = tuple(hypotheses)
    weights, klass, class_weights = hypothesis_weights(hypotheses)
    outlines = tuple(posed_polygon(h, models) for h in hypotheses)
    faces = posed_faces(hypotheses, models)
    scale = max(float(np.ptp(faces.start, axis=0).max()), 1e-12)
    exact = max(h.error_bound.eps_t for h in hypotheses) <= EXACT_TOLERANCE * scale
    if angle_tolerance is None:
        # nominal normals of h and g may differ by dtheta(h) + dtheta(g) on the same face
        angle_tolerance = EXACT_TOLERANCE + 2.0 * max(h.error_bound.rotation for h in hypotheses)
    pos_tol = EXACT_TOLERANCE * scale if position_tolerance is None else position_tolerance
    # snap-rounded overlays on a decimal grid below pos_tol: coincident outlines of
    # symmetric objects otherwise make floating-point overlay lose the whole intersection
    snap = 10.0 ** math.floor(math.log10(pos_tol))
    union = _polygonal(shapely.union_all(outlines, grid_size=snap))
    meet = partial(shapely.intersection, grid_size=snap)
    intersection = reduce(lambda a, b: _polygonal(meet(a, b)), outlines[1:], outlines[0])
    grown = None if exact else grown_faces(faces, floor=2.0 * pos_tol)
    certain = intersection
    if grown is not None:
        grown_union = shapely.union_all(grown, grid_size=snap)
        certain = _polygonal(shapely.difference(intersection, grown_union, grid_size=snap))
    blocking = blocking_boundaries(
        faces,
        class_weights,
        angle_tolerance=angle_tolerance,
        position_tolerance=pos_tol,
        exact=exact,
        grown=grown,
    )
    return VectorMII(
        hypotheses=hypotheses,
        weights=weights,
        classes=klass,
        class_weights=class_weights,
        outlines=outlines,
        union=union,
        intersection=intersection,
        certain_intersection=certain,
        faces=faces,
        grown=grown,
        blocking=tuple(blocking),
        exact=exact,
        angle_tolerance=float(angle_tolerance),
        position_tolerance=float(pos_tol),
    )


@dataclass(frozen=True, eq=False)
class Crossings:
    """Blocking boundaries met by each of P straight paths.

    `count` (P,) boundaries touched, `total` (P,) summed strength, `largest`
    (P,) the strongest one; ``1 - total`` bounds P(DM) from below (Theorem 2,
    summed over the boundaries crossed), `pairs` (path, boundary) index pairs.
    """

    count: np.ndarray
    total: np.ndarray
    largest: np.ndarray
    pairs: np.ndarray


def paths_crossings(
    mii: VectorMII, origins: np.ndarray, directions: np.ndarray, lengths: np.ndarray
) -> Crossings:
    """Which blocking boundaries each path (origin, unit direction, length) touches.

    Arrays are (P, 2), (P, 2), (P,) in the world frame; one STRtree query for all.

    With zero error, a path from outside the union into the IA with
    ``count == 0`` yields a distinguishing measurement (Theorem 1).

    >>> from planner.models.outlines import make_stable_pose
    >>> from planner.types import ErrorBound, Pose
    >>> sq = ObjectModel("sq", (make_stable_pose([[0, 0], [2, 0], [2, 1], [0, 1]]),))
    >>> hs = [Hypothesis("sq", 0, (), Pose(x, 0, 0), ErrorBound(0, 0, 0), 0.5,
    ...                  equivalence_class=i) for i, x in enumerate([0.0, 1.0])]
    >>> c = paths_crossings(build_mii(hs, [sq]), [[1.5, -1.0]], [[0.0, 1.0]], [1.5])
    >>> c.count.tolist(), c.total.tolist()
    ([1], [1.0])
    """
    origins = np.atleast_2d(np.asarray(origins, dtype=float))
    directions = np.atleast_2d(np.asarray(directions, dtype=float))
    lengths = np.atleast_1d(np.asarray(lengths, dtype=float))
    n = len(origins)
    ends = origins + directions * lengths[:, None]
    lines = shapely.linestrings(np.stack([origins, ends], axis=1))
    if not mii.blocking:
        zero = np.zeros(n)
        return Crossings(zero.astype(int), zero, zero.copy(), np.zeros((2, 0), dtype=int))
    path_i, bound_i = mii._tree.query(lines, predicate="intersects")
    strength = np.array([b.strength for b in mii.blocking])
    count = np.bincount(path_i, minlength=n)
    # P(DM) >= 1 - sum of the strengths of the boundaries crossed
    total = np.bincount(path_i, weights=strength[bound_i], minlength=n)
    largest = np.zeros(n)
    np.maximum.at(largest, path_i, strength[bound_i])
    return Crossings(count, total, largest, np.stack([path_i, bound_i]))
