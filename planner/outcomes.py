"""Predicted outcome of each sensing path for each hypothesis, and confusability (DESIGN §4.11).

Everything here is in the world frame, lengths in the object files' unit, angles
in radians (counter-clockwise positive). The pipeline is three numpy passes:

1. :func:`pose_hypotheses` packs the posed faces of all hypotheses into padded
   arrays (H hypotheses x F faces);
2. :func:`predict_outcomes` casts every candidate path against every posed
   hypothesis at once (chunked over candidates): first hit (point, face normal)
   or miss, and the ways the outcome is uncertain (vertex, grazing, near miss,
   contact at the very end of the path);
3. :func:`confusability` compares the outcomes of every pair of hypotheses on
   every path within the §4.11 tolerances, and :func:`survivor_table` turns the
   result into survivor sets over equivalence classes, stored as bitsets.

Posed hypotheses live in :mod:`planner.posed` and candidate paths in
:mod:`planner.candidates`; both are re-exported here.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields
from typing import Any

import numpy as np

from planner.bitsets import pack_bits, unpack_bits
from planner.candidates import CandidateConfig, Candidates, generate_candidates
from planner.errors import PlannerError
from planner.geometry import point_segment_distance, wrap_angle
from planner.posed import PosedSet, contains_points, pose_hypotheses
from planner.types import SensorBounds

__all__ = [
    "CandidateConfig",
    "Candidates",
    "OutcomeConfig",
    "Outcomes",
    "PosedSet",
    "SurvivorTable",
    "confusability",
    "contains_points",
    "generate_candidates",
    "pose_hypotheses",
    "predict_outcomes",
    "survivor_table",
]

#: Outcome slots per (path, hypothesis): nominal, vertex/near-miss alternative, slip-through.
SLOTS = 3


@dataclass(frozen=True)
class OutcomeConfig:
    """Tolerances of the outcome model beyond the sensor and pose error bounds.

    `grazing_angle` (radians): a hit whose path meets the face within this angle
    (plus the hypothesis' rotation bound) of parallel is grazing. `contact_patch`
    (length): half-size of the sensed patch (the thesis' finite data site), added
    to the vertex and near-miss zones. `chunk_elements` bounds the size of the
    intermediate arrays (candidates x hypotheses x faces) of one chunk.
    """

    grazing_angle: float = 0.1
    contact_patch: float = 0.0
    chunk_elements: int = 1_000_000

    def __post_init__(self) -> None:
        if not (math.isfinite(self.grazing_angle) and 0 <= self.grazing_angle < math.pi / 2):
            raise PlannerError("must lie in [0, pi/2)", field="outcome.grazing_angle")
        if not (math.isfinite(self.contact_patch) and self.contact_patch >= 0):
            raise PlannerError("must be a finite number >= 0", field="outcome.contact_patch")
        if self.chunk_elements < 1:
            raise PlannerError("must be >= 1", field="outcome.chunk_elements")


@dataclass(frozen=True, eq=False)
class Outcomes:
    """Predicted outcome of C paths on H hypotheses (world frame).

    Nominal outcome: `hit`, `distance` along the path (inf on a miss), `point`
    and `normal` (C, H, 2; NaN on a miss), `face` (-1 on a miss), `travel` (how
    far the sensor moves: the hit distance, or the path length on a miss).
    Uncertainty flags (C, H): `vertex` (hit within tolerance of a vertex),
    `grazing` (path nearly parallel to the face hit), `near_miss` (a miss that
    passes within tolerance of the outline), `end_of_path` (hit within tolerance
    of the path's end: it may be a miss).

    Outcome slots (C, H, 3) list everything the outcome could turn out to be:
    slot 0 the nominal outcome, slot 1 a hit near the nominal point (or near the
    closest approach of a near miss) whose normal may lie anywhere in the cone
    `slot_angle +- slot_spread` between the faces meeting at the vertex, slot 2
    the path slipping past the contact (the next hit further on, or a miss).
    `slot_slack` widens the point tolerance of grazing hits, whose contact
    slides along the path by `tolerance / |cos(incidence)|`.
    """

    hit: np.ndarray
    distance: np.ndarray
    point: np.ndarray
    normal: np.ndarray
    face: np.ndarray
    travel: np.ndarray
    vertex: np.ndarray
    grazing: np.ndarray
    near_miss: np.ndarray
    end_of_path: np.ndarray
    slot_valid: np.ndarray
    slot_hit: np.ndarray
    slot_point: np.ndarray
    slot_angle: np.ndarray
    slot_spread: np.ndarray
    slot_slack: np.ndarray

    @property
    def uncertain(self) -> np.ndarray:
        """(C, H) bool: the outcome may be something other than the nominal one."""
        return self.vertex | self.grazing | self.near_miss | self.end_of_path


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]


def _take(values: np.ndarray, index: np.ndarray) -> np.ndarray:
    """values (..., F[, 2]) at index (...) along the face axis."""
    if values.ndim == index.ndim + 2:
        return np.take_along_axis(values, index[..., None, None], axis=-2)[..., 0, :]
    return np.take_along_axis(values, index[..., None], axis=-1)[..., 0]


def _cone(a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Centre angle and half-width (radians) of the shorter arc between unit normals a, b."""
    ang_a = np.arctan2(a[..., 1], a[..., 0])
    diff = wrap_angle(np.arctan2(b[..., 1], b[..., 0]) - ang_a)
    return wrap_angle(ang_a + diff / 2), np.abs(diff) / 2


def _tolerances(posed: PosedSet, sensor: SensorBounds, config: OutcomeConfig) -> dict:
    floor = 1e-9 * posed.scale
    # how far the true outline may lie from the posed one: half the error disk
    geometric = posed.eps_t / 2 + config.contact_patch + floor
    return {
        "geometric": geometric,
        # a contact this close to a vertex may be on either face (or slip off)
        "vertex": geometric + sensor.position_error,
        # |dir . n| below this: the path meets the face nearly parallel
        "graze_sin": np.sin(np.minimum(config.grazing_angle + posed.rotation, math.pi / 2)),
    }


def predict_outcomes(
    posed: PosedSet,
    origins: np.ndarray,
    directions: np.ndarray,
    lengths: np.ndarray,
    sensor: SensorBounds,
    config: OutcomeConfig | None = None,
) -> Outcomes:
    """Cast C paths (origins (C, 2), unit directions (C, 2), lengths (C,)) against
    every posed hypothesis, in numpy passes chunked over the paths.

    >>> from planner.geometry import make_stable_pose
    >>> from planner.types import ErrorBound, Hypothesis, ObjectModel, Pose
    >>> square = ObjectModel("sq", (make_stable_pose([[-1, -1], [1, -1], [1, 1], [-1, 1]]),))
    >>> h = Hypothesis("sq", 0, (), Pose(0, 0, 0), ErrorBound(0, 0, 0), 1.0)
    >>> out = predict_outcomes(pose_hypotheses([h], {"sq": square}),
    ...     np.array([[5.0, 0.0]]), np.array([[-1.0, 0.0]]), np.array([10.0]), SensorBounds())
    >>> out.point[0, 0].tolist(), out.normal[0, 0].tolist()
    ([1.0, 0.0], [1.0, 0.0])
    """
    config = config or OutcomeConfig()
    origins = np.asarray(origins, dtype=float).reshape(-1, 2)
    directions = np.asarray(directions, dtype=float).reshape(-1, 2)
    lengths = np.asarray(lengths, dtype=float).reshape(-1)
    n_paths, (n_hyp, n_faces) = len(origins), posed.valid.shape
    tol = _tolerances(posed, sensor, config)
    chunk = max(1, config.chunk_elements // max(1, n_hyp * n_faces))
    parts = [
        _outcome_chunk(
            posed, tol, origins[i : i + chunk], directions[i : i + chunk], lengths[i : i + chunk]
        )
        for i in range(0, n_paths, chunk)
    ]
    if not parts:
        parts = [_outcome_chunk(posed, tol, origins, directions, lengths)]
    return Outcomes(**{k: np.concatenate([p[k] for p in parts]) for k in parts[0]})


def _outcome_chunk(
    posed: PosedSet, tol: dict, origins: np.ndarray, directions: np.ndarray, lengths: np.ndarray
) -> dict[str, np.ndarray]:
    o = origins[:, None, None, :]
    d = directions[:, None, None, :]
    length = lengths[:, None]
    ray_end = origins + directions * lengths[:, None]
    s, e, n = posed.start[None], posed.end[None], posed.normal[None]
    edge = e - s
    # o + t d meets s + u (e - s) at t = (w x e)/(d x e), u = (w x d)/(d x e), with w = s - o
    denom = _cross(d, edge)
    w = s - o
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        t = _cross(w, edge) / denom
        u = _cross(w, d) / denom
    meets = posed.valid[None] & (np.abs(denom) > 1e-12 * posed.length[None])
    meets &= (t >= 0) & (t <= length[..., None]) & (u >= 0) & (u <= 1)
    t = np.where(meets, t, np.inf)
    face = np.argmin(t, axis=-1)
    dist = _take(t, face)
    hit = np.isfinite(dist)
    face = np.where(hit, face, -1)
    f = np.maximum(face, 0)
    point = origins[:, None, :] + np.where(hit, dist, 0.0)[..., None] * directions[:, None, :]
    normal = _take(np.broadcast_to(n, (*t.shape, 2)), f)
    cos_in = np.abs(np.einsum("ck,chk->ch", directions, normal))
    geometric, vertex_tol = tol["geometric"][None], tol["vertex"][None]
    graze_sin = tol["graze_sin"][None]

    # vertex: the contact lies within the vertex zone of one end of the face hit
    u_hit = np.clip(_take(u, f), 0.0, 1.0)
    face_len = _take(np.broadcast_to(posed.length[None], t.shape), f)
    to_start, to_end = u_hit * face_len, (1 - u_hit) * face_len
    vertex = hit & (np.minimum(to_start, to_end) <= vertex_tol)
    prev, nxt = (np.broadcast_to(a[None], t.shape) for a in (posed.prev, posed.next))
    adjacent = np.where(to_start <= to_end, _take(prev, f), _take(nxt, f))
    adj_normal = _take(np.broadcast_to(n, (*t.shape, 2)), adjacent)
    grazing = hit & (cos_in < graze_sin)
    # a face displaced by delta moves the contact along the path by delta / |cos|
    along = geometric / np.maximum(cos_in, graze_sin)
    end_of_path = hit & (dist > length - along)

    # slip-through: the path passes the local geometry of the contact and goes on; past
    # the contact it is outside the object, so only faces turned toward it count
    near_contact = point_segment_distance(point[:, :, None, :], s, e) <= vertex_tol[..., None]
    facing = np.einsum("ck,chfk->chf", directions, np.broadcast_to(n, (*t.shape, 2))) < 0
    t_slip = np.where(near_contact | ~facing, np.inf, t)
    slip_face = np.argmin(t_slip, axis=-1)
    slip_dist = _take(t_slip, slip_face)
    facing_away = np.einsum("ck,chk->ch", directions, adj_normal) > -graze_sin
    slip = (vertex & facing_away) | grazing | end_of_path
    slip_hit = slip & np.isfinite(slip_dist) & ~end_of_path
    slip_point = (
        origins[:, None, :] + np.where(slip_hit, slip_dist, 0.0)[..., None] * directions[:, None, :]
    )
    slip_normal = _take(np.broadcast_to(n, (*t.shape, 2)), slip_face)

    near_miss, near_point, m_centre, m_spread = _near_miss(
        posed, o, ray_end, hit, geometric, prev, nxt
    )

    # outcome slots
    nan2 = np.full(point.shape, np.nan)
    angle0 = np.arctan2(normal[..., 1], normal[..., 0])
    v_centre, v_spread = _cone(normal, adj_normal)
    slot_valid = np.stack([np.ones_like(hit), vertex | near_miss, slip], axis=-1)
    slot_hit = np.stack([hit, vertex | near_miss, slip_hit], axis=-1)
    slot_point = np.stack(
        [
            np.where(hit[..., None], point, nan2),
            np.where(vertex[..., None], point, near_point),
            np.where(slip_hit[..., None], slip_point, nan2),
        ],
        axis=-2,
    )
    slot_angle = np.stack(
        [
            angle0,
            np.where(vertex, v_centre, m_centre),
            np.arctan2(slip_normal[..., 1], slip_normal[..., 0]),
        ],
        axis=-1,
    )
    slot_spread = np.stack(
        [np.zeros_like(angle0), np.where(vertex, v_spread, m_spread), np.zeros_like(angle0)],
        axis=-1,
    )
    slack = np.where(hit, along - geometric, 0.0)
    slot_slack = np.stack([slack, np.where(vertex, slack, 0.0), np.zeros_like(slack)], axis=-1)
    return {
        "hit": hit,
        "distance": dist,
        "point": np.where(hit[..., None], point, nan2),
        "normal": np.where(hit[..., None], normal, nan2),
        "face": face,
        "travel": np.where(hit, dist, length),
        "vertex": vertex,
        "grazing": grazing,
        "near_miss": near_miss,
        "end_of_path": end_of_path,
        "slot_valid": slot_valid,
        "slot_hit": slot_hit,
        "slot_point": slot_point,
        "slot_angle": slot_angle,
        "slot_spread": slot_spread,
        "slot_slack": slot_slack,
    }


def _near_miss(
    posed: PosedSet,
    o: np.ndarray,
    ray_end: np.ndarray,
    hit: np.ndarray,
    geometric: np.ndarray,
    prev: np.ndarray,
    nxt: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Misses passing within `geometric` of an outline: (flag, closest outline point,
    centre and half-width of the normals there), each (c, H)."""
    s, e, n = posed.start[None], posed.end[None], posed.normal[None]
    shape = prev.shape
    # the closest approach of two segments involves an endpoint of one of them
    d_start = point_segment_distance(s, o, ray_end[:, None, None, :])
    d_end = point_segment_distance(e, o, ray_end[:, None, None, :])
    d_ray = point_segment_distance(ray_end[:, None, None, :], s, e)
    gap = np.where(posed.valid[None], np.minimum(np.minimum(d_start, d_end), d_ray), np.inf)
    near_face = np.argmin(gap, axis=-1)
    near_miss = ~hit & (_take(gap, near_face) <= geometric)
    which = np.argmin(
        np.stack([_take(d_start, near_face), _take(d_end, near_face), _take(d_ray, near_face)]),
        axis=0,
    )
    nf_start = _take(np.broadcast_to(s, (*shape, 2)), near_face)
    nf_end = _take(np.broadcast_to(e, (*shape, 2)), near_face)
    nf_normal = _take(np.broadcast_to(n, (*shape, 2)), near_face)
    edge_nf = nf_end - nf_start
    proj = np.clip(
        np.einsum("chk,chk->ch", ray_end[:, None, :] - nf_start, edge_nf)
        / np.maximum(np.einsum("chk,chk->ch", edge_nf, edge_nf), 1e-300),
        0.0,
        1.0,
    )
    # at a vertex of the face the normal may be either face's; on the face, its own
    point = np.where(
        (which == 0)[..., None],
        nf_start,
        np.where((which == 1)[..., None], nf_end, nf_start + proj[..., None] * edge_nf),
    )
    other = np.where(which == 0, _take(prev, near_face), _take(nxt, near_face))
    other_normal = np.where(
        (which == 2)[..., None], nf_normal, _take(np.broadcast_to(n, (*shape, 2)), other)
    )
    centre, spread = _cone(nf_normal, other_normal)
    return near_miss, point, centre, spread


def confusability(
    posed: PosedSet,
    outcomes: Outcomes,
    sensor: SensorBounds,
    config: OutcomeConfig | None = None,
) -> np.ndarray:
    """(C, H, H) bool: can hypotheses h and g give the same measurement on path c?

    Two outcomes match when both miss, or both hit with points within
    ``2 eps_d + (eps_t(h) + eps_t(g)) / 2`` (plus grazing slack) and normals
    within ``2 phi + dtheta(h) + dtheta(g)`` (plus the vertex cones). Two
    hypotheses are confusable when any of their possible outcomes match;
    members of one equivalence class are always confusable.
    """
    config = config or OutcomeConfig()
    n_paths, n_hyp = outcomes.hit.shape
    slots = _Slots.of(posed, outcomes, sensor)
    same_class = posed.cls[:, None] == posed.cls[None, :]
    conf = np.empty((n_paths, n_hyp, n_hyp), dtype=bool)
    chunk = max(1, config.chunk_elements // max(1, n_hyp * n_hyp))
    for lo in range(0, n_paths, chunk):
        # nominal against nominal, for every pair
        nominal = slots.take(np.s_[lo : lo + chunk], 0)
        conf[lo : lo + chunk] = same_class | _match(nominal.expand(2), nominal.expand(1))
    # the uncertain outcomes: alternative k of h against slots 0..k of every g (the
    # symmetric update covers slot k of g against the alternatives of h below k)
    for k in range(1, SLOTS):
        c_idx, h_idx = np.nonzero(outcomes.slot_valid[..., k])
        per = max(1, config.chunk_elements // max(1, n_hyp * (k + 1)))
        for lo in range(0, len(c_idx), per):
            c, h = c_idx[lo : lo + per], h_idx[lo : lo + per]
            alt = slots.take((c, h), k).expand(1).expand(1)  # (E, 1, 1)
            other = slots.take(c, slice(0, k + 1))  # (E, H, k + 1)
            hit = _match(alt, other).any(axis=-1)
            conf[c, h, :] |= hit
            conf[c, :, h] |= hit
    return conf


@dataclass(frozen=True, eq=False)
class _Slots:
    """Outcome slot fields prepared for matching: point (x, y), normal (cos, sin),
    and each side's share of the tolerances (both sides' shares add up):
    `reach` = eps_d + eps_t / 2 + grazing slack, `alpha` = phi + dtheta + cone
    half-width, with its cosine and sine."""

    valid: np.ndarray
    hit: np.ndarray
    x: np.ndarray
    y: np.ndarray
    cos: np.ndarray
    sin: np.ndarray
    reach: np.ndarray
    alpha: np.ndarray
    cos_alpha: np.ndarray
    sin_alpha: np.ndarray

    @classmethod
    def of(cls, posed: PosedSet, o: Outcomes, sensor: SensorBounds) -> _Slots:
        floor = 1e-9 * posed.scale
        # points within 2 eps_d + (eps_t(h) + eps_t(g)) / 2: each side brings its half
        reach = sensor.position_error + posed.eps_t[None, :, None] / 2 + o.slot_slack + floor / 2
        # normals within 2 phi + dtheta(h) + dtheta(g): likewise, plus the vertex cones
        alpha = sensor.normal_error + posed.rotation[None, :, None] + o.slot_spread + 0.5e-9
        return cls(
            o.slot_valid,
            o.slot_hit,
            o.slot_point[..., 0],
            o.slot_point[..., 1],
            np.cos(o.slot_angle),
            np.sin(o.slot_angle),
            reach,
            alpha,
            np.cos(alpha),
            np.sin(alpha),
        )

    def take(self, rows: Any, k: int | slice | None = None) -> _Slots:
        """Path rows (a slice or index array) of the (C, H, SLOTS) fields; with `k`,
        only those slots (and `rows` may be a (paths, hypotheses) index pair)."""
        if k is None:
            sel = rows
        elif isinstance(rows, tuple):
            sel = (*rows, k)
        else:
            sel = (rows, slice(None), k)
        return _Slots(*(getattr(self, f.name)[sel] for f in fields(self)))

    def expand(self, axis: int) -> _Slots:
        """Insert a length-one axis at `axis`."""
        return _Slots(*(np.expand_dims(getattr(self, f.name), axis) for f in fields(self)))


def _match(a: _Slots, b: _Slots) -> np.ndarray:
    """Two outcome slots match: both miss, or both hit within the point and normal tolerances."""
    dx, dy = a.x - b.x, a.y - b.y
    reach = a.reach + b.reach
    # angle(n, m) <= alpha_a + alpha_b  <=>  cos(n, m) >= cos(alpha_a + alpha_b), or the
    # sum reaches pi; the 1e-12 absorbs rounding (equal normals match at zero tolerance)
    cos_turn = a.cos * b.cos + a.sin * b.sin
    cos_limit = a.cos_alpha * b.cos_alpha - a.sin_alpha * b.sin_alpha
    with np.errstate(invalid="ignore"):
        aligned = (cos_turn >= cos_limit - 1e-12) | (a.alpha + b.alpha >= np.pi)
        near = (dx * dx + dy * dy <= reach * reach) & aligned
    both_hit = a.hit & b.hit & near
    return a.valid & b.valid & ((~a.hit & ~b.hit) | both_hit)


@dataclass(frozen=True, eq=False)
class SurvivorTable:
    """Survivor sets over K equivalence classes for C paths, as bitsets.

    `bits[c, k]` (W uint64 words, bit j = class j) is S_c(k): the classes that
    survive path c when the truth is in class k. `weight` (K,) sums to 1.
    `inseparable` (K, W) marks, for each class, the classes confusable with it
    on every path (no candidate can tell them apart).
    """

    bits: np.ndarray
    weight: np.ndarray
    inseparable: np.ndarray

    @property
    def n_paths(self) -> int:
        return self.bits.shape[0]

    @property
    def n_classes(self) -> int:
        return len(self.weight)

    def matrix(self) -> np.ndarray:
        """(C, K, K) bool: class j survives path c when the truth is class k."""
        return unpack_bits(self.bits, self.n_classes)

    @classmethod
    def from_matrix(cls, confusable: np.ndarray, weight: np.ndarray) -> SurvivorTable:
        """Build from a (C, K, K) boolean matrix (made reflexive) and class weights."""
        conf = np.array(confusable, dtype=bool)
        if conf.ndim != 3 or conf.shape[1] != conf.shape[2]:
            raise PlannerError("must have shape (paths, classes, classes)", field="confusable")
        k = conf.shape[1]
        conf[:, np.arange(k), np.arange(k)] = True
        w = np.asarray(weight, dtype=float)
        if w.shape != (k,) or not np.all(w >= 0) or w.sum() <= 0:
            raise PlannerError("must be K weights >= 0 with a positive sum", field="weight")
        inseparable = np.asarray(conf.all(axis=0)) if len(conf) else np.ones((k, k), dtype=bool)
        return cls(bits=pack_bits(conf), weight=w / w.sum(), inseparable=pack_bits(inseparable))


def survivor_table(posed: PosedSet, confusable: np.ndarray) -> SurvivorTable:
    """Class-level survivor sets from the (C, H, H) hypothesis confusability.

    Class B survives truth class A on a path when some member of B is
    confusable with some member of A (a class is never split).
    """
    order = np.argsort(posed.cls, kind="stable")
    by_class = posed.cls[order]
    first = np.flatnonzero(np.r_[True, by_class[1:] != by_class[:-1]])
    conf = np.asarray(confusable, dtype=bool)
    if len(first) < len(order) or np.any(order != np.arange(len(order))):
        # conf_cls[c, A, B] = OR over h in A, g in B of conf[c, h, g]
        conf = conf[:, order][:, :, order]
        conf = np.logical_or.reduceat(conf, first, axis=1)
        conf = np.logical_or.reduceat(conf, first, axis=2)
    return SurvivorTable.from_matrix(conf, posed.class_weight)
