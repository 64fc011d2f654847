"""Probing heights over HTTP (DESIGN §4.13, §6): objects with slices, paths with a height."""

from __future__ import annotations

import io

import numpy as np
import pytest
import trimesh
from fastapi.testclient import TestClient

from app.main import create_app
from app.settings import Settings

SQUARE = [[-20, -20], [20, -20], [20, 20], [-20, 20]]
HOLE = [[-5, -5], [-5, 5], [5, 5], [5, -5]]
INSET = [[-16, -16], [16, -16], [16, 16], [-16, 16]]
OBJECTS = [
    {"name": "box", "stable_poses": [{"slices": [
        {"height": 10, "outline": SQUARE}, {"height": 36, "outline": SQUARE}]}]},
    {"name": "chamfered", "stable_poses": [{"slices": [
        {"height": 10, "outline": SQUARE}, {"height": 36, "outline": INSET}]}]},
]  # fmt: skip
SESSION = {
    "objects": OBJECTS,
    "sensor": {"position_error": 1.0, "normal_error": 0.05},
    "workspace": {"center": [0, 0], "radius": 100},
}


@pytest.fixture
def client(tmp_path):
    settings = Settings(db_path=str(tmp_path / "h.db"), max_slices=3, max_pose_faces=20)
    with TestClient(create_app(settings)) as c:
        yield c


def _observe(client, sid, path, contact):
    return client.post(f"/v1/sessions/{sid}/observations", json={"path": path, "contact": contact})


def test_the_plan_chooses_the_height_and_an_observation_carries_it(client):
    sid = client.post("/v1/sessions", json=SESSION).json()["id"]
    opening = client.get(f"/v1/sessions/{sid}/plan").json()["paths"][0]
    assert opening["height"] is None
    side = {"origin": [100, 0], "direction": [-1, 0], "length": 200}
    assert _observe(client, sid, side, {"point": [20, 0], "normal": [1, 0]}).status_code == 201
    assert _observe(client, sid, {**side, "origin": [0, 100], "direction": [0, -1]},
                    {"point": [0, 20], "normal": [0, 1]}).status_code == 201  # fmt: skip
    plan = client.get(f"/v1/sessions/{sid}/plan").json()
    assert plan["status"] == "ambiguous"
    assert plan["paths"][0]["height"] == 36.0  # only the top tells a chamfer
    # the chamfer answers 4 mm further in at that height
    top = {**side, "origin": [0, -100], "direction": [0, 1], "height": 36}
    answer = _observe(client, sid, top, {"point": [0, -16], "normal": [0, -1]}).json()
    assert {h["object"] for h in answer["hypotheses"]} == {"chamfered"}
    touches = client.get(f"/v1/sessions/{sid}/report.json").json()["touches"]
    assert [t["path"].get("height") for t in touches] == [None, None, 36.0]
    assert "height" in client.get(f"/v1/sessions/{sid}/report.csv").text.splitlines()[0]


def test_a_height_without_a_slice_is_refused_naming_the_field(client):
    sid = client.post("/v1/sessions", json=SESSION).json()["id"]
    path = {"origin": [0, -100], "direction": [0, 1], "length": 200, "height": 20}
    r = _observe(client, sid, path, None)
    assert r.status_code == 422
    assert r.json()["errors"][0]["field"] == "path.height"
    assert client.get(f"/v1/sessions/{sid}").json()["version"] == 1


@pytest.mark.parametrize(
    ("pose", "said"),
    [
        ({"slices": [{"height": h, "outline": SQUARE} for h in (1, 2, 3, 4)]}, "slices"),
        ({"slices": [{"height": h, "outline": SQUARE, "holes": [HOLE]} for h in (1, 2, 3)]},
         "max_pose_faces"),
        ({"outline": SQUARE, "slices": [{"height": 1, "outline": SQUARE}]}, "exactly one"),
    ],
)  # fmt: skip
def test_slices_are_held_to_their_limits(client, pose, said):
    r = client.post("/v1/objects", json={"name": "many", "stable_poses": [pose]})
    assert r.status_code == 422 and said in r.text


def test_objects_with_slices_round_trip(client):
    assert client.post("/v1/objects", json=OBJECTS[1]).status_code == 201
    got = client.get("/v1/objects/chamfered").json()["stable_poses"][0]
    assert [s["height"] for s in got["slices"]] == [10.0, 36.0]
    assert got["slices"][1]["outline"] == [[float(v) for v in p] for p in INSET]


def test_a_mesh_imports_with_slices_at_the_heights_asked(client):
    buf = io.BytesIO()
    trimesh.creation.box((40, 40, 40)).export(buf, file_type="stl")
    r = client.post(
        "/v1/objects:import-mesh?height=10&heights=30&name=cube&max_poses=1",
        content=buf.getvalue(),
        headers={"Content-Type": "application/octet-stream"},
    )
    assert r.status_code == 201, r.text
    pose = client.get("/v1/objects/cube").json()["stable_poses"][0]
    assert [s["height"] for s in pose["slices"]] == [10.0, 30.0]
    assert np.ptp(np.array(pose["slices"][1]["outline"]), axis=0).tolist() == [40.0, 40.0]
    too_many = client.post(
        "/v1/objects:import-mesh?height=5&heights=10&heights=15&heights=20&name=c2",
        content=buf.getvalue(),
        headers={"Content-Type": "application/octet-stream"},
    )
    assert too_many.status_code == 422 and "max_slices" in too_many.text
