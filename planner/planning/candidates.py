"""Candidate sensing paths (DESIGN §4.10).

Every path is straight, starts on the safe circle and is given in the world
frame: origin (length unit), unit direction, length, and the aim point it was
built for. The general set aims at points inside the intersection area (IA)
from origins spread around the circle, and at points just inside faces where
the hypotheses' boundaries differ (low blocking strength), approaching them head
on and at two oblique angles. Extra paths (thesis windows, strategy probes) are
passed in and always kept. Duplicates (same direction and line offset within a
resolution) are dropped, keeping the first in priority order: extra, IA, boundary.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from planner.errors import PlannerError
from planner.geometry import ANGLE_SLACK, LENGTH_SLACK, SHARE_SLACK
from planner.planning.casting import segment_distance
from planner.types import SensingPath, SensorBounds, Workspace

if TYPE_CHECKING:
    from planner.planning.posed_set import PosedSet

__all__ = [
    "CandidateConfig",
    "Candidates",
    "candidate_cap",
    "generate_candidates",
    "intersection_aims",
    "paths_through",
    "union_centre",
]


@dataclass(frozen=True)
class CandidateConfig:
    """Size and resolution of the general candidate set.

    `count` caps the general candidates (extra paths come on top) for up to
    `full_size_hypotheses` hypotheses; beyond, the cap shrinks as the square of
    their ratio (not below `min_count`), since the outcome and confusability
    passes cost candidates x hypotheses^2;
    `origins` is the number of origins spread on the safe circle for each IA aim;
    `intersection_aims`, `boundary_aims` the number of aim points of each kind;
    `oblique` (radians) the extra approach angles of boundary aims (0 and +-oblique);
    `angle_step` (radians) and `offset_step` (length; None = radius / 200) the
    dedupe resolution; `grid` the sample grid (per side) used to find IA points;
    `face_samples` the points per face examined for differing boundaries.
    """

    count: int = 256
    full_size_hypotheses: int = 64
    min_count: int = 48
    origins: int = 24
    intersection_aims: int = 6
    boundary_aims: int = 48
    oblique: float = 0.5
    angle_step: float = math.radians(1.0)
    offset_step: float | None = None
    grid: int = 24
    face_samples: int = 3

    def __post_init__(self) -> None:
        names = ("count", "min_count", "origins", "intersection_aims", "boundary_aims")
        for name in (*names, "face_samples", "full_size_hypotheses"):
            if getattr(self, name) < 0:
                raise PlannerError("must be >= 0", field=f"candidates.{name}")
        if self.grid < 2:
            raise PlannerError("must be >= 2", field="candidates.grid")
        if not (0 <= self.oblique < math.pi / 2):
            raise PlannerError("must lie in [0, pi/2)", field="candidates.oblique")
        if not self.angle_step > 0 or (self.offset_step is not None and not self.offset_step > 0):
            raise PlannerError("dedupe steps must be > 0", field="candidates.angle_step")


@dataclass(frozen=True, eq=False)
class Candidates:
    """C paths: `origins`, unit `directions`, `aims` (C, 2), `lengths` (C,),
    `source` (C,) naming where each came from (extra, intersection, boundary, ...),
    and `tier` (C,) the rank a strategy gave its own paths (the thesis window's
    level of admitted strength; 0 elsewhere)."""

    origins: np.ndarray
    directions: np.ndarray
    lengths: np.ndarray
    aims: np.ndarray
    source: np.ndarray
    tier: np.ndarray | None = None

    def __post_init__(self) -> None:
        if self.tier is None:
            object.__setattr__(self, "tier", np.zeros(len(self.lengths), dtype=int))

    def __len__(self) -> int:
        return len(self.lengths)

    def path(self, i: int) -> SensingPath:
        return SensingPath(
            tuple(self.origins[i]), tuple(self.directions[i]), float(self.lengths[i])
        )

    def subset(self, index: np.ndarray | Sequence[int]) -> Candidates:
        idx = np.asarray(index, dtype=int)
        return Candidates(
            self.origins[idx],
            self.directions[idx],
            self.lengths[idx],
            self.aims[idx],
            self.source[idx],
            self.tier[idx],
        )

    @classmethod
    def empty(cls) -> Candidates:
        return cls(
            np.zeros((0, 2)),
            np.zeros((0, 2)),
            np.zeros(0),
            np.zeros((0, 2)),
            np.zeros(0, dtype="<U12"),
        )

    @classmethod
    def concat(cls, parts: Sequence[Candidates]) -> Candidates:
        parts = [p for p in parts if len(p)] or [cls.empty()]
        return cls(
            *(
                np.concatenate([getattr(p, k) for p in parts])
                for k in ("origins", "directions", "lengths", "aims", "source", "tier")
            )
        )

    @classmethod
    def from_paths(
        cls,
        paths: Sequence[SensingPath],
        source: str = "extra",
        aims: np.ndarray | None = None,
        tier: np.ndarray | None = None,
    ) -> Candidates:
        """Wrap given paths; the aim defaults to the path's end point, the tier to 0."""
        if not paths:
            return cls.empty()
        origins = np.array([p.origin for p in paths], dtype=float)
        directions = np.array([p.direction for p in paths], dtype=float)
        lengths = np.array([p.length for p in paths], dtype=float)
        end = origins + directions * lengths[:, None]
        return cls(
            origins,
            directions,
            lengths,
            end if aims is None else np.asarray(aims, float),
            np.full(len(paths), source, dtype="<U12"),
            None if tier is None else np.asarray(tier, dtype=int),
        )


def paths_through(
    aims: np.ndarray, directions: np.ndarray, workspace: Workspace
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Trace each aim point back along -direction to the safe circle.

    Returns (origins (N, 2), distance from origin to aim (N,), chord length from
    the origin to where the line leaves the circle (N,)); NaN where the line
    misses the circle or the aim lies outside it.
    """
    c = np.asarray(workspace.center, dtype=float)
    rel = np.asarray(aims, dtype=float) - c
    d = np.asarray(directions, dtype=float)
    # |rel - s d| = R  ->  s = d.rel + sqrt((d.rel)^2 - |rel|^2 + R^2)
    b = np.einsum("nk,nk->n", d, rel)
    disc = b * b - np.einsum("nk,nk->n", rel, rel) + workspace.radius**2
    root = np.sqrt(np.where(disc >= 0, disc, np.nan))
    back = b + root
    back = np.where(back >= 0, back, np.nan)
    origins = np.asarray(aims, dtype=float) - back[:, None] * d
    return origins, back, 2 * root


def _ring_points(workspace: Workspace, count: int, start_angle: float) -> np.ndarray:
    angles = start_angle + 2 * np.pi * np.arange(count) / max(count, 1)
    return np.asarray(workspace.center) + workspace.radius * np.stack(
        [np.cos(angles), np.sin(angles)], axis=1
    )


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
    as (len(ys) * len(xs), H) bool: each row of the grid crosses a face at one x."""
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
    return inside.reshape(len(ys) * len(xs), -1)


def intersection_aims(posed: PosedSet, count: int, grid: int) -> np.ndarray:
    """Up to `count` spread points inside the intersection area (IA).

    The first is the IA centroid when it lies inside, else the IA's
    representative point. When the IA is empty, points inside the largest
    weight of posed outlines stand in for it.
    """
    if count == 0:
        return np.zeros((0, 2))
    aims: list[np.ndarray] = []
    ia = _intersection(_polygons(posed))
    if not ia.is_empty and ia.area > 0:
        centroid = ia.centroid
        first = centroid if ia.contains(centroid) else ia.representative_point()
        aims.append(np.array(first.coords[0]))
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


def _boundary_aims(
    posed: PosedSet, sensor: SensorBounds, config: CandidateConfig, rng: np.random.Generator
) -> tuple[np.ndarray, np.ndarray]:
    """Points on posed faces where the classes' boundaries differ, weakest blocking first.

    Returns (points (N, 2), outward normals (N, 2)).
    """
    if config.boundary_aims == 0 or config.face_samples == 0:
        return np.zeros((0, 2)), np.zeros((0, 2))
    frac = (np.arange(config.face_samples) + 0.5) / config.face_samples
    pts = posed.start[..., None, :] + frac[:, None] * (posed.end - posed.start)[..., None, :]
    owner = np.broadcast_to(np.arange(len(posed))[:, None, None], pts.shape[:-1])
    keep = np.broadcast_to(posed.valid[..., None], pts.shape[:-1])
    normals = np.broadcast_to(posed.normal[..., None, :], pts.shape)
    pts, owner, normals = pts[keep], owner[keep], normals[keep]
    limit = 8 * config.boundary_aims
    if len(pts) > limit:
        pick = np.sort(rng.choice(len(pts), size=limit, replace=False))
        pts, owner, normals = pts[pick], owner[pick], normals[pick]
    shared = np.zeros((len(pts), posed.n_classes), dtype=bool)
    q, h = _blocking_pairs(posed, sensor, pts, owner, normals)
    shared[q, posed.cls[h]] = True
    strength = np.empty(len(pts))
    chunk = max(1, 1_000_000 // max(1, posed.valid.size))
    for lo in range(0, len(pts), chunk):
        # blocking strength: weight of the classes with a face there
        strength[lo : lo + chunk] = shared[lo : lo + chunk] @ posed.class_weight
    differs = strength < 1 - SHARE_SLACK
    pts, normals, strength = pts[differs], normals[differs], strength[differs]
    order = rng.permutation(len(pts))
    order = order[np.argsort(strength[order], kind="stable")]
    # one aim per cell of a spacing grid, weakest blocking first
    spacing = max(float(np.median(posed.length[posed.valid])) / 4, 1e-6 * posed.scale)
    cells = np.floor(pts[order] / spacing).astype(np.int64)
    _, first = np.unique(cells, axis=0, return_index=True)
    chosen = order[np.sort(first)][: config.boundary_aims]
    return pts[chosen], normals[chosen]


def _blocking_pairs(
    posed: PosedSet,
    sensor: SensorBounds,
    pts: np.ndarray,
    owner: np.ndarray,
    normals: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """(point, hypothesis) pairs where a face of the hypothesis blocks the point: within
    the pose/sensor tolerance of it, with the same normal.

    Faces fall into buckets of normal angle at least as wide as the widest angle
    tolerance; in a bucket they are sorted by their extent along its direction n,
    and a face within p of a point q spans some of [n.q - p, n.q + p]. Only the
    faces of a point's bucket and its two neighbours that pass this are measured.
    """
    from planner.geometry import wrap_angle

    fh, ff = np.nonzero(posed.valid)
    face_angle = np.arctan2(posed.normal[fh, ff, 1], posed.normal[fh, ff, 0])
    angle = np.arctan2(normals[:, 1], normals[:, 0])
    # turn <= n_tol + ANGLE_SLACK with n_tol = 2 phi + dtheta(h) + dtheta(g) <= widest
    widest = 2 * sensor.normal_error + 2 * posed.rotation.max() + 2e-9
    n_buckets = int(min(1024, 2 * np.pi // max(widest * (1 + SHARE_SLACK), 1e-12)))
    if n_buckets < 3:  # some tolerance spans a third of the directions: every face
        q = np.repeat(np.arange(len(pts)), len(fh))
        face = np.tile(np.arange(len(fh)), len(pts))
    else:
        q, face = _bucket_pairs(posed, sensor, pts, owner, angle, face_angle, n_buckets)
    # the normals first (one gather each), the distances of the pairs they leave
    h, g = fh[face], owner[q]
    n_tol = 2 * sensor.normal_error + posed.rotation[g] + posed.rotation[h]
    turn = np.abs(wrap_angle(face_angle[face] - angle[q]))
    keep = turn <= n_tol + ANGLE_SLACK
    q, face, h, g = q[keep], face[keep], h[keep], g[keep]
    p_tol = 2 * sensor.position_error + (posed.eps_t[g] + posed.eps_t[h]) / 2
    s, e, p = posed.start[fh, ff][face], posed.end[fh, ff][face], pts[q]
    dist = segment_distance(p[:, 0], p[:, 1], s[:, 0], s[:, 1], e[:, 0], e[:, 1])
    ok = dist <= p_tol + LENGTH_SLACK * posed.scale
    return q[ok], h[ok]


def _bucket_pairs(
    posed: PosedSet,
    sensor: SensorBounds,
    pts: np.ndarray,
    owner: np.ndarray,
    angle: np.ndarray,
    face_angle: np.ndarray,
    n_buckets: int,
) -> tuple[np.ndarray, np.ndarray]:
    """Candidate (point, face) pairs: same or neighbouring normal-angle bucket, and
    overlapping extents along the bucket's direction (a superset of the blocking pairs)."""
    from planner.planning.bitsets import sorted_count

    fh, ff = np.nonzero(posed.valid)
    width = 2 * np.pi / n_buckets
    bucket = np.floor((face_angle + np.pi) / width).astype(np.int64) % n_buckets
    centre = (bucket + 0.5) * width - np.pi
    s, e = posed.start[fh, ff], posed.end[fh, ff]
    # extent of each face along its bucket's direction n
    along_s = s[:, 0] * np.cos(centre) + s[:, 1] * np.sin(centre)
    along_e = e[:, 0] * np.cos(centre) + e[:, 1] * np.sin(centre)
    low, high = np.minimum(along_s, along_e), np.maximum(along_s, along_e)
    used, row = np.unique(bucket, return_inverse=True)
    span = np.zeros(len(used))
    np.maximum.at(span, row, high - low)
    order = np.lexsort((low, row))
    size = np.bincount(row, minlength=len(used))
    first = np.cumsum(size) - size
    sorted_low = np.full((len(used), int(size.max())), np.inf)
    rank = np.arange(len(order)) - first[row[order]]
    sorted_low[row[order], rank] = low[order]
    # the point's bucket and its two neighbours, where used
    mine = np.floor((angle + np.pi) / width).astype(np.int64)
    near = (mine[:, None] + np.array([-1, 0, 1])) % n_buckets  # (Q, 3)
    slot = np.clip(np.searchsorted(used, near), 0, len(used) - 1)
    ok = used[slot] == near
    qi, k = np.nonzero(ok)
    b = slot[qi, k]
    n_dir = (used[b] + 0.5) * width - np.pi
    x = pts[qi, 0] * np.cos(n_dir) + pts[qi, 1] * np.sin(n_dir)
    # within p of the point: 2 eps_d + (eps_t(g) + eps_t(h)) / 2, at most this
    reach = 2 * sensor.position_error + (posed.eps_t[owner[qi]] + posed.eps_t.max()) / 2
    reach = reach + 2e-9 * posed.scale
    lo = sorted_count(sorted_low, b, x - reach - span[b], "left")
    hi = sorted_count(sorted_low, b, x + reach, "right")
    count = hi - lo
    q = np.repeat(qi, count)
    at = np.arange(len(q)) - np.repeat(np.cumsum(count) - count, count)
    face = order[first[np.repeat(b, count)] + np.repeat(lo, count) + at]
    return q, face


def _dedupe(
    c: Candidates, workspace: Workspace, config: CandidateConfig, keep: int = 0
) -> np.ndarray:
    """Indices of the first path of each (direction, line offset) cell, in order;
    the first `keep` paths are kept whatever their cell."""
    if len(c) == 0:
        return np.zeros(0, dtype=int)
    offset_step = config.offset_step or workspace.radius / 200
    angle = np.arctan2(c.directions[:, 1], c.directions[:, 0])
    n_steps = max(1, round(2 * math.pi / config.angle_step))
    k_angle = np.round(angle / config.angle_step).astype(np.int64) % n_steps
    rel = c.origins - np.asarray(workspace.center)
    offset = c.directions[:, 0] * rel[:, 1] - c.directions[:, 1] * rel[:, 0]
    k_offset = np.round(offset / offset_step).astype(np.int64)
    _, first = np.unique(np.stack([k_angle, k_offset], axis=1), axis=0, return_index=True)
    return np.union1d(np.arange(keep), first)


def generate_candidates(
    posed: PosedSet,
    workspace: Workspace,
    sensor: SensorBounds,
    config: CandidateConfig | None = None,
    rng: np.random.Generator | None = None,
    *,
    sensor_position: Sequence[float] | None = None,
    extra: Candidates | None = None,
) -> Candidates:
    """The candidate paths for a posed hypothesis set (world frame).

    IA aims get `config.origins` origins spread on the safe circle (the first at
    the sensor's place); paths end at the aim, inside every outline. Boundary
    aims sit just inside a face (by twice the largest tolerance) and are
    approached head on and at +-`config.oblique`. Extra paths are kept whole and
    first; the general ones are deduped and, beyond `config.count`, subsampled
    with `rng`.
    """
    config = config or CandidateConfig()
    rng = rng if rng is not None else np.random.default_rng(0)
    centre = np.asarray(workspace.center, dtype=float)
    sensor_xy = (
        centre + np.array([workspace.radius, 0.0]) if sensor_position is None else sensor_position
    )
    rel = np.asarray(sensor_xy, dtype=float) - centre
    start_angle = math.atan2(rel[1], rel[0]) if np.any(rel) else 0.0
    parts = []

    ia = intersection_aims(posed, config.intersection_aims, config.grid)
    if len(ia) and config.origins:
        origins = _ring_points(workspace, config.origins, start_angle)
        o = np.repeat(origins[None], len(ia), axis=0).reshape(-1, 2)
        a = np.repeat(ia, len(origins), axis=0)
        span = a - o
        length = np.hypot(*span.T)
        ok = length > LENGTH_SLACK * workspace.radius
        parts.append(_make(o[ok], span[ok] / length[ok, None], length[ok], a[ok], "intersection"))

    points, normals = _boundary_aims(posed, sensor, config, rng)
    if len(points):
        inset = 2 * (2 * sensor.position_error + posed.eps_t.max()) + 5e-3 * workspace.radius
        aims = points - inset * normals
        turns = [0.0, config.oblique, -config.oblique] if config.oblique > 0 else [0.0]
        for turn in turns:
            c, s = math.cos(turn), math.sin(turn)
            d = -normals @ np.array([[c, s], [-s, c]])
            o, to_aim, _ = paths_through(aims, d, workspace)
            ok = np.isfinite(to_aim) & (to_aim > LENGTH_SLACK * workspace.radius)
            parts.append(_make(o[ok], d[ok], to_aim[ok], aims[ok], "boundary"))

    extra = extra if extra is not None else Candidates.empty()
    merged = Candidates.concat([extra, *parts])
    merged = merged.subset(_dedupe(merged, workspace, config, keep=len(extra)))
    n_general = len(merged) - len(extra)
    cap = candidate_cap(config, len(posed))
    if n_general > cap:
        pick = np.sort(rng.choice(n_general, cap, replace=False)) + len(extra)
        merged = merged.subset(np.concatenate([np.arange(len(extra)), pick]))
    return merged


def candidate_cap(config: CandidateConfig, n_hypotheses: int) -> int:
    """How many general candidates to keep for `n_hypotheses` hypotheses.

    >>> candidate_cap(CandidateConfig(), 50), candidate_cap(CandidateConfig(), 128)
    (256, 64)
    """
    ratio = min(1.0, config.full_size_hypotheses / max(n_hypotheses, 1))
    # cost ~ candidates x hypotheses^2: keep it near the full-size budget
    return min(config.count, max(config.min_count, int(config.count * ratio * ratio)))


def _make(o: np.ndarray, d: np.ndarray, length: np.ndarray, aims: np.ndarray, source: str):
    return Candidates(o, d, length, aims, np.full(len(length), source, dtype="<U12"))
