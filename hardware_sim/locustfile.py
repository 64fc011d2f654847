"""Locust fleet: simulated robots, each running whole recognitions against the service.

A robot creates a session on a shared object set, asks for the plan, executes the best
path against its own simulated world, posts the observation, and repeats until the
session is localized (or a touch limit). Run through ``python -m hardware_sim.loadtest``.
"""

from __future__ import annotations

import json
import math
import os
from importlib import resources

import numpy as np
from locust import HttpUser, between, task

from hardware_sim.world import random_world
from planner.library import parse_objects
from planner.types import SensingPath, SensorBounds, Workspace

SET = os.environ.get("LOADTEST_OBJECTS", "thesis_like")
OBJECTS = json.loads((resources.files("planner") / "data" / f"{SET}.json").read_text())["objects"]
MODELS = parse_objects({"objects": OBJECTS})
WORKSPACE = Workspace((0.0, 0.0), 200.0)
BOUNDS = SensorBounds(1.0, math.radians(3.0))
STRATEGY = {"name": os.environ.get("LOADTEST_STRATEGY", "pdm"), "budget_ms": 200}
MAX_TOUCHES = 12


class Robot(HttpUser):
    wait_time = between(0.0, 0.05)

    def on_start(self) -> None:
        self.rng = np.random.default_rng(abs(hash(id(self))) % 2**32)

    @task
    def recognize(self) -> None:
        world = random_world(MODELS, WORKSPACE, self.rng)
        created = self.client.post(
            "/v1/sessions",
            json={
                "objects": OBJECTS,
                "sensor": {
                    "position_error": BOUNDS.position_error,
                    "normal_error": BOUNDS.normal_error,
                },
                "workspace": {"center": list(WORKSPACE.center), "radius": WORKSPACE.radius},
                "sensor_position": [WORKSPACE.radius, 0.0],
                "strategy": STRATEGY,
            },
            name="POST /v1/sessions",
        )
        if created.status_code != 201:
            return
        sid = created.json()["id"]
        for _ in range(MAX_TOUCHES):
            plan = self.client.get(
                f"/v1/sessions/{sid}/plan?limit=1", name="GET /v1/sessions/{id}/plan"
            )
            paths = plan.json().get("paths", []) if plan.status_code == 200 else []
            if not paths:
                break
            best = paths[0]
            path = SensingPath(tuple(best["origin"]), tuple(best["direction"]), best["length"])
            obs, _ = world.execute(path, BOUNDS, self.rng)
            contact = None
            if obs.contact is not None:
                contact = {"point": list(obs.contact.point), "normal": list(obs.contact.normal)}
            state = self.client.post(
                f"/v1/sessions/{sid}/observations",
                json={
                    "path": {
                        "origin": list(path.origin),
                        "direction": list(path.direction),
                        "length": path.length,
                    },
                    "contact": contact,
                },
                name="POST /v1/sessions/{id}/observations",
            )
            if state.status_code != 201 or state.json()["status"] in ("localized", "inconsistent"):
                break
        self.client.delete(f"/v1/sessions/{sid}", name="DELETE /v1/sessions/{id}")
