"""Forecast of a touch: what the recognition itself will make of it.

The outcome model (:mod:`planner.planning.outcomes`) tells hypotheses apart with
worst-case tolerances: two contacts count as confusable while they lie within
both error disks at once, and every uncertain outcome (a vertex, a grazing
hit, a close pass, ...) as confusable with all it could be mistaken for. That
makes its P(DM) sound where it says 1 and low elsewhere: with a 5 degree
sensor, touches it gave P(DM) = 0 ended in one class about one time in ten.
The recognition prunes more finely: it fits every hypothesis to the new
contact and keeps it only if some pose within the bounds explains all
contacts.

The forecast asks the recognition. Each class' most probable member predicts
its nominal outcome on the path (the first hit, with the posed face normal,
or a miss); the session observes that outcome; the touch is distinguishing
when one class is left. A class pinned poorly (a part free to slide along two
nearly parallel faces) predicts at the pose its touches still allow, and its
prediction counts for the share of its possible poses that agree with it
(:mod:`planner.planning.pose_spread`). ``p_forecast = sum_k w(k) [one class left | k's
outcome]``, the class weights being the session's probabilities. One
recognition update per class, so it is offered for the first few ranked
paths only, and only when the plan's budget can pay for every class: a
forecast cut short says nothing, so it is not begun.

World frame, lengths in the object files' unit.
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from planner.geometry import LENGTH_SLACK
from planner.models.tip import grown_models
from planner.planning.analysis import Analysis
from planner.planning.budget import Budget
from planner.planning.candidates import Candidates
from planner.planning.outcomes import OutcomeConfig, Outcomes, predict_outcomes
from planner.planning.pose_spread import agreement, recentred
from planner.planning.posed_set import PosedSet, pose_hypotheses
from planner.planning.predicted import class_count, classes_after, observed, prefetch
from planner.planning.representatives import face_counts
from planner.planning.result import Plan
from planner.planning.screen import screened_log
from planner.recognition.session import Session
from planner.types import Hypothesis, SensingPath, SensorBounds

__all__ = [
    "FACES_PER_HYPOTHESIS",
    "RecognitionRanking",
    "RefiningPrediction",
    "forecast_distinguishing",
    "outcomes_apart",
    "recognition_ranking",
    "recognition_refining",
    "update_size",
    "with_forecast",
]


def forecast_distinguishing(
    session: Session,
    path: SensingPath,
    budget: Budget | None = None,
    config: OutcomeConfig | None = None,
) -> float | None:
    """Probability that the touch along `path` leaves one equivalence class, as
    the session's recognition would judge each class' predicted outcome (None
    when there is nothing to forecast or the `budget` passed first)."""
    hypotheses = session.hypotheses
    if not hypotheses:
        return None
    budget = budget or Budget()
    cls = np.array([h.equivalence_class for h in hypotheses])
    weight = np.bincount(cls, weights=[h.probability for h in hypotheses])
    # hypotheses come most probable first: each class' first row is its best member
    _, first = np.unique(cls, return_index=True)
    total, size = 0.0, update_size(session)
    if not budget.affords_updates(len(first), size):
        return None  # it would stop before the last class: not even started
    # the ball tip's centre is what the session observes: cast the grown outlines
    # (a poorly pinned class at the pose its touches still allow, as the plan sees it)
    # only each class' best member predicts: only they are posed and cast
    models = grown_models(session.models_by_name, session.sensor.tip_radius)
    leaders = [hypotheses[r] for r in first]
    posed = pose_hypotheses(recentred(session, leaders), models, path.height)
    line = np.array([path.origin]), np.array([path.direction]), np.array([path.length])
    out = predict_outcomes(posed, *line, session.working_sensor, config or OutcomeConfig())
    trust = np.ones(len(first))  # the share of each class' poses its prediction holds for
    if path.height is None:
        trust = agreement(session, leaders, out.hit, *line)[0]
    prefetch(session, lambda _: path, out, [(0, j) for j in range(len(first))])
    for j, (k, share) in enumerate(zip(cls[first], trust, strict=True)):
        if budget.exhausted():
            return None
        after = observed(session, path, out, 0, j)
        budget.spend_updates(1, size)
        if class_count(after) == 1:
            total += float(weight[k]) * share
    return min(total / float(weight.sum()), 1.0)


def with_forecast(
    plan: Plan,
    session: Session,
    count: int = 1,
    budget: Budget | None = None,
    config: OutcomeConfig | None = None,
) -> Plan:
    """`plan` with `p_forecast` set on its first `count` paths (refining paths
    included), within what is left of the plan's `budget` (None: unlimited); the
    forecast's time is added to `elapsed_ms`, its work to `work`."""
    if not count or not plan.paths or not session.hypotheses:
        return plan
    start = time.perf_counter()
    budget = budget or Budget()
    paths = list(plan.paths)
    for i, p in enumerate(paths[:count]):
        if p.p_forecast is not None:  # ranked by the recognition: forecast already
            continue
        value = forecast_distinguishing(session, p.path, budget, config)
        if value is None:
            break
        paths[i] = dataclasses.replace(p, p_forecast=value)
    elapsed = plan.elapsed_ms + (time.perf_counter() - start) * 1000.0
    return dataclasses.replace(
        plan,
        paths=tuple(paths),
        elapsed_ms=elapsed,
        work=budget.units,
        stopped_by=plan.stopped_by or budget.stopped_by,
    )


#: Most candidate paths, and most classes, the recognition is asked about (one
#: update per pair), and how many times as many paths while none of them is
#: predicted to change anything. Where the outcome model calls every candidate
#: uninformative the recognition's ranking is all the plan has, and it judges
#: `SHORTLIST_CLASSES_ALONE` classes (near twins: four objects in two turns each).
SHORTLIST = 8
SHORTLIST_CLASSES = 4
SHORTLIST_CLASSES_ALONE = 8
SHORTLIST_ROUNDS = 4
#: How far a forecast from the most probable classes alone may stray from one over
#: every class: the share of the weight the classes left out may hold.
FORECAST_SLACK = 0.01


@dataclass(frozen=True, eq=False)
class RecognitionRanking:
    """What the recognition predicts of the shortlisted candidates `rows` (best
    first): `p_distinguishing` (the class-weighted share of predicted outcomes that
    leave one class), `expected_classes` (classes left, class-weighted) and
    `expected_log` (their logarithm, class-weighted: the touches a halving path
    leaves, in nats), against the `current` number of classes; the classes
    predicted (the most probable, their weights renormalized) hold the share
    `covered` of the class weight. Best is the least `expected_log`, then the
    largest P(DM), then the fewest classes: a path that halves eight classes
    (log 4) leaves fewer touches than one that settles one of four likely truths
    and leaves seven otherwise (0.75 log 7)."""

    rows: np.ndarray
    p_distinguishing: np.ndarray
    expected_classes: np.ndarray
    expected_log: np.ndarray
    current: int
    covered: float

    @property
    def forecasts(self) -> bool:
        """`p_distinguishing` is the forecast within `FORECAST_SLACK`: the classes
        left out hold at most that share of the weight (renormalized, the sample
        would overstate the forecast by up to their share)."""
        return self.covered >= 1.0 - FORECAST_SLACK

    @property
    def useful(self) -> np.ndarray:
        """(n,) bool: the judged paths predicted to leave fewer classes."""
        return self.expected_classes < self.current - 1e-9


def recognition_ranking(
    session: Session,
    found: Analysis,
    budget: Budget | None = None,
    first: Sequence[int] = (),
    until_sure: bool = False,
    classes: int = SHORTLIST_CLASSES,
) -> RecognitionRanking:
    """Rank candidates on what the recognition itself concludes (DESIGN §4.15).

    Shortlist: every path aimed at the classes' differences, and the others whose
    classes' nominal outcomes lie over a bound apart (or the first `SHORTLIST` of
    them by that distance, the outcome model's P(informative) and motion), ordered
    by the screen's guess at the expected log of the classes left
    (:mod:`planner.planning.screen`; ties keep that order): the budget pays for a
    handful of judged paths, and which handful decides the touch. Each of the
    most probable classes predicts its nominal outcome on a path with its best
    member (the cast of the analysis); the session observes it; the classes left
    are counted. ``E[classes] = sum_k w(k) classes(after k's
    outcome)``. The first path is always judged, the rest while the `budget`
    allows: `SHORTLIST` of them, and past that (up to `SHORTLIST_ROUNDS` times as
    many) while none is predicted to change the classes. Candidates `first` are
    judged before the shortlist. With `until_sure` the judging stops at the first
    path predicted to leave one class whatever the truth: nothing judged after it
    can rank above it (the paths below it are then not all judged). The most
    probable `classes` classes predict."""
    budget = budget or Budget()
    posed, out, cands = found.posed, found.outcomes, found.candidates
    current = posed.n_classes
    top = np.argsort(-posed.class_weight, kind="stable")[:classes]
    weight = posed.class_weight[top] / posed.class_weight[top].sum()
    best = posed.best_members(top)
    # the paths aimed at the classes' differences in the order they were made (one
    # per feature first), then the others where the classes' outcomes differ most;
    # then the likeliest splits first by the screen
    feature = np.flatnonzero(cands.source == "feature")
    other = np.flatnonzero(cands.source != "feature")
    apart = outcomes_apart(out, other, best, session.working_sensor)
    order = np.lexsort((found.motion[other], -found.info.p_informative[other], -apart))
    other, apart = other[order], apart[order]
    # past the first `SHORTLIST`, only paths where the outcomes lie over a bound apart
    shortlist = np.concatenate([feature, other])
    keep = np.arange(len(shortlist)) < SHORTLIST
    keep[: len(feature)] = True
    keep[len(feature) :] |= apart > 1.0
    shortlist = shortlist[keep]
    screen = screened_log(out, shortlist, posed, top, weight, session.working_sensor, budget)
    shortlist = shortlist[np.argsort(screen, kind="stable")][: SHORTLIST * SHORTLIST_ROUNDS]
    if len(first):
        ahead = np.asarray(first, dtype=int)
        shortlist = np.concatenate([ahead, shortlist[~np.isin(shortlist, ahead)]])
    rows, p_dm, expected, logs = [], [], [], []
    size = update_size(session)
    # the share of each prediction that holds wherever the class may lie
    trust = _trusted(session, posed, cands, out, shortlist, top, best)
    fetched = 0  # the shortlist's paths whose predictions are observed
    for j, c in enumerate(shortlist):
        if rows and budget.exhausted():
            break
        if len(rows) >= SHORTLIST and min(expected) < current - 1e-9:
            break  # a path predicted to change the classes is among those judged
        if j >= fetched:  # the next paths the budget would judge, observed at once
            ahead = SHORTLIST - len(rows) if len(rows) < SHORTLIST else SHORTLIST // 2
            if until_sure:  # the first paths judged are often sure: ask for more as none is
                ahead = min(ahead, max(1, len(rows)))
            fetched = j + int(min(ahead, max(1, budget.steps_affordable(len(best), size))))
            pairs = [(int(x), int(h)) for x in shortlist[j:fetched] for h in best]
            prefetch(session, cands.path, out, pairs)
        left = np.array([classes_after(session, cands.path(int(c)), out, int(c), h) for h in best])
        budget.spend_updates(len(best), size)
        left = np.where(left > 0, left, current)  # an impossible prediction teaches nothing
        rows.append(int(c))
        share = weight * trust[j]  # the rest of each class' weight: nothing changes
        p_dm.append(float(share @ (left == 1)))
        expected.append(float(share @ left + (1.0 - trust[j]) @ weight * current))
        logs.append(float(share @ np.log(left) + (1.0 - trust[j]) @ weight * np.log(current)))
        if until_sure and expected[-1] <= 1 + 1e-9:
            break  # it settles every truth: nothing judged later can rank above it
    # the logarithms tie to 9 decimals (halving paths alike); P(DM) and the classes
    # keep their last bits, which order the likelier classes' paths first
    keys = (np.array(expected), -np.array(p_dm), np.round(np.array(logs), 9))
    rank = np.lexsort(keys) if rows else np.zeros(0, int)
    return RecognitionRanking(
        np.array(rows, dtype=int)[rank],
        np.array(p_dm)[rank],
        np.array(expected)[rank],
        np.array(logs)[rank],
        current,
        float(posed.class_weight[top].sum() / posed.class_weight.sum()),
    )


def _trusted(
    session: Session,
    posed: PosedSet,
    cands: Candidates,
    out: Outcomes,
    rows: np.ndarray,
    top: np.ndarray,
    best: np.ndarray,
) -> np.ndarray:
    """(n, k) for each candidate of `rows` and each class of `top` (its posed best
    member `best`), the share of the class' poses whose outcome agrees with the
    nominal one (:func:`planner.planning.pose_spread.agreement`; 1 at other
    probing heights)."""
    trust = np.ones((len(rows), len(top)))
    default = np.isnan(cands.height[rows])  # type: ignore[index]
    if not default.any():
        return trust
    labels = posed.class_ids[top]
    lead: dict[int, Hypothesis] = {}
    for h in session.hypotheses:  # most probable first
        lead.setdefault(h.equivalence_class, h)
    if any(int(c) not in lead for c in labels):
        return trust
    at = rows[default]
    trust[default] = agreement(
        session,
        [lead[int(c)] for c in labels],
        out.hit[np.ix_(at, best)],
        cands.origins[at],
        cands.directions[at],
        cands.lengths[at],
    )
    return trust


def outcomes_apart(
    out: Outcomes, rows: np.ndarray, members: np.ndarray, sensor: SensorBounds
) -> np.ndarray:
    """(n,) for each candidate of `rows`, how far apart the nominal outcomes of the
    hypotheses `members` lie: the largest over pairs of the contacts' distance in
    position bounds plus their normals' angle in normal bounds (a hit against a
    miss counts as far as anything can be). Where they coincide within the bounds
    no contact tells them apart; where they lie far apart one may."""
    hit = out.hit[np.ix_(rows, members)]  # (n, k)
    point = np.nan_to_num(out.point[np.ix_(rows, members)])  # (n, k, 2)
    normal = np.nan_to_num(out.normal[np.ix_(rows, members)])
    gap = np.linalg.norm(point[:, :, None] - point[:, None], axis=-1)
    turn = np.arccos(np.clip(np.einsum("nkd,njd->nkj", normal, normal), -1.0, 1.0))
    far = gap / max(sensor.position_error, LENGTH_SLACK) + turn / max(sensor.normal_error, 1e-3)
    both = hit[:, :, None] & hit[:, None]
    either = hit[:, :, None] ^ hit[:, None]
    apart = np.where(either, np.inf, np.where(both, far, 0.0))
    return apart.max(axis=(1, 2)) if len(members) else np.zeros(len(rows))


#: Faces of a hypothesis counted as one in the cost of an update: an outline of
#: many faces costs as much more to re-check (as a cast cell does).
FACES_PER_HYPOTHESIS = 12


def update_size(session: Session) -> float:
    """What one observation update of `session` costs in hypotheses: each counted
    once per `FACES_PER_HYPOTHESIS` of its faces (at least once). A plan works on
    one hypothesis per class where they are many
    (:mod:`~planner.planning.representatives`); an update works on all of them."""
    faces = face_counts(session.hypotheses, session.models_by_name)
    return float(np.maximum(1.0, np.asarray(faces, dtype=float) / FACES_PER_HYPOTHESIS).sum())


@dataclass(frozen=True, eq=False)
class RefiningPrediction:
    """What the recognition predicts of shortlisted refining paths `rows` (best
    first: within the session's accuracy, then the smaller bound) for a session
    with one class left: the class' bound after each path's predicted contact
    (`translation`, `rotation`, `eps_t`); `current` the bound now; `pinning` the
    shortlist itself, best pinning first (the paths whose predicted contact
    constrains the pose most, judged or not), of which the first `tried` were
    judged before the budget ended the judging."""

    rows: np.ndarray
    translation: np.ndarray
    rotation: np.ndarray
    eps_t: np.ndarray
    current: tuple[float, float]
    pinning: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(0, dtype=int))
    tried: int = 0


def recognition_refining(
    session: Session, found: Analysis, budget: Budget | None = None
) -> RefiningPrediction:
    """Paths that shrink the one class' bound, as the recognition predicts it.

    The outcome model credits a refining touch only where the contact is sure;
    while the pose can still slide far (a part touched only on its flats) every
    contact near the parts that would pin it is uncertain. Here the class' most
    probable member predicts its nominal hit on each candidate; the candidates
    whose predicted contact constrains the pose most (largest smallest eigenvalue
    of the contacts' normal equations, rotation scaled by the part's size) are
    shortlisted, the session observes each prediction, and the bound it would
    report is read off. Best first: within the accuracy, then the smaller bound
    (each part as a share of the accuracy), then the shorter motion."""
    budget = budget or Budget()
    posed, out, cands = found.posed, found.outcomes, found.candidates
    best = int(np.argmax(posed.weight))
    now = session.localization.bound
    current = (float(now.translation), float(now.rotation)) if now else (np.inf, np.inf)
    default = np.isnan(cands.height)  # type: ignore[arg-type]
    rows = np.flatnonzero(out.hit[:, best] & default)
    hyp = session.hypotheses[0]
    score = _constraint_gain(session, out.point[rows, best], out.normal[rows, best], hyp)
    shortlist = rows[np.lexsort((found.motion[rows], -score))][:SHORTLIST]
    judged: list[tuple[int, float, float, float, bool]] = []
    size = update_size(session)
    accuracy = session.accuracy
    tried = 0
    steps = budget.steps_affordable(1, size)
    pairs = [(int(c), best) for c in shortlist[: int(min(len(shortlist), max(1, steps)))]]
    prefetch(session, cands.path, out, pairs)
    for c in shortlist:
        if judged and budget.exhausted():
            break
        tried += 1
        after = observed(session, cands.path(int(c)), out, int(c), best)
        budget.spend_updates(1, size)
        where = None if after is None else after.localization
        if where is None or where.bound is None or where.classes != 1:
            continue
        b = where.bound
        judged.append(
            (int(c), float(b.translation), float(b.rotation), float(b.eps_t), not where.missing)
        )
    if not judged:
        none = np.zeros(0)
        return RefiningPrediction(none.astype(int), none, none, none, current, shortlist, tried)
    c, t, r, e, ok = (np.array(v) for v in zip(*judged, strict=True))
    share = t / accuracy.translation + r / accuracy.rotation
    order = np.lexsort((found.motion[c], share, ~ok))
    return RefiningPrediction(c[order], t[order], r[order], e[order], current, shortlist, tried)


def _constraint_gain(
    session: Session, points: np.ndarray, normals: np.ndarray, hyp: Hypothesis
) -> np.ndarray:
    """(n,) the smallest eigenvalue of the contacts' normal equations over the pose
    (x, y, rotation x the part's size) with each predicted contact (points,
    normals (n, 2)) added to the session's: how well the pose would be pinned."""
    centre = np.array([hyp.pose.x, hyp.pose.y])
    scale = session.length_scale

    def rows(p: np.ndarray, n: np.ndarray) -> np.ndarray:
        arm = p - centre
        return np.column_stack([n, (arm[:, 0] * n[:, 1] - arm[:, 1] * n[:, 0]) / scale])

    contacts = session.contacts
    known = rows(
        np.array([c.point for c in contacts], dtype=float).reshape(-1, 2),
        np.array([c.normal for c in contacts], dtype=float).reshape(-1, 2),
    )
    new = rows(points, normals)
    normal_eq = (known.T @ known)[None] + new[:, :, None] * new[:, None, :]
    return np.linalg.eigvalsh(normal_eq)[:, 0]
