"""The planner's entry point (DESIGN §4.12, §6): a session in, a ranked plan out.

:func:`plan` is a pure function: hypotheses (with probabilities and equivalence
classes), the object models, sensor error bounds, the safe circle and the
sensor's place in, a ranked :class:`~planner.planning.result.Plan` out. It runs
in three steps, each usable alone: :func:`~planner.planning.analysis.analyse`
(candidates, outcome model, survivor sets, scores),
:func:`~planner.planning.strategies.rank_candidates` (the strategy, on the
outcome matrix only) and the assembly of the plan. :func:`plan_session` plans on
a session's state and adds the recognition's own forecast of the best paths.
The refining paths of a class short of the accuracy are assembled in
:mod:`planner.planning.refining_paths`, a candidate as a planned path in
:mod:`planner.planning.planned`.
All geometry is in the world frame, lengths in the object files' unit, angles in
radians.
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from planner.models.tip import grown_models
from planner.planning.analysis import Analysis, analyse, as_generator, models_by_name
from planner.planning.budget import Budget
from planner.planning.config import StrategyConfig
from planner.planning.forecast import (
    SHORTLIST_CLASSES_ALONE,
    RecognitionRanking,
    recognition_ranking,
    with_forecast,
)
from planner.planning.planned import planned
from planner.planning.pose_spread import recentred, spreads
from planner.planning.predicted import predictions
from planner.planning.probes import opening_probe
from planner.planning.refining_paths import apart_paths, one_class_paths, refining_paths
from planner.planning.representatives import (
    SAMPLE_FACES,
    face_counts,
    representatives,
    weighted_sample,
)
from planner.planning.result import Plan, PlannedPath
from planner.planning.strategies import Ranking, rank_candidates
from planner.recognition.session import Session
from planner.types import (
    Contact,
    Hypothesis,
    ObjectModel,
    Observation,
    SensingPath,
    SensorBounds,
    Workspace,
)

__all__ = ["plan", "plan_session"]

#: The share of a plan's work kept for the forecast of its first paths.
FORECAST_SHARE = 0.25
#: Below this probability of changing the hypotheses (for the outcome model) the
#: best path is weak, and the recognition's predictions rank the candidates.
_WEAK = 0.05
#: Strategies that take the recognition's ranking also when its predictions say its
#: best path does better than the outcome model's, not only when the outcome
#: model's best path is weak: the worst-case model calls too much confusable near
#: small features and on drawn curves (measured: README, "Beside the published
#: strategies"). ``optimal`` searches the same model as ``lookahead`` to the end,
#: so it asks the same question of the recognition.
PREDICTED_FIRST = ("lookahead", "optimal")


def plan_session(
    session: Session,
    sensor_position: Sequence[float],
    config: StrategyConfig | None = None,
    rng: np.random.Generator | int | None = None,
) -> Plan:
    """:func:`plan` on a session's state, its first
    `config.forecast` paths forecast within the same budget."""
    # one update per distinct predicted observation, one spread per hypothesis
    with predictions(), spreads():
        return _plan_session(session, sensor_position, config or StrategyConfig(), rng)


def _plan_session(
    session: Session,
    sensor_position: Sequence[float],
    config: StrategyConfig,
    rng: np.random.Generator | int | None,
) -> Plan:
    total = config.budget_work
    # the forecast (the probability to act on) keeps its share of the work: the search
    # may not spend it, and the forecast may spend what the search left
    share = total if total is None or not config.forecast else total * (1 - FORECAST_SHARE)
    budget = Budget(share, config.budget_ms)
    # one hypothesis per class where the posed faces are many (a finely drawn curve),
    # a weighted sample of them where even those are too many
    by_name = session.models_by_name
    faces = face_counts(session.hypotheses, by_name)
    reps = representatives(
        session.hypotheses, session.symmetry_tolerance, session.joined_classes, faces
    )
    sample = weighted_sample(reps, face_counts(reps, by_name))
    result = plan(
        recentred(session, sample),
        session.models,
        session.working_sensor,
        session.workspace,
        sensor_position,
        config,
        rng,
        observations=session.observations,
        localized=session.status == "localized",
        session=session,
        budget=budget,
    )
    budget.raise_to(total)
    if len(sample) < len(reps):
        return _on_sample(result, len(sample), len(reps))
    return with_forecast(result, session, config.forecast, budget, config.outcome)


def _on_sample(result: Plan, drawn: int, total: int) -> Plan:
    """A plan ranked on a weighted sample of the hypotheses: no touch is sure to
    leave one class while the hypotheses left out may survive it, so P(DM) is
    reported as its lower bound, 0 (and a path the sample calls distinguishing,
    informative); the ranking stands. Not forecast: the recognition would judge
    every class."""
    paths = tuple(
        dataclasses.replace(
            p,
            p_distinguishing=0.0,
            p_forecast=None,
            family="informative" if p.family == "distinguishing" else p.family,
        )
        for p in result.paths
    )
    note = (
        f"ranked on a weighted sample of {drawn} of {total} hypotheses (their posed faces "
        f"over {SAMPLE_FACES}); P(DM) counts those left out as surviving"
    )
    return dataclasses.replace(
        result,
        paths=paths,
        truncated=True,
        note="; ".join(filter(None, [note, result.note])),
    )


def plan(
    hypotheses: Sequence[Hypothesis],
    models: Mapping[str, ObjectModel] | Sequence[ObjectModel],
    sensor: SensorBounds,
    workspace: Workspace,
    sensor_position: Sequence[float],
    config: StrategyConfig | None = None,
    rng: np.random.Generator | int | None = None,
    *,
    observations: Sequence[Observation] = (),
    extra_paths: Sequence[SensingPath] = (),
    localized: bool | None = None,
    session: Session | None = None,
    budget: Budget | None = None,
) -> Plan:
    """Rank the next sensing paths for a hypothesis set (world frame).

    `hypotheses` carry probabilities (normalized here) and equivalence classes;
    `observations` (the session's, in order) tell whether anything was touched
    yet and give the contacts the thesis opening needs; `extra_paths` join the
    candidates; `rng` (or a seed; default 0) drives the random choices; the
    `budget` (default: `config`'s) covers the whole call.

    With no hypothesis and no contact the plan is the opening probe (status
    ``awaiting_contact``); with contacts but no hypothesis, empty
    (``inconsistent``); when `localized` (by default: one class left), empty;
    with one class left short of the session's accuracy, the paths that shrink
    its bound (``refining``); otherwise the ranked informative paths
    (``ambiguous``). When the outcome model calls no candidate informative, the
    candidates are ranked on what the recognition of `session` predicts
    (:func:`~planner.planning.forecast.recognition_ranking`), then refining paths
    are offered; only when nothing can change the hypotheses is the plan empty,
    with a note saying why."""
    start = time.perf_counter()
    config = config or StrategyConfig()
    gen = as_generator(rng)
    budget = budget or Budget(config.budget_work, config.budget_ms)
    contacts = [o.contact for o in observations if o.contact is not None]
    # with a ball tip the plan works where its centre goes: paths are cast against
    # the outlines grown by the radius, and contacts are the reported centres
    models = grown_models(models, sensor.tip_radius)

    def finish(status: str, paths: Sequence[PlannedPath], **kw: Any) -> Plan:
        elapsed, cut = (time.perf_counter() - start) * 1000.0, kw.pop("truncated", False)
        kw.update(work=budget.units, stopped_by=budget.stopped_by)
        return Plan(status, cut, elapsed, tuple(paths), config.name, **kw)

    if not hypotheses:
        if contacts:
            return finish("inconsistent", (), note="no hypothesis explains the contacts")
        probe = _opening(config, models, workspace, sensor_position, observations, gen, session)
        return finish("awaiting_contact", (probe,))
    classes = len({h.equivalence_class for h in hypotheses})
    if localized or (classes == 1 and localized is None):
        return finish("localized", (), classes=classes)
    found = analyse(
        hypotheses,
        models,
        sensor,
        workspace,
        sensor_position,
        config,
        gen,
        observations=observations,
        extra_paths=extra_paths,
        budget=budget,
    )
    if classes == 1:  # one class, its bound short of the required accuracy
        paths, note = one_class_paths(
            found, hypotheses, models, contacts, sensor, config, session, budget
        )
        return finish("ambiguous", paths, truncated=found.truncated, note=note, classes=1)
    ranking = rank_candidates(
        found.table,
        config,
        info=found.info,
        motion=found.motion,
        source=found.candidates.source,
        tier=found.candidates.tier,
        rng=gen,
        budget=budget,
    )
    paths = [planned(found, int(i), ranking) for i in ranking.order[: config.max_paths]]
    paths, note = _unless_weak(found, session, ranking, config, budget, paths)
    if not paths:
        paths, note = _uninformative(
            found, hypotheses, models_by_name(models), contacts, sensor, ranking, config, gen,
            session, budget,
        )  # fmt: skip
    cut = "candidates cut at the budget" if found.truncated else None
    note = "; ".join(filter(None, [note, cut])) or None
    return finish(
        "ambiguous",
        paths,
        truncated=ranking.truncated or found.truncated,
        note=note,
        candidates=len(found.candidates),
        classes=found.table.n_classes,
    )


def _opening(
    config: StrategyConfig,
    models: Sequence[ObjectModel],
    workspace: Workspace,
    sensor_position: Sequence[float],
    observations: Sequence[Observation],
    rng: np.random.Generator,
    session: Session | None,
) -> PlannedPath:
    """The probe before any contact, through the centre of the session's pose prior
    region when it has one (:func:`~planner.planning.probes.opening_probe`)."""
    prior = None if session is None else session.config.prior
    missed = [o.path for o in observations]
    aim = None if prior is None else prior.center
    return opening_probe(
        config, models_by_name(models), workspace, sensor_position, missed, rng, aim
    )


def _uninformative(
    found: Analysis,
    hypotheses: Sequence[Hypothesis],
    models: Mapping[str, ObjectModel],
    contacts: Sequence[Contact],
    sensor: SensorBounds,
    ranking: Ranking,
    config: StrategyConfig,
    rng: np.random.Generator,
    session: Session | None,
    budget: Budget,
) -> tuple[list[PlannedPath], str | None]:
    """The outcome model calls no candidate informative. The thesis refines, then
    takes its best window, as the thesis did; the other strategies rank on the
    recognition's predictions (given a session), then refine."""
    if config.name == "thesis":
        paths, note = refining_paths(found, hypotheses, models, contacts, sensor, ranking, config)
        if not paths:
            paths, note = _thesis_window(found, ranking, config, rng, note)
        return paths, note
    paths, note = [], ranking.note
    if session is not None:
        paths, note = _by_recognition(found, session, ranking, config, budget)
    if not paths:
        # the recognition's note says why nothing changes the classes; keep it
        paths, refined = refining_paths(
            found, hypotheses, models, contacts, sensor, ranking, config
        )
        note = refined if paths else note
    if not paths:
        paths, note = apart_paths(found, sensor, ranking, config, note)
    return paths, note


def _thesis_window(
    found: Analysis,
    ranking: Ranking,
    config: StrategyConfig,
    rng: np.random.Generator,
    note: str | None,
) -> tuple[list[PlannedPath], str | None]:
    """The thesis takes its best window whatever a finer model predicts of it (it
    raised the admitted strength until one opened): the first in CHOOSE order, or
    a random one of the lowest level; none when the grid found no window."""
    windows = np.flatnonzero(found.candidates.source == "window")
    if not len(windows):
        return [], note
    if config.thesis_choice == "random":
        tier = found.candidates.tier[windows]
        windows = rng.permutation(windows[tier == tier.min()])
    said = "the thesis' best window, though not informative"
    return [planned(found, int(windows[0]), ranking)], "; ".join(filter(None, [note, said]))


def _unless_weak(
    found: Analysis,
    session: Session | None,
    ranking: Ranking,
    config: StrategyConfig,
    budget: Budget,
    paths: list[PlannedPath],
) -> tuple[list[PlannedPath], str | None]:
    """The ranked `paths`, unless the best changes the hypotheses with probability
    under `_WEAK` for the outcome model: then (given the session) those the
    recognition predicts change them, when it finds any. Strategies of
    `PREDICTED_FIRST` also take the recognition's ranking when it predicts its
    best path does better than the outcome model's. ``thesis`` and ``random``
    keep their own choice."""
    if not paths or session is None or config.name in ("thesis", "random"):
        return paths, ranking.note
    p_inf = float(found.info.p_informative[ranking.order[0]])
    if p_inf >= _WEAK:
        if config.name in PREDICTED_FIRST:
            return _unless_predicted_better(found, session, ranking, config, budget, paths)
        return paths, ranking.note
    why = f"the outcome model's best path changes the hypotheses with probability {p_inf:.2g}"
    judged, said = _by_recognition(found, session, ranking, config, budget, why)
    if not judged:
        return paths, ranking.note
    return judged, "; ".join(filter(None, [said, ranking.note]))


def _unless_predicted_better(
    found: Analysis,
    session: Session,
    ranking: Ranking,
    config: StrategyConfig,
    budget: Budget,
    paths: list[PlannedPath],
) -> tuple[list[PlannedPath], str | None]:
    """The outcome model's ranked `paths`, unless the model is unsure of some
    outcome of its best path (or counts a group of several classes no path
    splits as done: :func:`_settles_short`) and the recognition, judging that path
    before its shortlist, ranks a path of the shortlist ahead of it by more than
    rounding (in :class:`RecognitionRanking`'s order). Where the model is sure of
    every outcome it is the recognition's nominal prediction looked at two touches
    deep, and its ranking stands; so it does with exact sensing, where the model's
    uncertain zones are the rounding slack and the pose bounds of classes the
    recognition's four-class sample may not see (measured: README, Table 4.1
    analog)."""
    best = int(ranking.order[0])
    sensor = session.working_sensor
    if sensor.position_error == 0 and sensor.normal_error == 0:
        return paths, ranking.note  # exact sensing: the model's zones are rounding only
    if not found.outcomes.uncertain_on(best).any() and not _settles_short(found, ranking, best):
        return paths, ranking.note  # the model is sure of every outcome: it stands
    if budget.exhausted():
        return paths, ranking.note  # only the best path would be judged: no other to take
    judged = recognition_ranking(session, found, budget, first=[best], until_sure=True)
    if judged.rows[0] == best:  # judged first, it stays first on a tie
        return paths, ranking.note
    at = int(np.flatnonzero(judged.rows == best)[0])  # the first path is always judged
    p_best, e_best = judged.p_distinguishing[at], judged.expected_classes[at]
    p_top, e_top = judged.p_distinguishing[0], judged.expected_classes[0]
    l_best, l_top = judged.expected_log[at], judged.expected_log[0]
    # ahead in the ranking's order by more than rounding, not by the last bits of a
    # weighted sum (the ranking itself orders by them: measured, the twins lost
    # 0.115 +- 0.040 touch when it did not)
    better = l_top < l_best - 1e-9 or (
        l_top < l_best + 1e-9
        and (p_top > p_best + 1e-9 or (p_top > p_best - 1e-9 and e_top < e_best - 1e-9))
    )
    if not better or not judged.useful.any():
        # ahead only by its logarithm, none predicted to leave fewer classes (a
        # split class' parts outweigh the classes it settles): nothing to put first
        return paths, ranking.note
    why = (
        "the recognition predicts a better path than the outcome model's best "
        f"(P(DM) {p_best:.2f}, classes {judged.current} -> {e_best:.2f} expected)"
    )
    return _recognition_paths(found, judged, ranking, config, paths), "; ".join(
        filter(None, [_ranked_note(why, judged), ranking.note])
    )


def _settles_short(found: Analysis, ranking: Ranking, best: int) -> bool:
    """Does the model's value of path `best` count groups of several classes done?
    Every outcome ends in a group no candidate splits (one touch expected) though
    not every one in one class (P(DM) < 1): the recognition, which prunes more
    finely, may split them, or not."""
    return bool(
        found.info.p_distinguishing[best] < 1 - 1e-9
        and ranking.expected_remaining[best] <= 1 + 1e-9
    )


def _by_recognition(
    found: Analysis,
    session: Session,
    ranking: Ranking,
    config: StrategyConfig,
    budget: Budget,
    why: str | None = None,
) -> tuple[list[PlannedPath], str | None]:
    """No candidate informative for the outcome model (or only weakly: `why`, by
    default the ranking's note): the shortlisted paths after which the
    recognition predicts fewer classes, best first (:class:`RecognitionRanking`),
    scored by the recognition, judged until one settles every truth; then the
    outcome model's. None when the recognition predicts no path changes the
    classes."""
    why = why or ranking.note
    judged = recognition_ranking(
        session, found, budget, until_sure=True, classes=SHORTLIST_CLASSES_ALONE
    )
    if not judged.useful.any():
        note = (
            f"{why}; the recognition predicts {judged.current} classes after each "
            f"of the {len(judged.rows)} paths it judged"
        )
        return [], note
    rest = [planned(found, int(i), ranking) for i in ranking.order[: config.max_paths]]
    return _recognition_paths(found, judged, ranking, config, rest), _ranked_note(why, judged)


def _recognition_paths(
    found: Analysis,
    judged: RecognitionRanking,
    ranking: Ranking,
    config: StrategyConfig,
    rest: Sequence[PlannedPath] = (),
) -> list[PlannedPath]:
    """The judged paths predicted to leave fewer classes, best first, scored by the
    recognition (where the classes it predicted hold nearly all the weight, its
    P(DM) is the forecast of the first `config.forecast`; from fewer it could
    overstate it, and the plan's forecast judges every class), then the paths of
    `rest` (the outcome model's ranking) not among them."""
    useful = judged.useful
    mine = [
        dataclasses.replace(
            planned(found, int(i), ranking, family="partial"),
            p_forecast=float(p) if k < config.forecast and judged.forecasts else None,
            scored_by="recognition",
        )
        for k, (i, p) in enumerate(
            zip(judged.rows[useful], judged.p_distinguishing[useful], strict=True)
        )
    ]
    taken = {p.path for p in mine}
    return [*mine, *(p for p in rest if p.path not in taken)][: config.max_paths]


def _ranked_note(why: str | None, judged: RecognitionRanking) -> str:
    """Why the recognition ranked the paths, and what it predicts of the first."""
    useful = judged.useful
    return (
        f"{why}: ranked on the recognition's predictions (classes "
        f"{judged.current} -> {judged.expected_classes[useful][0]:.2f} expected, "
        f"P(DM) {judged.p_distinguishing[useful][0]:.2f})"
    )
