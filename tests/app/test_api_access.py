"""Per-client API keys: each session and object belongs to the key that created it.

Two clients share one service. What one creates, the other's key does not find
(404, worded as for an id that does not exist), cannot change or delete, and may
name again for itself; Idempotency-Keys are per client; viewer links are signed
with the owner's key. The keys come from the environment (JSON) or a keys file.
"""

from __future__ import annotations

import json

import pytest
from fastapi.testclient import TestClient

from app.access import Clients, load_clients
from app.main import create_app
from tests.app.api_support import (
    BOTTOM,
    FAST_STRATEGY,
    RECT,
    SENSOR,
    SQUARE,
    WORKSPACE,
    is_problem,
    test_settings,
)

KEYS = {"cell-1": "key-of-cell-1", "rig": "key-of-the-rig"}
CELL = {"Authorization": "Bearer key-of-cell-1"}
RIG = {"Authorization": "Bearer key-of-the-rig"}


def _session(objects):
    return {"objects": objects, "sensor": SENSOR, "workspace": WORKSPACE, "strategy": FAST_STRATEGY}


@pytest.fixture
def client(tmp_path):
    with TestClient(create_app(test_settings(tmp_path, api_keys=KEYS))) as c:
        yield c


def test_another_client_s_session_is_not_found_and_cannot_be_changed(client):
    r = client.post("/v1/sessions", json=_session([SQUARE, RECT]), headers=CELL)
    assert r.status_code == 201
    sid, tag = r.json()["id"], r.headers["ETag"]
    unknown = client.get("/v1/sessions/00000000-0000-4000-8000-000000000000", headers=RIG)
    reads = ("", "/plan?limit=3", "/image.json", "/image.svg", "/report.json", "/view")
    for read in reads:
        theirs = client.get(f"/v1/sessions/{sid}{read}", headers=RIG)
        assert is_problem(theirs, 404), (read, theirs.text)
        assert theirs.json()["detail"].startswith("no session"), read
        assert client.get(f"/v1/sessions/{sid}{read}", headers=CELL).status_code == 200, read
    assert is_problem(unknown, 404)
    writes = [
        client.post(f"/v1/sessions/{sid}/observations", json=BOTTOM, headers=RIG),
        client.post(f"/v1/sessions/{sid}/view-link", headers=RIG),
        client.post(f"/v1/sessions/{sid}/observations/last:undo", headers={**RIG, "If-Match": tag}),
        client.delete(f"/v1/sessions/{sid}", headers={**RIG, "If-Match": tag}),
    ]
    assert [w.status_code for w in writes] == [404] * 4
    # nothing of it happened: the owner still finds the session unchanged
    mine = client.get(f"/v1/sessions/{sid}", headers=CELL)
    assert mine.headers["ETag"] == tag and mine.json()["observations"] == []
    assert client.post(f"/v1/sessions/{sid}/observations", json=BOTTOM, headers=CELL).is_success


def test_objects_are_named_per_client(client):
    bigger = {**SQUARE, "outline": [[-2, -2], [2, -2], [2, 2], [-2, 2]]}
    assert client.post("/v1/objects", json=SQUARE, headers=CELL).status_code == 201
    # the rig does not see the cell's square and may register its own, other, square
    assert is_problem(client.get("/v1/objects/square", headers=RIG), 404)
    assert client.get("/v1/objects", headers=RIG).json()["objects"] == []
    assert client.post("/v1/objects", json=bigger, headers=RIG).status_code == 201
    for headers, shape in ((CELL, SQUARE), (RIG, bigger)):
        got = client.get("/v1/objects/square", headers=headers).json()
        assert got["stable_poses"][0]["outline"] == shape["outline"]
    # a session by name takes the caller's object
    for headers, side in ((CELL, 2.0), (RIG, 4.0)):
        r = client.post("/v1/sessions", json=_session(["square"]), headers=headers)
        assert r.status_code == 201, r.text
        sid = r.json()["id"]
        assert client.post(f"/v1/sessions/{sid}/observations", json=BOTTOM, headers=headers)
        got = client.get(f"/v1/sessions/{sid}/image.json", headers=headers).json()
        assert got["outlines"]
        assert all(
            max(x for x, _ in o["rings"][0]) - min(x for x, _ in o["rings"][0])
            == pytest.approx(side, abs=1e-6)
            for o in got["outlines"]
        )
    # deleting is per client too
    assert is_problem(client.delete("/v1/objects/rect", headers=RIG), 404)
    assert client.delete("/v1/objects/square", headers=RIG).status_code == 204
    assert client.get("/v1/objects/square", headers=CELL).status_code == 200
    # a name only the other client registered is unknown to a session
    r = client.post("/v1/sessions", json=_session(["square"]), headers=RIG)
    assert is_problem(r, 422) and "square" in r.json()["detail"]


def test_an_idempotency_key_replays_only_its_own_client_s_answer(client):
    body = _session([SQUARE, RECT])
    first = client.post("/v1/sessions", json=body, headers={**CELL, "Idempotency-Key": "k1"})
    again = client.post("/v1/sessions", json=body, headers={**CELL, "Idempotency-Key": "k1"})
    other = client.post("/v1/sessions", json=body, headers={**RIG, "Idempotency-Key": "k1"})
    assert first.status_code == again.status_code == other.status_code == 201
    assert again.json()["id"] == first.json()["id"]
    assert other.json()["id"] != first.json()["id"]
    assert client.get(f"/v1/sessions/{other.json()['id']}", headers=RIG).status_code == 200


def test_keys_and_documents(client):
    assert is_problem(client.get("/v1/objects"), 401)
    assert is_problem(client.get("/v1/objects", headers={"Authorization": "Bearer nope"}), 401)
    for headers in (CELL, RIG):
        assert client.get("/openapi.json", headers=headers).status_code == 200
        assert client.get("/metrics", headers=headers).status_code == 200
    assert client.get("/openapi.json").status_code == 401
    assert client.get("/healthz").status_code == 200


def test_a_viewer_link_is_signed_with_the_owner_s_key(client):
    sid = client.post("/v1/sessions", json=_session([SQUARE]), headers=CELL).json()["id"]
    link = client.post(f"/v1/sessions/{sid}/view-link", headers=CELL).json()
    assert client.get(link["url"]).status_code == 200
    assert client.get(f"/v1/sessions/{sid}/view").status_code == 401
    from app.view_tokens import make_token

    # a token signed with the other client's key opens nothing of the cell's
    expires = link["token"].partition(".")[0]
    forged = make_token(KEYS["rig"], sid, int(expires))
    assert client.get(f"/v1/sessions/{sid}/view?token={forged}").status_code == 401


def test_keys_come_from_a_file_and_the_single_key_is_the_unnamed_client(tmp_path):
    path = tmp_path / "keys.json"
    path.write_text(json.dumps({"line-3": "key-of-line-3"}))
    settings = test_settings(tmp_path, api_keys_file=path, api_key="shared-key")
    clients = load_clients(settings)
    assert clients.client_of("key-of-line-3") == "line-3"
    assert clients.client_of("shared-key") == ""
    with TestClient(create_app(settings)) as c:
        old = c.post(
            "/v1/sessions", json=_session([SQUARE]), headers={"Authorization": "Bearer shared-key"}
        )
        line = {"Authorization": "Bearer key-of-line-3"}
        assert old.status_code == 201
        assert c.get(f"/v1/sessions/{old.json()['id']}", headers=line).status_code == 404


@pytest.mark.parametrize(
    "keys, message",
    [
        ({"a": "same-key", "b": "same-key"}, "share a key"),
        ({"a b": "k"}, "client name"),
        ({"a": "two words"}, "white space"),
        ({"a": ""}, "empty"),
    ],
)
def test_a_bad_key_configuration_is_refused_at_start(keys, message):
    with pytest.raises(ValueError, match=message):
        Clients(keys)


def test_a_broken_keys_file_is_refused_at_start(tmp_path):
    path = tmp_path / "keys.json"
    for text in ("not json", '["a list"]', '{"a": 1}'):
        path.write_text(text)
        with pytest.raises(ValueError, match="api_keys_file"):
            load_clients(test_settings(tmp_path, api_keys_file=path))
    path.write_text('{"rig": "k1"}')
    with pytest.raises(ValueError, match="both"):
        load_clients(test_settings(tmp_path, api_keys_file=path, api_keys={"rig": "k2"}))
