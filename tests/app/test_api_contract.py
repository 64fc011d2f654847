"""The HTTP contract of DESIGN §6, endpoint by endpoint, through the in-process app."""

from __future__ import annotations

import math
import uuid

import pytest
from fastapi import FastAPI

from app.answers import PlanOut
from app.schemas import HypothesisOut, SessionOut
from app.settings import Settings
from tests.app.api_support import (
    BOTTOM,
    FAST_STRATEGY,
    IMPOSSIBLE,
    RECT,
    RIGHT,
    SENSOR,
    SQUARE,
    WORKSPACE,
    api,
    create_session,
    is_problem,
    miss,
    test_settings,
)

TRIANGLE = {"name": "off_centre", "outline": [[10.5, 3.25], [14, 3.25], [10.5, 9]]}


@pytest.fixture
def client(tmp_path):
    with api(tmp_path) as c:
        yield c


# -- schema -----------------------------------------------------------------------------------
def test_openapi_lists_every_endpoint_with_stable_operation_ids(client):
    spec = client.get("/openapi.json").json()
    ops = {
        (path, method): op["operationId"]
        for path, item in spec["paths"].items()
        for method, op in item.items()
    }
    assert ops == {
        ("/v1/objects", "post"): "create_object",
        ("/v1/objects", "get"): "list_objects",
        ("/v1/objects/{name}", "get"): "get_object",
        ("/v1/objects/{name}", "delete"): "delete_object",
        ("/v1/sessions", "post"): "create_session",
        ("/v1/sessions/{session_id}", "get"): "get_session",
        ("/v1/sessions/{session_id}", "delete"): "delete_session",
        ("/v1/sessions/{session_id}/observations", "post"): "add_observation",
        ("/v1/sessions/{session_id}/observations/last", "delete"): "undo_observation",
        ("/v1/sessions/{session_id}/plan", "get"): "get_plan",
        ("/v1/sessions/{session_id}/image.svg", "get"): "get_image_svg",
        ("/v1/sessions/{session_id}/image.png", "get"): "get_image_png",
        ("/v1/sessions/{session_id}/image.json", "get"): "get_image_json",
        ("/v1/sessions/{session_id}/report.json", "get"): "get_report_json",
        ("/v1/sessions/{session_id}/report.csv", "get"): "get_report_csv",
        ("/v1/sessions/{session_id}/view", "get"): "get_view",
        ("/v1/sessions/{session_id}/view-link", "post"): "create_view_link",
        ("/v1/objects:import-mesh", "post"): "import_mesh",
        ("/healthz", "get"): "healthz",
        ("/readyz", "get"): "readyz",
    }
    errors = spec["paths"]["/v1/sessions/{session_id}/observations"]["post"]["responses"]
    for status in ("404", "412", "413", "422"):
        assert list(errors[status]["content"]) == ["application/problem+json"]


def test_limits_from_settings_appear_in_the_schema(tmp_path):
    settings = dict(
        max_outline_vertices=40,
        max_objects_per_session=3,
        max_plan_budget_ms=750.0,
        default_budget_ms=500.0,
        max_holes=2,
    )
    with api(tmp_path, **settings) as c:
        schemas = c.get("/openapi.json").json()["components"]["schemas"]
    outline = schemas["ObjectIn"]["properties"]["outline"]["anyOf"][0]
    assert (outline["minItems"], outline["maxItems"]) == (3, 40)
    assert schemas["SessionCreate"]["properties"]["objects"]["maxItems"] == 3
    assert schemas["StrategyIn"]["properties"]["budget_ms"]["maximum"] == 750.0
    assert schemas["StablePoseIn"]["properties"]["holes"]["maxItems"] == 2
    assert schemas["SensorIn"]["properties"]["normal_error"]["exclusiveMaximum"] == pytest.approx(
        math.pi / 4
    )


# -- objects ----------------------------------------------------------------------------------
def test_objects_are_registered_listed_and_fetched_with_their_own_coordinates(client):
    r = client.post("/v1/objects", json=TRIANGLE)
    assert r.status_code == 201 and r.json() == {"name": "off_centre"}
    assert r.headers["location"] == "/v1/objects/off_centre"
    again = client.post("/v1/objects", json=TRIANGLE)
    assert again.status_code == 200 and again.json() == {"name": "off_centre"}

    got = client.get("/v1/objects/off_centre").json()
    assert got["name"] == "off_centre" and len(got["stable_poses"]) == 1
    pose = got["stable_poses"][0]
    assert sorted(map(tuple, pose["outline"])) == sorted(map(tuple, TRIANGLE["outline"]))
    assert pose["probability"] == 1.0

    client.post("/v1/objects", json=SQUARE)
    listed = client.get("/v1/objects").json()
    assert [o["name"] for o in listed["objects"]] == ["off_centre", "square"]
    assert client.get("/v1/objects?limit=1").json()["objects"][0]["name"] == "off_centre"


def test_same_name_with_other_geometry_is_409_and_unknown_is_404(client):
    client.post("/v1/objects", json=SQUARE)
    r = client.post("/v1/objects", json={**SQUARE, "outline": [[0, 0], [3, 0], [0, 3]]})
    assert is_problem(r, 409) and r.json()["errors"][0]["field"] == "name"
    assert is_problem(client.get("/v1/objects/nothing"), 404)


def test_object_with_stable_poses_holes_and_prior_round_trips(client):
    obj = {
        "name": "plate",
        "prior": 2.0,
        "stable_poses": [
            {
                "outline": [[0, 0], [10, 0], [10, 10], [0, 10]],
                "holes": [[[4, 4], [4, 6], [6, 6], [6, 4]]],
                "probability": 0.75,
            },
            {"outline": [[0, 0], [10, 0], [10, 1], [0, 1]], "probability": 0.25},
        ],
    }
    assert client.post("/v1/objects", json=obj).status_code == 201
    got = client.get("/v1/objects/plate").json()
    assert got["prior"] == 2.0
    assert [p["probability"] for p in got["stable_poses"]] == [0.75, 0.25]
    assert len(got["stable_poses"][0]["holes"]) == 1 and "holes" not in got["stable_poses"][1]


def test_invalid_object_names_the_field(client):
    r = client.post(
        "/v1/objects", json={"name": "bow", "outline": [[0, 0], [1, 1], [1, 0], [0, 1]]}
    )
    assert is_problem(r, 422) and r.json()["errors"][0]["field"] == "outline"
    r = client.post("/v1/objects", json={"name": "two", "outline": [[0, 0], [1, 1]]})
    assert is_problem(r, 422) and r.json()["errors"][0]["field"] == "outline"


# -- sessions ---------------------------------------------------------------------------------
def test_create_session_answers_every_field_with_etag_and_location(client):
    client.post("/v1/objects", json=SQUARE)
    body = {
        "objects": ["square", RECT],
        "sensor": SENSOR,
        "workspace": WORKSPACE,
        "sensor_position": [0, 10],
        "strategy": {"name": "lookahead", "depth": 2, "budget_ms": 300},
        "max_outliers": 1,
    }
    r = client.post("/v1/sessions", json=body)
    assert r.status_code == 201
    s = SessionOut.model_validate(r.json()).model_dump()
    assert uuid.UUID(s["id"]).version == 4
    assert r.headers["etag"] == '"1"' and r.headers["location"] == f"/v1/sessions/{s['id']}"
    assert s["version"] == 1 and s["status"] == "awaiting_contact"
    assert s["objects"] == ["square", "rect"]
    assert s["sensor"] == {**SENSOR, "tip_radius": 0.0}
    assert s["workspace"] == {"center": [0.0, 0.0], "radius": 10.0}
    assert s["sensor_position"] == [0.0, 10.0]
    assert s["strategy"]["name"] == "lookahead" and s["strategy"]["depth"] == 2
    assert s["strategy"]["budget_ms"] == 300 and s["max_outliers"] == 1
    assert s["observations"] == [] and s["hypotheses"] == [] and s["hypothesis_count"] == 0
    assert client.get(f"/v1/sessions/{s['id']}").json() == r.json()


def test_session_defaults(client):
    s = client.post("/v1/sessions", json={"objects": [SQUARE]}).json()
    assert s["sensor"] == {"position_error": 0.0, "normal_error": 0.0, "tip_radius": 0.0}
    assert s["workspace"] == {"center": [0.0, 0.0], "radius": 200.0}
    assert s["sensor_position"] == [200.0, 0.0]
    assert s["strategy"]["name"] == "lookahead" and s["max_outliers"] == 0


def test_session_objects_must_be_registered_and_distinct(client):
    r = client.post("/v1/sessions", json={"objects": [SQUARE, "nowhere"]})
    assert is_problem(r, 422)
    assert r.json()["errors"][0]["field"] == "objects[1]"
    r = client.post("/v1/sessions", json={"objects": [SQUARE, SQUARE]})
    assert is_problem(r, 422) and r.json()["errors"][0]["field"] == "objects[1]"
    r = client.post("/v1/sessions", json={"objects": [{"name": "x", "outline": [[0, 0], [1, 0]]}]})
    assert is_problem(r, 422) and r.json()["errors"][0]["field"].startswith("objects[0]")


def test_observations_update_hypotheses_until_localized(client):
    s = create_session(client, objects=[SQUARE])
    url = f"/v1/sessions/{s['id']}"
    r = client.post(f"{url}/observations", json=BOTTOM)
    assert r.status_code == 201 and r.headers["etag"] == '"2"'
    first = SessionOut.model_validate(r.json())
    assert first.status == "ambiguous" and first.version == 2
    assert len(first.observations) == 1 and first.observations[0].contact is not None
    r = client.post(f"{url}/observations", json=RIGHT)
    state = r.json()
    assert state["status"] == "localized" and state["version"] == 3
    hyps = [HypothesisOut.model_validate(h) for h in state["hypotheses"]]
    assert len(hyps) == state["hypothesis_count"] > 0
    assert {h.equivalence_class for h in hyps} == {0} and state["class_count"] == 1
    assert math.isclose(sum(h.probability for h in hyps), 1.0, rel_tol=1e-9)
    assert all(len(h.assignment) == 2 for h in hyps)
    best = hyps[0]
    assert abs(best.pose.x) < 0.05 and abs(best.pose.y) < 0.05
    assert best.error_bound.translation >= 0 and best.error_bound.eps_t >= 0


def test_hypotheses_are_sorted_and_limit_caps_them(client):
    s = create_session(client)
    state = client.post(f"/v1/sessions/{s['id']}/observations", json=BOTTOM).json()
    probs = [h["probability"] for h in state["hypotheses"]]
    assert probs == sorted(probs, reverse=True) and len(probs) > 3
    capped = client.get(f"/v1/sessions/{s['id']}?limit=3").json()
    assert len(capped["hypotheses"]) == 3 and capped["hypothesis_count"] == len(probs)
    assert capped["hypotheses"] == state["hypotheses"][:3]


def test_a_miss_is_stored_as_null_contact(client):
    s = create_session(client)
    state = client.post(f"/v1/sessions/{s['id']}/observations", json=miss(0)).json()
    assert state["observations"][0]["contact"] is None
    assert state["status"] == "awaiting_contact"


def test_direction_and_normal_are_normalized(client):
    s = create_session(client, objects=[SQUARE])
    obs = {
        "path": {"origin": [0, -10], "direction": [0, 5], "length": 20},
        "contact": {"point": [0, -1], "normal": [0, -3]},
    }
    stored = client.post(f"/v1/sessions/{s['id']}/observations", json=obs).json()["observations"]
    assert stored[0]["path"]["direction"] == [0.0, 1.0]
    assert stored[0]["contact"]["normal"] == [0.0, -1.0]


def test_stale_if_match_is_412_and_current_one_passes(client):
    s = create_session(client)
    url = f"/v1/sessions/{s['id']}/observations"
    assert client.post(url, json=miss(1), headers={"If-Match": '"1"'}).status_code == 201
    r = client.post(url, json=miss(2), headers={"If-Match": '"1"'})
    assert is_problem(r, 412) and r.headers["etag"] == '"2"'
    assert client.post(url, json=miss(2), headers={"If-Match": 'W/"2"'}).status_code == 201
    assert client.post(url, json=miss(3), headers={"If-Match": "*"}).status_code == 201
    assert len(client.get(f"/v1/sessions/{s['id']}").json()["observations"]) == 3


def test_idempotency_key_replays_the_first_answer_once_stored(client):
    s = create_session(client)
    url = f"/v1/sessions/{s['id']}/observations"
    first = client.post(url, json=BOTTOM, headers={"Idempotency-Key": "touch-1"})
    again = client.post(url, json=BOTTOM, headers={"Idempotency-Key": "touch-1"})
    assert first.status_code == again.status_code == 201
    assert again.content == first.content and again.headers["etag"] == first.headers["etag"]
    assert again.headers["idempotent-replayed"] == "true"
    other = client.post(url, json=RIGHT, headers={"Idempotency-Key": "touch-1"})
    assert is_problem(other, 422) and other.json()["errors"][0]["field"] == "Idempotency-Key"
    assert len(client.get(f"/v1/sessions/{s['id']}").json()["observations"]) == 1


def test_idempotent_session_creation(client):
    body = {"objects": [SQUARE], "workspace": WORKSPACE}
    a = client.post("/v1/sessions", json=body, headers={"Idempotency-Key": "new-1"})
    b = client.post("/v1/sessions", json=body, headers={"Idempotency-Key": "new-1"})
    assert a.status_code == b.status_code == 201 and a.json()["id"] == b.json()["id"]


def test_undo_drops_the_last_observation(client):
    s = create_session(client)
    url = f"/v1/sessions/{s['id']}"
    client.post(f"{url}/observations", json=BOTTOM)
    two = client.post(f"{url}/observations", json=RIGHT).json()
    r = client.delete(f"{url}/observations/last", headers={"If-Match": '"3"'})
    assert r.status_code == 200 and r.headers["etag"] == '"4"'
    undone = r.json()
    assert undone["version"] == 4 and len(undone["observations"]) == 1
    assert undone["hypothesis_count"] > two["hypothesis_count"]
    client.delete(f"{url}/observations/last", headers={"Idempotency-Key": "undo-2"})
    r = client.delete(f"{url}/observations/last", headers={"If-Match": '"5"'})
    assert is_problem(r, 409) and r.json()["errors"][0]["field"] == "observations"


def test_undo_and_delete_without_a_precondition_are_428_and_change_nothing(client):
    # "undo whatever is last" could drop another client's acknowledged touch
    s = create_session(client)
    url = f"/v1/sessions/{s['id']}"
    one = client.post(f"{url}/observations", json=BOTTOM).json()
    for r in (client.delete(f"{url}/observations/last"), client.delete(url)):
        assert is_problem(r, 428)
        assert r.json()["errors"][0]["field"] == "If-Match"
        assert "ETag" in r.json()["detail"]
    assert client.get(url).json() == one
    # a stale ETag is still 412, the right one undoes
    assert is_problem(client.delete(f"{url}/observations/last", headers={"If-Match": '"1"'}), 412)
    r = client.delete(f"{url}/observations/last", headers={"If-Match": f'"{one["version"]}"'})
    assert r.status_code == 200 and r.json()["observations"] == []


def test_impossible_touch_is_inconsistent_not_an_error_and_undo_recovers(client):
    s = create_session(client)
    url = f"/v1/sessions/{s['id']}"
    client.post(f"{url}/observations", json=BOTTOM)
    before = client.post(f"{url}/observations", json=RIGHT).json()
    r = client.post(f"{url}/observations", json=IMPOSSIBLE)
    assert r.status_code == 201
    assert r.json()["status"] == "inconsistent" and r.json()["hypotheses"] == []
    plan = client.get(f"{url}/plan").json()
    assert plan["status"] == "inconsistent" and plan["paths"] == []
    back = client.delete(f"{url}/observations/last", headers={"Idempotency-Key": "u"}).json()
    assert back["status"] == before["status"] and back["hypotheses"] == before["hypotheses"]


def test_max_outliers_disowns_an_impossible_touch(client):
    s = create_session(client, objects=[SQUARE], max_outliers=1)
    url = f"/v1/sessions/{s['id']}/observations"
    for obs in (BOTTOM, RIGHT, IMPOSSIBLE):
        state = client.post(url, json=obs).json()
    assert state["status"] != "inconsistent"
    assert any(h["assignment"][2] is None for h in state["hypotheses"])


def test_delete_session(client):
    s = create_session(client)
    url = f"/v1/sessions/{s['id']}"
    assert is_problem(client.delete(url, headers={"If-Match": '"7"'}), 412)
    assert client.delete(url, headers={"If-Match": '"1"'}).status_code == 204
    assert is_problem(client.get(url), 404)
    assert is_problem(client.delete(url, headers={"If-Match": '"1"'}), 404)
    assert is_problem(client.post(f"{url}/observations", json=BOTTOM), 404)


# -- plan and pictures ------------------------------------------------------------------------
def test_plan_before_any_contact_is_the_opening_probe(client):
    s = create_session(client, sensor_position=[0, 10])
    r = client.get(f"/v1/sessions/{s['id']}/plan")
    plan = PlanOut.model_validate(r.json())
    assert plan.status == "awaiting_contact" and plan.version == 1 and len(plan.paths) == 1
    probe = plan.paths[0]
    assert math.hypot(*probe.origin) == pytest.approx(10.0)
    assert probe.direction[0] == pytest.approx(0.0, abs=1e-9)
    assert probe.direction[1] == pytest.approx(-1.0)


def test_plan_ranks_paths_with_every_field(client):
    s = create_session(client)
    client.post(f"/v1/sessions/{s['id']}/observations", json=BOTTOM)
    r = client.get(f"/v1/sessions/{s['id']}/plan?limit=3")
    assert r.status_code == 200 and r.headers["etag"] == '"2"'
    data = r.json()
    assert {"status", "truncated", "elapsed_ms", "paths"} <= set(data)
    plan = PlanOut.model_validate(data)
    assert plan.status == "ambiguous" and isinstance(plan.truncated, bool)
    assert plan.elapsed_ms >= 0 and 1 <= len(plan.paths) <= 3
    fields = {"origin", "direction", "length", "aim", "family", "p_distinguishing"}
    fields |= {"p_informative", "expected_pruning", "expected_remaining", "motion_cost"}
    for path in data["paths"]:
        assert fields <= set(path)
        assert path["family"] in {"distinguishing", "informative", "partial", "uninformative"}
        assert -1e-6 <= path["p_distinguishing"] <= path["p_informative"] + 1e-6 <= 1 + 2e-6
        assert math.hypot(*path["direction"]) == pytest.approx(1.0)
    assert len(client.get(f"/v1/sessions/{s['id']}/plan?limit=1").json()["paths"]) == 1


def test_plan_forecasts_the_best_path_unless_told_not_to(client):
    for forecast, expect in ((None, 1), (0, 0), (2, 2)):
        strategy = {"forecast": forecast, "budget_work": 3e6, "budget_ms": 10000}
        body = {} if forecast is None else {"strategy": strategy}
        s = create_session(client, **body)
        assert s["strategy"]["forecast"] == (1 if forecast is None else forecast)
        client.post(f"/v1/sessions/{s['id']}/observations", json=BOTTOM)
        paths = client.get(f"/v1/sessions/{s['id']}/plan?limit=3").json()["paths"]
        made = [p["p_forecast"] for p in paths]
        if forecast is not None:  # with the default budget the forecast may run out
            assert all(m is not None and 0 <= m <= 1 for m in made[:expect])
        assert all(m is None for m in made[expect:])
    bad = client.post("/v1/sessions", json={"objects": ["plate"], "strategy": {"forecast": -1}})
    assert bad.status_code == 422 and "forecast" in bad.text


def test_plan_from_the_sensor_position_given(client):
    s = create_session(client, sensor_position=[10, 0])
    url = f"/v1/sessions/{s['id']}/plan"
    probe = client.get(url, params={"sensor_x": 0, "sensor_y": -10}).json()["paths"][0]
    assert probe["origin"] == pytest.approx([0.0, -10.0])
    assert probe["direction"] == pytest.approx([0.0, 1.0], abs=1e-9)
    default = client.get(url).json()["paths"][0]  # the session's place, not the last asked
    assert default["origin"] == pytest.approx([10.0, 0.0])
    # one coordinate alone moves the session's place along that axis; the probe
    # starts on the safe circle (radius 10) toward the sensor
    bearing = [10**0.5, -3 * 10**0.5]  # radius 10 toward (10, -30)
    for params, origin in [({"sensor_x": -20}, [-10.0, 0.0]), ({"sensor_y": -30}, bearing)]:
        got = client.get(url, params=params).json()["paths"][0]["origin"]
        assert got == pytest.approx(origin, abs=1e-9)
    r = client.get(url, params={"sensor_x": "nan", "sensor_y": 0})
    assert is_problem(r, 422) and r.json()["errors"][0]["field"] == "sensor_x"


@pytest.mark.parametrize("seed", [0, 12345, 2**63 - 1])
def test_sessions_with_one_seed_make_the_same_plans(client, seed):
    def plans() -> list:
        # a budget that never binds: the seed, not the machine's speed, decides
        s = create_session(client, strategy={**FAST_STRATEGY, "budget_ms": 10000, "seed": seed})
        assert s["strategy"]["seed"] == seed
        client.post(f"/v1/sessions/{s['id']}/observations", json=BOTTOM)
        return client.get(f"/v1/sessions/{s['id']}/plan?limit=5").json()["paths"]

    assert plans() == plans()


def test_a_bad_seed_names_the_field(client):
    for seed in (-1, 2**63, 1.5, "x"):
        r = client.post(
            "/v1/sessions",
            json={"objects": [SQUARE], "workspace": WORKSPACE, "strategy": {"seed": seed}},
        )
        assert is_problem(r, 422) and r.json()["errors"][0]["field"] == "strategy.seed"


def test_plan_when_localized_is_empty(client):
    s = create_session(client, objects=[SQUARE])
    for obs in (BOTTOM, RIGHT):
        client.post(f"/v1/sessions/{s['id']}/observations", json=obs)
    plan = client.get(f"/v1/sessions/{s['id']}/plan").json()
    assert plan["status"] == "localized" and plan["paths"] == []


def test_a_required_accuracy_holds_back_localized_and_the_plan_refines(client):
    # the square touched twice, exactly: one class; an accuracy tighter than the
    # bound the two contacts leave keeps the session ambiguous and the plan refining
    loose = create_session(client, objects=[SQUARE])
    strict = create_session(
        client, objects=[SQUARE], accuracy={"translation": 1e-3, "rotation": 1e-3}
    )
    assert strict["accuracy"] == {"translation": 1e-3, "rotation": 1e-3}
    for s in (loose, strict):
        for obs in (BOTTOM, RIGHT):
            client.post(f"/v1/sessions/{s['id']}/observations", json=obs)
    done = client.get(f"/v1/sessions/{loose['id']}").json()
    assert done["status"] == "localized" and done["localization"]["missing"] == []
    state = client.get(f"/v1/sessions/{strict['id']}").json()
    assert state["status"] == "ambiguous" and state["localization"]["missing"] == ["accuracy"]
    assert state["localization"]["classes"] == 1
    assert state["localization"]["bound"]["translation"] > 1e-3
    plan = client.get(f"/v1/sessions/{strict['id']}/plan").json()
    assert plan["status"] == "ambiguous" and plan["classes"] == 1
    assert plan["paths"] or "no path shrinks" in plan["note"]
    bad = client.post("/v1/sessions", json={"objects": [SQUARE], "accuracy": {"rotation": 0.1}})
    assert is_problem(bad, 422) and "accuracy" in bad.text


def test_pictures_svg_and_png(client):
    s = create_session(client)
    url = f"/v1/sessions/{s['id']}"
    # before any contact: the scene and the opening probe, no MII yet
    first = client.get(f"{url}/image.svg")
    assert first.status_code == 200 and b"safe-circle" in first.content
    assert b"path-1" in first.content and b"outline-0" not in first.content
    assert b"P(DM)" not in first.content  # nothing to distinguish yet
    client.post(f"{url}/observations", json=BOTTOM)
    svg = client.get(f"{url}/image.svg")
    assert svg.status_code == 200 and svg.headers["content-type"].startswith("image/svg+xml")
    assert b"<svg" in svg.content[:2000] and b"contact-0" in svg.content
    png = client.get(f"{url}/image.png?dpi=40")
    assert png.status_code == 200 and png.headers["content-type"] == "image/png"
    assert png.content.startswith(b"\x89PNG\r\n\x1a\n")


# -- operations -------------------------------------------------------------------------------
def test_health_ready_and_metrics(client):
    assert client.get("/healthz").json() == {"status": "ok"}
    assert client.get("/readyz").json() == {"status": "ready"}
    client.get("/v1/objects")
    metrics = client.get("/metrics")
    assert metrics.status_code == 200
    assert 'http_requests_total{handler="/v1/objects",method="GET",status="200"}' in metrics.text


def test_request_id_is_echoed_and_logged(client, caplog):
    caplog.set_level("INFO", logger="app.access")
    r = client.get("/v1/objects", headers={"X-Request-ID": "robot-7.req-42"})
    assert r.headers["x-request-id"] == "robot-7.req-42"
    generated = client.get("/v1/objects", headers={"X-Request-ID": "bad id\x7f"})
    assert generated.headers["x-request-id"] != "bad id\x7f"
    lines = [rec.msg for rec in caplog.records if isinstance(rec.msg, dict)]
    assert any(line.get("request_id") == "robot-7.req-42" for line in lines)
    problem = client.get(f"/v1/sessions/{uuid.uuid4()}", headers={"X-Request-ID": "r-404"})
    assert problem.json()["request_id"] == "r-404"


def test_api_key_when_configured(tmp_path):
    with api(tmp_path, api_key="s3cret") as c:
        r = c.get("/v1/objects")
        assert is_problem(r, 401) and r.headers["www-authenticate"].startswith("Bearer")
        assert is_problem(c.get("/v1/objects", headers={"Authorization": "Bearer nope"}), 401)
        ok = c.get("/v1/objects", headers={"Authorization": "Bearer s3cret"})
        assert ok.status_code == 200
        assert c.get("/healthz").status_code == 200


def test_limits_are_settings(tmp_path):
    with api(tmp_path, max_objects_per_session=1, max_observations_per_session=2) as c:
        r = c.post("/v1/sessions", json={"objects": [SQUARE, RECT]})
        assert is_problem(r, 422) and r.json()["errors"][0]["field"] == "objects"
        s = create_session(c, objects=[SQUARE])
        url = f"/v1/sessions/{s['id']}/observations"
        assert c.post(url, json=miss(1)).status_code == 201
        assert c.post(url, json=miss(2)).status_code == 201
        r = c.post(url, json=miss(3))
        assert is_problem(r, 409) and r.json()["errors"][0]["field"] == "observations"
        big = {**FAST_STRATEGY, "budget_ms": 1e9}
        r = c.post("/v1/sessions", json={"objects": [SQUARE], "strategy": big})
        assert is_problem(r, 422) and r.json()["errors"][0]["field"] == "strategy.budget_ms"


def test_an_observation_leaving_too_many_hypotheses_is_409_and_not_recorded(tmp_path):
    with api(tmp_path) as c:
        s = create_session(c)
        first = c.post(f"/v1/sessions/{s['id']}/observations", json=BOTTOM).json()
    left = first["hypothesis_count"]
    assert left > 2
    with api(tmp_path, max_hypotheses=left - 1) as c:
        s = create_session(c)
        url = f"/v1/sessions/{s['id']}/observations"
        r = c.post(url, json=BOTTOM)
        assert is_problem(r, 409) and r.json()["errors"][0]["field"] == "max_hypotheses"
        assert str(left) in r.json()["detail"]
        after = c.get(f"/v1/sessions/{s['id']}").json()
        assert after["version"] == 1 and after["observations"] == []
        assert c.post(url, json=miss(1)).status_code == 201  # a miss leaves none
    with api(tmp_path, max_hypotheses=left) as c:
        s = create_session(c)
        assert c.post(f"/v1/sessions/{s['id']}/observations", json=BOTTOM).status_code == 201


def test_an_observation_too_costly_to_check_is_409_before_it_is_checked(tmp_path):
    with api(tmp_path, max_interpretation_work=1) as c:
        s = create_session(c)
        url = f"/v1/sessions/{s['id']}/observations"
        r = c.post(url, json=BOTTOM)
        assert is_problem(r, 409)
        assert r.json()["errors"][0]["field"] == "max_interpretation_work"
        after = c.get(f"/v1/sessions/{s['id']}").json()
        assert after["version"] == 1 and after["observations"] == []
    with api(tmp_path) as c:
        s = create_session(c)
        assert c.post(f"/v1/sessions/{s['id']}/observations", json=BOTTOM).status_code == 201


def test_sessions_survive_a_restart_on_the_same_file(tmp_path):
    with api(tmp_path) as c:
        s = create_session(c)
        c.post(f"/v1/sessions/{s['id']}/observations", json=BOTTOM)
        before = c.get(f"/v1/sessions/{s['id']}").json()
    with api(tmp_path) as c:
        assert c.get(f"/v1/sessions/{s['id']}").json() == before


def test_settings_come_from_the_environment(monkeypatch, tmp_path):
    monkeypatch.setenv("TACTILE_DB_PATH", str(tmp_path / "env.db"))
    monkeypatch.setenv("TACTILE_MAX_OBSERVATIONS_PER_SESSION", "7")
    monkeypatch.setenv("TACTILE_API_KEY", "k")
    settings = Settings()
    assert settings.db_path == tmp_path / "env.db"
    assert settings.max_observations_per_session == 7
    assert settings.api_key is not None and settings.api_key.get_secret_value() == "k"
    import app.main

    monkeypatch.setattr(app.main, "_default", None)
    default = app.main.app
    assert isinstance(default, FastAPI) and default is app.main.app
    assert default.state.settings.max_observations_per_session == 7


def test_in_memory_database_is_refused(tmp_path):
    with pytest.raises(ValueError, match="memory"):
        test_settings(tmp_path, db_path=":memory:")
