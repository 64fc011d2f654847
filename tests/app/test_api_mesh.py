"""POST /v1/objects:import-mesh: a triangle mesh upload becomes a registered object."""

from __future__ import annotations

import io

import pytest
import trimesh
from fastapi.testclient import TestClient

from app.main import create_app
from app.settings import Settings


def _stl(mesh: trimesh.Trimesh) -> bytes:
    buf = io.BytesIO()
    mesh.export(buf, file_type="stl")
    return buf.getvalue()


BINARY = {"Content-Type": "application/octet-stream"}


@pytest.fixture
def client(tmp_path):
    with TestClient(create_app(Settings(db_path=str(tmp_path / "m.db")))) as c:
        yield c


def test_a_box_mesh_registers_with_three_weighted_poses(client):
    body = _stl(trimesh.creation.box(extents=(40, 60, 100)))
    r = client.post(
        "/v1/objects:import-mesh?height=8&name=box",
        content=body,
        headers={"Content-Type": "application/octet-stream"},
    )
    assert r.status_code == 201 and r.headers["Location"] == "/v1/objects/box"
    obj = client.get("/v1/objects/box").json()
    probs = sorted((p["probability"] for p in obj["stable_poses"]), reverse=True)
    assert probs == pytest.approx([0.562, 0.3156, 0.1224], abs=0.03)
    again = client.post(
        "/v1/objects:import-mesh?height=8&name=box",
        content=body,
        headers={"Content-Type": "application/octet-stream"},
    )
    assert again.status_code == 200
    other = _stl(trimesh.creation.box(extents=(40, 60, 90)))
    clash = client.post("/v1/objects:import-mesh?height=8&name=box", content=other, headers=BINARY)
    assert clash.status_code == 409


@pytest.mark.parametrize(
    ("query", "body", "field"),
    [
        ("height=500&name=tall", "box", "height"),
        ("height=8&name=junk", b"not a mesh at all", "file"),
        ("height=8&name=empty", b"", "body"),
        ("height=-1&name=neg", "box", "height"),
        ("height=8&name=open", "open", "mesh"),
    ],
)
def test_bad_uploads_answer_problems_naming_the_field(client, query, body, field):
    if body == "box":
        body = _stl(trimesh.creation.box(extents=(40, 60, 100)))
    elif body == "open":
        mesh = trimesh.creation.box(extents=(40, 60, 100))
        mesh.update_faces(mesh.faces[:-2].__len__() * [True] + [False, False])
        body = _stl(mesh)
    r = client.post(f"/v1/objects:import-mesh?{query}", content=body, headers=BINARY)
    assert 400 <= r.status_code < 500
    assert r.headers["content-type"] == "application/problem+json"
    assert field in r.text
    assert client.get("/healthz").status_code == 200


@pytest.mark.parametrize(
    "content_type",
    [None, "text/plain", "application/x-www-form-urlencoded", "multipart/form-data; b=x"],
)
def test_a_mesh_without_a_binary_content_type_is_415_and_registers_nothing(client, content_type):
    """What a browser may send to any origin unasked (and no type at all) is refused."""
    headers = {} if content_type is None else {"Content-Type": content_type}
    body = _stl(trimesh.creation.box(extents=(40, 60, 100)))
    r = client.post("/v1/objects:import-mesh?height=8&name=sneaky", content=body, headers=headers)
    assert r.status_code == 415
    assert r.headers["content-type"] == "application/problem+json"
    assert "Content-Type" in r.text
    assert client.get("/v1/objects/sneaky").status_code == 404


@pytest.mark.parametrize("content_type", ["model/stl", "application/sla", "Model/STL; x=1"])
def test_model_and_stl_content_types_are_taken(client, content_type):
    body = _stl(trimesh.creation.box(extents=(40, 60, 100)))
    r = client.post(
        "/v1/objects:import-mesh?height=8&name=typed",
        content=body,
        headers={"Content-Type": content_type},
    )
    assert r.status_code == 201


def _upload(c, name, mesh):
    return c.post(
        f"/v1/objects:import-mesh?height=10&name={name}", content=_stl(mesh), headers=BINARY
    )


def test_a_finely_tessellated_sphere_is_refused_before_its_poses_are_computed(client):
    """5,120 hull faces are 5,120 stable poses to weigh and slice: 422 naming the limit."""
    r = _upload(client, "ball", trimesh.creation.icosphere(subdivisions=4, radius=30))
    assert r.status_code == 422 and "max_hull_faces" in r.json()["detail"]
    assert r.json()["errors"][0]["field"] == "mesh"


def test_mesh_limits_are_settings_and_the_result_meets_the_posted_limits(tmp_path):
    box = trimesh.creation.box(extents=(40, 60, 100))
    ball = trimesh.creation.icosphere(subdivisions=2, radius=30)
    settings = Settings(db_path=str(tmp_path / "l.db"), max_mesh_triangles=100)
    with TestClient(create_app(settings)) as c:
        r = _upload(c, "ball", ball)  # 320 triangles
        assert r.status_code == 422 and "max_mesh_triangles" in r.json()["detail"]
        assert _upload(c, "box", box).status_code == 201
    # the imported object is held to the limits of a posted one, and names where
    settings = Settings(db_path=str(tmp_path / "m.db"), max_stable_poses=2)
    with TestClient(create_app(settings)) as c:
        r = _upload(c, "box", box)  # three stable poses
        assert r.status_code == 422 and r.json()["errors"][0]["field"] == "mesh.stable_poses"
        assert c.get("/v1/objects/box").status_code == 404
        ok = c.post(
            "/v1/objects:import-mesh?height=10&name=box&max_poses=2",
            content=_stl(box),
            headers=BINARY,
        )
        assert ok.status_code == 201
    settings = Settings(db_path=str(tmp_path / "v.db"), max_outline_vertices=8)
    with TestClient(create_app(settings)) as c:
        r = _upload(c, "ball", ball)
        assert r.status_code == 422
        assert r.json()["errors"][0]["field"].startswith("mesh.stable_poses.0.outline")
