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

The outline distance is bounded above: measured at points at most ``tau / 8``
apart along the faces and widened by half that, or the largest move of a vertex
when that is smaller.

Cost: nothing unless several classes are left, all of the best part's stable
pose, each hypothesis' own bound and turn within the accuracy; then the outline
kernel decides, breaking off early, whether every one fits, and only then
measures them.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from planner.geometry import rotation_matrices, wrap_angle
from planner.recognition.equivalence import (
    CHUNK_ELEMENTS,
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
    # each pose's room: what the accuracy leaves of its own translation bound
    room = accuracy.translation - own[:, 0]
    apart = np.zeros(len(others))
    for layer in layers(best.object, best.stable_pose):
        found = _gaps_within(layer, theta, t, GAP_STEP * tau, room)
        if found is None:
            return None
        apart = np.maximum(apart, found)
    union = ErrorBound(
        float(max(bound.translation, (own[:, 0] + apart).max())),
        turned,
        float(max(bound.eps_t, (own[:, 2] + 2 * apart).max())),
    )
    return union if accuracy.admits(union, rotation_free=free) else None


def _gaps_within(
    layer: StablePose, theta: np.ndarray, t: np.ndarray, step: float, room: np.ndarray
) -> np.ndarray | None:
    """How far the outline posed at each of ``theta[1:], t[1:]`` may lie from the one
    at ``theta[0], t[0]`` (a Hausdorff distance bounded above), or None as soon as
    one lies farther than its `room`. The bound is the smaller of the distance
    measured at points at most `step` apart along the faces (farther when
    `ANSWER_POINTS` would not reach), widened by half the spacing, and the largest
    move of a vertex (a point along a face moves by at most its ends' larger
    move). Decided before it is measured (most sessions of several classes are
    not one answer): a pose whose vertices move less than its room is within, the
    others are measured only as far as the least room; then, all within, every
    pose is measured. The poses are posed `CHUNK_ELEMENTS` face ends at a time."""
    a, b = np.asarray(layer.faces.start, float), np.asarray(layer.faces.end, float)
    step = max(step, float(np.hypot(*(b - a).T).sum()) / ANSWER_POINTS)
    R = rotation_matrices(theta)
    out = np.empty(len(theta) - 1)
    chunk = max(1, CHUNK_ELEMENTS // len(a))
    for lo in range(1, len(theta), chunk):
        rows = np.r_[0, lo : min(lo + chunk, len(theta))]
        index = rows[1:] - 1  # into theta[1:] (and `room`)
        rings = PosedRings.of(layer, theta[rows], t[rows], step, most=math.inf)
        moved = np.einsum("nij,mj->nmi", R[rows[1:]] - R[:1], a) + (t[rows[1:]] - t[:1])[:, None]
        moved = np.hypot(moved[..., 0], moved[..., 1]).max(axis=1)
        half, limit = rings.gap / 2, room[index]
        rest = np.flatnonzero(moved > limit) + 1  # the rings' rows left to decide
        if len(rest):
            least = float(limit[rest - 1].min()) - half
            if least < 0:
                return None
            far = rest[~pairs_within(rings, np.zeros_like(rest), rings, rest, least)]
            beyond = pair_distances(rings, np.zeros_like(far), rings, far) + half
            if (beyond > limit[far - 1]).any():
                return None
        at = np.arange(1, len(rows))
        measured = pair_distances(rings, np.zeros_like(at), rings, at) + half
        out[index] = np.minimum(measured, moved)
    return out
