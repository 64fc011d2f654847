"""Planning on one hypothesis per equivalence class where the members are many.

On a finely drawn curve a contact fits several adjacent faces, and the
interpretations multiply: a cam touched five times leaves some two hundred
hypotheses, nearly all of one pose, each with some two hundred faces. The
planner casts every candidate against every posed face, so most of a plan's
work then goes into telling apart hypotheses that need not be told apart (they
are one class).

Where the posed faces exceed `PLAN_FACES`, each class is planned on as its most
probable member, carrying the class' probability and the class' error bound:
the widest member's, widened by how far the members may lie from it (``tau / 2``,
``tau`` in a joined class). Every member's posed outline then lies within the
representative's error disk, so the outcome model's worst case still covers
what any member would give: the planner is conservative, never over-confident.
The recognition itself (and its forecast of a path) keeps every hypothesis.

>>> from planner.types import ErrorBound, Hypothesis, Pose
>>> h = [Hypothesis("a", 0, (0,), Pose(0, 0, 0), ErrorBound(1, 0.1, 3), 0.6, 0),
...      Hypothesis("a", 0, (1,), Pose(0.2, 0, 0), ErrorBound(2, 0.1, 4), 0.4, 0)]
>>> [r.probability for r in representatives(h, 1.0, frozenset(), faces_each=10**6)]
[1.0]
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping, Sequence

import numpy as np

from planner.types import ErrorBound, Hypothesis, ObjectModel

__all__ = ["PLAN_FACES", "SAMPLE_FACES", "face_counts", "representatives", "weighted_sample"]

#: Posed faces (hypotheses x faces each) above which a plan works on one
#: representative per class.
PLAN_FACES = 12_000
#: Posed faces above which, even one per class, a plan works on a weighted sample
#: of the hypotheses (exact contacts on a finely drawn curve: ten thousand classes).
SAMPLE_FACES = 100_000


def face_counts(hypotheses: Sequence[Hypothesis], models: Mapping[str, ObjectModel]) -> list[int]:
    """Faces of each hypothesis' stable pose, every probing height's included."""
    return [len(models[h.object].stable_poses[h.stable_pose].all_faces.start) for h in hypotheses]


def representatives(
    hypotheses: Sequence[Hypothesis],
    tau: float,
    joined: frozenset[int],
    faces_each: int | Sequence[int],
) -> list[Hypothesis]:
    """The hypotheses a plan works on: all of them when their posed faces
    (`faces_each`, one count for all or one per hypothesis) are at most
    `PLAN_FACES`, else one per class (see the module's note); `tau` is the
    symmetry tolerance and `joined` the classes whose members lie within ``tau``
    of their leader, not ``tau / 2``. Order and class numbers are kept."""
    counts = [faces_each] * len(hypotheses) if isinstance(faces_each, int) else list(faces_each)
    if sum(counts) <= PLAN_FACES:
        return list(hypotheses)
    members: dict[int, list[Hypothesis]] = {}
    for h in hypotheses:
        members.setdefault(h.equivalence_class, []).append(h)
    out = []
    for c, group in members.items():
        lead = max(group, key=lambda h: h.probability)
        if len(group) == 1:
            out.append(lead)
            continue
        half = tau if c in joined else tau / 2
        bound = ErrorBound(
            max(h.error_bound.translation for h in group) + half,
            max(h.error_bound.rotation for h in group),
            max(h.error_bound.eps_t for h in group) + 2 * half,
        )
        out.append(
            dataclasses.replace(
                lead, error_bound=bound, probability=sum(h.probability for h in group)
            )
        )
    out.sort(key=lambda h: (-h.probability, h.equivalence_class))
    return out


def weighted_sample(
    hypotheses: Sequence[Hypothesis], faces_each: Sequence[int], limit: int | None = None
) -> list[Hypothesis]:
    """The hypotheses a plan can afford: all of them when their posed faces
    (`faces_each`) are at most `limit` (default `SAMPLE_FACES`), else a
    systematic sample by probability of about `limit` faces' worth, each drawn
    one carrying its share of the draws (a hypothesis likelier than one draw is
    always drawn, with its own weight or more). When the draws fall in one class,
    the most probable hypothesis of another joins them, so that a plan never
    takes a sample for one class.
    Deterministic; order (most probable first) and class numbers are kept.

    >>> from planner.types import ErrorBound, Hypothesis, Pose
    >>> h = [Hypothesis("a", 0, (k,), Pose(k, 0, 0), ErrorBound(1, 0.1, 2), p, k)
    ...      for k, p in enumerate([0.5, 0.2, 0.1, 0.1, 0.1])]
    >>> [(r.equivalence_class, r.probability) for r in weighted_sample(h, [10] * 5, 20)]
    [(0, 0.5), (2, 0.5)]
    """
    limit = SAMPLE_FACES if limit is None else limit
    counts = np.asarray(faces_each, dtype=float)
    if counts.sum() <= limit or len(hypotheses) < 2:
        return list(hypotheses)
    draws = max(2, int(len(hypotheses) * limit / counts.sum()))
    weight = np.array([h.probability for h in hypotheses], dtype=float)
    cumulative = np.cumsum(weight) / weight.sum()
    picks = np.minimum(
        np.searchsorted(cumulative, (np.arange(draws) + 0.5) / draws), len(hypotheses) - 1
    )
    rows, times = np.unique(picks, return_counts=True)
    chosen = {int(r): int(n) / draws for r, n in zip(rows, times, strict=True)}
    classes = {hypotheses[r].equivalence_class for r in chosen}
    other = next((k for k, h in enumerate(hypotheses) if h.equivalence_class not in classes), None)
    if len(classes) == 1 and other is not None:
        chosen[other] = float(weight[other] / weight.sum())
    return [dataclasses.replace(hypotheses[r], probability=p) for r, p in sorted(chosen.items())]
