"""Experiments: many seeded recognitions per strategy, the thesis' Table 4.1 layout.

One trial = a random true object (or the given one), stable pose (by its
probability) and pose (uniform orientation, position inside the safe circle),
recognized by the closed loop of :mod:`hardware_sim.client` with the arm and
sensor of a preset. Trial ``i`` uses the same world and the same hardware noise
streams for every strategy (seeds derived from ``(seed, i)``), so strategies are
compared on identical cases, and results do not depend on how trials are batched
or on the number of workers (as long as the planner's time budget does not bind:
strategies whose search stops at `budget_ms` depend on the machine's speed).

Per strategy: the share of trials needing 1, 2, ..., 10 and more than 10 touches
(unlocalized trials count as "> 10"), mean and max touches (an unlocalized trial
is charged `max_touches`), success rate (localized, right object and pose within
the hypothesis' own error bound), and planning time per step.

Parallel: joblib (loky processes) by default, trials batched per task; a Dask
cluster with ``dask=ADDRESS`` (``dask.distributed`` imported only then).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import signal
import sys
import threading
from collections.abc import Callable, Iterable, Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from hardware_sim.client import InProcessService, outline_distance, run_recognition
from hardware_sim.presets import PRESETS, Preset, build_arm, explicit_preset, resolve_preset
from hardware_sim.world import PLACEMENTS, random_world
from planner.errors import PlannerError
from planner.interpretation import RecognitionConfig
from planner.strategies import STRATEGIES, THESIS_CHOICES, StrategyConfig
from planner.types import ObjectModel, Workspace

__all__ = [
    "BINS",
    "ExperimentSpec",
    "StrategySummary",
    "TrialResult",
    "add_simulate_command",
    "histogram",
    "run_experiment",
    "run_trial",
    "summarize",
]

#: Table 4.1 columns: 1, 2, ..., 10 touches, then more than 10.
BINS = (*(str(k) for k in range(1, 11)), ">10")

Progress = Callable[[int, int], None]


@dataclass(frozen=True, eq=False)
class ExperimentSpec:
    """Everything a trial needs (picklable: it is shipped to workers).

    `models` the object set the planner knows; `truth` the name of the true
    object (None: drawn by the objects' priors); `preset` the hardware (its
    bounds configure the planner); `workspace` the safe circle; `strategy`
    extra :class:`StrategyConfig` fields shared by all strategies (e.g.
    ``{"budget_ms": None}``); `pose_slack` (length) added to the hypothesis'
    error bound when judging the pose; `trial_timeout` (s of wall time, None: no
    limit) ends a trial as status ``timeout`` (unlocalized, no steps kept)."""

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


@dataclass(frozen=True)
class TrialResult:
    """One recognition: `touches` executed, final `status`, `success`, the pose
    error (Hausdorff distance of posed vertex sets, length; inf when wrong),
    per-step planning time (ms), predicted P(DM) by the outcome model and by the
    recognition's forecast (None for the opening probe, or not forecast) and
    whether the step was distinguishing, and the rig's travel."""

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

    @property
    def localized(self) -> bool:
        return self.status == "localized"


@dataclass(frozen=True)
class StrategySummary:
    """One row of the Table 4.1 analog (shares in [0, 1], times in ms)."""

    strategy: str
    trials: int
    histogram: dict[str, float]
    mean_touches: float
    max_touches: int
    success_rate: float
    mean_plan_ms: float
    p95_plan_ms: float

    def as_dict(self) -> dict[str, Any]:
        """The ``tactile simulate --json`` form of one strategy (DESIGN §7)."""
        return {
            "strategy": self.strategy,
            "trials": self.trials,
            "histogram": dict(self.histogram),
            "mean_touches": self.mean_touches,
            "max_touches": self.max_touches,
            "success_rate": self.success_rate,
            "mean_plan_ms": self.mean_plan_ms,
            "p95_plan_ms": self.p95_plan_ms,
        }


def _seed(spec: ExperimentSpec, trial: int, stream: int) -> np.random.SeedSequence:
    # one independent stream per (trial, purpose): 0 world, 1 hardware, 2 planner
    return np.random.SeedSequence(spec.seed, spawn_key=(trial, stream))


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
        RecognitionConfig(**spec.recognition),
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
        success = error <= best.eps_t / 2 + spec.pose_slack
    return TrialResult(
        strategy=strategy,
        trial=trial,
        truth=world.model.name,
        touches=rec.touches,
        status=rec.status,
        success=bool(success),
        pose_error=error,
        plan_ms=tuple(s.advice.plan_ms for s in rec.steps),
        p_distinguishing=tuple(s.advice.p_distinguishing for s in rec.steps),
        p_forecast=tuple(s.advice.p_forecast for s in rec.steps),
        distinguishing=tuple(s.distinguishing for s in rec.steps),
        distance=rec.distance,
        time=rec.time,
    )


class _TrialTimeoutError(Exception):
    pass


@contextmanager
def _time_limit(seconds: float | None) -> Iterator[None]:
    """Raise _TrialTimeoutError after `seconds` of wall time (SIGALRM; only in a
    process's main thread on POSIX, elsewhere no limit). The signal is handled
    between Python bytecodes, so one long C call overruns the limit."""
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
    signal.setitimer(signal.ITIMER_REAL, float(seconds or 0.0))
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)


def run_batch(spec: ExperimentSpec, tasks: Sequence[tuple[str, int]]) -> list[TrialResult]:
    """Several (strategy, trial) tasks in one worker call."""
    return [run_trial(spec, s, t) for s, t in tasks]


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


def histogram(touches: Sequence[int], localized: Sequence[bool]) -> dict[str, float]:
    """Share of trials per Table 4.1 column: "1" ... "10", ">10" (unlocalized
    trials count as ">10"); the shares sum to 1."""
    counts = dict.fromkeys(BINS, 0)
    for t, ok in zip(touches, localized, strict=True):
        counts[str(t) if ok and 1 <= t <= 10 else ">10"] += 1
    n = max(len(touches), 1)
    return {k: v / n for k, v in counts.items()}


def summarize(
    results: Sequence[TrialResult], strategies: Sequence[str], max_touches: int
) -> list[StrategySummary]:
    """One Table 4.1 row per strategy, in the given order."""
    rows = []
    for name in strategies:
        rs = [r for r in results if r.strategy == name]
        if not rs:
            continue
        # an unlocalized trial is charged the whole touch budget
        charged = np.array([r.touches if r.localized else max_touches for r in rs])
        times = np.concatenate([np.asarray(r.plan_ms, dtype=float) for r in rs] + [np.zeros(0)])
        rows.append(
            StrategySummary(
                strategy=name,
                trials=len(rs),
                histogram=histogram([r.touches for r in rs], [r.localized for r in rs]),
                mean_touches=float(charged.mean()),
                max_touches=int(charged.max()),
                success_rate=float(np.mean([r.success for r in rs])),
                mean_plan_ms=float(times.mean()) if len(times) else 0.0,
                p95_plan_ms=float(np.percentile(times, 95)) if len(times) else 0.0,
            )
        )
    return rows


# -- command line -----------------------------------------------------------------------


def add_simulate_command(subparsers: Any, extended: bool = False) -> argparse.ArgumentParser:
    """Add ``tactile simulate`` (DESIGN §7) to an argparse subparsers object.

    `extended` adds options beyond the DESIGN's contract (``--trial-timeout``),
    used by ``python -m hardware_sim.experiments simulate``."""
    p = subparsers.add_parser(
        "simulate",
        help="many simulated recognitions per strategy: the thesis' Table 4.1 layout",
        description=__doc__.split("\n\n")[0],
    )
    p.add_argument("--objects", required=True, help="object file (or embedded set name)")
    p.add_argument("--truth", default=None, help="name of the true object (default: random)")
    p.add_argument(
        "--strategy",
        action="append",
        required=True,
        choices=STRATEGIES,
        help="planning strategy (repeatable)",
    )
    p.add_argument("--trials", type=int, default=100)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument(
        "--sensor",
        default=None,
        choices=sorted(PRESETS),
        help="hardware preset (default ideal); or give --position-error and --normal-error",
    )
    p.add_argument("--position-error", type=float, default=None, help="bounded noise (length)")
    p.add_argument("--normal-error", type=float, default=None, help="bounded noise (radians)")
    p.add_argument("--max-touches", type=int, default=20)
    p.add_argument(
        "--placement",
        default="anywhere",
        choices=PLACEMENTS,
        help="where the true object lies: anywhere inside the safe circle (default), or "
        "centred on it as in the thesis' simulations",
    )
    p.add_argument(
        "--error-disk",
        type=float,
        default=None,
        metavar="FRACTION",
        help="recognize with the thesis' fixed error disk, this fraction of the object's "
        "effective diameter (its simulations used 0.1), instead of bounds from the sensor",
    )
    p.add_argument(
        "--thesis-choice",
        default="choose",
        choices=THESIS_CHOICES,
        help="how `thesis` picks among its best windows: the nearest origin (the thesis' "
        "hardware, default) or at random (the thesis' simulations)",
    )
    where = p.add_mutually_exclusive_group()
    where.add_argument("--workers", type=int, default=None, help="joblib processes (all cores)")
    where.add_argument("--dask", default=None, metavar="ADDRESS", help="Dask scheduler address")
    p.add_argument("--plot", default=None, metavar="FILE", help="write the histograms as PNG")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    if extended:
        p.add_argument(
            "--trial-timeout",
            type=float,
            default=None,
            metavar="SECONDS",
            help="end a trial after this wall time (status timeout, counted unlocalized)",
        )
    p.set_defaults(func=cmd_simulate)
    return p


def _preset_from_args(args: argparse.Namespace) -> Preset:
    explicit = args.position_error is not None or args.normal_error is not None
    if explicit and args.sensor is not None:
        raise ValueError("give either --sensor or --position-error/--normal-error")
    if explicit:
        return explicit_preset(args.position_error or 0.0, args.normal_error or 0.0)
    return resolve_preset(args.sensor or "ideal")


def _load(value: str) -> list[ObjectModel]:
    from pathlib import Path

    from planner.library import load_objects

    path = Path(value)
    if not path.exists() and not value.endswith(".json"):
        from importlib import resources

        path = Path(str(resources.files("planner") / "data" / f"{value}.json"))
    return load_objects(path)


def _progress_bar(total: int) -> tuple[Progress, Callable[[], None]]:
    """A progress bar on stderr (tqdm when installed, else a plain counter)."""
    try:
        from tqdm import tqdm
    except ImportError:

        def plain(done: int, _total: int) -> None:
            print(f"\rtrials {done}/{_total}", end="", file=sys.stderr, flush=True)

        return plain, lambda: print(file=sys.stderr)
    bar = tqdm(total=total, unit="trial", file=sys.stderr, leave=False)

    def update(done: int, _total: int) -> None:
        bar.update(done - bar.n)

    return update, bar.close


def format_table(rows: Sequence[StrategySummary]) -> str:
    """The Table 4.1 layout: percent of trials per number of touches, then stats."""
    head = f"{'strategy':10s} " + " ".join(f"{b:>4s}" for b in BINS)
    head += "   mean  max  success  plan ms mean/p95"
    lines = [head]
    for r in rows:
        cells = " ".join(f"{100 * r.histogram[b]:4.0f}" for b in BINS)
        lines.append(
            f"{r.strategy:10s} {cells}  {r.mean_touches:5.2f} {r.max_touches:4d}  "
            f"{100 * r.success_rate:6.1f}%  {r.mean_plan_ms:7.1f} / {r.p95_plan_ms:.1f}"
        )
    return "\n".join(lines)


def cmd_simulate(args: argparse.Namespace) -> int:
    """Run ``tactile simulate``; prints the table (or JSON) on stdout."""
    try:
        preset = _preset_from_args(args)
        spec = ExperimentSpec(
            models=tuple(_load(args.objects)),
            strategies=tuple(dict.fromkeys(args.strategy)),
            trials=args.trials,
            seed=args.seed,
            preset=preset,
            max_touches=args.max_touches,
            truth=args.truth,
            trial_timeout=getattr(args, "trial_timeout", None),
            placement=args.placement,
            strategy=(
                {} if args.thesis_choice == "choose" else {"thesis_choice": args.thesis_choice}
            ),
            recognition=(
                {}
                if args.error_disk is None
                else {"bound_mode": "thesis", "thesis_fraction": args.error_disk}
            ),
        )
    except (ValueError, PlannerError) as exc:
        print(f"tactile simulate: error: {exc}", file=sys.stderr)
        return 2
    update, close = _progress_bar(spec.trials * len(spec.strategies))
    try:
        results = run_experiment(spec, args.workers, args.dask, update)
    except RuntimeError as exc:
        close()
        print(f"tactile simulate: error: {exc}", file=sys.stderr)
        return 2
    close()
    rows = summarize(results, spec.strategies, spec.max_touches)
    if args.plot:
        from hardware_sim.plots import plot_histograms

        plot_histograms(rows, args.plot, title=f"{args.objects}, {preset.name}")
    if args.json:
        print(json.dumps({"strategies": [r.as_dict() for r in rows]}))
        return 0
    b = preset.bounds
    print(
        f"{args.objects}: {len(spec.models)} objects, truth {args.truth or 'random'}, "
        f"sensor {preset.name} (bounds {b.position_error:g}, "
        f"{math.degrees(b.normal_error):g} deg), {spec.trials} trials, seed {spec.seed}, "
        f"max {spec.max_touches} touches, object placed {spec.placement}"
        + (f", error disk {args.error_disk:g} of the diameter" if args.error_disk else "")
        + (f", thesis picks {args.thesis_choice}" if "thesis" in spec.strategies else "")
    )
    print("percent of trials needing N touches (unlocalized: >10)")
    print(format_table(rows))
    timeouts = sum(r.status == "timeout" for r in results)
    if timeouts:
        print(f"{timeouts} trials stopped at the trial timeout (counted unlocalized)")
    if args.plot:
        print(f"wrote {args.plot}")
    return 0


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m hardware_sim.experiments simulate ...``: the same command as
    ``tactile simulate`` plus the extended options."""
    parser = argparse.ArgumentParser(prog="python -m hardware_sim.experiments")
    add_simulate_command(parser.add_subparsers(dest="command", required=True), extended=True)
    args = parser.parse_args(argv)
    return int(args.func(args))


if __name__ == "__main__":
    sys.exit(main())
