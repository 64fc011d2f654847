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
d), and the pairs measured are bounded in advance by `JOIN_POINTS`; a pair of
classes beyond what is left stays apart (more classes, never a wrong one).

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

from planner.recognition.equivalence import PosedRings, pairs_within

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
) -> tuple[np.ndarray, np.ndarray]:
    """Class labels (N,) after joining, renumbered as their leaders come in
    `order`, and per class whether it was joined (its members then lie within
    ``tau`` of its leader, not ``tau / 2``).

    `label` (N,) are the leaders' classes over the hypotheses stacked over the
    stable poses of `rings`, numbered in leader order; `family` (N,) labels the
    slide families (never two samples of one in a class); `tau` is the symmetry
    tolerance."""
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
    points = np.array([r.points.shape[1] for r in rings])[group]
    # the members of each class in `order` (one sort, not a pass per class): the
    # first is its leader
    place = np.empty(n, dtype=np.int64)
    place[np.asarray(order, dtype=np.int64)] = np.arange(n)
    by_class = np.lexsort((place, label))
    members = np.split(by_class, np.searchsorted(label[by_class], np.arange(1, count)))
    leaders = np.array([m[0] for m in members])
    tree = cKDTree(support[leaders])
    # a margin for rounding: the filter must never drop a pair that passes
    reach = tau * (1 + 1e-9) + 1e-12 * (1.0 + float(np.abs(support).max()))
    near = tree.query_pairs(reach, p=np.inf, output_type="ndarray")
    into = np.arange(count)
    wide = np.zeros(count, dtype=bool)
    left = max_points
    for a, b in near[np.lexsort((near[:, 1], near[:, 0]))]:
        if into[a] != a or into[b] != b:  # a class joins at most once, into a leader
            continue
        mine, theirs = members[a], members[b]
        if not _disjoint(family[mine], family[theirs]):
            continue
        cost = len(mine) * int(points[theirs].sum()) + len(theirs) * int(points[mine].sum())
        if cost > left:
            continue
        left -= cost
        if _all_within(rings, group, local, mine, theirs, tau):
            members[a] = np.concatenate([mine, theirs])
            into[b], wide[a] = a, True
    joined = into[label]
    # classes numbered as their leaders come in `order`
    first = np.full(count, n, dtype=np.int64)
    np.minimum.at(first, joined, place)
    kept = np.flatnonzero(first < n)
    rank = np.empty(count, dtype=np.int64)
    rank[kept[np.argsort(first[kept], kind="stable")]] = np.arange(len(kept))
    return rank[joined], wide[kept[np.argsort(first[kept], kind="stable")]]


def _all_within(
    rings: Sequence[PosedRings],
    group: np.ndarray,
    local: np.ndarray,
    mine: np.ndarray,
    theirs: np.ndarray,
    tau: float,
) -> bool:
    """Does every hypothesis of `mine` lie within `tau` of every one of `theirs`?
    Measured one pass per two stable poses (most classes hold one hypothesis, or
    hypotheses of one stable pose: one pass)."""
    mine_groups, their_groups = group[mine], group[theirs]
    for ga in _distinct(mine_groups):
        ia = local[mine[mine_groups == ga]] if len(mine) > 1 else local[mine]
        for gb in _distinct(their_groups):
            ib = local[theirs[their_groups == gb]] if len(theirs) > 1 else local[theirs]
            a, b = np.repeat(ia, len(ib)), np.tile(ib, len(ia))
            if not pairs_within(rings[ga], a, rings[gb], b, tau).all():
                return False
    return True


def _distinct(values: np.ndarray) -> list[int]:
    """The distinct values, ascending (one without a sort when all are equal)."""
    first = int(values[0])
    return [first] if (values == first).all() else np.unique(values).tolist()


def _disjoint(a: np.ndarray, b: np.ndarray) -> bool:
    """No value in both (few values: sets, not sorts)."""
    return set(a.tolist()).isdisjoint(b.tolist())
