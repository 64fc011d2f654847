"""The answers' JSON forms (planner.codec) encode exactly what the response schemas write,
and the observation's forms keep their bytes."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from app.answers import PlanOut
from app.convert import plan_json, session_json
from app.schemas import SessionOut
from app.viewer import mii_json
from hardware_sim.world import random_world
from planner.codec import observation_from_dict, observation_to_dict, plan_to_dict, session_to_dict
from planner.planning.config import StrategyConfig
from planner.planning.plan import plan_session
from planner.planning.result import Plan, PlannedPath
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


def _touched(set_name: str, seed: int, touches: int) -> Session:
    models = object_set(set_name)
    rng = np.random.default_rng(seed)
    world = random_world(models, WORKSPACE, rng)
    session = Session(models, BOUNDS, WORKSPACE)
    for _ in range(touches):
        session = session.observe(world.execute(world.hitting_path(rng), BOUNDS, rng)[0])
    return session


def _schema_session(session_id, version, cfg, session, limit) -> bytes:
    data = session_to_dict(session_id, version, cfg, session, limit)
    return SessionOut.model_validate(data).model_dump_json().encode()


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    set_name=st.sampled_from(["thesis_like", "symmetric"]),
    seed=st.integers(0, 10_000),
    touches=st.integers(0, 4),
    limit=st.one_of(st.none(), st.integers(0, 8)),
    strategy_seed=st.one_of(st.none(), st.integers(0, 2**63 - 1)),
)
def test_session_json_is_the_schema_encoding(set_name, seed, touches, limit, strategy_seed):
    session = _touched(set_name, seed, touches)
    cfg = _config(strategy_seed)
    fast = session_json("abc", 1 + touches, cfg, session, limit)
    assert fast == _schema_session("abc", 1 + touches, cfg, session, limit)
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
    assert fast == _schema_session("abc", 3, cfg, session, None)
    answered = json.loads(fast)["observations"]
    assert answered[0] == {
        "index": 0,
        "path": {"origin": [200.0, 5.0], "direction": [-1.0, 0.0], "length": 5.0, "height": None},
        "contact": None,
    }
    assert answered[1]["contact"] == {"point": [40.0, 0.0], "normal": [1.0, 0.0], "normal_z": 0.25}


@settings(max_examples=8, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    seed=st.integers(0, 10_000),
    touches=st.integers(0, 2),
    limit=st.one_of(st.none(), st.integers(0, 6)),
)
def test_plan_json_is_the_schema_encoding(seed, touches, limit):
    session = _touched("thesis_like", seed, touches)
    cfg = StrategyConfig(name="pdm", budget_ms=200)
    result = plan_session(session, (WORKSPACE.radius, 0.0), cfg, np.random.default_rng(seed))
    fast = plan_json(result, 1 + touches, limit)
    schema = PlanOut.model_validate(plan_to_dict(result, 1 + touches, limit))
    assert fast == schema.model_dump_json().encode()


def test_plan_numbers_take_the_schema_types_and_non_finite_scores_are_null():
    path = PlannedPath(
        origin=(200, 0),
        direction=(-1.0, 0.0),
        length=400,
        aim=(0, 0),
        family="informative",
        p_distinguishing=1,
        p_informative=1,
        expected_pruning=0,
        expected_remaining=math.inf,
        motion_cost=math.nan,
        expected_eps_t=2,
        p_forecast=None,
    )
    result = Plan("ambiguous", False, 3, (path, path), "pdm", candidates=7, classes=2)
    fast = plan_json(result, 4, 1)
    assert fast == PlanOut.model_validate(plan_to_dict(result, 4, 1)).model_dump_json().encode()
    assert fast == (
        b'{"status":"ambiguous","truncated":false,"elapsed_ms":3.0,"paths":[{"origin":[200.0,0.0],'
        b'"direction":[-1.0,0.0],"length":400.0,"aim":[0.0,0.0],"family":"informative",'
        b'"p_distinguishing":1.0,"p_informative":1.0,"expected_pruning":0.0,'
        b'"expected_remaining":null,"motion_cost":null,"source":"general","expected_eps_t":2.0,'
        b'"p_forecast":null,"scored_by":"outcome_model","height":null}],"strategy":"pdm",'
        b'"note":null,'
        b'"candidates":7,"classes":2,"work":0.0,"stopped_by":null,"version":4}'
    )


TOUCH = {
    "path": {"origin": [0, -200], "direction": [0, 2], "length": 400},
    "contact": {"point": [5, -40], "normal": [0, -3], "normal_z": 0.5},
}
MISS = {"path": {"origin": [200, 5], "direction": [-1, 0], "length": 5}, "contact": None}


@pytest.mark.parametrize(
    ("body", "stored"),
    [
        (
            TOUCH,
            '{"path": {"origin": [0.0, -200.0], "direction": [0.0, 1.0], "length": 400.0}, '
            '"contact": {"point": [5.0, -40.0], "normal": [0.0, -1.0], "normal_z": 0.5}}',
        ),
        (
            MISS,
            '{"path": {"origin": [200.0, 5.0], "direction": [-1.0, 0.0], "length": 5.0}, '
            '"contact": null}',
        ),
        (
            {**TOUCH, "contact": {"point": [5, -40], "normal": [0, -1]}},
            '{"path": {"origin": [0.0, -200.0], "direction": [0.0, 1.0], "length": 400.0}, '
            '"contact": {"point": [5.0, -40.0], "normal": [0.0, -1.0]}}',
        ),
    ],
)
def test_the_stored_observation_form_is_the_request_form_normalized(body, stored):
    obs = observation_from_dict(body)
    assert json.dumps(observation_to_dict(obs)) == stored
    assert observation_from_dict(observation_to_dict(obs)) == obs


def test_the_viewer_draws_observations_without_normal_z():
    session = Session(object_set("thesis_like"), BOUNDS, WORKSPACE)
    for body in (MISS, TOUCH):
        session = session.observe(observation_from_dict(body))
    drawn = json.dumps(mii_json(session, [200.0, 0.0])["observations"])
    assert drawn == (
        '[{"origin": [200.0, 5.0], "direction": [-1.0, 0.0], "length": 5.0, "contact": null}, '
        '{"origin": [0.0, -200.0], "direction": [0.0, 1.0], "length": 400.0, '
        '"contact": {"point": [5.0, -40.0], "normal": [0.0, -1.0]}}]'
    )
