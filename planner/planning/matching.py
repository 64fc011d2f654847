"""Matching of outcome slots within the tolerances of DESIGN §4.11: which hypotheses
(or classes) can give the same measurement on each path.

Two slots match when both miss, or both hit with points within
``2 eps_d + (eps_t(h) + eps_t(g)) / 2`` (plus grazing slack) and normals within
``2 phi + dtheta(h) + dtheta(g)`` (plus vertex cones): :func:`slots_match`, the
reference. Slot points lie on the path (a near miss's closest approach aside), so
:func:`match_rows` tests only slots within reach along the path (a compiled sweep,
:mod:`planner.planning.match_kernel`), or, where most pairs are within reach, gets
the same answer from sorted interval ends along the path and of normal arcs;
misses are one set per path (:func:`miss_bits`). World frame, lengths in the
object files' unit, radians.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields
from typing import TYPE_CHECKING

import numpy as np

from planner.geometry import LENGTH_SLACK
from planner.planning.bitsets import (
    IntervalUnions,
    close_ends,
    compact,
    n_words,
    pack_bits,
    unpack_bits,
)
from planner.planning.match_kernel import pair_rows, window_pairs
from planner.types import SensorBounds

if TYPE_CHECKING:
    from planner.planning.outcomes import Outcomes
    from planner.planning.posed_set import PosedSet

__all__ = ["SLOTS", "Slots", "match_rows", "miss_bits", "slots_match"]

#: Outcome slots per (path, hypothesis): nominal, vertex/near-miss alternative,
#: slip-through, and a face passed near after a slip.
SLOTS = 4


def miss_bits(outcomes: Outcomes, group: np.ndarray, n_groups: int) -> np.ndarray:
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

#: Pairs per hit slot and bitset word up to which the sweep tests pairs one by one
#: (:mod:`planner.planning.match_kernel`, ~10 ns a pair); past it sorted interval
#: ends are cheaper (~2.5 us a hit slot at three words, growing with the words).
_PAIRS_PER_HIT = 64


def match_rows(
    posed: PosedSet,
    outcomes: Outcomes,
    sensor: SensorBounds,
    chunk_elements: int,
    order: np.ndarray | None = None,
) -> np.ndarray:
    """(C, H, W) bitsets R over hypotheses (taken in `order`, default as given) such
    that R | R^T is the confusability of hits (misses: `miss_bits`).

    Where few pairs of hit slots lie within reach of each other along the path,
    those pairs are tested one by one (:func:`~planner.planning.match_kernel.pair_rows`).
    Otherwise: slot points lie on the path (a near miss's closest approach aside), so two
    hits match when their intervals ``distance +- reach`` and their normal arcs
    ``angle +- alpha`` both overlap; sorted interval ends turn these tests into
    prefix and suffix unions of bitsets (:class:`~planner.planning.bitsets.IntervalUnions`).
    R[c, h] holds the g one of whose slots matches a slot of h at least as far
    down the slot list. Slots near a tie (ends within rounding, or within the
    cosine test's slack, of another's) and near misses bound their matches from
    inside and outside and test what lies between one by one (`slots_match`); arcs
    across the heading are also tested one turn up or down.
    """
    n_paths, n_hyp = outcomes.hit.shape
    slots = Slots.of(posed, outcomes, sensor)
    width = n_words(n_hyp)
    rows = np.zeros((n_paths, n_hyp, width), dtype=np.uint64)
    chunk = max(1, chunk_elements // max(1, SLOTS * n_hyp * width))
    for lo in range(0, n_paths, chunk):
        part = slice(lo, min(lo + chunk, n_paths))
        items = _Items.of(outcomes, slots, part, np.arange(n_hyp) if order is None else order)
        rows[items.part] = items.rows(posed, width, chunk_elements)
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
    slots: Slots

    @classmethod
    def of(cls, o: Outcomes, slots: Slots, part: slice, order: np.ndarray) -> _Items:
        n_paths = part.stop - part.start
        flat = lambda a: np.swapaxes(a[part][:, order], 1, 2).reshape(n_paths, -1)  # noqa: E731
        # the slot fields in item order, for the one-by-one tests
        items = Slots(*(flat(getattr(slots, f.name)) for f in fields(Slots)))
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

    def _slots_at(self, c: np.ndarray, k: np.ndarray) -> Slots:
        """The slot fields of items (c, k) (broadcast)."""
        c, k = np.broadcast_arrays(c, k)
        at = c * self.hit.shape[1] + k
        return Slots(*(getattr(self.slots, f.name).take(at) for f in fields(Slots)))

    def rows(self, posed: PosedSet, width: int, chunk_elements: int) -> np.ndarray:
        n_paths, n_items = self.hit.shape
        n_hyp = n_items // SLOTS
        owner, slot = np.arange(n_items) % n_hyp, np.arange(n_items) // n_hyp
        owners = np.broadcast_to(owner, self.hit.shape)
        rows = np.zeros((n_paths, n_hyp, width), dtype=np.uint64)
        # (misses match misses: see `miss_bits`)
        band = 1e-13 * posed.scale
        # few pairs of slots within reach along the path: test those one by one
        allowed = _PAIRS_PER_HIT * (width + 1) * self.hit.sum()
        if window_pairs(self.hit, self.d, self.r, 1e4 * band) <= allowed:
            slots = self.slots
            columns = (slots.x, slots.y, slots.cos, slots.sin, self.r, self.a)
            columns += (slots.cos_alpha, slots.sin_alpha)
            pair_rows(self.hit, self.d, columns, owner, 1e4 * band, rows)
            return rows
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
        """(E, W): the owners g in `maybe` whose slot j matches item (c, k) (`slots_match`)."""
        n_hyp = self.hit.shape[1] // SLOTS
        e, g = np.nonzero(unpack_bits(maybe, n_hyp))
        ok = np.zeros((len(c), n_hyp), dtype=bool)
        if len(e):
            hit = slots_match(self._slots_at(c[e], k[e]), self._slots_at(c[e], j * n_hyp + g))
            ok[e[hit], g[hit]] = True
        return pack_bits(ok)

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
                rows = Slots(*(getattr(theirs, f.name)[cc, :width] for f in fields(Slots)))
                e, t = np.nonzero(slots_match(mine, rows) & member[cc, :width])
                hits = np.zeros((len(cc), n_hyp), dtype=bool)
                hits[e, owner[at[cc[e], t]]] = True
                out[pick] = pack_bits(hits)
        return out


@dataclass(frozen=True, eq=False)
class Slots:
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
    def of(cls, posed: PosedSet, o: Outcomes, sensor: SensorBounds) -> Slots:
        floor = LENGTH_SLACK * posed.scale
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


def slots_match(a: Slots, b: Slots) -> np.ndarray:
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
