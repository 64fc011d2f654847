"""Experiments: many seeded recognitions per strategy, the thesis' Table 4.1 layout.

One trial = a random true object (or the given one), stable pose (by its
probability) and pose (uniform orientation, position inside the safe circle),
recognized by the closed loop of :mod:`hardware_sim.client` with the arm and
sensor of a preset. Trial ``i`` uses the same world and the same hardware noise
streams for every strategy (seeds derived from ``(seed, i)``), so strategies are
compared on identical cases, and results do not depend on how trials are batched
or on the number of workers, nor on the machine's load: the planner's budget is
counted in work (`budget_work`); only its wall-clock cap (`budget_ms`), when it
bites, depends on the machine's speed (the trial's plans then say
``stopped_by: "time"``).

Each trial's result (:class:`TrialResult`) says how many touches it took, whether
it ended localized on the right object and pose, and the planning time per step;
:mod:`hardware_sim.summary` turns them into the Table 4.1 rows.

Parallel: joblib (loky processes) by default, trials batched per task; a Dask
cluster with ``dask=ADDRESS`` (``dask.distributed`` imported only then).
"""

from __future__ import annotations

import functools
import math
import os
import signal
import threading
from collections.abc import Callable, Iterable, Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from hardware_sim.client import InProcessService, outline_distance, run_recognition
from hardware_sim.presets import PRESETS, Preset, build_arm
from hardware_sim.world import PLACEMENTS, World, random_world
from planner.planning.config import STRATEGIES, StrategyConfig
from planner.recognition.config import RecognitionConfig
from planner.types import ObjectModel, PosePrior, Workspace
from planner.warmup import warm_up

__all__ = ["ExperimentSpec", "TrialResult", "run_experiment", "run_trial"]


Progress = Callable[[int, int], None]


@dataclass(frozen=True, eq=False)
class ExperimentSpec:
    """Everything a trial needs (picklable: it is shipped to workers).

    `models` the object set the planner knows; `truth` the name of the true
    object (None: drawn by the objects' priors); `preset` the hardware (its
    bounds configure the planner); `workspace` the safe circle; `strategy`
    extra :class:`StrategyConfig` fields shared by all strategies (e.g.
    ``{"budget_ms": None, "budget_work": None}``); `pose_slack` (length) added to the error
    bound the session answers with (its most probable class', which covers every member's)
    when judging the pose; `trial_timeout` (s of wall time, None: no
    limit) ends a trial as status ``timeout`` (unlocalized, no steps kept).
    `prior_radius` (length) and `prior_theta` (radians, half-width) give each trial
    a pose prior drawn around its world, the truth uniform inside it
    (:func:`trial_prior`)."""

    models: tuple[ObjectModel, ...]
    strategies: tuple[str, ...]
    trials: int
    seed: int = 0
    preset: Preset = field(default_factory=lambda: PRESETS["ideal"])
    max_touches: int = 20
    workspace: Workspace = field(default_factory=lambda: Workspace((0.0, 0.0), 200.0))
    truth: str | None = None
    strategy: dict[str, Any] = field(default_factory=dict)
    pose_slack: float = 1e-6
    trial_timeout: float | None = None
    placement: str = "anywhere"
    recognition: dict[str, Any] = field(default_factory=dict)
    prior_radius: float | None = None
    prior_theta: float | None = None

    def __post_init__(self) -> None:
        unknown = [s for s in self.strategies if s not in STRATEGIES]
        if unknown:
            raise ValueError(f"unknown strategy {unknown}; one of {list(STRATEGIES)}")
        if self.truth is not None and self.truth not in {m.name for m in self.models}:
            raise ValueError(f"--truth {self.truth!r} is not an object of the set")
        if self.trials < 1 or self.max_touches < 1:
            raise ValueError("trials and max_touches must be >= 1")
        if self.placement not in PLACEMENTS:
            raise ValueError(f"--placement must be one of {list(PLACEMENTS)}")
        RecognitionConfig(**self.recognition)  # refuses unknown or invalid settings
        for name in ("prior_radius", "prior_theta"):
            value = getattr(self, name)
            if value is not None and not (math.isfinite(value) and value > 0):
                raise ValueError(f"--{name.replace('_', '-')} must be a finite number > 0")


@dataclass(frozen=True)
class TrialResult:
    """One recognition: `touches` executed, final `status`, `success`, the pose
    error (Hausdorff distance of posed vertex sets, length; inf when wrong),
    per-step planning time (ms), predicted P(DM) by the outcome model and by the
    recognition's forecast (None for the opening probe, or not forecast) and
    whether the step was distinguishing, the rig's travel, per step what
    ended its plan early (``"work"``, ``"time"`` or None), and per step the
    best path's `expected_remaining` (None where unknown) and whether the plan's
    search was `truncated`."""

    strategy: str
    trial: int
    truth: str
    touches: int
    status: str
    success: bool
    pose_error: float
    plan_ms: tuple[float, ...]
    p_distinguishing: tuple[float | None, ...]
    p_forecast: tuple[float | None, ...]
    distinguishing: tuple[bool, ...]
    distance: float
    time: float
    stopped_by: tuple[str | None, ...] = ()
    expected_remaining: tuple[float | None, ...] = ()
    truncated: tuple[bool, ...] = ()

    @property
    def localized(self) -> bool:
        return self.status == "localized"


def _seed(spec: ExperimentSpec, trial: int, stream: int) -> np.random.SeedSequence:
    # one independent stream per (trial, purpose): 0 world, 1 hardware, 2 planner
    return np.random.SeedSequence(spec.seed, spawn_key=(trial, stream))


def trial_prior(
    spec: ExperimentSpec, world: World, seed: np.random.SeedSequence
) -> PosePrior | None:
    """The pose prior of a trial (None without `prior_radius` and `prior_theta`): a
    region of `prior_radius` whose centre lies uniformly within that distance of the
    true centroid, and a rotation range of half-width `prior_theta` whose middle lies
    uniformly within it of the true rotation: as a fixture or a camera would give."""
    if spec.prior_radius is None and spec.prior_theta is None:
        return None
    rng = np.random.default_rng(seed)
    center = radius = theta = None
    if spec.prior_radius is not None:
        stable = world.model.stable_poses[world.pose_index]
        c = world.pose.apply(np.asarray(stable.centroid, dtype=float)[None])[0]
        r, a = spec.prior_radius * math.sqrt(rng.random()), rng.uniform(-math.pi, math.pi)
        center = (float(c[0] + r * math.cos(a)), float(c[1] + r * math.sin(a)))
        radius = float(spec.prior_radius)
    if spec.prior_theta is not None:
        mid = world.pose.theta + rng.uniform(-spec.prior_theta, spec.prior_theta)
        theta = (float(mid - spec.prior_theta), float(mid + spec.prior_theta))
    return PosePrior(center, radius, theta)


def run_trial(spec: ExperimentSpec, strategy: str, trial: int) -> TrialResult:
    """Recognize the world of trial `trial` with `strategy` (deterministic given
    the spec, unless the planner's time budget binds)."""
    models = list(spec.models)
    candidates = [m for m in models if m.name == spec.truth] if spec.truth else models
    world_rng = np.random.default_rng(_seed(spec, trial, 0))
    world = random_world(candidates, spec.workspace, world_rng, spec.placement)
    arm = build_arm(world, spec.preset, _seed(spec, trial, 1))
    config = StrategyConfig.from_dict({**spec.strategy, "name": strategy})
    service = InProcessService(
        models,
        spec.preset.bounds,
        spec.workspace,
        config,
        RecognitionConfig(
            **spec.recognition, prior=trial_prior(spec, world, _seed(spec, trial, 3))
        ),
        rng=np.random.default_rng(_seed(spec, trial, 2)),
    )
    try:
        with _time_limit(spec.trial_timeout):
            rec = run_recognition(service, arm, spec.max_touches)
    except _TrialTimeoutError:
        return TrialResult(
            strategy,
            trial,
            world.model.name,
            0,
            "timeout",
            False,
            math.inf,
            (),
            (),
            (),
            (),
            0.0,
            0.0,
        )
    error = math.inf
    success = False
    if rec.status == "localized" and rec.estimates:
        best = rec.estimates[0]
        error = outline_distance(models, best, world.model.name, world.pose_index, world.pose)
        # the bound the session answers with: its class', which covers every member's
        reported = best.eps_t if rec.bound is None else rec.bound
        success = error <= reported / 2 + spec.pose_slack
    return TrialResult(
        strategy=strategy,
        trial=trial,
        truth=world.model.name,
        touches=rec.touches,
        status=rec.status,
        success=bool(success),
        pose_error=error,
        plan_ms=tuple(s.advice.plan_ms for s in rec.steps),
        stopped_by=tuple(s.advice.stopped_by for s in rec.steps),
        p_distinguishing=tuple(s.advice.p_distinguishing for s in rec.steps),
        p_forecast=tuple(s.advice.p_forecast for s in rec.steps),
        distinguishing=tuple(s.distinguishing for s in rec.steps),
        expected_remaining=tuple(s.advice.expected_remaining for s in rec.steps),
        truncated=tuple(s.advice.truncated for s in rec.steps),
        distance=rec.distance,
        time=rec.time,
    )


class _TrialTimeoutError(Exception):
    pass


#: How soon a trial's time limit is raised again when the first raise was lost.
_RETRY_S = 0.05


@contextmanager
def _time_limit(seconds: float | None) -> Iterator[None]:
    """Raise _TrialTimeoutError after `seconds` of wall time (SIGALRM; only in a
    process's main thread on POSIX, elsewhere no limit). The signal is handled
    between Python bytecodes, so one long C call overruns the limit. The alarm
    repeats every `_RETRY_S` until the block ends: an exception raised while a
    garbage-collector callback or a finalizer runs is swallowed there."""
    usable = (
        seconds is not None
        and hasattr(signal, "setitimer")
        and threading.current_thread() is threading.main_thread()
    )
    if not usable:
        yield
        return

    def expire(signum: int, frame: object) -> None:
        raise _TrialTimeoutError

    previous = signal.signal(signal.SIGALRM, expire)
    signal.setitimer(signal.ITIMER_REAL, float(seconds or 0.0), _RETRY_S)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)


def run_batch(spec: ExperimentSpec, tasks: Sequence[tuple[str, int]]) -> list[TrialResult]:
    """Several (strategy, trial) tasks in one worker call, the planner's compiled
    kernels loaded first (once per process): their loading, or their build on a
    fresh installation, must not fall inside a trial's plan and its wall-clock cap."""
    _warm_once()
    return [run_trial(spec, s, t) for s, t in tasks]


@functools.cache
def _warm_once() -> None:
    warm_up()


def _batches(spec: ExperimentSpec, workers: int) -> list[list[tuple[str, int]]]:
    tasks = [(s, t) for t in range(spec.trials) for s in spec.strategies]
    # about 4 batches per worker for load balance, at most 16 trials per batch
    size = max(1, min(16, math.ceil(len(tasks) / (4 * max(workers, 1)))))
    return [tasks[i : i + size] for i in range(0, len(tasks), size)]


def run_experiment(
    spec: ExperimentSpec,
    workers: int | None = None,
    dask_address: str | None = None,
    progress: Progress | None = None,
) -> list[TrialResult]:
    """All trials of all strategies, sorted by (strategy order, trial).

    `workers`: joblib processes (None: all cores; 1: in this process).
    `dask_address`: run the batches on that Dask scheduler instead.
    `progress(done, total)` is called as trials finish.
    """
    workers = workers or os.cpu_count() or 1
    batches = _batches(spec, workers)
    total = spec.trials * len(spec.strategies)
    done = 0
    results: list[TrialResult] = []

    def collect(batch: Iterable[TrialResult]) -> None:
        nonlocal done
        part = list(batch)
        results.extend(part)
        done += len(part)
        if progress is not None:
            progress(done, total)

    if dask_address is not None:
        for part in _dask_map(spec, batches, dask_address):
            collect(part)
    elif workers == 1:
        for batch in batches:
            collect(run_batch(spec, batch))
    else:
        from joblib import Parallel, delayed

        parallel = Parallel(n_jobs=workers, return_as="generator_unordered")
        for part in parallel(delayed(run_batch)(spec, b) for b in batches):
            collect(part)
    order = {s: i for i, s in enumerate(spec.strategies)}
    return sorted(results, key=lambda r: (order[r.strategy], r.trial))


def _dask_map(
    spec: ExperimentSpec, batches: list[list[tuple[str, int]]], address: str
) -> Iterable[list[TrialResult]]:
    try:
        from dask.distributed import Client, as_completed
    except ImportError as exc:
        raise RuntimeError(
            "--dask needs the dask.distributed package: pip install 'dask[distributed]'"
        ) from exc
    with Client(address) as client:
        spec_future = client.scatter(spec, broadcast=True)
        futures = [client.submit(run_batch, spec_future, b, pure=False) for b in batches]
        for future in as_completed(futures):
            yield future.result()
