"""Benchmarks (DESIGN §9) for fixed seeded scenarios: hypotheses left after random
touches and the time of one observation update (recognition), the update time
against the number of earlier observations (growth), and the time and work of one
plan per strategy after 0, 1, 2, ... touches (planning)."""

from __future__ import annotations

import math
import time
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from hardware_sim.world import random_world
from planner.planning.config import StrategyConfig
from planner.planning.plan import plan_session
from planner.recognition.session import Session
from planner.types import ObjectModel, SensorBounds, Workspace

__all__ = [
    "PlanningStats",
    "RecognitionStats",
    "default_bounds",
    "planning_stats",
    "recognition_stats",
    "update_growth",
]


@dataclass(frozen=True)
class RecognitionStats:
    """Means over trials after 1, 2, ... touches, and update-time percentiles (ms)."""

    hypotheses: tuple[float, ...]
    classes: tuple[float, ...]
    update_p50_ms: float
    update_p95_ms: float
    trials: int


def recognition_stats(
    models: list[ObjectModel],
    bounds: SensorBounds,
    workspace: Workspace,
    trials: int = 50,
    touches: int = 3,
    seed: int = 0,
    repeat: int = 1,
) -> RecognitionStats:
    """Random true objects touched along random paths aimed at them. With `repeat`
    > 1 each trial's touches are replayed in that many fresh sessions (its first
    update building the session's tables each time) and each update keeps its
    shortest time: what other jobs on the machine add is left out."""
    rng = np.random.default_rng(seed)
    counts = np.zeros((trials, touches))
    classes = np.zeros((trials, touches))
    times = np.full((trials, touches), np.inf)
    for trial in range(trials):
        world = random_world(models, workspace, rng)
        touched = [world.execute(world.hitting_path(rng), bounds, rng)[0] for _ in range(touches)]
        for _ in range(max(1, repeat)):
            session = Session(models, bounds, workspace)
            for k, obs in enumerate(touched):
                start = time.perf_counter()
                session = session.observe(obs)
                hyps = session.hypotheses
                times[trial, k] = min(times[trial, k], time.perf_counter() - start)
                counts[trial, k] = len(hyps)
                classes[trial, k] = len({h.equivalence_class for h in hyps})
    return RecognitionStats(
        hypotheses=tuple(float(v) for v in counts.mean(axis=0)),
        classes=tuple(float(v) for v in classes.mean(axis=0)),
        update_p50_ms=1e3 * float(np.percentile(times, 50)),
        update_p95_ms=1e3 * float(np.percentile(times, 95)),
        trials=trials,
    )


def update_growth(
    models: list[ObjectModel],
    bounds: SensorBounds,
    workspace: Workspace,
    touches: int = 40,
    trials: int = 2,
    seed: int = 0,
) -> dict[int, float]:
    """The median time (ms) of the n-th observation update of a long session, for n
    in 1, 2, 5, 10, 20, 40 (up to `touches`): random paths aimed at the object,
    kept touching after it is localized (as a robot checking its work would)."""
    rng = np.random.default_rng(seed)
    times = np.zeros((trials, touches))
    for trial in range(trials):
        world = random_world(models, workspace, rng)
        session = Session(models, bounds, workspace)
        for k in range(touches):
            obs, _ = world.execute(world.hitting_path(rng), bounds, rng)
            start = time.perf_counter()
            session = session.observe(obs)
            session.hypotheses  # noqa: B018 - the update is the derivation
            times[trial, k] = 1e3 * (time.perf_counter() - start)
    marks = [n for n in (1, 2, 5, 10, 20, 40) if n <= touches]
    return {n: float(np.median(times[:, n - 1])) for n in marks}


@dataclass(frozen=True)
class PlanningStats:
    """One plan per trial and strategy after `touches` random touches: means and
    largest of the hypothesis, class and candidate counts, and per strategy the
    plan-time percentiles (ms, wall clock, the median of `repeat` runs of each
    plan), the share of plans the budget cut short (`truncated`), the mean work
    spent (units, :mod:`planner.planning.budget`) and the share of plans the
    wall-clock cap stopped (`capped`: only these depend on the machine)."""

    touches: int
    trials: int
    hypotheses: float
    hypotheses_max: int
    classes: float
    candidates: float
    candidates_max: int
    p50_ms: dict[str, float]
    p95_ms: dict[str, float]
    truncated: dict[str, float]
    work: dict[str, float]
    capped: dict[str, float]


def planning_stats(
    models: list[ObjectModel],
    bounds: SensorBounds,
    workspace: Workspace,
    strategies: Sequence[str] = ("pdm", "pruning", "lookahead"),
    trials: int = 10,
    touches: int = 3,
    seed: int = 0,
    repeat: int = 1,
) -> list[PlanningStats]:
    """Plan times after 0, 1, ..., `touches` random touches of random true objects,
    each strategy at its default settings (sensor at the safe circle's +x point), as
    the service plans: :func:`~planner.planning.plan.plan_session`, its forecast and
    the recognition's predictions included.

    >>> from planner.models.library import object_from_dict
    >>> sq = object_from_dict({"name": "sq", "outline": [[-9, -9], [9, -9], [9, 9], [-9, 9]]})
    >>> rows = planning_stats([sq], SensorBounds(), Workspace((0, 0), 50), ["pdm"], 1, 1)
    >>> [r.touches for r in rows], rows[0].hypotheses
    ([0, 1], 0.0)
    """
    rng = np.random.default_rng(seed)
    where = (workspace.center[0] + workspace.radius, workspace.center[1])
    configs = {name: StrategyConfig(name=name) for name in strategies}
    shape = (touches + 1, trials)
    hyps, classes, cands = (np.zeros(shape, dtype=int) for _ in range(3))
    times = {name: np.zeros(shape) for name in strategies}
    cut = {name: np.zeros(shape, dtype=bool) for name in strategies}
    work = {name: np.zeros(shape) for name in strategies}
    capped = {name: np.zeros(shape, dtype=bool) for name in strategies}
    for trial in range(trials):
        world = random_world(models, workspace, rng)
        session = Session(models, bounds, workspace)
        for k in range(touches + 1):
            if k:
                obs, _ = world.execute(world.hitting_path(rng), bounds, rng)
                session = session.observe(obs)
            found = session.hypotheses
            hyps[k, trial] = len(found)
            classes[k, trial] = len({h.equivalence_class for h in found})
            for name, config in configs.items():
                runs = []
                for _ in range(repeat):
                    start = time.perf_counter()
                    result = plan_session(session, where, config, seed + trial)
                    runs.append(1e3 * (time.perf_counter() - start))
                times[name][k, trial] = float(np.median(runs))
                cut[name][k, trial] = result.truncated
                work[name][k, trial] = result.work
                capped[name][k, trial] = result.stopped_by == "time"
                # the candidates analysed (fewer when the budget cut the analysis)
                cands[k, trial] = max(cands[k, trial], result.candidates)
    return [
        PlanningStats(
            touches=k,
            trials=trials,
            hypotheses=float(hyps[k].mean()),
            hypotheses_max=int(hyps[k].max(initial=0)),
            classes=float(classes[k].mean()),
            candidates=float(cands[k].mean()),
            candidates_max=int(cands[k].max(initial=0)),
            p50_ms={n: float(np.percentile(times[n][k], 50)) for n in strategies},
            p95_ms={n: float(np.percentile(times[n][k], 95)) for n in strategies},
            truncated={n: float(cut[n][k].mean()) for n in strategies},
            work={n: float(work[n][k].mean()) for n in strategies},
            capped={n: float(capped[n][k].mean()) for n in strategies},
        )
        for k in range(touches + 1)
    ]


def default_bounds() -> list[SensorBounds]:
    """Exact measurements and the (1 length unit, 3 degree) error case."""
    return [SensorBounds(0.0, 0.0), SensorBounds(1.0, math.radians(3.0))]
