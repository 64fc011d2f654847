"""Vector multi-interpretation image (DESIGN §4.8; thesis ch. 3 and §4.2).

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

from planner.errors import InvalidModelError, PlanningNotPossibleError
from planner.memo import cached_property
from planner.types import Hypothesis, ObjectModel

__all__ = [
    "BlockingBoundary",
    "Crossings",
    "PosedFaces",
    "VectorMII",
    "blocking_boundaries",
    "build_mii",
    "cluster_sorted",
    "grown_faces",
    "hypothesis_weights",
    "model_map",
    "normal_groups",
    "paths_crossings",
    "posed_faces",
    "posed_outline",
    "posed_polygon",
]

#: Relative tolerance (of the MII's extent) used when every error bound is zero.
EXACT_TOLERANCE = 1e-7


def model_map(models: Mapping[str, ObjectModel] | Iterable[ObjectModel]) -> dict[str, ObjectModel]:
    """Models by name; accepts a mapping or any iterable of :class:`ObjectModel`."""
    if isinstance(models, Mapping):
        return dict(models)
    return {m.name: m for m in models}


def _stable_pose(h: Hypothesis, models: Mapping[str, ObjectModel]):
    model = models.get(h.object)
    if model is None:
        raise InvalidModelError(f"no object model named {h.object!r}", field="models")
    if not 0 <= h.stable_pose < len(model.stable_poses):
        raise InvalidModelError(
            f"object {h.object!r} has no stable pose {h.stable_pose}", field="hypotheses"
        )
    return model.stable_poses[h.stable_pose]


def posed_outline(
    h: Hypothesis, models: Mapping[str, ObjectModel]
) -> tuple[np.ndarray, tuple[np.ndarray, ...]]:
    """World-frame outline (N, 2) and holes of hypothesis `h`.

    >>> from planner.geometry import make_stable_pose
    >>> from planner.types import ErrorBound, Pose
    >>> sq = ObjectModel("sq", (make_stable_pose([[0, 0], [1, 0], [1, 1], [0, 1]]),))
    >>> h = Hypothesis("sq", 0, (), Pose(2.0, 0.0, 0.0), ErrorBound(0, 0, 0), 1.0)
    >>> posed_outline(h, {"sq": sq})[0][0].tolist()
    [2.0, 0.0]
    """
    pose = _stable_pose(h, models)
    return h.pose.apply(pose.outline), tuple(h.pose.apply(r) for r in pose.holes)


def posed_polygon(h: Hypothesis, models: Mapping[str, ObjectModel]) -> shapely.Polygon:
    """The posed outline of `h` as a shapely polygon (world frame)."""
    outline, holes = posed_outline(h, models)
    return shapely.Polygon(outline, list(holes))


@dataclass(frozen=True, eq=False)
class PosedFaces:
    """Every face of every hypothesis in the world frame, as flat arrays of length F.

    `start`, `end`, `normal` (outward unit) are (F, 2); `offset` is ``n·start``;
    `hypothesis` indexes the hypothesis list, `klass` the equivalence classes
    (renumbered 0..C-1); `eps_t` is the owning hypothesis' error disk diameter.
    """

    start: np.ndarray
    end: np.ndarray
    normal: np.ndarray
    offset: np.ndarray
    length: np.ndarray
    hypothesis: np.ndarray
    klass: np.ndarray
    eps_t: np.ndarray

    def __len__(self) -> int:
        return len(self.length)

    @property
    def angle(self) -> np.ndarray:
        return np.arctan2(self.normal[:, 1], self.normal[:, 0])


def hypothesis_weights(
    hypotheses: Sequence[Hypothesis],
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Normalized weights w(h), class index per hypothesis (0..C-1), class weights w(k).

    Classes come from ``equivalence_class``; a class counts once with the summed
    weight of its members.
    """
    if not hypotheses:
        raise PlanningNotPossibleError("no hypotheses to build an image from", field="hypotheses")
    p = np.array([h.probability for h in hypotheses], dtype=float)
    if not np.all(np.isfinite(p)) or np.any(p < 0) or p.sum() <= 0:
        raise PlanningNotPossibleError(
            "hypothesis probabilities must be finite, >= 0 and not all zero", field="hypotheses"
        )
    # w(h) = p(h) / sum_g p(g)
    weights = p / p.sum()
    _, klass = np.unique([h.equivalence_class for h in hypotheses], return_inverse=True)
    klass = klass.reshape(-1)
    # w(k) = sum_{h in k} w(h)
    class_weights = np.bincount(klass, weights=weights)
    return weights, klass, class_weights


def posed_faces(
    hypotheses: Sequence[Hypothesis], models: Mapping[str, ObjectModel] | Iterable[ObjectModel]
) -> PosedFaces:
    """Collect the posed faces of all hypotheses (world frame, outline and holes)."""
    models = model_map(models)
    _, klass, _ = hypothesis_weights(hypotheses)
    pairs = [(h, _stable_pose(h, models).faces) for h in hypotheses]
    # v_world = R(theta) v_model + t;  n_world = R(theta) n_model
    start = np.concatenate([h.pose.apply(f.start) for h, f in pairs])
    end = np.concatenate([h.pose.apply(f.end) for h, f in pairs])
    normal = np.concatenate([f.normal @ h.pose.rotation().T for h, f in pairs])
    hyp = np.repeat(np.arange(len(hypotheses)), [len(f) for _, f in pairs])
    eps = np.array([h.error_bound.eps_t for h in hypotheses], dtype=float)[hyp]
    edge = end - start
    return PosedFaces(
        start=start,
        end=end,
        normal=normal,
        offset=np.einsum("ij,ij->i", normal, start),
        length=np.hypot(edge[:, 0], edge[:, 1]),
        hypothesis=hyp,
        klass=klass[hyp],
        eps_t=np.maximum(eps, 0.0),
    )


def cluster_sorted(values: np.ndarray, tolerance: float, *, circular: bool = False) -> np.ndarray:
    """Cluster 1-D values so that every cluster spans at most `tolerance`.

    Values are visited in sorted order and a new cluster starts when a value lies
    more than `tolerance` beyond the first value of the current cluster (so no
    chaining across a fan of small steps). With `circular` the values are angles
    in radians and the sweep starts after the widest gap, so no cluster straddles
    the +-pi seam. Returns a cluster label per value (0..K-1).

    >>> cluster_sorted(np.array([0.0, 0.05, 1.0, 0.02]), 0.1).tolist()
    [0, 0, 1, 0]
    """
    values = np.asarray(values, dtype=float)
    if values.size == 0:
        return np.zeros(0, dtype=int)
    order = np.argsort(values, kind="stable")
    ordered = values[order]
    if circular:
        gaps = np.diff(np.append(ordered, ordered[0] + 2 * np.pi))
        first = (int(np.argmax(gaps)) + 1) % len(ordered)
        order = np.roll(order, -first)
        ordered = np.unwrap(values[order])
    labels_sorted = np.empty(len(order), dtype=int)
    label, anchor = 0, ordered[0]
    for k, v in enumerate(ordered):  # one pass over faces, never over pairs
        if v - anchor > tolerance:
            label, anchor = label + 1, v
        labels_sorted[k] = label
    labels = np.empty_like(labels_sorted)
    labels[order] = labels_sorted
    return labels


def normal_groups(faces: PosedFaces, angle_tolerance: float) -> np.ndarray:
    """Group faces whose outward normals agree within `angle_tolerance` (radians)."""
    return cluster_sorted(faces.angle, angle_tolerance, circular=True)


@dataclass(frozen=True, eq=False)
class BlockingBoundary:
    """A stretch of boundary shared by several equivalence classes with one normal.

    `geometry` is a shapely LineString (zero error) or Polygon (grown faces),
    world frame. `hypotheses` and `classes` index the MII's hypothesis list and
    its classes; ``degree = len(classes) - 1``; `strength` is the summed
    normalized weight of the classes (each class once).
    """

    geometry: shapely.Geometry
    normal: np.ndarray
    hypotheses: tuple[int, ...]
    classes: tuple[int, ...]
    degree: int
    strength: float

    @property
    def is_region(self) -> bool:
        return self.geometry.geom_type in ("Polygon", "MultiPolygon")


def _boundary(
    geometry: shapely.Geometry,
    normal: np.ndarray,
    hyps: np.ndarray,
    classes: np.ndarray,
    class_weights: np.ndarray,
) -> BlockingBoundary:
    # degree = |K| - 1, strength = sum_{k in K} w(k)
    return BlockingBoundary(
        geometry=geometry,
        normal=np.array(normal, dtype=float),
        hypotheses=tuple(int(h) for h in hyps),
        classes=tuple(int(c) for c in classes),
        degree=len(classes) - 1,
        strength=float(class_weights[classes].sum()),
    )


def _segments_on_line(
    faces: PosedFaces,
    idx: np.ndarray,
    class_weights: np.ndarray,
    tol: float,
) -> list[BlockingBoundary]:
    """Overlap the faces `idx` (one supporting line) and emit shared stretches."""
    n_bar = faces.normal[idx].mean(axis=0)
    n_bar /= np.hypot(*n_bar)
    t_bar = np.array([-n_bar[1], n_bar[0]])
    d_bar = float(np.mean(np.concatenate([faces.start[idx], faces.end[idx]]) @ n_bar))
    # s = t·p: position of each endpoint along the line
    s0, s1 = faces.start[idx] @ t_bar, faces.end[idx] @ t_bar
    lo, hi = np.minimum(s0, s1), np.maximum(s0, s1)
    breaks = np.unique(np.concatenate([lo, hi]))
    breaks = breaks[np.concatenate([[True], np.diff(breaks) > tol])]
    if len(breaks) < 2:
        return []
    mid = 0.5 * (breaks[:-1] + breaks[1:])
    # cover[f, e]: face f spans elementary interval e
    cover = (lo[:, None] <= mid[None, :]) & (hi[:, None] >= mid[None, :])
    n_classes = len(class_weights)
    by_class = np.zeros((n_classes, len(mid)), dtype=bool)
    np.logical_or.at(by_class, faces.klass[idx], cover)
    shared = by_class.sum(axis=0) >= 2
    if not shared.any():
        return []
    # merge neighbouring intervals with the same set of classes
    key_change = np.any(by_class[:, 1:] != by_class[:, :-1], axis=0) | (shared[1:] != shared[:-1])
    run_start = np.flatnonzero(np.concatenate([[True], key_change]))
    run_end = np.append(run_start[1:], len(mid))
    out = []
    for a, b in zip(run_start, run_end, strict=True):
        if not shared[a]:
            continue
        classes = np.flatnonzero(by_class[:, a])
        members = idx[cover[:, a]]
        ends = d_bar * n_bar + breaks[[a, b], None] * t_bar
        hyps = np.unique(faces.hypothesis[members])
        out.append(_boundary(shapely.LineString(ends), n_bar, hyps, classes, class_weights))
    return out


def _regions_in_group(
    faces: PosedFaces,
    idx: np.ndarray,
    rects: np.ndarray,
    class_weights: np.ndarray,
    grid_size: float,
) -> list[BlockingBoundary]:
    """Overlay the grown faces `idx` (one normal group); emit cells shared by 2+ classes."""
    tree = shapely.STRtree(rects[idx])
    a, b = tree.query(rects[idx], predicate="intersects")
    pairs = faces.klass[idx][a] != faces.klass[idx][b]
    if not pairs.any():
        return []
    involved = idx[np.unique(np.concatenate([a[pairs], b[pairs]]))]
    # snap-rounded noding: nearly collinear rectangle sides defeat floating-point noding
    sub = shapely.set_precision(rects[involved], grid_size)
    noded = shapely.union_all(shapely.boundary(sub), grid_size=grid_size)
    cells = shapely.get_parts(shapely.polygonize(shapely.get_parts(noded)))
    xmin, ymin, xmax, ymax = shapely.total_bounds(sub)
    # drop slivers left by coincident rectangle sides
    cells = cells[shapely.area(cells) > grid_size * max(xmax - xmin, ymax - ymin)]
    if len(cells) == 0:
        return []
    reps = shapely.point_on_surface(cells)
    cell_i, rect_i = shapely.STRtree(sub).query(reps, predicate="within")
    n_classes = len(class_weights)
    by_class = np.zeros((len(cells), n_classes), dtype=bool)
    by_class[cell_i, faces.klass[involved][rect_i]] = True
    by_hyp = np.zeros((len(cells), int(faces.hypothesis.max()) + 1), dtype=bool)
    by_hyp[cell_i, faces.hypothesis[involved][rect_i]] = True
    shared = by_class.sum(axis=1) >= 2
    if not shared.any():
        return []
    keys, key_of = np.unique(by_class[shared], axis=0, return_inverse=True)
    key_of = key_of.reshape(-1)
    n_bar = faces.normal[involved].mean(axis=0)
    n_bar /= np.hypot(*n_bar)
    out: list[BlockingBoundary] = []
    for k, key in enumerate(keys):
        chosen = key_of == k
        region = shapely.union_all(cells[shared][chosen])
        hyps = np.flatnonzero(by_hyp[shared][chosen].any(axis=0))
        classes = np.flatnonzero(key)
        out.extend(
            _boundary(part, n_bar, hyps, classes, class_weights)
            for part in shapely.get_parts(region)
        )
    return out


def grown_faces(faces: PosedFaces, floor: float = 0.0) -> np.ndarray:
    """Grown rectangle of every face: square-capped buffer of ``max(eps_t, floor) / 2``."""
    lines = shapely.linestrings(np.stack([faces.start, faces.end], axis=1))
    # widened by eps_t, lengthened by eps_t / 2 at each end (thesis §4.2.3)
    half = 0.5 * np.maximum(faces.eps_t, floor)
    return shapely.buffer(lines, half, cap_style="square", join_style="mitre")


def blocking_boundaries(
    faces: PosedFaces,
    class_weights: np.ndarray,
    *,
    angle_tolerance: float,
    position_tolerance: float,
    exact: bool,
    grown: np.ndarray | None = None,
) -> list[BlockingBoundary]:
    """Blocking boundaries from posed faces (DESIGN §4.8).

    Faces are grouped by normal within `angle_tolerance` (radians). `exact`:
    each normal group is split by supporting line (offset within
    `position_tolerance`) and faces are overlapped along the line, giving
    segments. Otherwise faces are grown rectangles and the shared parts of the
    overlay are regions (`grown`: the faces' rectangles, built when not given).
    Sorted by decreasing strength.
    """
    groups = normal_groups(faces, angle_tolerance)
    out: list[BlockingBoundary] = []
    rects = np.empty(0, dtype=object)
    if not exact:
        rects = grown if grown is not None else grown_faces(faces, 2.0 * position_tolerance)
    for g in np.unique(groups):
        idx = np.flatnonzero(groups == g)
        if len(np.unique(faces.klass[idx])) < 2:
            continue
        if exact:
            n_bar = faces.normal[idx].mean(axis=0)
            n_bar /= np.hypot(*n_bar)
            mid = 0.5 * (faces.start[idx] + faces.end[idx])
            lines = cluster_sorted(mid @ n_bar, position_tolerance)
            for line in np.unique(lines):
                on_line = idx[lines == line]
                if len(np.unique(faces.klass[on_line])) >= 2:
                    out.extend(_segments_on_line(faces, on_line, class_weights, position_tolerance))
        else:
            out.extend(_regions_in_group(faces, idx, rects, class_weights, position_tolerance))
    out.sort(key=lambda b: (-b.strength, b.geometry.bounds))
    return out


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

    >>> from planner.geometry import make_stable_pose
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

    >>> from planner.geometry import make_stable_pose
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
