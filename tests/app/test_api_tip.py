"""POST /v1/sessions with a ball tip: echoed, contacts taken as the ball's centre."""

from __future__ import annotations

import pytest

from tests.app.api_support import (
    BOTTOM,
    SENSOR,
    SQUARE,
    api,
    create_session,
    is_problem,
    observation,
)

TIP = {**SENSOR, "tip_radius": 0.5}


@pytest.fixture
def client(tmp_path):
    with api(tmp_path) as c:
        yield c


def test_the_tip_is_echoed_and_its_centres_localize_the_square(client):
    s = create_session(client, [SQUARE], sensor=TIP)
    assert s["sensor"]["tip_radius"] == 0.5
    assert create_session(client)["sensor"]["tip_radius"] == 0.0
    # the ball's centre stops 0.5 out from the bottom and right faces
    bottom = observation((0, -10), (0, 1), (0, -1.5), (0, -1))
    right = observation((10, 0), (-1, 0), (1.5, 0), (1, 0))
    for obs in (bottom, right):
        state = client.post(f"/v1/sessions/{s['id']}/observations", json=obs).json()
    assert state["status"] == "localized", state
    best = state["hypotheses"][0]
    assert best["object"] == "square"
    assert abs(best["pose"]["x"]) < 0.05 and abs(best["pose"]["y"]) < 0.05


def test_centres_taken_as_surface_points_are_another_pose(client):
    """The same centres without the tip: the square would sit 0.5 further out."""
    s = create_session(client, [SQUARE])
    for obs in (
        observation((0, -10), (0, 1), (0, -1.5), (0, -1)),
        observation((10, 0), (-1, 0), (1.5, 0), (1, 0)),
    ):
        state = client.post(f"/v1/sessions/{s['id']}/observations", json=obs).json()
    poses = [(h["pose"]["x"], h["pose"]["y"]) for h in state["hypotheses"]]
    assert all(abs(x) > 0.4 or abs(y) > 0.4 for x, y in poses)


def test_a_tip_session_plans_paths(client):
    s = create_session(client, sensor=TIP)
    client.post(f"/v1/sessions/{s['id']}/observations", json=BOTTOM)
    plan = client.get(f"/v1/sessions/{s['id']}/plan").json()
    assert plan["status"] == "ambiguous" and plan["paths"]


@pytest.mark.parametrize("radius", [-1.0, "wide", 1e12])
def test_a_bad_tip_radius_is_a_422_naming_it(client, radius):
    r = client.post(
        "/v1/sessions",
        json={"objects": [SQUARE], "sensor": {**SENSOR, "tip_radius": radius}},
    )
    assert is_problem(r, 422)
    assert any("tip_radius" in e["field"] for e in r.json()["errors"]), r.json()
