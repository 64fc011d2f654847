"""Blocking boundaries of the vector MII (DESIGN §4.8; thesis §3.1, §3.2.1, §4.2.3).

A blocking boundary is a stretch of boundary shared with the same outward
normal by two or more equivalence classes ``K``: degree ``|K| - 1``, weighted
strength ``sum_{k in K} w(k)`` with ``w(k)`` the summed normalized probability
of the class' hypotheses (equivalent hypotheses count once, thesis §3.1.3).
Posed faces are grouped by normal within the angular tolerance and by
supporting line within the position tolerance, overlapped along the line, and
emitted as segments. With error the faces are grown rectangles and blocking
boundaries become regions where grown faces of similar normal from two or
more classes overlap.

All coordinates are world-frame lengths in the unit of the object files;
angles are radians, counter-clockwise positive.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import shapely

from planner.image.faces import PosedFaces, cluster_sorted, grown_faces, normal_groups

__all__ = ["BlockingBoundary", "blocking_boundaries"]


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
