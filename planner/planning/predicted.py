"""What the recognition concludes of a predicted touch, for a plan (DESIGN §4.15).

A plan asks the session what it would conclude after each of a handful of
touches, each predicted by a class' best member: :func:`observed` is the session
once it observes that outcome. Within :func:`predictions` (one plan) each such
observation is observed once, and :func:`prefetch` observes the ones a stage is
about to ask for in one evaluation
(:meth:`~planner.recognition.session.Session.predict_many`): each is a few rows,
and an evaluation's fixed cost, not its rows, was most of each one.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from contextlib import AbstractContextManager

from planner.errors import InvalidObservationError
from planner.memo import ScopedMemo
from planner.planning.outcomes import Outcomes
from planner.recognition.session import Session
from planner.types import Contact, Observation, SensingPath

__all__ = ["class_count", "classes_after", "observed", "predictions", "prefetch"]

#: The sessions predicted during one plan, by the session and what it observed:
#: hypotheses of equal pose (twins told apart elsewhere; classes that all miss)
#: predict the same observation, and one update serves them all. Set by
#: :func:`predictions` for the length of a plan, so nothing outlives it.
_PREDICTED = ScopedMemo("predicted")


def predictions() -> AbstractContextManager[None]:
    """Within it, a predicted observation is observed once (:func:`observed`)."""
    return _PREDICTED.scope()


def _observation(path: SensingPath, out: Outcomes, c: int, h: int) -> Observation:
    """Hypothesis `h`'s nominal outcome on candidate `c` along `path`: its first hit
    with the posed face's normal, or a miss."""
    contact = None
    if out.hit[c, h]:
        contact = Contact(tuple(out.point[c, h].tolist()), tuple(out.normal[c, h].tolist()))
    return Observation(path, contact)


def observed(session: Session, path: SensingPath, out: Outcomes, c: int, h: int) -> Session | None:
    """The session once it observes hypothesis `h`'s nominal outcome on candidate
    `c` (the first hit with its posed face normal, or a miss), as a prediction
    (:meth:`Session.predict`: weighed without the residual fitness); None when
    that is not a valid observation."""
    observation = _observation(path, out, c, h)
    memo = _PREDICTED.get()
    key = (session, observation)
    if memo is not None and key in memo:
        return memo[key]
    try:
        after: Session | None = session.predict(observation)
    except InvalidObservationError:
        after = None
    if memo is not None:
        memo[key] = after
    return after


def prefetch(
    session: Session,
    path: Callable[[int], SensingPath],
    out: Outcomes,
    pairs: Iterable[tuple[int, int]],
) -> None:
    """Within :func:`predictions`, observe the outcomes of hypothesis h on candidate c
    (`pairs` of (c, h); `path(c)` the candidate's path) that are not observed yet,
    in one evaluation: what :func:`observed` then returns for them, sooner."""
    memo = _PREDICTED.get()
    if memo is None:
        return
    wanted: dict[Observation, None] = {}
    for c, h in pairs:
        observation = _observation(path(c), out, c, h)
        if (session, observation) not in memo:
            wanted[observation] = None
    if len(wanted) < 2:
        return
    for observation, after in zip(wanted, session.predict_many(list(wanted)), strict=True):
        memo[(session, observation)] = after


def classes_after(session: Session, path: SensingPath, out: Outcomes, c: int, h: int) -> int:
    """Classes left once the session observes hypothesis `h`'s nominal outcome on
    candidate `c` (0 when the predicted observation is not a valid one)."""
    return class_count(observed(session, path, out, c, h))


def class_count(after: Session | None) -> int:
    """Classes a predicted session holds (0: none, or not a valid observation).
    One hypothesis or none is as many classes, known before the classes are
    found: most predictions leave one, and the classes cost a fifth of one."""
    if after is None:
        return 0
    if after.hypothesis_count <= 1:
        return after.hypothesis_count
    return after.class_count
