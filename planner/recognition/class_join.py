"""Classes joined where the leaders split what coincides (DESIGN §2).

The leaders of :func:`~planner.recognition.equivalence.equivalence_classes` take
in what lies within ``tau / 2`` of themselves, so that a class never chains. On
a curved part the hypotheses fill a continuum of nearby poses, and a hypothesis
just beyond ``tau / 2`` of its leader leads a class of its own while it lies
within ``tau`` of every member of the first: two "classes" that no touch can
tell apart (their outlines coincide within the sensor's tolerance), and a
session that can never say `localized`.

Here such classes are joined, complete linkage: class B joins class A when every
member of B lies within ``tau`` of every member of A (and no slide family is in
both). Any two members of a joined class are still within ``tau`` of each other,
so a class still never chains; a member lies within ``tau`` of its leader
(within ``tau / 2`` without a join), which the class bound must add.

Cost: only classes whose leaders' support values (:data:`SUPPORT_DIRECTIONS`)
lie within ``tau`` are candidates (outlines within d have support values within
d); they are measured together, one array pass per two stable poses (a joined
class is then judged from the pairs of the classes it took in), and the pairs
measured are bounded in advance by `JOIN_POINTS`; a pair of classes beyond what
is left stays apart (more classes, never a wrong one).

>>> from planner.models.library import object_from_dict
>>> sq = object_from_dict({"name": "sq", "outline": [[-5, -5], [5, -5], [5, 5], [-5, 5]]})
>>> rings = [PosedRings.of(sq.stable_poses[0], np.zeros(2), np.array([[0.0, 0], [0.6, 0]]))]
>>> label = np.array([0, 1])
>>> joined, wide = join_classes(rings, label, np.arange(2), np.arange(2), 1.0)
>>> joined.tolist(), wide.tolist()
([0, 0], [True])
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from scipy.spatial import cKDTree

from planner.recognition.equivalence import PosedRings, near_pairs, pairs_within, screen_reach

__all__ = ["JOIN_POINTS", "join_classes"]

#: The most boundary points one session's joins measure (each pair measured costs
#: the points of its two outlines).
JOIN_POINTS = 4_000_000


def join_classes(
    rings: Sequence[PosedRings],
    label: np.ndarray,
    order: np.ndarray,
    family: np.ndarray,
    tau: float,
    max_points: int = JOIN_POINTS,
    *,
    shapes: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Class labels (N,) after joining, renumbered as their leaders come in
    `order`, and per class whether it was joined (its members then lie within
    ``tau`` of its leader, not ``tau / 2``).

    `label` (N,) are the leaders' classes over the hypotheses stacked over the
    stable poses of `rings`, numbered in leader order; `family` (N,) labels the
    slide families (never two samples of one in a class); `tau` is the symmetry
    tolerance; `shapes` (one per stable pose of `rings`) which are one shape: as
    in :func:`~planner.recognition.equivalence.equivalence_classes`, only those
    share a class."""
    label = np.asarray(label, dtype=np.int64).copy()
    n = len(label)
    count = int(label.max()) + 1 if n else 0
    if count < 2 or not tau > 0:
        return label, np.zeros(count, dtype=bool)
    sizes = [len(r) for r in rings]
    offsets = np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64)
    group = np.repeat(np.arange(len(rings)), sizes)
    local = np.arange(n) - offsets[group]
    support = np.concatenate([r.support for r in rings])
    points = np.array([len(r.model_points) for r in rings])[group]
    # the members of each class in `order` (one sort, not a pass per class): the
    # first is its leader
    place = np.empty(n, dtype=np.int64)
    place[np.asarray(order, dtype=np.int64)] = np.arange(n)
    by_class = np.lexsort((place, label))
    starts = np.searchsorted(label[by_class], np.arange(count + 1))
    leaders = by_class[starts[:-1]]
    # a margin for rounding: the filter must never drop a pair that passes
    reach = screen_reach(tau, support)
    near = _near_leaders(support[leaders], reach)
    size = np.diff(starts)
    points_of = np.add.reduceat(points[by_class], starts[:-1])
    apart = _apart_families(family, by_class, starts, near)
    if shapes is not None:
        shape = np.asarray(shapes)[group[leaders]]
        apart &= shape[near[:, 0]] == shape[near[:, 1]]
    cost = size[near[:, 0]] * points_of[near[:, 1]] + size[near[:, 1]] * points_of[near[:, 0]]
    measured = near[_within_budget(np.where(apart, cost, max_points + 1), max_points)]
    close = measured[_all_within(rings, group, local, by_class, starts, measured, tau)]
    within = set(map(tuple, close.tolist()))
    into = np.arange(count)
    wide = np.zeros(count, dtype=bool)
    held: list[list[int]] = [[c] for c in range(count)]  # the classes each leader took in
    for a, b in close.tolist():
        if into[a] != a or into[b] != b:  # a class joins at most once, into a leader
            continue
        # b's leader comes after a's: b took in nothing yet, and every class a took
        # in has a smaller number than b
        if all((c, b) in within for c in held[a][1:]):
            held[a].append(b)
            into[b], wide[a] = a, True
    joined = into[label]
    # classes numbered as their leaders come in `order`
    first = np.full(count, n, dtype=np.int64)
    np.minimum.at(first, joined, place)
    kept = np.flatnonzero(first < n)
    rank = np.empty(count, dtype=np.int64)
    rank[kept[np.argsort(first[kept], kind="stable")]] = np.arange(len(kept))
    return rank[joined], wide[kept[np.argsort(first[kept], kind="stable")]]


def _within_budget(cost: np.ndarray, budget: int) -> np.ndarray:
    """(M,) bool: the pairs measured, in order, each while its cost (M,) still fits
    in what the ones before it left of `budget` (a pair too dear is passed over,
    a cheaper one after it may still fit)."""
    keep = np.zeros(len(cost), dtype=bool)
    left = budget
    for i, c in enumerate(cost.tolist()):
        if c <= left:
            keep[i], left = True, left - c
    return keep


#: Up to this many classes every pair of leaders is screened directly (a tree
#: costs more than the pairs).
TREE_FROM = 16


def _near_leaders(support: np.ndarray, reach: float) -> np.ndarray:
    """(M, 2) the pairs i < j of leaders whose support values (C, K) all lie within
    `reach` of each other, sorted: the tree's pairs, or every pair screened at once
    for a few classes."""
    if len(support) <= TREE_FROM:
        near = near_pairs(support, reach)
    else:
        near = cKDTree(support).query_pairs(reach, p=np.inf, output_type="ndarray")
    return near[np.lexsort((near[:, 1], near[:, 0]))]


def _apart_families(
    family: np.ndarray, by_class: np.ndarray, starts: np.ndarray, pairs: np.ndarray
) -> np.ndarray:
    """(M,) bool: do the two classes of each pair (M, 2) hold no slide family in common?"""
    fam = {
        c: set(family[by_class[starts[c] : starts[c + 1]]].tolist())
        for c in np.unique(pairs).tolist()
    }
    return np.array([fam[a].isdisjoint(fam[b]) for a, b in pairs.tolist()], dtype=bool)


def _all_within(
    rings: Sequence[PosedRings],
    group: np.ndarray,
    local: np.ndarray,
    by_class: np.ndarray,
    starts: np.ndarray,
    pairs: np.ndarray,
    tau: float,
) -> np.ndarray:
    """(M,) bool: does every hypothesis of the first class of each pair (M, 2) lie
    within `tau` of every one of the second? The members of class c are
    ``by_class[starts[c]:starts[c + 1]]``. All pairs measured together, one pass per
    two stable poses."""
    size = np.diff(starts)
    sa, sb = size[pairs[:, 0]], size[pairs[:, 1]]
    span = sa * sb
    pair = np.repeat(np.arange(len(pairs)), span)
    k = np.arange(int(span.sum())) - np.repeat(np.cumsum(span) - span, span)
    i = by_class[starts[pairs[pair, 0]] + k // sb[pair]]
    j = by_class[starts[pairs[pair, 1]] + k % sb[pair]]
    ok = np.ones(len(pair), dtype=bool)
    key = group[i] * len(rings) + group[j]
    for g in np.unique(key).tolist():
        sel = np.flatnonzero(key == g)
        ga, gb = divmod(g, len(rings))
        ok[sel] = pairs_within(rings[ga], local[i[sel]], rings[gb], local[j[sel]], tau)
    return np.bincount(pair[~ok], minlength=len(pairs)) == 0
