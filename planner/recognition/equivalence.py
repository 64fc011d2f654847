"""Equivalence classes of hypotheses: posed outlines that coincide (DESIGN §2).

Two hypotheses are equivalent when their posed outlines coincide within the
symmetry tolerance ``tau``: the rotations of a square, a disc turned about its
centre, two congruent objects in the same place. ``tau`` is fixed by the sensor
(``2 eps_d``: outlines closer than that give the same contacts within the
errors), never by the pose error bounds, so two distinct poses that the error
disks merely overlap stay apart.

A class never chains. The hypotheses are taken most probable first; the first
one not yet in a class leads a new class and takes in every hypothesis not yet
in one whose outline lies within ``tau / 2`` of its own. Any two members are
then within ``tau`` of each other (the triangle inequality), whatever the
order. The samples of one slide family (DESIGN §4.6) stay apart: the slide
they sample is not known yet; and so do hypotheses of stable poses that are not
one shape (congruent, :mod:`planner.models.congruence`): two objects whose
outlines differ by less than ``tau`` are still two answers, and more touches may
tell them apart.

Outline distance: the larger of the two directed distances from the points of
one posed outline's boundary (holes included) to the faces of the other, a
symmetric Hausdorff distance between the boundaries measured at every vertex
and at up to `EDGE_SAMPLES` points inside every face (vertices alone miss a
non-convex outline turned so that its corners fall on the other's edges), no
closer together than ``SAMPLE_SPACING * tau``: a curve drawn with hundreds of
short faces is measured at about as many points as its length needs, not seven
more per face; a point of a short face lies within ``tau / 8`` of a measured
one, a point of a long face within a sixteenth of its length (`gap`). Only
pairs that can pass are measured: when every vertex of A lies within d of B's
faces and back, the support functions ``h(u) = max_v u.v`` of the two vertex
sets differ by at most d in every direction u, so a k-d tree over the support
values in a few directions (max norm) finds every candidate pair, and the
work grows with the hypotheses and the faces, not with their pairs. The
support sees only the convex hull, under which the rotations of a round outline
with a hole or a small notch all look alike; so the tree also holds each
outline's distance from a few fixed probe points (points of the most probable
outline). A point x of A's faces nearest a probe q lies within g/2 of a sample
of A (g: the longest gap between samples), which lies within d of B's faces:
the two distances from q differ by at most d + g/2, scaled to the tree's reach.
A first tree over a few of these keys finds the pairs, which are then held to
all of them (a tree over forty-odd keys is slow); when there are few, every
pair is decided in one pass before the leaders take their classes, otherwise
(a round part's rotations) each leader measures only what is left.

Each candidate pair is then measured only as far as its answer needs, by a
compiled early-break scan whose cost grows with the points and the faces, not
with their product (:mod:`planner.recognition.outline_kernel`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

from planner.geometry import rotate, rotation_matrices
from planner.memo import cached_property
from planner.recognition.outline_kernel import nearest_face_distances, pair_outline_distances
from planner.types import StablePose

__all__ = [
    "BRUTE_FORCE_FACES",
    "CHUNK_ELEMENTS",
    "PAIR_BATCH",
    "SUPPORT_DIRECTIONS",
    "SYMMETRY_FLOOR",
    "PosedRings",
    "equivalence_classes",
    "near_pairs",
    "none_can_share",
    "outline_distance",
    "pair_distances",
    "pairs_within",
    "screen_reach",
    "support_values",
    "within",
]

#: Smallest symmetry tolerance, as a share of the scene's scale: exact sensing
#: still leaves rounding between the rotations of a symmetric outline.
SYMMETRY_FLOOR = 1e-6
#: The most key values one pass of the candidate-pair screen holds at once.
CHUNK_ELEMENTS = 1_000_000
#: Outlines with at most this many faces have few close rotations: their candidate
#: pairs are decided in one batch (see PAIR_BATCH).
BRUTE_FORCE_FACES = 64
#: The most points measured inside each face, besides its ends.
EDGE_SAMPLES = 7
#: The least spacing of those points, as a share of the symmetry tolerance.
SAMPLE_SPACING = 0.25
#: Probe points whose distances to each posed outline also find candidate pairs:
#: a PROBE_GRID x PROBE_GRID grid over the most probable outline's box, and PROBES
#: points along its boundary.
PROBE_GRID = 5
PROBES = 8
#: The most candidate pairs per hypothesis decided in one batch before the classes
#: are formed, on outlines of at most BRUTE_FORCE_FACES faces (a part's discrete
#: symmetries: a square's four rotations); beyond it, or on outlines with more
#: faces (a round part, whose rotations are all near one another, each pair dear),
#: each leader decides its own, and no member of a class is measured again.
PAIR_BATCH = 8
#: Up to this many hypotheses every pair is measured, without the screen (its keys
#: and trees cost more than the pairs themselves; the screen drops no pair that is close).
SCREEN_FROM = 16
#: Unit directions (every 30 degrees) of the support values that find candidate pairs.
SUPPORT_DIRECTIONS = np.column_stack(
    [np.cos(np.arange(12) * np.pi / 6), np.sin(np.arange(12) * np.pi / 6)]
)
#: The columns of the screening keys a first k-d tree holds: the support values
#: at 0, 90, 180 and 270 degrees (the outline's box), the distance from the centre
#: of the probe grid and from the last probe along the boundary.
FIRST_KEYS = np.array([0, 3, 6, 9, len(SUPPORT_DIRECTIONS) + PROBE_GRID**2 // 2, -1])


@dataclass(frozen=True, eq=False)
class PosedRings:
    """Posed outlines of N hypotheses of one stable pose: `model_points` (P, 2) on
    the boundary in the model frame (every vertex and up to `EDGE_SAMPLES` points
    inside each face; :attr:`points` posed, (N, P, 2)), `starts`/`ends` (N, F, 2)
    of every face in the world frame, and `support` (N, K): the support function
    of the vertices in the K directions of :data:`SUPPORT_DIRECTIONS`; the poses
    `theta` (N,) and `t` (N, 2) and their `rotations` (N, 2, 2), the stable pose's
    faces in its model frame, `model_starts`/`model_ends` (F, 2), and `gap`: the
    longest step between two consecutive points along a face. The points are
    posed where they are measured (:mod:`planner.recognition.outline_kernel`),
    the same numbers as :attr:`points`: most pairs are decided on a few of them."""

    model_points: np.ndarray
    starts: np.ndarray
    ends: np.ndarray
    support: np.ndarray
    theta: np.ndarray
    t: np.ndarray
    rotations: np.ndarray
    model_starts: np.ndarray
    model_ends: np.ndarray
    gap: float

    @classmethod
    def of(
        cls,
        stable: StablePose,
        theta: np.ndarray,
        t: np.ndarray,
        spacing: float = 0.0,
        most: float = EDGE_SAMPLES,
    ) -> PosedRings:
        """The stable pose moved to each pose (theta (N,), t (N, 2)):
        ``v_world = R(theta) v_model + t``. A face holds `most` points inside, or
        fewer where they would lie closer than `spacing` (the short faces of a
        finely drawn curve): any point of a face then lies within
        ``max(spacing, gap) / 2`` of a measured one (within ``spacing / 2`` when
        `most` is unbounded)."""
        theta = np.asarray(theta, dtype=float).reshape(-1)
        R = rotation_matrices(theta)
        t = np.asarray(t, dtype=float).reshape(-1, 2)
        faces = stable.faces
        a, b = np.asarray(faces.start, dtype=float), np.asarray(faces.end, dtype=float)
        length = np.hypot(*(b - a).T)
        room = np.floor(length / spacing) if spacing > 0 else np.full(len(length), np.inf)
        inside = np.minimum(most, room)
        steps = inside.astype(np.int64) + 1
        along = _along(a, b, steps, ends=False)  # the next face's start is this one's end
        starts = _moved(R, a, t)
        support = support_values(starts)
        gap = float((length / steps).max(initial=0.0))
        return cls(along, starts, _moved(R, b, t), support, theta, t, R, a, b, gap)

    def __len__(self) -> int:
        return len(self.support)

    @cached_property
    def points(self) -> np.ndarray:
        """(N, P, 2) the boundary points posed."""
        return _moved(self.rotations, self.model_points, self.t)

    def posed_points(self, row: int) -> np.ndarray:
        """(P, 2) hypothesis `row`'s boundary points posed (a row of :attr:`points`)."""
        return _moved(self.rotations[row : row + 1], self.model_points, self.t[row : row + 1])[0]

    def to_model(self, points: np.ndarray, rows: np.ndarray) -> np.ndarray:
        """World points (M, P, 2) into the model frame of hypotheses `rows` (M,):
        ``v_model = R(theta)^T (v_world - t)``."""
        R = rotation_matrices(self.theta[rows])
        return rotate(R.transpose(0, 2, 1), points - self.t[rows, None, :])


def _moved(R: np.ndarray, points: np.ndarray, t: np.ndarray) -> np.ndarray:
    """``R v + t`` (N, P, 2) of model points (P, 2) for rotations R (N, 2, 2) and
    translations t (N, 2): the arithmetic the pair kernel repeats point by point."""
    return rotate(R, points) + t[:, None, :]


def _along(a: np.ndarray, b: np.ndarray, steps: np.ndarray, *, ends: bool) -> np.ndarray:
    """Points splitting each face a[f] -> b[f] (F, 2 each) into steps[f] equal steps,
    face after face: its start and the points inside, and its end when `ends`."""
    count = steps + 1 if ends else steps
    face = np.repeat(np.arange(len(a)), count)
    first = np.repeat(np.cumsum(count) - count, count)
    share = (np.arange(len(face)) - first) / steps[face]
    return a[face] + share[:, None] * (b - a)[face]


def outline_distance(a: PosedRings, i: int, b: PosedRings, rows: np.ndarray) -> np.ndarray:
    """Distance of hypothesis `i` of `a` to each hypothesis `rows` of `b`: the larger
    of the two directed boundary-to-face distances between their posed outlines."""
    rows = np.asarray(rows, dtype=np.int64)
    return pair_distances(a, np.full(len(rows), i, np.int64), b, rows)


def pair_distances(a: PosedRings, ia: np.ndarray, b: PosedRings, ib: np.ndarray) -> np.ndarray:
    """(M,) :func:`outline_distance` of each pair: hypothesis ia[m] of `a` and ib[m] of `b`."""
    return pair_outline_distances(_kernel_args(a), ia, _kernel_args(b), ib)


def within(a: PosedRings, i: int, b: PosedRings, rows: np.ndarray, limit: float) -> np.ndarray:
    """(len(rows),) bool: ``outline_distance(a, i, b, rows) <= limit``."""
    rows = np.asarray(rows, dtype=np.int64)
    return pairs_within(a, np.full(len(rows), i, np.int64), b, rows, limit)


def pairs_within(
    a: PosedRings, ia: np.ndarray, b: PosedRings, ib: np.ndarray, limit: float
) -> np.ndarray:
    """(M,) bool: ``pair_distances(a, ia, b, ib) <= limit``, each pair measured only
    as far as the answer needs (:mod:`planner.recognition.outline_kernel`)."""
    if not math.isfinite(limit) or limit < 0:
        return np.full(len(ia), limit >= 0, dtype=bool)
    found = pair_outline_distances(_kernel_args(a), ia, _kernel_args(b), ib, limit)
    return found <= limit


def _kernel_args(r: PosedRings) -> tuple[np.ndarray, ...]:
    """What the pair kernel measures outlines by: the model points and the poses
    that move them, and the posed faces."""
    return r.model_points, r.rotations, r.t, r.starts, r.ends


def _probe_distances(rings: Sequence[PosedRings], probes: np.ndarray) -> np.ndarray:
    """(N, J) distance from each probe point (J, 2) to each posed outline's faces:
    the probes moved into each hypothesis' model frame, measured against the
    stable pose's faces."""
    out = []
    for r in rings:
        q = r.to_model(np.broadcast_to(probes, (len(r), *probes.shape)), np.arange(len(r)))
        out.append(nearest_face_distances(q, r.model_starts, r.model_ends))
    return np.concatenate(out)


def _screen_keys(rings: Sequence[PosedRings], leader: tuple[int, int], tau: float) -> np.ndarray:
    """(N, K + J) the values the candidate tree holds: the support values, and the
    probe distances scaled so that the same reach (tau / 2) bounds both."""
    support = np.concatenate([r.support for r in rings])
    g, k = leader
    points = rings[g].posed_points(k)
    # a grid over the outline's box (near a hole or a notch, a rotation shows) and
    # a few points along its boundary
    (x0, y0), (x1, y1) = points.min(axis=0), points.max(axis=0)
    side = np.linspace(0.0, 1.0, PROBE_GRID)
    gx, gy = np.meshgrid(x0 + side * (x1 - x0), y0 + side * (y1 - y0))
    along = points[np.linspace(0, len(points) - 1, min(PROBES, len(points))).astype(np.int64)]
    probes = np.vstack([np.column_stack([gx.ravel(), gy.ravel()]), along])
    gap = max(r.gap for r in rings)
    scale = (tau / 2) / (tau / 2 + gap / 2) if tau > 0 else 0.0
    return np.hstack([support, _probe_distances(rings, probes) * scale])


def _keys_within(keys: np.ndarray, pairs: np.ndarray, reach: float) -> np.ndarray:
    """(M,) bool: are the keys of each pair (M, 2) within `reach` in every column?"""
    out = np.zeros(len(pairs), dtype=bool)
    step = max(1, CHUNK_ELEMENTS // max(1, keys.shape[1]))
    for lo in range(0, len(pairs), step):
        i, j = pairs[lo : lo + step, 0], pairs[lo : lo + step, 1]
        out[lo : lo + step] = np.abs(keys[i] - keys[j]).max(axis=1) <= reach
    return out


def equivalence_classes(
    rings: Sequence[PosedRings],
    order: np.ndarray,
    family: np.ndarray,
    tau: float,
    shapes: np.ndarray | None = None,
) -> np.ndarray:
    """Class label (N,) of N hypotheses stacked over the stable poses of `rings`.

    `order` (N,) is the order in which hypotheses lead classes (most probable
    first); `family` (N,) labels the interpretation each came from (samples of
    one slide family never share a class); `tau` is the symmetry tolerance;
    `shapes` (one per stable pose of `rings`, default all equal) which stable
    poses are one shape (:func:`~planner.models.congruence.shape_labels`): only
    those share a class, so that distinct objects do only when congruent.
    """
    sizes = [len(r) for r in rings]
    offsets = np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64)
    n = int(offsets[-1])
    label = np.full(n, -1, dtype=np.int64)
    if not n:
        return label
    group = np.repeat(np.arange(len(rings)), sizes)
    local = np.arange(n) - offsets[group]
    order = np.asarray(order, dtype=np.int64)
    shape = np.zeros(n, dtype=np.int64) if shapes is None else np.asarray(shapes)[group]
    ctx = _Leading(rings, group, local, family, shape, label, tau)
    if n <= SCREEN_FROM:
        # a handful (a plan's predicted sessions): every pair measured, no screen
        ctx.lead_decided(order, np.column_stack(np.triu_indices(n, 1)))
        return _numbered(label, order)
    first = int(order[0])
    keys = _screen_keys(rings, (int(group[first]), int(local[first])), tau)
    # a margin for rounding: the filter must never drop a pair that passes
    reach = screen_reach(tau / 2, keys)
    # pairs first found in a few of the keys (a tree in all of them is slow), then
    # held to all: the same pairs as one tree over every key
    low = keys[:, FIRST_KEYS]
    first_tree = cKDTree(low)
    count = int(first_tree.query_ball_point(low, r=reach, p=np.inf, return_length=True).sum())
    cheap = max(r.starts.shape[1] for r in rings) <= BRUTE_FORCE_FACES
    if cheap and count - n <= 2 * PAIR_BATCH * n:
        found = first_tree.query_pairs(reach, p=np.inf, output_type="ndarray")
        ctx.lead_decided(order, found[_keys_within(keys, found, reach)])
    else:
        ctx.lead_lazily(order, cKDTree(keys), keys, reach)
    return _numbered(label, order)


#: Most hypotheses :func:`none_can_share` compares pair by pair.
SHARE_SCREEN_MOST = 64


def none_can_share(
    stables: Sequence[StablePose],
    theta: Sequence[np.ndarray],
    t: Sequence[np.ndarray],
    family: np.ndarray,
    shapes: np.ndarray,
    tau: float,
) -> bool:
    """True when no two posed outlines can share a class, known without measuring
    them: outlines of stable pose k at poses ``theta[k]``, ``t[k]``, stacked;
    every two of one shape (`shapes`, one per stable pose) and of different slide
    families (`family`, one per outline) have support values
    (:data:`SUPPORT_DIRECTIONS`, of their vertices) over `tau` apart in some
    direction. No class holds two outlines farther apart than `tau`, and outlines
    within d of each other have support values within d (every vertex is a
    measured point). False, too, past `SHARE_SCREEN_MOST` outlines."""
    sizes = [len(x) for x in theta]
    n = sum(sizes)
    if n > SHARE_SCREEN_MOST:
        return False
    support = np.concatenate(
        [
            support_values(
                rotate(rotation_matrices(np.asarray(th, dtype=float)), stable.faces.start)
                + np.asarray(tt, dtype=float).reshape(-1, 2)[:, None, :]
            )
            for stable, th, tt in zip(stables, theta, t, strict=True)
        ]
    )
    shape = np.repeat(np.asarray(shapes), sizes)
    i, j = near_pairs(support, screen_reach(tau, support)).T
    return not ((family[i] != family[j]) & (shape[i] == shape[j])).any()


def support_values(vertices: np.ndarray) -> np.ndarray:
    """(N, K) the support function of each posed outline's vertices (N, P, 2) in
    the directions of :data:`SUPPORT_DIRECTIONS`: outlines within d of each other
    have support values within d."""
    return (vertices @ SUPPORT_DIRECTIONS.T).max(axis=1)


def screen_reach(limit: float, values: np.ndarray) -> float:
    """How far apart screening values (support values, keys) may lie for outlines
    within `limit`: the limit with a margin for rounding, so that a screen never
    drops a pair the measure would pass."""
    return limit * (1 + 1e-9) + 1e-12 * (1.0 + float(np.abs(values).max(initial=0.0)))


def near_pairs(values: np.ndarray, reach: float) -> np.ndarray:
    """(M, 2) the pairs i < j of rows of `values` (N, K) within `reach` of each
    other in every column, in order: every pair screened at once (a few rows)."""
    i, j = np.triu_indices(len(values), 1)
    return np.column_stack([i, j])[np.abs(values[i] - values[j]).max(axis=1, initial=0.0) <= reach]


def _numbered(label: np.ndarray, order: np.ndarray) -> np.ndarray:
    """Each hypothesis' class from its leader (`label`, -1: it leads its own): the
    classes numbered as their leaders come in `order` (a leader precedes its members)."""
    label[label < 0] = np.flatnonzero(label < 0)
    place = np.empty(len(label), dtype=np.int64)
    place[order] = np.arange(len(label))
    return np.unique(place[label], return_inverse=True)[1].reshape(-1)


@dataclass(frozen=True, eq=False)
class _Leading:
    """Leaders taking in their classes: `label` (N,) is filled with each
    hypothesis' leader (-1 while none has taken it)."""

    rings: Sequence[PosedRings]
    group: np.ndarray
    local: np.ndarray
    family: np.ndarray
    shape: np.ndarray
    label: np.ndarray
    tau: float

    def lead_decided(self, order: np.ndarray, found: np.ndarray) -> None:
        """Few candidate pairs `found` (M, 2) (parts without a continuous symmetry):
        every pair decided in one pass per two stable poses, then the leaders in
        `order` take in the unlabelled hypotheses they are close to."""
        group, local, label = self.group, self.local, self.label
        a, b = found[:, 0], found[:, 1]
        found = found[(self.family[a] != self.family[b]) & (self.shape[a] == self.shape[b])]
        close = np.zeros(len(found), dtype=bool)
        key = group[found[:, 0]] * len(self.rings) + group[found[:, 1]]
        for k in np.unique(key):
            sel = np.flatnonzero(key == k)
            a, b = found[sel, 0], found[sel, 1]
            ra, rb = self.rings[group[a[0]]], self.rings[group[b[0]]]
            close[sel] = pairs_within(ra, local[a], rb, local[b], self.tau / 2)
        edges = np.concatenate([found[close], found[close][:, ::-1]])
        edges = edges[np.argsort(edges[:, 0], kind="stable")]
        starts = np.searchsorted(edges[:, 0], np.arange(len(label) + 1))
        for leader in order[np.diff(starts)[order] > 0]:
            if label[leader] >= 0:
                continue
            near = edges[starts[leader] : starts[leader + 1], 1]
            label[leader] = leader
            label[near[label[near] < 0]] = leader

    def lead_lazily(self, order: np.ndarray, tree: cKDTree, keys: np.ndarray, reach: float) -> None:
        """Many candidate pairs (a round part's rotations, all near one another):
        each leader in `order` measures only the hypotheses no class has taken."""
        group, local, label = self.group, self.local, self.label
        for leader in order:
            if label[leader] >= 0:
                continue
            label[leader] = leader
            near = np.asarray(tree.query_ball_point(keys[leader], r=reach, p=np.inf), np.int64)
            near = near[
                (label[near] < 0)
                & (self.family[near] != self.family[leader])
                & (self.shape[near] == self.shape[leader])
            ]
            ring = self.rings[group[leader]]
            for h in np.unique(group[near]):
                mine = near[group[near] == h]
                close = within(ring, local[leader], self.rings[h], local[mine], self.tau / 2)
                label[mine[close]] = leader
