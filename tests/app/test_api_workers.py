"""Two worker processes on one database (two in-process apps on one file): a worker
that missed some versions catches up from what it has, and answers as if it had
derived the session from every observation."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import app.convert
from app.convert import build_session, catch_up, derive
from app.store_types import SessionRecord
from hardware_sim.world import random_world
from planner.codec import observation_to_dict
from planner.recognition.session import Session
from planner.types import SensorBounds
from tests.app.api_support import BOTTOM, RIGHT, SQUARE, WORKSPACE, api, miss
from tests.conftest import WORKSPACE as BIG_WORKSPACE
from tests.conftest import object_set

MODELS = object_set("thesis_like")
BOUNDS = SensorBounds(1.0, math.radians(3.0))
CONFIG = {
    "objects": [],  # filled below
    "sensor": {"position_error": BOUNDS.position_error, "normal_error": BOUNDS.normal_error},
    "workspace": {"center": [0.0, 0.0], "radius": BIG_WORKSPACE.radius},
    "sensor_position": [BIG_WORKSPACE.radius, 0.0],
    "max_outliers": 0,
}


def _touches(seed: int, n: int) -> list[dict]:
    rng = np.random.default_rng(seed)
    world = random_world(MODELS, BIG_WORKSPACE, rng)
    return [
        observation_to_dict(world.execute(world.hitting_path(rng), BOUNDS, rng)[0])
        for _ in range(n)
    ]


def _same_hypotheses(a: Session, b: Session) -> None:
    def key(h):
        return (h.object, h.stable_pose, h.assignment, h.equivalence_class)

    assert [key(h) for h in a.hypotheses] == [key(h) for h in b.hypotheses]
    for x, y in zip(a.hypotheses, b.hypotheses, strict=True):
        values = (y.pose.x, y.pose.y, y.pose.theta, y.probability, y.error_bound.eps_t)
        expected = (x.pose.x, x.pose.y, x.pose.theta, x.probability, x.error_bound.eps_t)
        assert values == pytest.approx(expected, rel=1e-9, abs=1e-9)


@settings(max_examples=15, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(seed=st.integers(0, 10_000), n=st.integers(1, 5), data=st.data())
def test_catching_up_from_any_prefix_equals_deriving_from_scratch(seed, n, data):
    from planner.models.library import object_to_dict

    config = {**CONFIG, "objects": [object_to_dict(m) for m in MODELS]}
    touches = _touches(seed, n)
    record = SessionRecord("s", 1 + n, config, tuple(touches), 0.0)
    known = data.draw(st.integers(0, n), label="observations the worker saw")
    base = derive(build_session(SessionRecord("s", 1 + known, config, tuple(touches[:known]), 0)))
    _same_hypotheses(derive(catch_up(base, record)), derive(build_session(record)))


def test_a_worker_that_missed_versions_extends_what_it_has(tmp_path, monkeypatch):
    body = {"objects": [SQUARE], "workspace": WORKSPACE, "strategy": {"name": "pdm"}}
    with api(tmp_path) as a, api(tmp_path) as b:
        sid = a.post("/v1/sessions", json=body).json()["id"]
        url = f"/v1/sessions/{sid}"
        a.post(f"{url}/observations", json=BOTTOM)
        assert b.get(url).json()["version"] == 2  # b derives version 2 (from scratch)
        a.post(f"{url}/observations", json=miss(1))
        a.post(f"{url}/observations", json=RIGHT)
        rebuilt = []
        real = app.convert.build_session
        monkeypatch.setattr(
            "app.convert.catch_up",
            lambda base, record: rebuilt.append(base is None) or catch_up(base, record),
        )
        monkeypatch.setattr("app.convert.build_session", lambda r: rebuilt.append(r) or real(r))
        seen_by_b = b.get(url).json()
        assert rebuilt == [False]  # one catch-up from version 2, no rebuild
        assert seen_by_b == a.get(url).json()
        assert seen_by_b["version"] == 4 and seen_by_b["status"] == "localized"
        # after an undo on a, b catches up from a version whose observations still fit
        a.delete(f"{url}/observations/last", headers={"If-Match": '"4"'})
        rebuilt.clear()
        assert b.get(url).json() == a.get(url).json()
        assert rebuilt == [False]


@pytest.mark.parametrize("known", [0, 1])
def test_a_write_on_a_worker_that_missed_versions_is_correct(tmp_path, known):
    body = {"objects": [SQUARE], "workspace": WORKSPACE, "strategy": {"name": "pdm"}}
    with api(tmp_path) as a, api(tmp_path) as b:
        sid = a.post("/v1/sessions", json=body).json()["id"]
        url = f"/v1/sessions/{sid}"
        if known:
            b.get(url)
        a.post(f"{url}/observations", json=BOTTOM)
        r = b.post(f"{url}/observations", json=RIGHT, headers={"If-Match": '"2"'})
        assert r.status_code == 201 and r.json()["status"] == "localized"
        assert a.get(url).json()["hypotheses"] == r.json()["hypotheses"]
