"""``tactile simulate`` (DESIGN §7): many seeded recognitions per strategy, the thesis'
Table 4.1 layout, run by :mod:`hardware_sim.experiments` and summed up by
:mod:`hardware_sim.summary`."""

from __future__ import annotations

import argparse
import json
import math
import sys
from collections.abc import Callable, Sequence
from typing import Any

from tqdm import tqdm

from hardware_sim.experiments import ExperimentSpec, Progress, run_experiment
from hardware_sim.presets import PRESETS, Preset, explicit_preset, resolve_preset
from hardware_sim.summary import format_table, summarize
from hardware_sim.world import PLACEMENTS
from planner.errors import PlannerError
from planner.models.library import load_objects
from planner.planning.config import STRATEGIES, THESIS_CHOICES

__all__ = ["add_simulate_command", "cmd_simulate", "main", "progress_bar"]


# -- command line -----------------------------------------------------------------------


def add_simulate_command(subparsers: Any, extended: bool = False) -> argparse.ArgumentParser:
    """Add ``tactile simulate`` (DESIGN §7) to an argparse subparsers object.

    `extended` adds options beyond the DESIGN's contract (``--trial-timeout``),
    used by ``python -m tactile.simulate simulate``."""
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
    _add_sensor_arguments(p)
    p.add_argument("--max-touches", type=int, default=20)
    p.add_argument(
        "--placement",
        default="anywhere",
        choices=PLACEMENTS,
        help="where the true object lies: anywhere inside the safe circle (default), or "
        "centred on it as in the thesis' simulations",
    )
    _add_session_arguments(p)
    p.add_argument(
        "--thesis-choice",
        default="choose",
        choices=THESIS_CHOICES,
        help="how `thesis` picks among its best windows: the nearest origin (the thesis' "
        "hardware, default) or at random (the thesis' simulations)",
    )
    p.add_argument(
        "--budget-work",
        type=float,
        default=None,
        metavar="UNITS",
        help="each plan's work budget (default: the planner's; 0: unlimited); the same "
        "touches on any machine under any load",
    )
    p.add_argument(
        "--budget-ms",
        type=float,
        default=None,
        metavar="MS",
        help="each plan's wall-clock cap, a safety net (default: the planner's; 0: none)",
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


def _add_sensor_arguments(p: argparse.ArgumentParser) -> None:
    """The simulated sensor: a hardware preset, or bounded noise with an optional ball tip."""
    p.add_argument(
        "--sensor",
        default=None,
        choices=sorted(PRESETS),
        help="hardware preset (default ideal); or give --position-error and --normal-error",
    )
    p.add_argument("--position-error", type=float, default=None, help="bounded noise (length)")
    p.add_argument("--normal-error", type=float, default=None, help="bounded noise (radians)")
    p.add_argument(
        "--tip-radius",
        type=float,
        default=0.0,
        metavar="R",
        help="with the bounded noise: a ball tip of radius R (length); the arm reports "
        "the ball's centre and each session is told the radius",
    )


def _add_session_arguments(p: argparse.ArgumentParser) -> None:
    """What each session is told besides the sensor: the thesis' fixed error disk, a pose prior."""
    p.add_argument(
        "--error-disk",
        type=float,
        default=None,
        metavar="FRACTION",
        help="recognize with the thesis' fixed error disk, this fraction of the object's "
        "effective diameter (its simulations used 0.1), instead of bounds from the sensor",
    )
    p.add_argument(
        "--prior-radius",
        type=float,
        default=None,
        metavar="R",
        help="give each session a pose prior: a region of radius R (length) around a "
        "point drawn within R of the true centroid, as a fixture or camera would",
    )
    p.add_argument(
        "--prior-theta",
        type=float,
        default=None,
        metavar="T",
        help="and/or a rotation range of +-T degrees around an angle drawn within T of the "
        "true rotation",
    )


def _preset_from_args(args: argparse.Namespace) -> Preset:
    explicit = args.position_error is not None or args.normal_error is not None
    if explicit and args.sensor is not None:
        raise ValueError("give either --sensor or --position-error/--normal-error")
    if args.tip_radius and not explicit:
        raise ValueError("--tip-radius goes with --position-error/--normal-error")
    if explicit:
        return explicit_preset(
            args.position_error or 0.0, args.normal_error or 0.0, args.tip_radius
        )
    return resolve_preset(args.sensor or "ideal")


def progress_bar(total: int) -> tuple[Progress, Callable[[], None]]:
    """A progress bar of trials on stderr."""
    bar = tqdm(total=total, unit="trial", file=sys.stderr, leave=False)

    def update(done: int, _total: int) -> None:
        bar.update(done - bar.n)

    return update, bar.close


def _strategy_settings(args: argparse.Namespace) -> dict[str, Any]:
    settings: dict[str, Any] = {}
    if args.thesis_choice != "choose":
        settings["thesis_choice"] = args.thesis_choice
    if args.budget_work is not None:
        settings["budget_work"] = None if args.budget_work == 0 else args.budget_work
    if args.budget_ms is not None:
        settings["budget_ms"] = None if args.budget_ms == 0 else args.budget_ms
    return settings


def cmd_simulate(args: argparse.Namespace) -> int:
    """Run ``tactile simulate``; prints the table (or JSON) on stdout."""
    try:
        preset = _preset_from_args(args)
        spec = ExperimentSpec(
            models=tuple(load_objects(args.objects)),
            strategies=tuple(dict.fromkeys(args.strategy)),
            trials=args.trials,
            seed=args.seed,
            preset=preset,
            max_touches=args.max_touches,
            truth=args.truth,
            trial_timeout=getattr(args, "trial_timeout", None),
            placement=args.placement,
            prior_radius=args.prior_radius,
            prior_theta=None if args.prior_theta is None else math.radians(args.prior_theta),
            strategy=_strategy_settings(args),
            recognition=(
                {}
                if args.error_disk is None
                else {"bound_mode": "thesis", "thesis_fraction": args.error_disk}
            ),
        )
    except (ValueError, PlannerError) as exc:
        print(f"tactile simulate: error: {exc}", file=sys.stderr)
        return 2
    update, close = progress_bar(spec.trials * len(spec.strategies))
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
        trials = [
            {
                "strategy": r.strategy,
                "trial": r.trial,
                "touches": r.touches,
                "status": r.status,
                "success": r.success,
                "stopped_by": [s for s in r.stopped_by if s],
            }
            for r in results
        ]
        print(json.dumps({"strategies": [r.as_dict() for r in rows], "trials": trials}))
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
    """``python -m tactile.simulate simulate ...``: the same command as
    ``tactile simulate`` plus the extended options."""
    parser = argparse.ArgumentParser(prog="python -m tactile.simulate")
    add_simulate_command(parser.add_subparsers(dest="command", required=True), extended=True)
    args = parser.parse_args(argv)
    return int(args.func(args))


if __name__ == "__main__":
    sys.exit(main())
