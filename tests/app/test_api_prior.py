"""POST /v1/sessions with a pose prior: echoed, obeyed by the first probe, checked."""

from __future__ import annotations

import pytest

from tests.app.api_support import BOTTOM, api, create_session, is_problem

PRIOR = {"region": {"center": [0.5, -0.5], "radius": 1.0}, "theta": [-0.2, 0.2]}


@pytest.fixture
def client(tmp_path):
    with api(tmp_path) as c:
        yield c


def test_a_prior_is_echoed_and_the_first_probe_aims_at_its_region(client):
    s = create_session(client, prior=PRIOR)
    assert s["prior"] == PRIOR
    probe = client.get(f"/v1/sessions/{s['id']}/plan").json()["paths"][0]
    (ox, oy), (dx, dy) = probe["origin"], probe["direction"]
    cx, cy = PRIOR["region"]["center"]
    assert abs(dx * (cy - oy) - dy * (cx - ox)) < 1e-9  # the probe's line meets the centre
    state = client.post(f"/v1/sessions/{s['id']}/observations", json=BOTTOM).json()
    plain = create_session(client)
    unbound = client.post(f"/v1/sessions/{plain['id']}/observations", json=BOTTOM).json()
    assert 0 < state["hypothesis_count"] <= unbound["hypothesis_count"]
    assert create_session(client)["prior"] is None


@pytest.mark.parametrize(
    "prior",
    [
        {"theta": [0.3, 0.1]},
        {"theta": [0.0, 7.0]},
        {"region": {"center": [0, 0], "radius": 0}},
        {"region": {"center": [0, 0]}},
        {"theta": [0.0]},
    ],
)
def test_a_malformed_prior_is_a_422_naming_it(client, prior):
    r = client.post(
        "/v1/sessions",
        json={"objects": [{"name": "sq", "outline": [[-1, -1], [1, -1], [1, 1], [-1, 1]]}],
              "prior": prior},
    )  # fmt: skip
    assert is_problem(r, 422)
    assert any("prior" in e["field"] for e in r.json()["errors"]), r.json()
