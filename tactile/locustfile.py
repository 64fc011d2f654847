"""Locust fleet: simulated robots, each running whole recognitions against the service.

Two kinds of robot (pick one by class name on the locust command line; both by
default):

- :class:`Robot` creates a session on a shared object set, asks for the plan,
  executes the best path against its own simulated world, posts the observation,
  and repeats until the session is localized (or a touch limit);
- :class:`Prober` posts observations only: random paths aimed at its object
  (no plan asked), until localized or the touch limit. It measures what the
  observation endpoint sustains by itself.

Run through ``python -m tactile.loadtest``. ``LOADTEST_KEEPALIVE=0`` opens a
connection per request. ``LOADTEST_HOSTS`` (comma-separated base URLs) spreads
each robot's requests over several hosts at random, so that every host serves
every session (as behind a reverse proxy); each request is then reported under
its endpoint and host (``... @h0``). Observations are posted with
``?limit=LOADTEST_HYPOTHESES`` (default: no limit, the whole hypothesis list).
Robot k of a run draws its worlds from ``LOADTEST_SEED`` (default 0) and k, and
the sessions plan with seed 0, so runs compare like with like.
The robots use locust's geventhttpclient user (keep-alive, far less CPU per
request than python-requests), which matters when locust shares the machine.
"""

from __future__ import annotations

import itertools
import json
import math
import os
import uuid
from importlib import resources

import numpy as np
from locust import FastHttpUser, between, task

from hardware_sim.world import World, random_world
from planner.codec import observation_to_dict, sensor_to_dict, workspace_to_dict
from planner.models.library import parse_objects
from planner.types import Observation, SensingPath, SensorBounds, Workspace

SET = os.environ.get("LOADTEST_OBJECTS", "thesis_like")
OBJECTS = json.loads((resources.files("planner") / "data" / f"{SET}.json").read_text())["objects"]
MODELS = parse_objects({"objects": OBJECTS})
WORKSPACE = Workspace((0.0, 0.0), 200.0)
BOUNDS = SensorBounds(1.0, math.radians(3.0))
#: 200,000 units of work (about 200 ms on the reference machine), the 1.5 s cap a safety net
STRATEGY = {"name": os.environ.get("LOADTEST_STRATEGY", "pdm"), "budget_work": 200_000, "seed": 0}
SEED = int(os.environ.get("LOADTEST_SEED", "0"))
_ROBOTS = itertools.count()
MAX_TOUCHES = 12
HYPOTHESES = os.environ.get("LOADTEST_HYPOTHESES", "")
OBSERVE_QUERY = f"?limit={int(HYPOTHESES)}" if HYPOTHESES else ""
#: LOADTEST_KEEPALIVE=0: a new connection per request (with several workers, a
#: session's requests then land on any worker, as behind a load balancer)
KEEPALIVE = os.environ.get("LOADTEST_KEEPALIVE", "1") != "0"
DONE = ("localized", "inconsistent")
HOSTS = [h.rstrip("/") for h in os.environ.get("LOADTEST_HOSTS", "").split(",") if h]


class _Fleet(FastHttpUser):
    abstract = True
    wait_time = between(0.0, 0.05)
    default_headers = None if KEEPALIVE else {"Connection": "close"}

    def on_start(self) -> None:
        # robot k of a run draws the same worlds in every run (LOADTEST_SEED): two runs
        # of one fleet compare the service, not the worlds each happened to draw
        self.rng = np.random.default_rng([SEED, next(_ROBOTS)])
        self.pick = np.random.default_rng(self.rng.integers(2**32))  # hosts, apart from worlds

    def _at(self, path: str, name: str) -> tuple[str, str]:
        """The URL and report name of the next request: a host drawn at random (every
        endpoint of every session spread evenly, as a round-robin proxy would)."""
        if not HOSTS:
            return path, name
        host = int(self.pick.integers(len(HOSTS)))
        return HOSTS[host] + path, f"{name} @h{host}"

    def _create(self) -> str | None:
        url, name = self._at("/v1/sessions", "POST /v1/sessions")
        created = self.client.post(
            url,
            json={
                "objects": OBJECTS,
                "sensor": sensor_to_dict(BOUNDS),
                "workspace": workspace_to_dict(WORKSPACE),
                "sensor_position": [WORKSPACE.radius, 0.0],
                "strategy": STRATEGY,
            },
            name=name,
        )
        return created.json()["id"] if created.status_code == 201 else None

    def _observe(self, sid: str, obs: Observation) -> str | None:
        url, name = self._at(
            f"/v1/sessions/{sid}/observations{OBSERVE_QUERY}",
            "POST /v1/sessions/{id}/observations",
        )
        state = self.client.post(url, json=observation_to_dict(obs), name=name)
        return state.json()["status"] if state.status_code == 201 else None

    def _delete(self, sid: str) -> None:
        url, name = self._at(f"/v1/sessions/{sid}", "DELETE /v1/sessions/{id}")
        # a delete needs If-Match or an Idempotency-Key; this one request is the key
        self.client.delete(url, name=name, headers={"Idempotency-Key": uuid.uuid4().hex})


class Robot(_Fleet):
    """Plan, touch, observe: the closed loop of a robot using the planner."""

    @task
    def recognize(self) -> None:
        world = random_world(MODELS, WORKSPACE, self.rng)
        sid = self._create()
        if sid is None:
            return
        for _ in range(MAX_TOUCHES):
            url, name = self._at(f"/v1/sessions/{sid}/plan?limit=1", "GET /v1/sessions/{id}/plan")
            plan = self.client.get(url, name=name)
            paths = plan.json().get("paths", []) if plan.status_code == 200 else []
            if not paths:
                break
            best = paths[0]
            path = SensingPath(tuple(best["origin"]), tuple(best["direction"]), best["length"])
            obs, _ = world.execute(path, BOUNDS, self.rng)
            if self._observe(sid, obs) in (None, *DONE):
                break
        self._delete(sid)


class Prober(_Fleet):
    """Observations only: random paths aimed at the object, no plan asked."""

    @task
    def probe(self) -> None:
        world: World = random_world(MODELS, WORKSPACE, self.rng)
        sid = self._create()
        if sid is None:
            return
        for _ in range(MAX_TOUCHES):
            obs, _ = world.execute(world.hitting_path(self.rng), BOUNDS, self.rng)
            if self._observe(sid, obs) in (None, *DONE):
                break
        self._delete(sid)
