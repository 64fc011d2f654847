"""Calibration of the planner's P(DM) against simulated touches (DESIGN §4.7).

Every planned touch after the opening carries two predictions of the
probability that it is a distinguishing measurement (one equivalence class
left afterwards): the outcome model's worst-case `p_distinguishing` and the
recognition's own `p_forecast` (:mod:`planner.planning.forecast`). Both are tabled; the
check judges the forecast, the probability the planner offers as such. Over
many simulated touches, grouped in bins of the prediction, the observed share
of distinguishing touches should match the bin's mean prediction: within
`tolerance` (0.05) for every bin holding at least `min_count` (100) touches.

The best path's `expected_remaining` (the expected touches still needed,
itself included) is tabled too, against the touches the localized trials then
took: it is the search's value, reported as information, not judged.

Run it::

    python -m tactile.calibration --objects thesis_like --trials 250 \\
        --strategy random --strategy pruning --strategy pdm --sensor ideal
"""

from __future__ import annotations

import argparse
import itertools
import json
import math
import sys
from collections.abc import Sequence
from dataclasses import asdict, dataclass

import numpy as np

from hardware_sim.experiments import ExperimentSpec, TrialResult, run_experiment
from hardware_sim.presets import PRESETS, resolve_preset
from planner.models.library import load_objects
from planner.planning.config import STRATEGIES
from tactile.simulate import progress_bar

__all__ = [
    "PREDICTIONS",
    "REMAINING_EDGES",
    "ReliabilityBin",
    "RemainingBin",
    "calibration_ok",
    "main",
    "reliability_table",
    "remaining_records",
    "remaining_table",
    "touch_records",
]


@dataclass(frozen=True)
class ReliabilityBin:
    """Touches whose predicted P(DM) fell in [`low`, `high`) (the last bin
    includes 1): how many, their mean prediction and the observed share of
    distinguishing touches, and whether the bin passes (`ok` is None when the
    bin has too few touches to judge)."""

    low: float
    high: float
    count: int
    mean_predicted: float
    observed: float
    ok: bool | None


#: Which prediction a touch is judged by: the recognition's forecast, or the
#: outcome model's worst-case P(DM).
PREDICTIONS = ("forecast", "model")


def touch_records(
    results: Sequence[TrialResult], prediction: str = "forecast"
) -> tuple[np.ndarray, np.ndarray]:
    """(predicted P(DM), observed distinguishing) of every planned touch that had
    a prediction of that kind (the opening probes have none)."""
    if prediction not in PREDICTIONS:
        raise ValueError(f"prediction must be one of {list(PREDICTIONS)}")
    pred, obs = [], []
    for r in results:
        made = r.p_forecast if prediction == "forecast" else r.p_distinguishing
        for p, d in zip(made, r.distinguishing, strict=True):
            if p is not None:
                pred.append(p)
                obs.append(d)
    return np.asarray(pred, dtype=float), np.asarray(obs, dtype=bool)


@dataclass(frozen=True)
class RemainingBin:
    """Planned touches of localized trials whose best path's `expected_remaining`
    fell in [`low`, `high`): how many, how many of them from a plan whose search
    the budget stopped, the mean expected and the mean touches the trial then
    took (that touch included), and the share where the expectation exceeded them."""

    low: float
    high: float
    count: int
    truncated: int
    mean_expected: float
    mean_taken: float
    over: float


#: Edges of the expected-remaining bins (the last is open).
REMAINING_EDGES = (1.0, 1.5, 2.0, 3.0, 5.0, 10.0, math.inf)


def remaining_records(results: Sequence[TrialResult]) -> tuple[np.ndarray, ...]:
    """(expected remaining, touches taken from there on, truncated) of every
    planned touch of a localized trial that had an expectation."""
    rows = [
        (e, r.touches - k, bool(t))
        for r in results
        if r.localized
        for k, (e, t) in enumerate(zip(r.expected_remaining, r.truncated, strict=True))
        if e is not None and math.isfinite(e)
    ]
    e, taken, cut = (np.array(c) for c in zip(*rows, strict=True)) if rows else ([],) * 3
    return np.asarray(e, float), np.asarray(taken, float), np.asarray(cut, bool)


def remaining_table(
    expected: np.ndarray, taken: np.ndarray, truncated: np.ndarray
) -> list[RemainingBin]:
    """Bin the touches by expected remaining (:data:`REMAINING_EDGES`) and compare
    with the touches taken."""
    table = []
    for low, high in itertools.pairwise(REMAINING_EDGES):
        sel = (expected >= low) & (expected < high)
        n = int(sel.sum())
        table.append(
            RemainingBin(
                low,
                high,
                n,
                int(truncated[sel].sum()),
                float(expected[sel].mean()) if n else math.nan,
                float(taken[sel].mean()) if n else math.nan,
                float((expected[sel] > taken[sel]).mean()) if n else math.nan,
            )
        )
    return table


def reliability_table(
    predicted: np.ndarray,
    observed: np.ndarray,
    bins: int = 10,
    tolerance: float = 0.05,
    min_count: int = 100,
) -> list[ReliabilityBin]:
    """Bin touches by prediction (`bins` equal bins on [0, 1]) and compare the
    observed frequency with the mean prediction of each bin."""
    predicted = np.clip(np.asarray(predicted, dtype=float), 0.0, 1.0)
    observed = np.asarray(observed, dtype=float)
    index = np.minimum((predicted * bins).astype(int), bins - 1)
    table = []
    for b in range(bins):
        sel = index == b
        n = int(sel.sum())
        mean_p = float(predicted[sel].mean()) if n else math.nan
        freq = float(observed[sel].mean()) if n else math.nan
        ok = None if n < min_count else bool(abs(freq - mean_p) <= tolerance)
        table.append(ReliabilityBin(b / bins, (b + 1) / bins, n, mean_p, freq, ok))
    return table


def calibration_ok(table: Sequence[ReliabilityBin]) -> bool:
    """True when every bin with enough touches passes."""
    return all(b.ok is not False for b in table)


def main(argv: Sequence[str] | None = None) -> int:
    """Command line: run the trials, print the reliability table; exit 1 when a
    bin with enough touches is off by more than the tolerance."""
    parser = argparse.ArgumentParser(prog="python -m tactile.calibration", description=__doc__)
    parser.add_argument("--objects", default="thesis_like")
    parser.add_argument("--truth", default=None)
    parser.add_argument("--strategy", action="append", choices=STRATEGIES)
    parser.add_argument("--trials", type=int, default=250, help="trials per strategy")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--sensor", default="ideal", choices=sorted(PRESETS))
    parser.add_argument("--max-touches", type=int, default=20)
    parser.add_argument("--workers", type=int, default=None)
    parser.add_argument("--bins", type=int, default=10)
    parser.add_argument("--tolerance", type=float, default=0.05)
    parser.add_argument("--min-count", type=int, default=100)
    parser.add_argument("--trial-timeout", type=float, default=None, metavar="SECONDS")
    parser.add_argument(
        "--budget-work",
        type=float,
        default=None,
        help="plan work budget (default: none, the predictions unbounded by it; the "
        "service's default is 400000)",
    )
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args(argv)
    spec = ExperimentSpec(
        models=tuple(load_objects(args.objects)),
        strategies=tuple(args.strategy or ("random", "pruning", "pdm")),
        trials=args.trials,
        seed=args.seed,
        preset=resolve_preset(args.sensor),
        max_touches=args.max_touches,
        truth=args.truth,
        trial_timeout=args.trial_timeout,
        # the predictions are measured, not the speed: no time budget cuts a plan
        strategy={"budget_ms": None, "budget_work": args.budget_work},
    )
    update, close = progress_bar(spec.trials * len(spec.strategies))
    results = run_experiment(spec, args.workers, None, update)
    close()
    timeouts = sum(r.status == "timeout" for r in results)
    tables = {}
    for kind in PREDICTIONS:
        pred, obs = touch_records(results, kind)
        table = reliability_table(pred, obs, args.bins, args.tolerance, args.min_count)
        tables[kind] = (len(pred), table)
    ok = calibration_ok(tables["forecast"][1])  # the forecast is the probability offered
    remaining = remaining_table(*remaining_records(results))
    if args.json:
        out = {
            kind: {"touches": n, "ok": calibration_ok(t), "bins": [asdict(b) for b in t]}
            for kind, (n, t) in tables.items()
        }
        out["expected_remaining"] = {"bins": [_finite(asdict(b)) for b in remaining]}
        print(json.dumps({"timeouts": timeouts, "ok": ok, **out}))
        return 0 if ok else 1
    print(
        f"{args.objects}, sensor {args.sensor}, strategies {', '.join(spec.strategies)}"
        + (f" ({timeouts} trials stopped at the trial timeout, left out)" if timeouts else "")
    )
    for kind, (n, table) in tables.items():
        title = "forecast (p_forecast)" if kind == "forecast" else "model (p_distinguishing)"
        print(f"{title}: {n} planned touches with a prediction")
        print("  P(DM) bin     touches  mean predicted  observed  |diff|  check")
        for b in table:
            check = "-" if b.ok is None else ("ok" if b.ok else "OFF")
            diff = abs(b.observed - b.mean_predicted) if b.count else math.nan
            print(
                f"  [{b.low:.1f}, {b.high:.1f})  {b.count:8d}  {b.mean_predicted:14.3f}  "
                f"{b.observed:8.3f}  {diff:6.3f}  {check}"
            )
    print("expected remaining touches (best path; localized trials), against those taken")
    print("  E bin          touches  truncated  mean expected  mean taken  expected > taken")
    for b in remaining:
        print(
            f"  [{b.low:g}, {b.high:g})".ljust(16)
            + f"{b.count:7d}  {b.truncated:9d}  {b.mean_expected:13.2f}  {b.mean_taken:10.2f}"
            + f"  {b.over:16.2f}"
        )
    print(
        "forecast calibrated" if ok else "forecast NOT calibrated",
        f"(tolerance {args.tolerance}, bins with >= {args.min_count} touches)",
    )
    return 0 if ok else 1


def _finite(row: dict) -> dict:
    """JSON has no infinity: an open bin edge and an empty bin's means as None."""
    return {k: None if isinstance(v, float) and not math.isfinite(v) else v for k, v in row.items()}


if __name__ == "__main__":
    sys.exit(main())
