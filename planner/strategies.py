"""Planning strategies and the planner's entry point :func:`plan` (DESIGN §4.12, §6).

``plan`` is a pure function: hypotheses (with probabilities and equivalence
classes), the object models, sensor error bounds, the safe circle and the
sensor's place in, a ranked :class:`~planner.plans.Plan` out. All geometry is
in the world frame, lengths in the object files' unit, angles in radians.
It runs in three steps, each usable alone: :func:`analyse` (candidates, outcome
model, survivor sets, scores), :func:`rank_candidates` (the strategy, on the
outcome matrix only) and the assembly of the plan.

Strategies: ``random`` (thesis Exp. I), ``thesis`` (opening probes, then the
grid windows of :mod:`planner.grid` in CHOOSE order), ``pdm`` (max P(DM)),
``pruning`` (max expected pruning), ``lookahead`` (min expected remaining
touches, `depth` deep), ``optimal`` (exact DP over survivor sets for at most
`optimal_max_classes` classes, else lookahead, saying so). None of them
returns an uninformative path while an informative candidate exists.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field, fields
from typing import Any

import numpy as np

from planner.candidates import CandidateConfig, Candidates
from planner.errors import PlannerError
from planner.outcomes import (
    OutcomeConfig,
    Outcomes,
    PosedSet,
    SurvivorTable,
    class_bits,
    generate_candidates,
    pose_hypotheses,
    predict_outcomes,
)
from planner.plans import REFINING, Plan, PlannedPath, opening_path
from planner.probes import opening_probe, strategy_paths
from planner.refine import refinement, scores_after
from planner.scoring import (
    FAMILIES,
    UNINFORMATIVE,
    InformationScores,
    combined_objective,
    information_scores,
    motion_cost,
)
from planner.search import Deadline, expected_remaining
from planner.survivors import pin_families, repeated_paths
from planner.types import (
    Contact,
    Hypothesis,
    ObjectModel,
    Observation,
    SensingPath,
    SensorBounds,
    Workspace,
)

__all__ = [
    "STRATEGIES",
    "Analysis",
    "Plan",
    "PlannedPath",
    "Ranking",
    "StrategyConfig",
    "analyse",
    "opening_path",
    "plan",
    "rank_candidates",
]

STRATEGIES = ("random", "thesis", "pdm", "pruning", "lookahead", "optimal")
THESIS_CHOICES = ("choose", "random")

#: Fewest candidates per block when a time budget splits the outcome passes, and
#: fewest candidates x hypotheses per block.
_BLOCK = 16
_BLOCK_ELEMENTS = 4096
#: Smallest share of the expected error disk a refining path must remove.
_REFINE_GAIN = 0.05


@dataclass(frozen=True)
class StrategyConfig:
    """How to plan: strategy `name`, lookahead `depth` (touches), `budget_ms`
    (None: unlimited; it covers the whole plan: candidates, outcomes, search),
    `optimal_max_classes` (the most classes ``optimal`` solves exactly, and the
    most for which strategies that do not search still score their paths `depth`
    touches deep), `max_paths` in the ranked list,
    `motion_weight` (touches per unit of motion length in the combined
    objective; 0 = motion only breaks ties), `random_draws` (origins drawn at
    once by ``random``), `grid_size` (B of the thesis' B x B grid),
    `thesis_choice` (how ``thesis`` picks among the windows of the lowest admitted
    strength: ``choose``, the nearest origin, as the thesis' hardware did (ch. 5),
    or ``random``, as its simulations did (§4.3.6)), and the candidate and outcome
    settings. `forecast` is how many of the ranked paths a session-aware caller
    has the recognition forecast (:mod:`planner.forecast`; 0: none)."""

    name: str = "lookahead"
    depth: int = 2
    budget_ms: float | None = 500.0
    optimal_max_classes: int = 12
    max_paths: int = 5
    motion_weight: float = 0.0
    random_draws: int = 16
    grid_size: int = 70
    thesis_choice: str = "choose"
    forecast: int = 1
    candidates: CandidateConfig = field(default_factory=CandidateConfig)
    outcome: OutcomeConfig = field(default_factory=OutcomeConfig)

    def __post_init__(self) -> None:
        if self.name not in STRATEGIES:
            raise PlannerError(
                f"unknown strategy; one of {list(STRATEGIES)}", field="strategy.name"
            )
        for name in ("depth", "max_paths", "random_draws", "grid_size"):
            if getattr(self, name) < 1:
                raise PlannerError("must be >= 1", field=f"strategy.{name}")
        if self.thesis_choice not in THESIS_CHOICES:
            raise PlannerError(
                f"must be one of {list(THESIS_CHOICES)}", field="strategy.thesis_choice"
            )
        if self.forecast < 0:
            raise PlannerError("must be >= 0", field="strategy.forecast")
        if self.optimal_max_classes < 1:
            raise PlannerError("must be >= 1", field="strategy.optimal_max_classes")
        if self.budget_ms is not None and not (
            self.budget_ms > 0 and math.isfinite(self.budget_ms)
        ):
            raise PlannerError("must be a finite number > 0", field="strategy.budget_ms")
        if not (math.isfinite(self.motion_weight) and self.motion_weight >= 0):
            raise PlannerError("must be a finite number >= 0", field="strategy.motion_weight")

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> StrategyConfig:
        """From the session's JSON, e.g. ``{"name": "lookahead", "depth": 2, "budget_ms": 500}``."""
        known = {f.name for f in fields(cls)}
        unknown = set(data) - known
        if unknown:
            raise PlannerError(f"unknown keys {sorted(unknown)}", field="strategy")
        values = dict(data)
        try:
            if isinstance(values.get("candidates"), Mapping):
                values["candidates"] = CandidateConfig(**values["candidates"])
            if isinstance(values.get("outcome"), Mapping):
                values["outcome"] = OutcomeConfig(**values["outcome"])
            return cls(**values)
        except TypeError as exc:  # unknown nested keys, or a value of the wrong type
            raise PlannerError(f"invalid strategy settings: {exc}", field="strategy") from exc


@dataclass(frozen=True, eq=False)
class Analysis:
    """Everything known about the candidates before a strategy chooses.

    `posed` hypotheses, `candidates` (C paths), their `outcomes`, the class
    survivor `table`, the information scores `info` and `motion` cost (C,);
    `truncated` when the time budget left candidates out."""

    posed: PosedSet
    candidates: Candidates
    outcomes: Outcomes
    table: SurvivorTable
    info: InformationScores
    motion: np.ndarray
    truncated: bool = False


@dataclass(frozen=True, eq=False)
class Ranking:
    """A strategy's answer: informative candidate indices, best first (`order`);
    `expected_remaining` (C,) with `exact` (C,) bool (a lower bound where not
    exact; inf where never scored); `truncated` when the budget stopped the
    search; `note` when the strategy deviated or found nothing."""

    order: np.ndarray
    expected_remaining: np.ndarray
    exact: np.ndarray
    truncated: bool = False
    note: str | None = None


def _rng(rng: np.random.Generator | int | None) -> np.random.Generator:
    return rng if isinstance(rng, np.random.Generator) else np.random.default_rng(rng or 0)


def _models(models: Mapping[str, ObjectModel] | Sequence[ObjectModel]) -> dict:
    return dict(models) if isinstance(models, Mapping) else {m.name: m for m in models}


def analyse(
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
    deadline: Deadline | None = None,
) -> Analysis:
    """Candidates (the strategy's own first, then `extra_paths`, then the general
    set), their predicted outcomes, survivor sets and scores (world frame).

    With a `deadline`, outcomes are worked out block by block of candidates and
    stop (`truncated`) once it passes; the first block is always done."""
    config = config or StrategyConfig()
    gen = _rng(rng)
    by_name = _models(models)
    posed = pose_hypotheses(hypotheses, by_name)
    contacts = [o.contact for o in observations if o.contact is not None]
    own = strategy_paths(
        config, hypotheses, by_name, posed, contacts, workspace, sensor, sensor_position, gen
    )
    cands = generate_candidates(
        posed,
        workspace,
        sensor,
        config.candidates,
        gen,
        sensor_position=sensor_position,
        extra=Candidates.concat([own, Candidates.from_paths(list(extra_paths))]),
    )
    fresh = np.flatnonzero(~repeated_paths(cands, observations, posed, sensor))
    if 0 < len(fresh) < len(cands):
        cands = cands.subset(fresh)
    outcomes: list[Outcomes] = []
    bits: list[np.ndarray] = []
    deadline = deadline or Deadline()
    # anytime: candidates in blocks, best first (the strategy's own, extra, general);
    # when the budget runs out, the blocks done so far are the candidates
    size = max(_BLOCK, _BLOCK_ELEMENTS // len(posed))
    block = len(cands) if deadline.end == np.inf else size
    for lo in range(0, max(len(cands), 1), max(block, 1)):
        if outcomes and deadline.expired():
            break
        part = cands.subset(np.arange(lo, min(lo + block, len(cands))))
        outcomes.append(
            predict_outcomes(
                posed, part.origins, part.directions, part.lengths, sensor, config.outcome
            )
        )
        bits.append(
            pin_families(
                hypotheses,
                posed,
                outcomes[-1],
                class_bits(posed, outcomes[-1], sensor, config.outcome),
                sensor,
            )
        )
    found = Outcomes.concat(outcomes)
    truncated = len(found.hit) < len(cands)
    cands = cands.subset(np.arange(len(found.hit)))
    table = SurvivorTable.from_bits(np.concatenate(bits), posed.class_weight)
    motion = motion_cost(cands.origins, found.travel @ posed.weight, workspace, sensor_position)
    info = information_scores(table)
    return Analysis(posed, cands, found, table, info, motion, truncated)


def rank_candidates(
    table: SurvivorTable,
    config: StrategyConfig | None = None,
    *,
    info: InformationScores | None = None,
    motion: np.ndarray | None = None,
    source: np.ndarray | None = None,
    tier: np.ndarray | None = None,
    rng: np.random.Generator | int | None = None,
    deadline: Deadline | None = None,
) -> Ranking:
    """Apply the configured strategy to an outcome matrix (C paths x K classes).

    `motion` (C,) defaults to zero; `source` (C,) names each candidate's origin
    (``random`` draws and thesis ``probe``/``window`` rows are what those
    strategies pick from) and `tier` (C,) their rank (the windows' level, default
    0); `deadline` bounds the search. Expected remaining
    touches are computed for the first `max_paths` of the order when the
    strategy did not compute them itself (``random``, ``thesis``, ``pdm``,
    ``pruning``): searched `depth` touches deep when there are at most
    `optimal_max_classes` classes, else one touch deep, the bound
    ``(1 + w(open)) / (1 - w(stay))`` that lower-bounds the deeper value.
    """
    config = config or StrategyConfig()
    n = table.n_paths
    ctx = _Context(
        config,
        table,
        info if info is not None else information_scores(table),
        np.zeros(n) if motion is None else np.asarray(motion, dtype=float),
        np.full(n, "", dtype="<U12") if source is None else np.asarray(source),
        np.zeros(n, dtype=int) if tier is None else np.asarray(tier, dtype=int),
        _rng(rng),
        deadline or Deadline.after_ms(config.budget_ms),
    )
    ranking = _STRATEGIES[config.name](ctx)
    if ranking.note is None and not len(ranking.order):
        ranking = Ranking(
            ranking.order,
            ranking.expected_remaining,
            ranking.exact,
            False,
            f"no informative path among {n} candidates",
        )
    top = ranking.order[: config.max_paths]
    if len(top) and not ranking.exact[top].all():
        # strategies that do not search: `depth` deep on small sets, else one touch deep
        depth = config.depth if table.n_classes <= config.optimal_max_classes else 1
        result = expected_remaining(table, depth, paths=top, deadline=ctx.deadline)
        value = np.where(ranking.exact, ranking.expected_remaining, result.value)
        exact = ranking.exact | result.exact
        return Ranking(
            ranking.order, value, exact, ranking.truncated or result.truncated, ranking.note
        )
    return ranking


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
) -> Plan:
    """Rank the next sensing paths for a hypothesis set (world frame).

    `hypotheses` carry probabilities (normalized here) and equivalence classes;
    `observations` (the session's, in order) tell whether anything was touched
    yet and give the contacts the thesis opening needs; `extra_paths` join the
    candidates; `rng` (or a seed; default 0) drives the random choices. The
    time budget (`config.budget_ms`) covers the whole call.

    With no hypothesis and no contact the plan is the opening probe (status
    ``awaiting_contact``); with one class left it is empty (``localized``);
    with contacts but no hypothesis, empty (``inconsistent``); otherwise the
    ranked informative paths (``ambiguous``), empty with a note when no
    candidate is informative.
    """
    start = time.perf_counter()
    config = config or StrategyConfig()
    gen = _rng(rng)
    deadline = Deadline.after_ms(config.budget_ms)
    contacts = [o.contact for o in observations if o.contact is not None]

    def finish(status: str, paths: Sequence[PlannedPath], **kw: Any) -> Plan:
        elapsed = (time.perf_counter() - start) * 1000.0
        return Plan(status, kw.pop("truncated", False), elapsed, tuple(paths), config.name, **kw)

    if not hypotheses:
        if contacts:
            return finish("inconsistent", (), note="no hypothesis explains the contacts")
        missed = [o.path for o in observations]
        probe = opening_probe(config, _models(models), workspace, sensor_position, missed, gen)
        return finish("awaiting_contact", (probe,))
    classes = len({h.equivalence_class for h in hypotheses})
    if classes == 1:
        return finish("localized", (), classes=1)
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
        deadline=deadline,
    )
    ranking = rank_candidates(
        found.table,
        config,
        info=found.info,
        motion=found.motion,
        source=found.candidates.source,
        tier=found.candidates.tier,
        rng=gen,
        deadline=deadline,
    )
    paths = [_planned(found, int(i), ranking) for i in ranking.order[: config.max_paths]]
    note = ranking.note
    if not paths:
        paths, note = _refining(
            found, hypotheses, _models(models), contacts, sensor, ranking, config
        )
    if not paths and config.name == "thesis":
        paths, note = _thesis_window(found, ranking, config, gen, note)
    if found.truncated:
        note = "; ".join(filter(None, [note, "candidates cut at the time budget"]))
    return finish(
        "ambiguous",
        paths,
        truncated=ranking.truncated or found.truncated,
        note=note,
        candidates=len(found.candidates),
        classes=found.table.n_classes,
    )


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
    return [_planned(found, int(windows[0]), ranking)], "; ".join(filter(None, [note, said]))


def _refining(
    found: Analysis,
    hypotheses: Sequence[Hypothesis],
    models: Mapping[str, ObjectModel],
    contacts: Sequence[Contact],
    sensor: SensorBounds,
    ranking: Ranking,
    config: StrategyConfig,
) -> tuple[list[PlannedPath], str | None]:
    """No informative path: the paths that shrink the expected error disk most
    (at least by `_REFINE_GAIN` of it), with a note saying so. Their scores are
    those of the outcome model with the disks each class is predicted to have
    once the touch is made (with today's disks every outcome is confusable)."""
    refine = refinement(hypotheses, models, found.posed, found.outcomes, contacts, sensor)
    gain = refine.current - refine.expected
    ok = np.flatnonzero(gain > _REFINE_GAIN * refine.current)
    if not len(ok):
        return [], ranking.note
    order = ok[np.lexsort((found.motion[ok], refine.expected[ok]))][: config.max_paths]
    paths = []
    for i in order:
        info = scores_after(
            hypotheses, found.posed, refine, found.candidates, int(i), sensor, config.outcome
        )
        paths.append(
            _planned(
                found,
                int(i),
                ranking,
                family=REFINING,
                expected_eps_t=refine.expected[i],
                scores=(info, 0),
            )
        )
    note = (
        f"{ranking.note}: refining the pose instead "
        f"(expected error disk {refine.current:.3g} -> {refine.expected[order[0]]:.3g})"
    )
    return paths, note


def _planned(
    found: Analysis,
    i: int,
    ranking: Ranking,
    family: str | None = None,
    expected_eps_t: float | None = None,
    scores: tuple[InformationScores, int] | None = None,
) -> PlannedPath:
    """Candidate `i` as a planned path; `scores` (information scores, row) replace
    the analysis' own for that path."""
    c = found.candidates
    info, j = scores if scores is not None else (found.info, i)
    return PlannedPath(
        origin=(float(c.origins[i, 0]), float(c.origins[i, 1])),
        direction=(float(c.directions[i, 0]), float(c.directions[i, 1])),
        length=float(c.lengths[i]),
        aim=(float(c.aims[i, 0]), float(c.aims[i, 1])),
        family=family or FAMILIES[int(info.family[j])],
        p_distinguishing=float(info.p_distinguishing[j]),
        p_informative=float(info.p_informative[j]),
        expected_pruning=float(info.expected_pruning[j]),
        expected_remaining=float(ranking.expected_remaining[i]),
        motion_cost=float(found.motion[i]),
        source=str(c.source[i]),
        expected_eps_t=None if expected_eps_t is None else float(expected_eps_t),
    )


@dataclass(frozen=True, eq=False)
class _Context:
    config: StrategyConfig
    table: SurvivorTable
    info: InformationScores
    motion: np.ndarray
    source: np.ndarray
    tier: np.ndarray
    rng: np.random.Generator
    deadline: Deadline


def _informative(ctx: _Context, rows: np.ndarray | None = None) -> np.ndarray:
    rows = np.arange(ctx.table.n_paths) if rows is None else rows
    return rows[ctx.info.family[rows] != UNINFORMATIVE]


def _unscored(ctx: _Context, order: np.ndarray, note: str | None = None) -> Ranking:
    n = ctx.table.n_paths
    return Ranking(order, np.full(n, np.inf), np.zeros(n, dtype=bool), False, note)


def _pdm(ctx: _Context) -> Ranking:
    ok, info = _informative(ctx), ctx.info
    # cost = (1 - P(DM)) + motion_weight * motion_cost
    cost = combined_objective(1.0 - info.p_distinguishing, ctx.motion, ctx.config.motion_weight)
    keys = (ctx.motion[ok], -info.expected_pruning[ok], -info.p_informative[ok], cost[ok])
    return _unscored(ctx, ok[np.lexsort(keys)])


def _pruning(ctx: _Context) -> Ranking:
    ok, info = _informative(ctx), ctx.info
    # cost = -expected pruning + motion_weight * motion_cost
    cost = combined_objective(-info.expected_pruning, ctx.motion, ctx.config.motion_weight)
    return _unscored(ctx, ok[np.lexsort((ctx.motion[ok], -info.p_distinguishing[ok], cost[ok]))])


def _lookahead(ctx: _Context, depth: int | None = None, note: str | None = None) -> Ranking:
    ok = _informative(ctx)
    result = expected_remaining(
        ctx.table,
        depth,
        paths=ok,
        top_k=ctx.config.max_paths,
        extra_cost=ctx.config.motion_weight * ctx.motion,
        deadline=ctx.deadline,
    )
    # cost = E_P + motion_weight * motion_cost; exact values rank before bounds
    cost = combined_objective(result.value, ctx.motion, ctx.config.motion_weight)
    keys = (ctx.motion[ok], -ctx.info.p_distinguishing[ok], cost[ok], ~result.exact[ok])
    if result.truncated:
        note = "; ".join(filter(None, [note, "search stopped at the time budget"]))
    return Ranking(ok[np.lexsort(keys)], result.value, result.exact, result.truncated, note)


def _depth_lookahead(ctx: _Context) -> Ranking:
    return _lookahead(ctx, ctx.config.depth)


def _optimal(ctx: _Context) -> Ranking:
    k, limit = ctx.table.n_classes, ctx.config.optimal_max_classes
    if k <= limit:
        return _lookahead(ctx, None)  # no depth limit: the exact DP over survivor sets
    note = f"optimal played lookahead (depth {ctx.config.depth}): {k} classes > {limit}"
    return _lookahead(ctx, ctx.config.depth, note)


def _random(ctx: _Context) -> Ranking:
    drawn = _informative(ctx, np.flatnonzero(ctx.source == "random"))
    if len(drawn):
        return _unscored(ctx, drawn)
    ok = _informative(ctx)
    if not len(ok):
        return _unscored(ctx, ok)
    pick = ok[ctx.rng.integers(len(ok))]
    return _unscored(ctx, np.array([pick]), "no informative random draw: a random candidate")


def _thesis(ctx: _Context) -> Ranking:
    for kind in ("probe", "random"):
        rows = _informative(ctx, np.flatnonzero(ctx.source == kind))
        if len(rows):
            return _unscored(ctx, rows)
    # windows come in CHOOSE order (lowest admitted strength, then nearest origin)
    rows = _informative(ctx, np.flatnonzero(ctx.source == "window"))
    if len(rows) and ctx.config.thesis_choice == "random":
        # §4.3.6: "at random from among the most highly diagnostic family of paths"
        family = ctx.tier[rows] == ctx.tier[rows].min()
        rows = np.concatenate([ctx.rng.permutation(rows[family]), rows[~family]])
    if len(rows):
        return _unscored(ctx, rows)
    fallback = _pdm(ctx)
    note = (
        "no informative thesis window: best P(DM) among all candidates"
        if len(fallback.order)
        else None
    )
    return _unscored(ctx, fallback.order, note)


_STRATEGIES: dict[str, Callable[[_Context], Ranking]] = {
    "random": _random,
    "thesis": _thesis,
    "pdm": _pdm,
    "pruning": _pruning,
    "lookahead": _depth_lookahead,
    "optimal": _optimal,
}
