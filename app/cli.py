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
from planner.library import load_objects

__all__ = ["main"]

SETS = ["thesis_like", "workshop", "symmetric", "mcube_prisms", "table_poses"]


def embedded_set(name: str) -> Path:
    """Path of an object set shipped with the package."""
    return Path(str(resources.files("planner") / "data" / f"{name}.json"))


def _objects(value: str) -> list:
    path = Path(value)
    return load_objects(path if path.exists() or value not in SETS else embedded_set(value))


def cmd_bench(args: argparse.Namespace) -> int:
    from hardware_sim.bench import default_bounds, recognition_stats
    from planner.types import Workspace

    workspace = Workspace((0.0, 0.0), args.radius)
    rows = []
    for name in args.sets:
        models = _objects(name)
        for bounds in default_bounds():
            stats = recognition_stats(models, bounds, workspace, args.trials, 3, args.seed)
            rows.append(
                {
                    "set": name,
                    "position_error": bounds.position_error,
                    "normal_error_deg": round(math.degrees(bounds.normal_error), 3),
                    "hypotheses_after": stats.hypotheses,
                    "classes_after": stats.classes,
                    "update_p50_ms": stats.update_p50_ms,
                    "update_p95_ms": stats.update_p95_ms,
                    "trials": stats.trials,
                }
            )
    if args.json:
        print(json.dumps({"recognition": rows}, indent=1))
        return 0
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
    return 0


def cmd_demo(args: argparse.Namespace) -> int:
    from hardware_sim.demo import run_demo

    return run_demo(args.objects, args.seed, args.max_touches, out=sys.stdout)


def cmd_import_mesh(args: argparse.Namespace) -> int:
    from planner.library import object_to_dict
    from planner.mesh_files import import_mesh_file

    model = import_mesh_file(args.mesh, args.height, args.name, args.max_poses)
    text = json.dumps({"objects": [object_to_dict(model)]}, indent=1)
    if args.out:
        from planner.library import dump_objects

        dump_objects([model], args.out)
        print(f"wrote {len(model.stable_poses)} stable poses of {model.name!r} to {args.out}")
    else:
        print(text)
    return 0


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="tactile", description=__doc__)
    sub = parser.add_subparsers(dest="command", required=True)

    demo = sub.add_parser("demo", help="one recognition of a randomly posed object, step by step")
    demo.add_argument("--objects", default="thesis_like", help="object file or embedded set name")
    demo.add_argument("--seed", type=int, default=7)
    demo.add_argument("--max-touches", type=int, default=12)
    demo.set_defaults(func=cmd_demo)

    bench = sub.add_parser("bench", help="recognition and planning benchmarks")
    bench.add_argument("--sets", nargs="+", default=SETS, help="object files or embedded set names")
    bench.add_argument("--trials", type=int, default=40)
    bench.add_argument("--seed", type=int, default=0)
    bench.add_argument("--radius", type=float, default=200.0, help="safe circle radius")
    bench.add_argument("--json", action="store_true")
    bench.set_defaults(func=cmd_bench)

    mesh = sub.add_parser("import-mesh", help="3-D mesh -> stable poses sliced at a height")
    mesh.add_argument("mesh", help="STL, OBJ, PLY or OFF file")
    mesh.add_argument("--height", type=float, required=True, help="slice height above the table")
    mesh.add_argument("--name", default=None)
    mesh.add_argument("--max-poses", type=int, default=None)
    mesh.add_argument("--out", default=None, help="write an object file instead of printing")
    mesh.set_defaults(func=cmd_import_mesh)

    from app.serve import add_serve_command

    add_serve_command(sub)

    from hardware_sim.experiments import add_simulate_command

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
