"""Predicted outcome of each sensing path for each hypothesis, and confusability (DESIGN §4.11).

Everything here is in the world frame, lengths in the object files' unit, angles
in radians (counter-clockwise positive). The pipeline is three numpy passes:

1. :func:`pose_hypotheses` packs the posed faces of all hypotheses into padded
   arrays (H hypotheses x F faces);
2. :func:`predict_outcomes` casts every candidate path against every posed
   hypothesis at once (chunked over candidates): first hit (point, face normal)
   or miss, and the ways the outcome is uncertain (vertex, grazing, near miss,
   contact at the very end of the path);
3. :func:`class_survivors` compares the outcomes of every pair of hypotheses on
   every path within the §4.11 tolerances and gives the survivor sets over
   equivalence classes as bitsets (:class:`SurvivorTable`). Slot points lie on
   the path, so a match is an overlap of intervals along it and of normal arcs:
   sorted interval ends answer all pairs at once with unions of bitsets, and
   only slots near a tie (or off the path) are compared one by one. The
   hypothesis-level matrix (:func:`confusability`) comes from the same pass.

Posed hypotheses live in :mod:`planner.posed` and candidate paths in
:mod:`planner.candidates`; both are re-exported here.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields

import numpy as np

from planner.bitsets import (
    IntervalUnions,
    SurvivorTable,
    close_ends,
    compact,
    n_words,
    pack_bits,
    transpose_bits,
    unpack_bits,
)
from planner.candidates import CandidateConfig, Candidates, generate_candidates
from planner.errors import PlannerError
from planner.posed import PosedSet, cast_paths, contains_points, pose_hypotheses
from planner.types import SensorBounds

__all__ = [
    "CandidateConfig",
    "Candidates",
    "OutcomeConfig",
    "Outcomes",
    "PosedSet",
    "SurvivorTable",
    "class_bits",
    "class_survivors",
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
    slides along the path by `tolerance / |cos(incidence)|`. `slot_distance`
    is how far along the path a slot's point lies (NaN for a miss) and
    `slot_offset` how far off the path, to its left (only a near miss's closest
    approach lies off it); `heading` (C,) is each path's direction angle.
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
    slot_distance: np.ndarray
    slot_offset: np.ndarray
    heading: np.ndarray

    @classmethod
    def concat(cls, parts: list[Outcomes]) -> Outcomes:
        """The outcomes of several groups of paths, one after the other."""
        return cls(
            **{f.name: np.concatenate([getattr(p, f.name) for p in parts]) for f in fields(cls)}
        )

    @property
    def uncertain(self) -> np.ndarray:
        """(C, H) bool: the outcome may be something other than the nominal one."""
        return self.vertex | self.grazing | self.near_miss | self.end_of_path


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
    tol = _tolerances(posed, sensor, config)
    return Outcomes(
        **cast_paths(
            posed,
            origins,
            directions,
            lengths,
            (tol["geometric"], tol["vertex"], tol["graze_sin"]),
            config.chunk_elements,
        )
    )


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
    n_hyp = len(posed)
    rows = _match_rows(posed, outcomes, sensor, config)
    rows |= transpose_bits(rows, n_hyp) | _miss_bits(outcomes, np.arange(n_hyp), n_hyp)
    return unpack_bits(rows, n_hyp) | (posed.cls[:, None] == posed.cls[None, :])


def class_survivors(
    posed: PosedSet,
    outcomes: Outcomes,
    sensor: SensorBounds,
    config: OutcomeConfig | None = None,
) -> SurvivorTable:
    """The class survivor table straight from the outcomes, as
    ``survivor_table(posed, confusability(...))`` but never forming the (C, H, H)
    matrix: class B survives truth class A on a path when some member of B is
    confusable with some member of A."""
    return SurvivorTable.from_bits(class_bits(posed, outcomes, sensor, config), posed.class_weight)


def class_bits(
    posed: PosedSet,
    outcomes: Outcomes,
    sensor: SensorBounds,
    config: OutcomeConfig | None = None,
) -> np.ndarray:
    """(C, K, W) class confusability as bitsets (see :func:`class_survivors`)."""
    n_hyp, n_cls = len(posed), posed.n_classes
    # hypotheses in class order: rows and bits of one class side by side
    order = np.argsort(posed.cls, kind="stable")
    rows = _match_rows(posed, outcomes, sensor, config, order)
    misses = _miss_bits(outcomes, posed.cls, n_cls)
    if n_cls == n_hyp:  # one hypothesis per class: R is the class relation
        return rows | transpose_bits(rows, n_hyp) | misses
    by_class = posed.cls[order]
    first = np.flatnonzero(np.r_[True, by_class[1:] != by_class[:-1]])
    # X[c, A, g] = OR_{h in A} R[c, h, g]; then Y[c, B, A] = OR_{g in B} X[c, A, g]
    y = transpose_bits(np.bitwise_or.reduceat(rows, first, axis=1), n_hyp)
    y = np.bitwise_or.reduceat(y, first, axis=1)
    # confusability is symmetric: conf = Y | Y^T
    return y | transpose_bits(y, n_cls) | misses


def _miss_bits(outcomes: Outcomes, group: np.ndarray, n_groups: int) -> np.ndarray:
    """(C, n_groups, W): misses match misses, so on each path every group (hypothesis
    or class) with a missing outcome slot is confusable with every other such group;
    `group` (H,) is each hypothesis' group."""
    missing = (outcomes.slot_valid & ~outcomes.slot_hit).any(axis=-1)
    found = np.zeros((len(missing), n_groups), dtype=bool)
    c, h = np.nonzero(missing)
    found[c, group[h]] = True
    return np.where(found[..., None], pack_bits(found)[:, None, :], np.uint64(0))


#: Angle margin (radians) where the cosine test's 1e-12 slack can still decide:
#: cos(A) - 1e-12 = cos(A + x) needs x <= sqrt(2e-12) ~ 1.42e-6.
_ANGLE_BAND = 1.5e-6

#: Hit slots per path up to which every pair is compared one by one (cheaper than
#: sorting intervals when there are few).
_FEW_HITS = 24


def _match_rows(
    posed: PosedSet,
    outcomes: Outcomes,
    sensor: SensorBounds,
    config: OutcomeConfig | None = None,
    order: np.ndarray | None = None,
) -> np.ndarray:
    """(C, H, W) bitsets R over hypotheses (taken in `order`, default as given) such
    that R | R^T is the confusability of hits (misses: `_miss_bits`).

    Slot points lie on the path (a near miss's closest approach aside), so two
    hits match when their intervals ``distance +- reach`` and their normal arcs
    ``angle +- alpha`` both overlap; sorted interval ends turn these tests into
    prefix and suffix unions of bitsets (:class:`~planner.bitsets.IntervalUnions`).
    R[c, h] holds the g one of whose slots matches a slot of h at least as far
    down the slot list. Slots near a tie (ends within rounding, or within the
    cosine test's slack, of another's) and near misses bound their matches from
    inside and outside and test what lies between one by one (`_match`); arcs
    across the heading are also tested one turn up or down.
    """
    config = config or OutcomeConfig()
    n_paths, n_hyp = outcomes.hit.shape
    slots = _Slots.of(posed, outcomes, sensor)
    width = n_words(n_hyp)
    rows = np.zeros((n_paths, n_hyp, width), dtype=np.uint64)
    chunk = max(1, config.chunk_elements // max(1, SLOTS * n_hyp * width))
    for lo in range(0, n_paths, chunk):
        part = slice(lo, min(lo + chunk, n_paths))
        items = _Items.of(outcomes, slots, part, np.arange(n_hyp) if order is None else order)
        rows[items.part] = items.rows(posed, width, config.chunk_elements)
    return rows


@dataclass(frozen=True, eq=False)
class _Items:
    """The outcome slots of some paths as items (c, SLOTS H), item k = slot k // H
    of hypothesis k % H: `valid`, `hit`, interval centre `d` (along the path) and
    half-width `r`, `off` (distance off the path), normal angle `u` from the
    heading in [0, 2 pi) with half-width `a`; `slots` holds every item's slot
    fields (c, SLOTS H) for the one-by-one tests."""

    part: slice
    order: np.ndarray
    valid: np.ndarray
    hit: np.ndarray
    d: np.ndarray
    r: np.ndarray
    off: np.ndarray
    u: np.ndarray
    a: np.ndarray
    slots: _Slots

    @classmethod
    def of(cls, o: Outcomes, slots: _Slots, part: slice, order: np.ndarray) -> _Items:
        n_paths = part.stop - part.start
        flat = lambda a: np.swapaxes(a[part][:, order], 1, 2).reshape(n_paths, -1)  # noqa: E731
        # the slot fields in item order, for the one-by-one tests
        items = _Slots(*(flat(getattr(slots, f.name)) for f in fields(_Slots)))
        hit = items.hit & items.valid
        # angles from the path's heading: hit normals face back along it
        u = np.mod(flat(o.slot_angle) - o.heading[part, None], 2 * math.pi)
        off = np.where(hit, np.abs(flat(o.slot_offset)), np.inf)
        return cls(
            part,
            order,
            items.valid,
            hit,
            flat(o.slot_distance),
            items.reach,
            off,
            u,
            items.alpha,
            items,
        )

    def _slots_at(self, c: np.ndarray, k: np.ndarray) -> _Slots:
        """The slot fields of items (c, k) (broadcast)."""
        c, k = np.broadcast_arrays(c, k)
        at = c * self.hit.shape[1] + k
        return _Slots(*(getattr(self.slots, f.name).take(at) for f in fields(_Slots)))

    def rows(self, posed: PosedSet, width: int, chunk_elements: int) -> np.ndarray:
        n_paths, n_items = self.hit.shape
        n_hyp = n_items // SLOTS
        owner, slot = np.arange(n_items) % n_hyp, np.arange(n_items) // n_hyp
        owners = np.broadcast_to(owner, self.hit.shape)
        rows = np.zeros((n_paths, n_hyp, width), dtype=np.uint64)
        # (misses match misses: see `_miss_bits`)
        if self.hit.sum(axis=1).max(initial=0) <= _FEW_HITS:  # few: every pair one by one
            return rows | self._all_pairs(owner)
        # arcs clear of the cut at the heading overlap iff their intervals do
        finite = self.hit & np.isfinite(self.d)
        clear = (self.u - self.a >= _ANGLE_BAND) & (self.u + self.a <= 2 * math.pi - _ANGLE_BAND)
        clear &= finite
        d_low, d_high, u_low, u_high = (
            self.d - self.r,
            self.d + self.r,
            self.u - self.a,
            self.u + self.a,
        )
        # near a tie: another slot's interval starts within rounding (distances) or
        # within the cosine slack (angles) of this one's end
        band = 1e-13 * posed.scale
        on_path = clear & (self.off == 0)
        regular = on_path & ~close_ends(d_low, d_high, on_path, -band, band)
        regular &= ~close_ends(u_low, u_high, on_path, -1e-12, _ANGLE_BAND)
        # each slot's regular items by interval ends: distances on rows c, arcs on
        # rows n_paths + c
        lists = [
            IntervalUnions.of(
                np.concatenate([d_low[:, at], u_low[:, at]]),
                np.concatenate([d_high[:, at], u_high[:, at]]),
                np.concatenate([owners[:, at], owners[:, at]]),
                np.concatenate([regular[:, at], regular[:, at]]),
                width,
            )
            for at in (slice(j * n_hyp, (j + 1) * n_hyp) for j in range(SLOTS))
        ]
        regulars = [np.nonzero(regular & (slot == i)) for i in range(SLOTS)]
        # near ties, near misses and arcs across the heading: sure matches from shrunk
        # intervals and arcs, and the others of grown ones confirmed one by one; an arc
        # across the heading is also tested one turn up or down
        loose = finite & ~regular
        lc, lk = np.nonzero(loose)
        inside, turns = self._margins(lc, lk, band)
        found = np.zeros((len(lc), width), dtype=np.uint64)
        for j in range(SLOTS):
            # against the regular slots j: regular slots i >= j (both ways: R | R^T)
            # and the loose slots, all in one pass
            parts = [(c, k, 0.0, 0.0, 0.0) for c, k in regulars[j:]]
            for e, turn in turns:
                parts.append((lc[e], lk[e], inside[e], -1e-12, turn))
                parts.append((lc[e], lk[e], 2 * band, _ANGLE_BAND, turn))
            answers = self._overlaps(lists[j], parts)
            for (c, k), answer in zip(regulars[j:], answers, strict=False):
                rows[c, owner[k]] |= answer
            sure, maybe = np.zeros_like(found), np.zeros_like(found)
            rest = answers[SLOTS - j :]
            for (e, _), got_sure, got_maybe in zip(turns, rest[::2], rest[1::2], strict=True):
                sure[e] |= got_sure
                maybe[e] |= got_maybe
            found |= sure | self._confirm(lc, lk, maybe & ~sure, j)
        if len(lc):
            np.bitwise_or.at(rows, (lc, owner[lk]), found)
        # what the lists leave out, one by one: loose slots against each other, and
        # any slot not on the path's line
        stray = self.hit & ~finite
        for queries, targets in ((stray, self.hit), (loose, loose | stray)):
            c, k = np.nonzero(queries)
            if len(c):
                found = self._exact(c, k, targets, owner, chunk_elements)
                np.bitwise_or.at(rows, (c, owner[k]), found)
        return rows

    def _margins(self, c: np.ndarray, k: np.ndarray, band: float) -> tuple[np.ndarray, list]:
        """How far the intervals of loose items (c, k) shrink for sure matches, and
        the turns (query indices, angle shift) their arcs are tested at."""
        r_min = float(self.r[self.hit].min(initial=0.0))
        off, r = self.off[c, k], self.r[c, k]
        # off the path by x: |p - q|^2 = dd^2 + x^2 <= R^2 holds once |dd| <= R - x^2 / R
        shrink = np.where(off > 0, off**2 / (r + r_min), 0.0)
        u_low = self.u[c, k] - self.a[c, k] - _ANGLE_BAND
        u_high = self.u[c, k] + self.a[c, k] + _ANGLE_BAND
        turns = [(np.arange(len(c)), 0.0)]
        for need, shift in ((u_low < 0, 2 * math.pi), (u_high > 2 * math.pi, -2 * math.pi)):
            if need.any():
                turns.append((np.flatnonzero(need), shift))
        return -shrink - 2 * band, turns

    def _overlaps(self, unions: IntervalUnions, parts: list[tuple]) -> list[np.ndarray]:
        """For each part (c, k, grow_d, grow_u, turn): the (E, W) owners of the slots
        in `unions` whose interval and arc overlap those of items (c, k), half-widths
        grown by `grow_d` and `grow_u` and arc turned by `turn`; one pass for all."""
        sizes = [len(part[0]) for part in parts]
        c, k, grow_d, grow_u, turn = (
            np.concatenate([np.broadcast_to(p[i], n) for p, n in zip(parts, sizes, strict=True)])
            for i in range(5)
        )
        d, r = self.d[c, k], self.r[c, k] + grow_d
        u, a = self.u[c, k] + turn, self.a[c, k] + grow_u
        n, n_paths = len(c), self.hit.shape[0]
        both = unions.overlapping(np.r_[c, c + n_paths], np.r_[d - r, u - a], np.r_[d + r, u + a])
        return np.split(both[:n] & both[n:], np.cumsum(sizes)[:-1])

    def _confirm(self, c: np.ndarray, k: np.ndarray, maybe: np.ndarray, j: int) -> np.ndarray:
        """(E, W): the owners g in `maybe` whose slot j `_match`es item (c, k)."""
        n_hyp = self.hit.shape[1] // SLOTS
        e, g = np.nonzero(unpack_bits(maybe, n_hyp))
        ok = np.zeros((len(c), n_hyp), dtype=bool)
        if len(e):
            hit = _match(self._slots_at(c[e], k[e]), self._slots_at(c[e], j * n_hyp + g))
            ok[e[hit], g[hit]] = True
        return pack_bits(ok)

    def _all_pairs(self, owner: np.ndarray) -> np.ndarray:
        """(c, H, W): for each pair of hit slots of a path, each pair once (the
        transpose completes it), the owner of the second in the first's row."""
        n_paths, n_hyp = len(self.hit), len(owner) // SLOTS
        at = compact(self.hit)
        path = np.arange(n_paths)[:, None]
        first, second = np.triu_indices(at.shape[1])
        ok = (at[:, first] >= 0) & (at[:, second] >= 0)
        columns = self._slots_at(path, np.maximum(at, 0))
        mine = _Slots(*(getattr(columns, f.name)[:, first] for f in fields(_Slots)))
        theirs = _Slots(*(getattr(columns, f.name)[:, second] for f in fields(_Slots)))
        c, p = np.nonzero(_match(mine, theirs) & ok)
        pairs = np.zeros((n_paths, n_hyp, n_hyp), dtype=bool)
        pairs[c, owner[at[c, first[p]]], owner[at[c, second[p]]]] = True
        return pack_bits(pairs)

    def _exact(
        self, c: np.ndarray, k: np.ndarray, targets: np.ndarray, owner: np.ndarray, chunk: int
    ) -> np.ndarray:
        """(E, W) hypotheses one of whose `targets` slots (c, items) matches item (c, k)."""
        n_hyp = len(owner) // SLOTS
        at = compact(targets)
        member = at >= 0
        theirs = self._slots_at(np.arange(len(targets))[:, None], np.maximum(at, 0))
        size = member.sum(axis=1)[c]
        out = np.zeros((len(c), n_words(n_hyp)), dtype=np.uint64)
        # queries with as many targets to within a factor two together, each batch as
        # wide as its widest path and of about `chunk` pairs
        level = np.ceil(np.log2(np.maximum(size, 1))).astype(int)
        for lvl in np.unique(level[size > 0]):
            group = np.flatnonzero((level == lvl) & (size > 0))
            width = int(size[group].max())
            for pick in np.array_split(group, -(-len(group) * width // chunk)):
                cc, kk = c[pick], k[pick]
                mine = self._slots_at(cc[:, None], kk[:, None])
                rows = _Slots(*(getattr(theirs, f.name)[cc, :width] for f in fields(_Slots)))
                e, t = np.nonzero(_match(mine, rows) & member[cc, :width])
                hits = np.zeros((len(cc), n_hyp), dtype=bool)
                hits[e, owner[at[cc[e], t]]] = True
                out[pick] = pack_bits(hits)
        return out


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
