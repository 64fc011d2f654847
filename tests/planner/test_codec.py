"""The JSON forms of DESIGN §6: the names of the contract, and observations that
come back as they went."""

from __future__ import annotations

import math

from hypothesis import given
from hypothesis import strategies as st

from planner.codec import observation_from_dict, observation_to_dict, plan_to_dict
from planner.planning.config import StrategyConfig
from planner.planning.plan import plan
from planner.planning.scoring import FAMILIES
from planner.types import Contact, Observation, SensingPath
from tests.planner.planning.test_strategies import FAST, FIG71, MODELS, SENSOR, WORKSPACE

coordinate = st.floats(-1e4, 1e4, allow_nan=False)
angle = st.floats(-math.pi, math.pi, allow_nan=False)


@given(coordinate, coordinate, angle, st.floats(1, 1e4), st.booleans(), angle, coordinate)
def test_an_observation_comes_back_from_its_json_form(x, y, way, length, hit, turn, along):
    direction = (math.cos(way), math.sin(way))
    path = SensingPath((x, y), direction, length)
    contact = None
    if hit:
        t = abs(along) % length
        point = (x + t * direction[0], y + t * direction[1])
        contact = Contact(point, (math.cos(turn), math.sin(turn)))
    obs = Observation(path, contact)
    back = observation_from_dict(observation_to_dict(obs))
    assert back == obs


def test_plan_json_uses_the_contract_names():
    result = plan(FIG71, MODELS, SENSOR, WORKSPACE, (100.0, 0.0), StrategyConfig(**FAST))
    body = plan_to_dict(result, version=3, limit=2)
    assert {"status", "truncated", "elapsed_ms", "paths"} <= set(body)
    assert len(body["paths"]) == 2
    assert {
        "origin",
        "direction",
        "length",
        "aim",
        "family",
        "p_distinguishing",
        "p_informative",
        "expected_pruning",
        "expected_remaining",
        "motion_cost",
    } <= set(body["paths"][0])
    assert body["paths"][0]["family"] in FAMILIES
    assert body["version"] == 3
