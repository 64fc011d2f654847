"""Hostile input: every bad request is a 4xx problem+json and the service stays healthy."""

from __future__ import annotations

import json
import uuid

import pytest

from tests.app.api_support import BOTTOM, RECT, SQUARE, api, create_session, is_problem

MAX_BODY = 20_000


@pytest.fixture(scope="module")
def hostile(tmp_path_factory):
    with api(tmp_path_factory.mktemp("hostile"), max_body_bytes=MAX_BODY) as client:
        session = create_session(client)
        yield client, session["id"]


def _observation(**path_and_contact):
    body = json.loads(json.dumps(BOTTOM))
    for key, value in path_and_contact.items():
        part, name = key.split("__")
        body[part][name] = value
    return body


RAW_OBSERVATIONS = {
    "malformed json": b'{"path": {"origin": [0, -10]',
    "not json at all": b"\x00\xff\xfe garbage",
    "nan": b'{"path": {"origin": [NaN, -10], "direction": [0, 1], "length": 20}}',
    "infinity": b'{"path": {"origin": [0, -10], "direction": [0, 1], "length": Infinity}}',
    "overflowing number": b'{"path": {"origin": [1e400, -10], "direction": [0, 1], "length": 2}}',
    "deep nesting": b'{"path": ' + b"[" * 5000 + b"]" * 5000 + b"}",
    "empty body": b"",
    "array body": b"[1, 2, 3]",
    "string body": b'"path"',
}

BAD_OBSERVATIONS = {
    "zero direction": _observation(path__direction=[0, 0]),
    "zero normal": _observation(contact__normal=[0.0, 0.0]),
    "negative length": _observation(path__length=-5),
    "zero length": _observation(path__length=0),
    "three coordinates": _observation(path__origin=[0, -10, 3]),
    "one coordinate": _observation(contact__point=[0]),
    "string coordinate": _observation(path__origin=["0", "x"]),
    "huge coordinate": _observation(path__origin=[1e300, 0]),
    "contact behind origin": _observation(contact__point=[0, -30]),
    "unknown field": {**BOTTOM, "force": 3},
    "no path": {"contact": None},
    "normal_z out of range": _observation(contact__normal_z=2.0),
}

BAD_OBJECTS = {
    "self-intersecting outline": {"name": "bow", "outline": [[0, 0], [2, 2], [2, 0], [0, 2]]},
    "two vertices": {"name": "line", "outline": [[0, 0], [1, 1]]},
    "collinear": {"name": "flat", "outline": [[0, 0], [1, 0], [2, 0]]},
    "repeated vertex": {"name": "dup", "outline": [[0, 0], [0, 0], [1, 0], [0, 1]]},
    "hole outside": {
        "name": "h",
        "outline": [[0, 0], [1, 0], [1, 1], [0, 1]],
        "holes": [[[5, 5], [6, 5], [6, 6]]],
    },
    "both shapes": {"name": "both", "outline": SQUARE["outline"], "stable_poses": []},
    "neither shape": {"name": "none"},
    "empty name": {"name": "", "outline": SQUARE["outline"]},
    "slash in name": {"name": "a/b", "outline": SQUARE["outline"]},
    "probabilities over one": {
        "name": "p",
        "stable_poses": [
            {"outline": SQUARE["outline"], "probability": 0.8},
            {"outline": RECT["outline"], "probability": 0.8},
        ],
    },
    "negative prior": {"name": "p", "outline": SQUARE["outline"], "prior": -1},
    "nan in outline": {"name": "n", "outline": [[0, 0], [1, 0], [float("nan"), 1]]},
}

BAD_SESSIONS = {
    "unknown strategy": {"objects": [SQUARE], "strategy": {"name": "telepathy"}},
    "negative position error": {"objects": [SQUARE], "sensor": {"position_error": -1}},
    "normal error of 45 degrees": {"objects": [SQUARE], "sensor": {"normal_error": 0.8}},
    "zero radius": {"objects": [SQUARE], "workspace": {"radius": 0}},
    "unknown object name": {"objects": ["ghost"]},
    "no objects": {"objects": []},
    "negative outliers": {"objects": [SQUARE], "max_outliers": -1},
    "zero depth": {"objects": [SQUARE], "strategy": {"name": "lookahead", "depth": 0}},
    "zero budget": {"objects": [SQUARE], "strategy": {"budget_ms": 0}},
}


def _healthy(client, session_id):
    assert client.get("/healthz").status_code == 200
    assert client.get("/readyz").status_code == 200
    assert client.get(f"/v1/sessions/{session_id}").status_code == 200


@pytest.mark.parametrize("name", list(RAW_OBSERVATIONS))
def test_raw_garbage_is_a_4xx_problem(hostile, name):
    client, sid = hostile
    r = client.post(
        f"/v1/sessions/{sid}/observations",
        content=RAW_OBSERVATIONS[name],
        headers={"content-type": "application/json"},
    )
    assert 400 <= r.status_code < 500 and is_problem(r), r.text
    _healthy(client, sid)


@pytest.mark.parametrize("name", list(BAD_OBSERVATIONS))
def test_bad_observations_name_the_field(hostile, name):
    client, sid = hostile
    r = client.post(f"/v1/sessions/{sid}/observations", json=BAD_OBSERVATIONS[name])
    assert is_problem(r, 422), r.text
    fields = [e["field"] for e in r.json()["errors"]]
    assert fields and all(fields)
    _healthy(client, sid)


@pytest.mark.parametrize("name", list(BAD_OBJECTS))
def test_bad_objects_are_refused(hostile, name):
    client, sid = hostile
    body = json.dumps(BAD_OBJECTS[name], allow_nan=True)
    r = client.post("/v1/objects", content=body, headers={"content-type": "application/json"})
    assert is_problem(r, 422), r.text
    _healthy(client, sid)


@pytest.mark.parametrize("name", list(BAD_SESSIONS))
def test_bad_sessions_are_refused(hostile, name):
    client, sid = hostile
    r = client.post("/v1/sessions", json=BAD_SESSIONS[name])
    assert is_problem(r, 422), r.text
    assert r.json()["errors"][0]["field"].split(".")[0].split("[")[0] in BAD_SESSIONS[name]
    _healthy(client, sid)


def test_oversized_bodies_are_413_declared_or_streamed(hostile):
    client, sid = hostile
    url = f"/v1/sessions/{sid}/observations"
    big = json.dumps({**BOTTOM, "pad": "x" * (2 * MAX_BODY)}).encode()
    r = client.post(url, content=big, headers={"content-type": "application/json"})
    assert is_problem(r, 413)

    def chunks():
        for _ in range(10):
            yield b" " * (MAX_BODY // 4)

    r = client.post(url, content=chunks(), headers={"content-type": "application/json"})
    assert is_problem(r, 413)
    outline = [[i, i * i] for i in range(MAX_BODY)]
    r = client.post("/v1/objects", json={"name": "huge", "outline": outline})
    assert is_problem(r, 413)
    _healthy(client, sid)
    assert len(client.get(f"/v1/sessions/{sid}").json()["observations"]) == 0


def test_too_many_vertices_is_422_naming_the_outline(tmp_path):
    with api(tmp_path, max_outline_vertices=8) as client:
        outline = [[10 * (i % 2) + i, i * i] for i in range(9)]
        r = client.post("/v1/objects", json={"name": "many", "outline": outline})
        assert is_problem(r, 422) and r.json()["errors"][0]["field"] == "outline"


@pytest.mark.parametrize(
    ("method", "path"),
    [
        ("get", "/v1/sessions/{unknown}"),
        ("get", "/v1/sessions/{unknown}/plan"),
        ("get", "/v1/sessions/{unknown}/image.svg"),
        ("get", "/v1/sessions/{unknown}/image.png"),
        ("delete", "/v1/sessions/{unknown}"),
        ("delete", "/v1/sessions/{unknown}/observations/last"),
        ("get", "/v1/sessions/not-a-uuid"),
        ("get", "/v1/sessions/{session}/plan?limit=0"),
        ("get", "/v1/sessions/{session}/plan?limit=lots"),
        ("get", "/v1/sessions/{session}/image.svg?view=cubist"),
        ("get", "/v1/sessions/{session}/image.png?dpi=100000"),
        ("get", "/v1/sessions/{session}?limit=-1"),
        ("get", "/v1/objects/%00"),
        ("get", "/v1/nothing-here"),
        ("put", "/v1/sessions/{session}"),
    ],
)
def test_unknown_ids_and_bad_parameters_are_4xx_problems(hostile, method, path):
    client, sid = hostile
    url = path.format(unknown=uuid.UUID(int=7), session=sid)
    r = client.request(method, url)
    assert 400 <= r.status_code < 500 and is_problem(r), (r.status_code, r.text)
    _healthy(client, sid)


def test_bad_headers_are_4xx(hostile):
    client, sid = hostile
    url = f"/v1/sessions/{sid}/observations"
    r = client.post(url, json=BOTTOM, headers={"Idempotency-Key": "has space"})
    assert is_problem(r, 422)
    r = client.post(url, json=BOTTOM, headers={"If-Match": "garbage"})
    assert is_problem(r, 412)
    r = client.post(url, content=json.dumps(BOTTOM), headers={"content-type": "text/plain"})
    assert 400 <= r.status_code < 500 and is_problem(r)
    _healthy(client, sid)
    assert len(client.get(f"/v1/sessions/{sid}").json()["observations"]) == 0


@pytest.mark.parametrize(
    "name",
    [
        "plaque ø 40 — 日本",
        "a?b#c",
        "$x^2$ \\frac{1}{0}",
        "cut $\\nosuch{$ 2",
        "<b>bold<b> & 'q'",
        "100%",
        "_{}^$",
    ],
)
def test_any_name_is_registered_located_and_drawn(hostile, name):
    client, _ = hostile
    outline = [[-2, -1], [2, -1], [2, 1], [-2, 1]]
    r = client.post("/v1/objects", json={"name": name, "outline": outline})
    assert r.status_code in (200, 201), r.text
    location = r.headers["location"]
    assert location.isascii() and "?" not in location and "#" not in location
    got = client.get(location)
    assert got.status_code == 200 and got.json()["name"] == name
    sid = create_session(client, objects=[name])["id"]
    assert client.post(f"/v1/sessions/{sid}/observations", json=BOTTOM).status_code == 201
    for kind in ("png", "svg"):
        picture = client.get(f"/v1/sessions/{sid}/image.{kind}")
        assert picture.status_code == 200, (kind, picture.text[:200])
    # unregistered: gone from the registry, the session keeps its copy
    assert client.delete(location).status_code == 204
    assert is_problem(client.get(location), 404) and is_problem(client.delete(location), 404)
    assert client.get(f"/v1/sessions/{sid}").json()["objects"] == [name]


@pytest.mark.parametrize(
    "path",
    [
        "/v1/sessions/{session}/plan?limt=3",
        "/v1/sessions/{session}/image.png?dpi=50&colour=red",
        "/v1/sessions/{session}?verbose=1",
        "/v1/objects?pge=2",
    ],
)
def test_an_unknown_query_parameter_is_a_422_naming_it(hostile, path):
    client, sid = hostile
    r = client.get(path.format(session=sid))
    assert is_problem(r, 422)
    name = path.split("?")[1].split("&")[-1].split("=")[0]
    assert r.json()["errors"][0]["field"] == name
    _healthy(client, sid)
