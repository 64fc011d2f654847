"""Latency of the HTTP service over a real socket (not a test; run it by hand).

Starts ``tactile serve`` (one worker by default) on 127.0.0.1, registers the
five objects of ``workshop.json``, and runs seeded recognitions of randomly
posed objects with the simulated world: each step asks ``GET .../plan``, runs
the best path in the world, and posts the observation. Prints p50/p95 of both
requests as seen by the client::

    .venv/bin/python -m tactile.latency --trials 6 --max-touches 6
"""

from __future__ import annotations

import argparse
import json
import math
import tempfile
import time
from pathlib import Path

import httpx
import numpy as np

from hardware_sim.world import random_world
from planner.codec import observation_to_dict
from planner.models.library import load_objects, object_file
from planner.types import SensingPath, SensorBounds, Workspace
from tactile.server import Server


def _percentiles(values: list[float]) -> dict[str, float]:
    if not values:
        return {"n": 0}
    return {
        "n": len(values),
        "p50_ms": round(float(np.percentile(values, 50)), 1),
        "p95_ms": round(float(np.percentile(values, 95)), 1),
        "max_ms": round(max(values), 1),
    }


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--objects", default="workshop", help="object file or embedded set name")
    parser.add_argument("--trials", type=int, default=6)
    parser.add_argument("--max-touches", type=int, default=6)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--workers", type=int, default=1)
    parser.add_argument("--strategy", default="lookahead")
    parser.add_argument("--budget-ms", type=float, default=None, help="default: the service's")
    parser.add_argument("--budget-work", type=float, default=None, help="default: the service's")
    args = parser.parse_args(argv)

    models = load_objects(args.objects)
    documents = json.loads(object_file(args.objects).read_text())["objects"]
    workspace = Workspace((0.0, 0.0), 200.0)
    bounds = SensorBounds(1.0, math.radians(5.0))
    rng = np.random.default_rng(args.seed)
    post_ms: list[float] = []
    plan_ms: list[float] = []
    plan_contact_ms: list[float] = []
    planner_ms: list[float] = []  # the same plans as the planner timed them
    finals: dict[str, int] = {}
    with tempfile.TemporaryDirectory() as folder:
        server = Server(Path(folder) / "latency.db", "--workers", str(args.workers))
        with server, httpx.Client(base_url=server.url, timeout=120) as http:
            for doc in documents:
                assert http.post("/v1/objects", json=doc).status_code in (200, 201)
            for _ in range(args.trials):
                world = random_world(models, workspace, rng)
                body = {
                    "objects": [m.name for m in models],
                    "sensor": {
                        "position_error": bounds.position_error,
                        "normal_error": bounds.normal_error,
                    },
                    "workspace": {"center": [0, 0], "radius": workspace.radius},
                    "strategy": {
                        "name": args.strategy,
                        # the plans' own random stream too (else seeded from the session
                        # id): two runs of one seed make the same plans, to compare
                        "seed": args.seed,
                        **({} if args.budget_ms is None else {"budget_ms": args.budget_ms}),
                        **({} if args.budget_work is None else {"budget_work": args.budget_work}),
                    },
                }
                sid = http.post("/v1/sessions", json=body).json()["id"]
                contacts = 0
                status = "awaiting_contact"
                for _step in range(args.max_touches):
                    t0 = time.perf_counter()
                    plan = http.get(f"/v1/sessions/{sid}/plan").json()
                    elapsed = (time.perf_counter() - t0) * 1000
                    plan_ms.append(elapsed)
                    planner_ms.append(plan["elapsed_ms"])
                    if contacts:
                        plan_contact_ms.append(elapsed)
                    if not plan["paths"]:
                        break
                    best = plan["paths"][0]
                    path = SensingPath(
                        tuple(best["origin"]), tuple(best["direction"]), best["length"]
                    )
                    obs, _ = world.execute(path, bounds, rng)
                    payload = observation_to_dict(obs)
                    t0 = time.perf_counter()
                    r = http.post(f"/v1/sessions/{sid}/observations", json=payload)
                    post_ms.append((time.perf_counter() - t0) * 1000)
                    assert r.status_code == 201, r.text
                    contacts += obs.contact is not None
                    status = r.json()["status"]
                    if status in ("localized", "inconsistent"):
                        break
                finals[status] = finals.get(status, 0) + 1
    report = {
        "objects": Path(args.objects).name,
        "workers": args.workers,
        "strategy": args.strategy,
        "budget_ms": args.budget_ms,
        "budget_work": args.budget_work,
        "post_observation": _percentiles(post_ms),
        "get_plan_all": _percentiles(plan_ms),
        "get_plan_after_a_contact": _percentiles(plan_contact_ms),
        "plan_inside_the_planner": _percentiles(planner_ms),
        "final_status": finals,
    }
    print(json.dumps(report, indent=1))


if __name__ == "__main__":
    main()
