"""The `tactile` command line (DESIGN §7)."""

from __future__ import annotations

import argparse
import json
import math
import sys
from collections.abc import Sequence
from importlib import resources
from pathlib import Path

from planner.errors import PlannerError
from planner.models.library import load_objects

__all__ = ["main"]

SETS = ["thesis_like", "workshop", "symmetric", "mcube_prisms", "table_poses"]


def embedded_set(name: str) -> Path:
    """Path of an object set shipped with the package."""
    return Path(str(resources.files("planner") / "data" / f"{name}.json"))


def _objects(value: str) -> list:
    path = Path(value)
    return load_objects(path if path.exists() or value not in SETS else embedded_set(value))


def cmd_bench(args: argparse.Namespace) -> int:
    from planner.types import Workspace
    from planner.warmup import warm_up
    from tactile.bench import default_bounds, planning_stats, recognition_stats, update_growth

    warm_up()  # kernels loaded (or built) before anything is timed
    workspace = Workspace((0.0, 0.0), args.radius)
    rows, plans = [], []
    for name in args.sets:
        models = _objects(name)
        for bounds in [b for b in default_bounds() if b.position_error > 0 or not args.no_exact]:
            error = {
                "set": name,
                "position_error": bounds.position_error,
                "normal_error_deg": round(math.degrees(bounds.normal_error), 3),
            }
            if args.planning:
                for s in planning_stats(
                    models,
                    bounds,
                    workspace,
                    args.strategies,
                    args.plan_trials,
                    args.plan_touches,
                    args.seed,
                    args.repeat,
                ):
                    plans.append({**error, **s.__dict__})
            if args.no_recognition:
                continue
            stats = recognition_stats(
                models, bounds, workspace, args.trials, 3, args.seed, args.repeat
            )
            growth = {}
            if args.growth:
                growth = update_growth(models, bounds, workspace, args.growth, 2, args.seed)
            rows.append(
                {
                    **error,
                    "update_ms_by_n": growth,
                    "hypotheses_after": stats.hypotheses,
                    "classes_after": stats.classes,
                    "update_p50_ms": stats.update_p50_ms,
                    "update_p95_ms": stats.update_p95_ms,
                    "trials": stats.trials,
                }
            )
    if args.json:
        out = {"recognition": rows} if not args.no_recognition else {}
        if args.planning:
            out["planning"] = plans
        print(json.dumps(out, indent=1))
        return 0
    if rows:
        _print_recognition(rows)
    if plans:
        _print_planning(plans, args.strategies)
    return 0


def _print_recognition(rows: list[dict]) -> None:
    print(
        f"{'set':14s} {'error':>12s}  hypotheses after 1/2/3     "
        "classes after 1/2/3    update p50/p95 ms"
    )
    for r in rows:
        err = f"{r['position_error']:g}/{r['normal_error_deg']:g}deg"
        h = " ".join(f"{v:7.1f}" for v in r["hypotheses_after"])
        c = " ".join(f"{v:7.1f}" for v in r["classes_after"])
        print(
            f"{r['set']:14s} {err:>12s}  {h}   {c}   "
            f"{r['update_p50_ms']:6.1f} {r['update_p95_ms']:6.1f}"
        )
    if any(r["update_ms_by_n"] for r in rows):
        print("\nupdate time (median ms) of the n-th observation of one session:")
        for r in rows:
            err = f"{r['position_error']:g}/{r['normal_error_deg']:g}deg"
            by_n = "  ".join(f"n={n}: {v:.1f}" for n, v in r["update_ms_by_n"].items())
            print(f"{r['set']:14s} {err:>12s}  {by_n}")


def _print_planning(plans: list[dict], strategies: Sequence[str]) -> None:
    heads = "".join(f" {s + ' p50/p95 ms':>22s}" for s in strategies)
    print(f"{'set':14s} {'error':>12s} {'touches':>7s} {'hyps':>11s} {'cands':>9s}{heads}")
    for r in plans:
        err = f"{r['position_error']:g}/{r['normal_error_deg']:g}deg"
        hyps = f"{r['hypotheses']:.0f}/{r['hypotheses_max']}"
        cands = f"{r['candidates']:.0f}/{r['candidates_max']}"
        times = "".join(
            f" {r['p50_ms'][s]:10.1f} {r['p95_ms'][s]:7.1f}{_cut_mark(r, s):3s}" for s in strategies
        )
        work = "".join(f" {r['work'][s] / 1e3:7.0f}k" for s in strategies)
        print(
            f"{r['set']:14s} {err:>12s} {r['touches']:7d} {hyps:>11s} {cands:>9s}{times}"
            f"   work{work}"
        )
    print(
        "hyps, cands: mean/max over trials; work: mean units per plan, per strategy;"
        " * some plans stopped by the work budget, ! some by the wall-clock cap"
    )


def _cut_mark(row: dict, strategy: str) -> str:
    if row["capped"][strategy]:
        return "!"
    return "*" if row["truncated"][strategy] else ""


def _picture(value: str) -> str:
    if Path(value).suffix.lower() not in (".png", ".svg"):
        raise argparse.ArgumentTypeError("must end in .png or .svg")
    return value


def cmd_demo(args: argparse.Namespace) -> int:
    """Start the service on embedded defaults (SQLite in a temporary folder, a free
    loopback port) unless given `--url`, and run one recognition against it over HTTP."""
    import contextlib
    import tempfile
    import time

    from app.serve import serve_in_thread
    from app.settings import Settings
    from hardware_sim.http_service import ServiceError
    from tactile.demo import run_demo

    objects = args.objects if args.objects.endswith(".json") else embedded_set(args.objects)
    picture = Path(args.out)

    def demo(url: str) -> int:
        try:
            code = run_demo(url, str(objects), args.seed, args.max_touches, sys.stdout, picture,
                            args.sensor, report=args.report)  # fmt: skip
        except ServiceError as exc:  # the service refused the objects (a limit, a field)
            print(f"tactile: error: {exc}", file=sys.stderr)
            return 2
        if args.linger > 0:
            print(f"serving for {args.linger:g} s more (Ctrl-C stops)", flush=True)
            with contextlib.suppress(KeyboardInterrupt):
                time.sleep(args.linger)
        return code

    if args.url:
        return demo(args.url.rstrip("/"))
    with tempfile.TemporaryDirectory(prefix="tactile-demo-") as tmp:
        settings = Settings(
            db_path=Path(tmp) / "demo.db", api_key=None, log_level="warning", log_json=False
        )
        with serve_in_thread(settings) as url:
            return demo(url)


def cmd_import_mesh(args: argparse.Namespace) -> int:
    from planner.models.library import object_to_dict
    from planner.models.mesh_files import import_mesh_file

    heights = ([] if args.height is None else [args.height]) + list(args.heights or [])
    if not heights:
        from planner.errors import InvalidModelError

        raise InvalidModelError("give --height Z or --heights Z [Z ...]", field="height")
    model = import_mesh_file(args.mesh, heights[0], args.name, args.max_poses, heights[1:])
    text = json.dumps({"objects": [object_to_dict(model)]}, indent=1)
    if args.out:
        from planner.models.library import dump_objects

        dump_objects([model], args.out)
        print(f"wrote {len(model.stable_poses)} stable poses of {model.name!r} to {args.out}")
    else:
        print(text)
    return 0


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="tactile", description=__doc__)
    sub = parser.add_subparsers(dest="command", required=True)

    demo = sub.add_parser(
        "demo", help="start the service, recognize one randomly posed object over HTTP"
    )
    demo.add_argument("--objects", default="thesis_like", help="object file or embedded set name")
    demo.add_argument("--seed", type=int, default=7, help="the world, the sensor and the plans")
    demo.add_argument("--max-touches", type=int, default=12)
    demo.add_argument(
        "--sensor",
        choices=["bounded", "ideal", "thesis_sensor"],
        default="bounded",
        help="bounded: errors within 1 mm and 3 degrees (default); or a hardware preset",
    )
    demo.add_argument(
        "--out", type=_picture, default="tactile-demo.png", help="the final picture (.png or .svg)"
    )
    demo.add_argument(
        "--report",
        type=Path,
        default=None,
        metavar="FILE",
        help="write the session's report: each touch with its residuals, the answer "
        "(FILE.csv: CSV, else JSON)",
    )
    demo.add_argument("--url", default=None, help="use a running service instead of starting one")
    demo.add_argument(
        "--linger", type=float, default=0.0, help="keep serving this many s for the live view"
    )
    demo.set_defaults(func=cmd_demo)

    bench = sub.add_parser("bench", help="recognition and planning benchmarks")
    bench.add_argument("--sets", nargs="+", default=SETS, help="object files or embedded set names")
    bench.add_argument("--trials", type=int, default=40)
    bench.add_argument("--seed", type=int, default=0)
    bench.add_argument("--radius", type=float, default=200.0, help="safe circle radius")
    bench.add_argument("--json", action="store_true")
    bench.add_argument(
        "--planning", action="store_true", help="also time plans after 0-5 touches (§9)"
    )
    bench.add_argument("--no-recognition", action="store_true", help="skip the recognition part")
    bench.add_argument(
        "--strategies", nargs="+", default=["pdm", "pruning", "lookahead"], help="planning"
    )
    bench.add_argument("--plan-trials", type=int, default=10, help="planning trials per set")
    bench.add_argument(
        "--plan-touches", type=int, default=5, help="plans after 0 ... this many touches"
    )
    bench.add_argument(
        "--growth",
        type=int,
        default=0,
        metavar="N",
        help="also time the updates of a session touched N times (e.g. 40)",
    )
    bench.add_argument(
        "--repeat",
        type=int,
        default=1,
        help="runs per plan (median kept) and replays per recognition trial (shortest kept)",
    )
    bench.add_argument(
        "--no-exact",
        action="store_true",
        help="skip exact sensing; time the 1 mm / 3 degree case only",
    )
    bench.set_defaults(func=cmd_bench)

    mesh = sub.add_parser("import-mesh", help="3-D mesh -> stable poses sliced at heights")
    mesh.add_argument("mesh", help="STL, OBJ, PLY or OFF file")
    mesh.add_argument("--height", type=float, default=None, help="slice height above the table")
    mesh.add_argument(
        "--heights",
        type=float,
        nargs="+",
        default=None,
        help="probing heights, each stable pose sliced at every one (the first, or "
        "--height when given, is the default height)",
    )
    mesh.add_argument("--name", default=None)
    mesh.add_argument("--max-poses", type=int, default=None)
    mesh.add_argument("--out", default=None, help="write an object file instead of printing")
    mesh.set_defaults(func=cmd_import_mesh)

    from app.serve import add_serve_command

    add_serve_command(sub)

    from tactile.simulate import add_simulate_command

    add_simulate_command(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.func(args))
    except PlannerError as exc:
        print(f"tactile: error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
