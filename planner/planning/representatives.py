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

from planner.types import ErrorBound, Hypothesis, ObjectModel

__all__ = ["PLAN_FACES", "face_counts", "representatives"]

#: Posed faces (hypotheses x faces each) above which a plan works on one
#: representative per class.
PLAN_FACES = 12_000


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
