"""Refining paths (DESIGN §4.11): one class is left (or nothing tells the classes
apart) and its bound is short of the required accuracy, so the plan offers the
paths expected to shrink the error disk most.

The outcome model's refinement (:func:`~planner.planning.refinement.refinement`)
comes first: its sure contacts give the expected disk after each path. When it
is weak (leaves more than `WEAK_REFINEMENT` of the disk, or finds nothing), the
recognition's own predictions judge a shortlist
(:func:`~planner.planning.forecast.recognition_refining`), and the smaller
predicted disk wins.

Where several classes are left and neither the outcome model, the recognition's
predictions nor refining finds a path (near twins whose outlines differ by about
the error bounds), :func:`apart_paths` offers the paths where the classes'
nominal outcomes lie farthest apart.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping, Sequence

import numpy as np

from planner.planning.analysis import Analysis, models_by_name
from planner.planning.budget import Budget
from planner.planning.config import StrategyConfig
from planner.planning.forecast import (
    SHORTLIST_CLASSES_ALONE,
    outcomes_apart,
    recognition_refining,
)
from planner.planning.planned import no_ranking, planned
from planner.planning.refinement import refinement, scores_after
from planner.planning.result import REFINING, PlannedPath
from planner.planning.strategies import Ranking
from planner.recognition.session import Session
from planner.types import Contact, Hypothesis, ObjectModel, SensorBounds

__all__ = [
    "REFINE_GAIN",
    "WEAK_REFINEMENT",
    "apart_paths",
    "one_class_paths",
    "refining_paths",
]

#: Smallest share of the expected error disk a refining path must remove.
REFINE_GAIN = 0.01

#: A refining touch the outcome model expects to leave more than this share of
#: the error disk is weak: the recognition's predictions are asked as well.
WEAK_REFINEMENT = 0.5


def refining_paths(
    found: Analysis,
    hypotheses: Sequence[Hypothesis],
    models: Mapping[str, ObjectModel],
    contacts: Sequence[Contact],
    sensor: SensorBounds,
    ranking: Ranking,
    config: StrategyConfig,
) -> tuple[list[PlannedPath], str | None]:
    """No informative path: the paths that shrink the expected error disk most
    (at least by `REFINE_GAIN` of it), with a note saying so. Their scores are
    those of the outcome model with the disks each class is predicted to have
    once the touch is made (with today's disks every outcome is confusable)."""
    refine = refinement(hypotheses, models, found.posed, found.outcomes, contacts, sensor)
    gain = refine.current - refine.expected
    # refining paths at the default height: their scores are worked out on its outlines
    default = np.isnan(found.candidates.height)  # type: ignore[arg-type]
    ok = np.flatnonzero((gain > REFINE_GAIN * refine.current) & default)
    if not len(ok):
        return [], ranking.note
    order = ok[np.lexsort((found.motion[ok], refine.expected[ok]))][: config.max_paths]
    paths = []
    for i in order:
        info = scores_after(
            hypotheses, found.posed, refine, found.candidates, int(i), sensor, config.outcome
        )
        paths.append(
            planned(
                found,
                int(i),
                ranking,
                family=REFINING,
                expected_eps_t=refine.expected[i],
                scores=(info, 0),
            )
        )
    note = (
        f"{ranking.note or 'one class left, its bound short of the required accuracy'}: "
        "refining the pose instead "
        f"(expected error disk {refine.current:.3g} -> {refine.expected[order[0]]:.3g})"
    )
    return paths, note


def one_class_paths(
    found: Analysis,
    hypotheses: Sequence[Hypothesis],
    models: Mapping[str, ObjectModel] | Sequence[ObjectModel],
    contacts: Sequence[Contact],
    sensor: SensorBounds,
    config: StrategyConfig,
    session: Session | None,
    budget: Budget,
) -> tuple[list[PlannedPath], str]:
    """One class left, its bound short of the accuracy: the paths sure to shrink it by
    the outcome model, or (given the session) those the recognition predicts do."""
    by_name = models_by_name(models)
    paths, note = refining_paths(
        found, hypotheses, by_name, contacts, sensor, no_ranking(found), config
    )
    current = max(h.error_bound.eps_t for h in hypotheses)
    weak = not paths or _eps_t(paths[0]) > WEAK_REFINEMENT * current
    if weak and session is not None:
        # the outcome model credits few contacts near other faces: ask the recognition
        judged, judged_note = _refining_by_recognition(found, session, config, budget)
        if judged and (not paths or _eps_t(judged[0]) < _eps_t(paths[0])):
            paths, note = judged, judged_note
        elif not paths:
            note = judged_note
    return paths, note or "one class left; no path shrinks its bound further"


def _eps_t(path: PlannedPath) -> float:
    return math.inf if path.expected_eps_t is None else path.expected_eps_t


def _refining_by_recognition(
    found: Analysis, session: Session, config: StrategyConfig, budget: Budget
) -> tuple[list[PlannedPath], str | None]:
    """One class left, short of the accuracy, and no refining touch sure for the
    outcome model: the paths after which the recognition predicts the smaller
    bound (:func:`~planner.planning.forecast.recognition_refining`), those that
    shrink it by at least `REFINE_GAIN`, best first."""
    judged = recognition_refining(session, found, budget)
    now_t, now_r = judged.current
    useful = (judged.translation < (1 - REFINE_GAIN) * now_t) | (
        judged.rotation < (1 - REFINE_GAIN) * now_r
    )
    ranking = no_ranking(found)
    paths = [
        dataclasses.replace(
            planned(found, int(i), ranking, family=REFINING, expected_eps_t=float(e)),
            scored_by="recognition",
        )
        for i, e in zip(judged.rows[useful], judged.eps_t[useful], strict=True)
    ][: config.max_paths]
    if not paths and not len(judged.rows) and len(judged.pinning):
        # no prediction it could judge (a loosely pinned class' nominal pose, a fit, lies
        # off its contacts): the paths whose contact would pin the pose most, not none
        pinning = judged.pinning[: config.max_paths]
        paths = [planned(found, int(i), ranking, family=REFINING) for i in pinning]
        return paths, (
            "one class left, its bound short of the required accuracy: the recognition "
            "could not judge its predicted contacts (they contradict the contacts so "
            "far); refining where a contact would pin the pose most"
        )
    if not paths and judged.tried < len(judged.pinning):
        # the budget ended the judging: what was not judged may still shrink the bound
        rest = judged.pinning[judged.tried :][: config.max_paths]
        paths = [planned(found, int(i), ranking, family=REFINING) for i in rest]
        return paths, (
            "one class left, its bound short of the required accuracy: the budget judged "
            f"{judged.tried} of the {len(judged.pinning)} shortlisted paths, none predicted "
            "to shrink the bound; refining where a contact would pin the pose most among "
            "the others"
        )
    if not paths:
        return [], (
            "one class left, its bound short of the required accuracy; no path shrinks its "
            "bound further: the recognition predicts no smaller bound after any of the "
            f"{len(judged.rows)} paths it judged"
        )
    first = np.flatnonzero(useful)[0]
    note = (
        "one class left, its bound short of the required accuracy: refining the pose "
        "on the recognition's predictions (translation bound "
        f"{now_t:.3g} -> {judged.translation[first]:.3g}, rotation "
        f"{now_r:.3g} -> {judged.rotation[first]:.3g})"
    )
    return paths, note


def apart_paths(
    found: Analysis,
    sensor: SensorBounds,
    ranking: Ranking,
    config: StrategyConfig,
    why: str | None,
) -> tuple[list[PlannedPath], str | None]:
    """Nothing is predicted to change the classes on their nominal contacts (near
    twins whose outlines differ by about the error bounds): the paths where the
    most probable classes' nominal outcomes lie farthest apart, in error bounds
    (:func:`~planner.planning.forecast.outcomes_apart`), then the shorter motion.
    A measurement within the bounds may still tell the classes apart there, as it
    cannot where their outcomes coincide. None where they coincide on every path."""
    posed, out = found.posed, found.outcomes
    top = np.argsort(-posed.class_weight, kind="stable")[:SHORTLIST_CLASSES_ALONE]
    rows = np.arange(len(found.candidates))
    apart = outcomes_apart(out, rows, posed.best_members(top), sensor)
    order = np.lexsort((found.motion, -apart))
    order = order[apart[order] > 0][: config.max_paths]
    if not len(order):
        return [], why
    paths = [planned(found, int(i), ranking, family="partial") for i in order]
    note = (
        f"{why}; offered where the classes' nominal contacts lie farthest apart "
        f"({float(apart[order[0]]):.2f} error bounds on the first path), where a "
        "measurement within the bounds may still tell them apart"
    )
    return paths, note
