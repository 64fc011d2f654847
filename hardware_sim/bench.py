"""Recognition benchmark (DESIGN §9): hypotheses left after random touches, and the
time of one observation update, for fixed seeded scenarios."""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

from hardware_sim.world import random_world
from planner.session import Session
from planner.types import ObjectModel, SensorBounds, Workspace

__all__ = ["RecognitionStats", "recognition_stats"]


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
) -> RecognitionStats:
    """Random true objects touched along random paths aimed at them."""
    rng = np.random.default_rng(seed)
    counts = np.zeros((trials, touches))
    classes = np.zeros((trials, touches))
    times: list[float] = []
    for trial in range(trials):
        world = random_world(models, workspace, rng)
        session = Session(models, bounds, workspace)
        for k in range(touches):
            obs, _ = world.execute(world.hitting_path(rng), bounds, rng)
            start = time.perf_counter()
            session = session.observe(obs)
            hyps = session.hypotheses
            times.append(time.perf_counter() - start)
            counts[trial, k] = len(hyps)
            classes[trial, k] = len({h.equivalence_class for h in hyps})
    return RecognitionStats(
        hypotheses=tuple(float(v) for v in counts.mean(axis=0)),
        classes=tuple(float(v) for v in classes.mean(axis=0)),
        update_p50_ms=1e3 * float(np.percentile(times, 50)),
        update_p95_ms=1e3 * float(np.percentile(times, 95)),
        trials=trials,
    )


def default_bounds() -> list[SensorBounds]:
    """Exact measurements and the (1 length unit, 3 degree) error case."""
    return [SensorBounds(0.0, 0.0), SensorBounds(1.0, math.radians(3.0))]
