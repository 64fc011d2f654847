"""HttpService: the closed loop over HTTP (generated client, in-process app) behaves
like the in-process loop, retries are safe, and problems become clear exceptions."""

from __future__ import annotations

import math
from collections.abc import Iterator

import httpx
import numpy as np
import pytest
from fastapi.testclient import TestClient

from app.main import create_app
from hardware_sim.api_client import Client
from hardware_sim.client import InProcessService, run_recognition
from hardware_sim.http_service import HttpService, InvalidRequestError, StaleVersionError
from hardware_sim.presets import build_arm, explicit_preset
from hardware_sim.world import random_world
from planner.planning.config import StrategyConfig
from planner.types import Contact, Observation, SensingPath, SensorBounds
from tests.app.api_support import test_settings
from tests.conftest import WORKSPACE, object_set

MODELS = object_set("thesis_like")
PRESET = explicit_preset(1.0, math.radians(3.0))
#: pdm with a budget it never reaches on this set: deterministic given the seed
PDM = {"name": "pdm", "budget_ms": 10_000.0}


@pytest.fixture(scope="module")
def http(tmp_path_factory: pytest.TempPathFactory) -> Iterator[TestClient]:
    app = create_app(test_settings(tmp_path_factory.mktemp("http")))
    with TestClient(app) as client:
        yield client


@pytest.fixture
def client(http: TestClient) -> Client:
    return Client(base_url="http://testserver").set_httpx_client(http)


def _new(client: Client, seed: int = 0, **kw) -> HttpService:
    return HttpService.create(
        client, MODELS, PRESET.bounds, WORKSPACE, strategy={**PDM, "seed": seed}, **kw
    )


@pytest.mark.parametrize("seed", [0, 1, 2, 5])
def test_http_loop_makes_the_same_touches_as_the_in_process_loop(client, seed):
    world = random_world(MODELS, WORKSPACE, np.random.default_rng(seed))
    local = InProcessService(MODELS, PRESET.bounds, WORKSPACE, StrategyConfig(**PDM), seed=seed)
    a = run_recognition(local, build_arm(world, PRESET, seed), max_touches=12)
    remote = _new(client, seed)
    b = run_recognition(remote, build_arm(world, PRESET, seed), max_touches=12)
    assert not any(s.advice.truncated for s in (*a.steps, *b.steps))  # the premise
    assert b.status == a.status
    # the same paths and contacts, to rounding (the service re-derives the session from
    # its stored observations, so numpy may sum in another order)
    assert len(b.steps) == len(a.steps)
    for x, y in zip(a.steps, b.steps, strict=True):
        assert _flat(y.observation) == pytest.approx(_flat(x.observation), abs=1e-9)
    assert [s.update for s in b.steps] == [s.update for s in a.steps]
    assert [s.advice.p_distinguishing for s in b.steps] == pytest.approx(
        [s.advice.p_distinguishing for s in a.steps]
    )
    # the bound each answers with (its most probable class')
    assert (b.bound is None) == (a.bound is None)
    assert b.bound is None or b.bound == pytest.approx(a.bound, abs=1e-9)
    assert len(b.estimates) == len(a.estimates)
    for x, y in zip(a.estimates, b.estimates, strict=True):
        assert (y.object, y.stable_pose, y.equivalence_class) == (
            x.object,
            x.stable_pose,
            x.equivalence_class,
        )
        assert (y.pose.x, y.pose.y, y.pose.theta, y.eps_t) == pytest.approx(
            (x.pose.x, x.pose.y, x.pose.theta, x.eps_t), abs=1e-9
        )
    assert remote.version == 1 + b.touches


def test_the_answer_is_read_in_one_request(client, monkeypatch):
    # the hypotheses and the bound of one state, not two reads of the session
    world = random_world(MODELS, WORKSPACE, np.random.default_rng(3))
    remote = _new(client, 3)
    sent = []
    send = remote._send

    def counted(what, call, *expected):
        sent.append(what)
        return send(what, call, *expected)

    monkeypatch.setattr(remote, "_send", counted)
    rec = run_recognition(remote, build_arm(world, PRESET, 3), max_touches=12)
    assert rec.status == "localized" and rec.bound is not None and rec.estimates
    assert sent.count("GET /v1/sessions/{id}") == 1


def _flat(o: Observation) -> list[float]:
    """An observation's numbers (a miss: zeros and a 0 flag for its contact)."""
    c = o.contact
    contact = [1.0, *c.point, *c.normal] if c is not None else [0.0] * 5
    return [*o.path.origin, *o.path.direction, o.path.length, *contact]


def test_advice_plans_from_the_sensor_position_given(client):
    service = _new(client)
    opening = service.advise((0.0, 200.0))
    assert opening.status == "awaiting_contact" and opening.p_distinguishing is None
    assert opening.path.origin == pytest.approx((0.0, 200.0))
    assert opening.path.direction == pytest.approx((0.0, -1.0))


def _contact_touch() -> Observation:
    path = SensingPath((200.0, 0.0), (-1.0, 0.0), 400.0)
    return Observation(path, Contact((40.0, 0.0), (1.0, 0.0)))


def test_a_retried_observation_is_recorded_once(http, client):
    service = _new(client, retries=2, backoff_s=0.0)
    lost = []

    def lose_first_answer(response: httpx.Response) -> None:
        if response.request.method == "POST" and not lost:
            lost.append(response.request.headers["Idempotency-Key"])
            raise httpx.ReadError("connection reset", request=response.request)

    http.event_hooks = {"request": [], "response": [lose_first_answer]}
    try:
        update = service.observe(_contact_touch())
    finally:
        http.event_hooks = {"request": [], "response": []}
    assert lost, "the first answer was not lost"
    assert update.status == "ambiguous" and update.hypotheses > 0
    state = http.get(f"/v1/sessions/{service.session_id}").json()
    assert state["version"] == service.version == 2
    assert len(state["observations"]) == 1


def test_a_stale_version_names_if_match(client):
    first = _new(client)
    second = HttpService.attach(client, first.session_id)
    second.observe(_contact_touch())
    with pytest.raises(StaleVersionError) as err:
        first.observe(_contact_touch())
    assert err.value.status == 412 and err.value.field == "If-Match"
    assert "If-Match" in str(err.value)


def test_bad_input_becomes_an_exception_naming_the_field(client):
    service = _new(client)
    far = Observation(SensingPath((1e7, 0.0), (-1.0, 0.0), 10.0), None)
    with pytest.raises(InvalidRequestError) as err:
        service.observe(far)
    assert err.value.status == 422 and err.value.field.startswith("path.origin")
    with pytest.raises(InvalidRequestError) as err:
        HttpService.create(client, MODELS, PRESET.bounds, WORKSPACE, max_outliers=1000)
    assert err.value.field == "max_outliers" and "max_outliers" in str(err.value)
    with pytest.raises(ValueError, match=r"strategy\.budget"):
        HttpService.create(client, MODELS, PRESET.bounds, WORKSPACE, strategy={"budget": 1})


def test_objects_by_registered_name(http, client):
    square = {"name": "sq40", "outline": [[-20, -20], [20, -20], [20, 20], [-20, 20]]}
    assert http.post("/v1/objects", json=square).status_code in (200, 201)
    service = HttpService.create(
        client, ["sq40"], SensorBounds(), WORKSPACE, strategy={"name": "pdm"}
    )
    update = service.observe(
        Observation(SensingPath((200.0, 0.0), (-1.0, 0.0), 400.0), Contact((20.0, 3.0), (1, 0)))
    )
    assert update.status == "ambiguous"
    assert {e.object for e in service.estimates()} == {"sq40"}


def test_an_observation_is_sent_in_the_form_the_service_stores(http, client):
    service = _new(client)
    touch = Observation(
        SensingPath((200.0, 0.0), (-2.0, 0.0), 400.0), Contact((40.0, 0.0), (3.0, 0.0), 0.25)
    )
    service.observe(touch)
    service.observe(Observation(SensingPath((200.0, 5.0), (-1.0, 0.0), 5.0), None))
    answered = http.get(f"/v1/sessions/{service.session_id}").json()["observations"]
    assert [{k: v for k, v in o.items() if k != "index"} for o in answered] == [
        {
            "path": {"origin": [200.0, 0.0], "direction": [-1.0, 0.0], "length": 400.0}
            | {"height": None},
            "contact": {"point": [40.0, 0.0], "normal": [1.0, 0.0], "normal_z": 0.25},
        },
        {
            "path": {"origin": [200.0, 5.0], "direction": [-1.0, 0.0], "length": 5.0}
            | {"height": None},
            "contact": None,
        },
    ]
