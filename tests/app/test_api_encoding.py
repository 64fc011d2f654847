"""The session answer's fast encoder writes exactly what the response schema writes."""

from __future__ import annotations

import math

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from app.convert import session_json, session_out
from app.schemas import SessionOut
from hardware_sim.world import random_world
from planner.recognition.session import Session
from planner.types import Contact, Observation, SensingPath, SensorBounds
from tests.conftest import WORKSPACE, object_set

BOUNDS = SensorBounds(1.0, math.radians(3.0))
STRATEGY = {
    "name": "pdm",
    "depth": 2,
    "budget_ms": 200,  # an int where the schema has a float
    "max_paths": 5,
    "motion_weight": 0,
    "grid_size": 70,
}


def _config(seed: int | None) -> dict:
    return {
        "sensor": {"position_error": 1, "normal_error": BOUNDS.normal_error},
        "workspace": {"center": [0, 0], "radius": WORKSPACE.radius},
        "sensor_position": [WORKSPACE.radius, 0],
        "strategy": {**STRATEGY, "seed": seed},
        "max_outliers": 0,
    }


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    set_name=st.sampled_from(["thesis_like", "symmetric"]),
    seed=st.integers(0, 10_000),
    touches=st.integers(0, 4),
    limit=st.one_of(st.none(), st.integers(0, 8)),
    strategy_seed=st.one_of(st.none(), st.integers(0, 2**63 - 1)),
)
def test_session_json_is_the_schema_encoding(set_name, seed, touches, limit, strategy_seed):
    models = object_set(set_name)
    rng = np.random.default_rng(seed)
    world = random_world(models, WORKSPACE, rng)
    session = Session(models, BOUNDS, WORKSPACE)
    for _ in range(touches):
        session = session.observe(world.execute(world.hitting_path(rng), BOUNDS, rng)[0])
    cfg = _config(strategy_seed)
    fast = session_json("abc", 1 + touches, cfg, session, limit)
    assert fast == session_out("abc", 1 + touches, cfg, session, limit).model_dump_json().encode()
    SessionOut.model_validate_json(fast)


def test_misses_and_out_of_plane_normals_encode_alike():
    models = object_set("symmetric")
    session = Session(models, BOUNDS, WORKSPACE).observe(
        Observation(SensingPath((200.0, 5.0), (-1.0, 0.0), 5.0), None)
    )
    touch = Contact((40.0, 0.0), (1.0, 0.0), normal_z=0.25)
    session = session.observe(Observation(SensingPath((200.0, 0.0), (-1.0, 0.0), 400.0), touch))
    cfg = _config(None)
    fast = session_json("abc", 3, cfg, session, None)
    assert fast == session_out("abc", 3, cfg, session, None).model_dump_json().encode()
