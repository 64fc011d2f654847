"""How far a session is from `localized` (DESIGN §2), and the one answer that
several classes of a curved part's pose can make.

A session is localized when one equivalence class is left and its bound is
within the session's accuracy. On a curved part the hypotheses fill a continuum
of nearby poses of one part: with bounded errors the poses every contact admits
lie within ``eps_d`` of the true outline at the contacts, so two of them may
differ by about ``tau = 2 eps_d`` there and by more between the contacts, and
the classes (never wider than ``tau``) may never come down to one however many
touches are taken. Those classes are one answer when they are all the best
hypothesis' part in its stable pose and one bound covers them all within the
accuracy: the true pose lies within some hypothesis' bound, and the answer's
bound holds every hypothesis' bound, so it holds the truth whichever class is
right, and no touch can move the answer by more than the user asked for.
With the thesis' fixed error disk (whose accuracy asks for nothing beyond one
class, as the thesis did) the session never asks for one answer.

The answer's bound adds to each hypothesis' own bound how far it lies from the
answer: its outline's distance from the best one's (at every probing height) on
the translation and twice that on the outline disk, its turn from the nearest
member of the best class on the rotation (a member of that class is the answer
turned by a symmetry of the outline) -- as the class bound adds ``tau / 2``
for its members.

Cost: nothing unless several classes are left, all of the best part's stable
pose, each hypothesis' own bound within the accuracy; then one pass of the
outline kernel over the hypotheses outside the best class.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass

import numpy as np

from planner.geometry import rotation_matrices, wrap_angle
from planner.recognition.equivalence import (
    CHUNK_ELEMENTS,
    EDGE_SAMPLES,
    PosedRings,
    pair_distances,
    pairs_within,
)
from planner.types import Accuracy, ErrorBound, Hypothesis, StablePose

__all__ = ["ANSWER_POINTS", "GAP_STEP", "Localization", "answer_bound", "class_bound"]

#: The most spacing of the points at which an answer measures how far a class'
#: outline lies from the best one, as a share of the symmetry tolerance; the
#: distance is widened by half of it (a point between two measured ones).
GAP_STEP = 0.125
#: The most points measured along one outline for an answer: the spacing widens
#: (and the bound with it, by half the spacing) rather than the work grow, as
#: with exact sensing, whose tolerance is a rounding error.
ANSWER_POINTS = 4096


@dataclass(frozen=True)
class Localization:
    """How far a session is from `localized` (DESIGN §2): the number of equivalence
    `classes` left, the `bound` of the answer (None without a hypothesis), the
    required `accuracy`, and what is `missing`: ``one_class`` while several
    classes are left that are not one answer within the accuracy, ``accuracy``
    while the one class' bound exceeds it. The bound is the most probable class'
    own, or, when the classes left are one answer, the bound covering them all;
    `covered` says how many classes it covers. `rotation_free` when the class'
    outline is round (:mod:`planner.models.round`): its rotation cannot be
    measured and need not be, the bound's rotation is then pi and the accuracy
    asks for the translation only."""

    classes: int
    bound: ErrorBound | None
    accuracy: Accuracy
    missing: tuple[str, ...]
    rotation_free: bool = False
    covered: int = 1


def class_bound(members: Sequence[Hypothesis], half: float, free: bool) -> ErrorBound:
    """The bound of a class: the widest member's, widened by `half` (how far a
    member's outline may lie from its leader's) on the translation and twice that
    on the outline disk; the rotation is pi when `free`."""
    return ErrorBound(
        max(h.error_bound.translation for h in members) + half,
        math.pi if free else max(h.error_bound.rotation for h in members),
        max(h.error_bound.eps_t for h in members) + 2 * half,
    )


def answer_bound(
    hypotheses: Sequence[Hypothesis],
    bound: ErrorBound,
    accuracy: Accuracy,
    layers: Callable[[str, int], Sequence[StablePose]],
    tau: float,
    free: bool,
) -> ErrorBound | None:
    """The bound of one answer covering every class of `hypotheses` (most probable
    first, their classes numbered), given the best class' own `bound`; None when
    the classes are not one answer within `accuracy` (another part or stable pose
    is left, or the bound exceeds it). `layers(object, stable_pose)` gives the
    outline at each probing height; `tau` is the symmetry tolerance (it sets the
    spacing of the points measured along the faces, `GAP_STEP`)."""
    best = hypotheses[0]
    others = [h for h in hypotheses if h.equivalence_class != best.equivalence_class]
    if not others:
        return bound
    same = all(h.object == best.object and h.stable_pose == best.stable_pose for h in others)
    if not same or not all(accuracy.admits(h.error_bound, rotation_free=free) for h in others):
        return None
    theta = np.array([best.pose.theta] + [h.pose.theta for h in others])
    t = np.array([(best.pose.x, best.pose.y)] + [(h.pose.x, h.pose.y) for h in others])
    own = np.array([(b.translation, b.rotation, b.eps_t) for b in (h.error_bound for h in others)])
    turned = math.pi
    if not free:
        klass = best.equivalence_class
        turns = np.array([h.pose.theta for h in hypotheses if h.equivalence_class == klass])
        gap = np.abs(wrap_angle(theta[1:, None] - turns[None, :]))
        turned = float(max(bound.rotation, (own[:, 1] + gap.min(axis=1)).max()))
        if turned > accuracy.rotation:
            return None
    outlines = layers(best.object, best.stable_pose)
    step = GAP_STEP * tau
    # decided first (cheap: most such sessions are not one answer), then measured
    room = accuracy.translation - own[:, 0]
    if not all(_within(layer, theta, t, step, room) for layer in outlines):
        return None
    apart = np.max([_outline_gaps(layer, theta, t, step) for layer in outlines], axis=0)
    union = ErrorBound(
        float(max(bound.translation, (own[:, 0] + apart).max())),
        turned,
        float(max(bound.eps_t, (own[:, 2] + 2 * apart).max())),
    )
    return union if accuracy.admits(union, rotation_free=free) else None


@dataclass(frozen=True)
class _Faces:
    start: np.ndarray
    end: np.ndarray


@dataclass(frozen=True)
class _Split:
    """An outline's faces split so that the points measured along them lie `step`
    apart at most (what :meth:`PosedRings.of` reads of a stable pose)."""

    faces: _Faces

    @classmethod
    def of(cls, layer: StablePose, step: float) -> _Split:
        a, b = np.asarray(layer.faces.start, float), np.asarray(layer.faces.end, float)
        pieces = np.ceil(np.hypot(*(b - a).T) / ((EDGE_SAMPLES + 1) * step)).astype(np.int64)
        pieces = np.maximum(pieces, 1)
        face = np.repeat(np.arange(len(a)), pieces)
        k = np.arange(len(face)) - np.repeat(np.cumsum(pieces) - pieces, pieces)
        u0, u1 = k / pieces[face], (k + 1) / pieces[face]
        d = (b - a)[face]
        return cls(_Faces(a[face] + u0[:, None] * d, a[face] + u1[:, None] * d))


def _posed(
    layer: StablePose, theta: np.ndarray, t: np.ndarray, step: float
) -> Iterator[tuple[np.ndarray, PosedRings, np.ndarray]]:
    """The poses ``theta[1:], t[1:]`` in chunks of `CHUNK_ELEMENTS` face ends: the
    indices (into ``theta[1:]``), the rings (the first pose, then the chunk's) with
    the faces split `step` apart at most (farther when `ANSWER_POINTS` would not
    reach), and each pose's largest vertex move from the first one."""
    a, b = np.asarray(layer.faces.start, float), np.asarray(layer.faces.end, float)
    split = _Split.of(layer, max(step, float(np.hypot(*(b - a).T).sum()) / ANSWER_POINTS))
    R = rotation_matrices(theta)
    chunk = max(1, CHUNK_ELEMENTS // len(split.faces.start))
    for lo in range(1, len(theta), chunk):
        rows = np.r_[0, lo : min(lo + chunk, len(theta))]
        rings = PosedRings.of(split, theta[rows], t[rows], step)  # type: ignore[arg-type]
        moved = np.einsum("nij,mj->nmi", R[rows[1:]] - R[:1], a) + (t[rows[1:]] - t[:1])[:, None]
        yield rows[1:] - 1, rings, np.hypot(*moved.transpose(2, 0, 1)).max(axis=1)


def _outline_gaps(layer: StablePose, theta: np.ndarray, t: np.ndarray, step: float) -> np.ndarray:
    """How far the outline posed at each of ``theta[1:], t[1:]`` may lie from the one
    at ``theta[0], t[0]`` (a Hausdorff distance bounded above): the smaller of the
    distance measured at points at most `step` apart along the faces, widened by
    half that step, and the largest displacement of a vertex (a point along a face
    moves by at most its ends' larger move)."""
    out = np.empty(len(theta) - 1)
    for index, rings, moved in _posed(layer, theta, t, step):
        at = np.arange(1, len(index) + 1)
        measured = pair_distances(rings, np.zeros_like(at), rings, at) + rings.gap / 2
        out[index] = np.minimum(measured, moved)
    return out


def _within(
    layer: StablePose, theta: np.ndarray, t: np.ndarray, step: float, room: np.ndarray
) -> bool:
    """Whether ``_outline_gaps(layer, theta, t, step) <= room`` for every pose,
    decided without measuring what the answer does not need: a pose whose vertices
    move less is within; the others are measured only as far as the least room."""
    for index, rings, moved in _posed(layer, theta, t, step):
        half, limit = rings.gap / 2, room[index]
        rest = np.flatnonzero(moved > limit) + 1
        if not len(rest):
            continue
        least = float(limit[rest - 1].min()) - half
        if least < 0:
            return False
        near = pairs_within(rings, np.zeros_like(rest), rings, rest, least)
        far = rest[~near]
        if (
            len(far)
            and (
                pair_distances(rings, np.zeros_like(far), rings, far) + half > limit[far - 1]
            ).any()
        ):
            return False
    return True
