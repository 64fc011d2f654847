"""What browsers are told (nosniff, content security policies) and the Host allow-list."""

from __future__ import annotations

import json

import httpx
import pytest
from fastapi.testclient import TestClient

from app.main import create_app
from app.security import STRICT_CSP, host_name
from app.settings import Settings
from app.viewer import VIEW_CSP, VIEW_HTML
from tactile.server import Server
from tests.conftest import DATA

SESSION = {
    "objects": json.loads((DATA / "thesis_like.json").read_text())["objects"][:1],
    "sensor": {"position_error": 1.0, "normal_error": 0.05},
    "workspace": {"center": [0, 0], "radius": 200},
}


@pytest.fixture
def client(tmp_path):
    with TestClient(create_app(Settings(db_path=str(tmp_path / "s.db")))) as c:
        yield c


def test_every_answer_is_nosniff_and_inert_but_the_viewer_runs_its_own_script(client):
    sid = client.post("/v1/sessions", json=SESSION).json()["id"]
    answers = {
        "health": client.get("/healthz"),
        "json": client.get(f"/v1/sessions/{sid}"),
        "svg": client.get(f"/v1/sessions/{sid}/image.svg"),
        "problem": client.get("/v1/sessions/00000000-0000-4000-8000-000000000000"),
        "metrics": client.get("/metrics"),
        "view": client.get(f"/v1/sessions/{sid}/view"),
    }
    for name, r in answers.items():
        assert r.status_code < 500, name
        assert r.headers["x-content-type-options"] == "nosniff", name
        assert r.headers["referrer-policy"] == "no-referrer", name
        expected = VIEW_CSP if name == "view" else STRICT_CSP
        assert r.headers["content-security-policy"] == expected, name
    # the viewer's policy names exactly its inline script and style, nothing else runs
    policy = dict(d.strip().split(" ", 1) for d in VIEW_CSP.split(";"))
    assert policy["default-src"] == "'none'" and policy["frame-ancestors"] == "'none'"
    assert policy["connect-src"] == "'self'"
    assert policy["script-src"].startswith("'sha256-") and " " not in policy["script-src"]
    assert "unsafe" not in VIEW_CSP
    assert VIEW_HTML.count("<script>") == 1 and VIEW_HTML.count("<style>") == 1


def test_the_policy_hash_follows_the_page_script():
    """The hash is computed from the page: a changed script gets a changed hash."""
    import app.viewer as viewer

    other = viewer.VIEW_HTML.replace("setInterval(refresh, 1500)", "setInterval(refresh, 1600)")
    assert viewer._inline_hash(other, "script") != viewer._inline_hash(viewer.VIEW_HTML, "script")
    assert viewer._inline_hash(other, "style") == viewer._inline_hash(viewer.VIEW_HTML, "style")


def test_the_documentation_pages_keep_their_scripts(client):
    r = client.get("/docs")
    assert r.status_code == 200 and "content-security-policy" not in r.headers
    assert r.headers["x-content-type-options"] == "nosniff"


@pytest.mark.parametrize(
    ("header", "name"),
    [
        ("localhost:8000", "localhost"),
        ("LOCALHOST", "localhost"),
        ("[::1]:80", "::1"),
        ("::1", "::1"),
        ("127.0.0.1:1", "127.0.0.1"),
        ("evil.example:80", "evil.example"),
        ("", ""),
    ],
)
def test_host_names_drop_port_brackets_and_case(header, name):
    assert host_name(header) == name


def test_a_host_off_the_allow_list_is_400_naming_the_setting(tmp_path):
    settings = Settings(db_path=str(tmp_path / "h.db"), allowed_hosts=["localhost", "::1"])
    with TestClient(create_app(settings), base_url="http://localhost") as c:
        assert c.get("/healthz").status_code == 200
        assert c.get("/healthz", headers={"Host": "[::1]:8000"}).status_code == 200
        for host in ("rebound.example", "localhost.example", "127.0.0.2", "127.0.0.1.nip.io"):
            r = c.post("/v1/sessions", json=SESSION, headers={"Host": host})
            assert r.status_code == 400, host
            assert r.headers["content-type"] == "application/problem+json"
            assert "allowed_hosts" in r.json()["detail"]


def test_tactile_serve_on_loopback_answers_loopback_names_only(tmp_path):
    """A real `tactile serve` on 127.0.0.1 with the setting unset: a page that rebinds
    its own name to 127.0.0.1 reaches nothing; the loopback names work."""
    with Server(tmp_path / "serve.db") as server:
        port = server.port
        assert httpx.get(server.url + "/healthz").status_code == 200
        assert httpx.get(f"http://localhost:{port}/healthz").status_code == 200
        r = httpx.get(server.url + "/healthz", headers={"Host": f"attacker.example:{port}"})
        assert r.status_code == 400 and "allowed_hosts" in r.text
        assert r.headers["content-type"] == "application/problem+json"


def test_an_explicit_allow_list_wins_over_the_loopback_default(tmp_path):
    env = {"TACTILE_ALLOWED_HOSTS": json.dumps(["tactile.lab"])}
    with Server(tmp_path / "serve.db", env=env) as server:
        assert httpx.get(server.url + "/healthz").status_code == 400
        r = httpx.get(server.url + "/healthz", headers={"Host": "tactile.lab"})
        assert r.status_code == 200


@pytest.mark.parametrize("path", ["/docs", "/redoc", "/openapi.json", "/metrics"])
def test_with_a_key_the_schema_docs_and_metrics_need_it(tmp_path, path):
    key = {"Authorization": "Bearer s3cret"}
    settings = Settings(db_path=str(tmp_path / "k.db"), api_key="s3cret")
    with TestClient(create_app(settings)) as c:
        r = c.get(path)
        assert r.status_code == 401 and r.headers["content-type"] == "application/problem+json"
        assert r.headers["www-authenticate"].startswith("Bearer")
        assert c.get(path, headers={"Authorization": "Bearer nope"}).status_code == 401
        assert c.get(path, headers=key).status_code == 200
        assert c.get("/healthz").status_code == 200  # probes need no key
    opened = Settings(db_path=str(tmp_path / "o.db"), api_key="s3cret", public_docs=True)
    with TestClient(create_app(opened)) as c:
        assert c.get(path).status_code == 200
        assert c.get("/v1/objects").status_code == 401  # the API itself still needs it


def test_the_schema_links_what_is_created_to_the_operations_on_it(client):
    """Each link names a real operation and only parameters it takes; following the
    links of a created session and object reaches them with 2xx."""
    schema = client.get("/openapi.json").json()
    ops = {
        op["operationId"]: (path, method, op)
        for path, item in schema["paths"].items()
        for method, op in item.items()
    }
    followed = set()
    sid = client.post("/v1/sessions", json=SESSION)
    plate = client.post("/v1/objects", json={**SESSION["objects"][0], "name": "linked"})
    answers = {"create_session": sid, "create_object": plate}
    for op_id, (_, _, op) in ops.items():
        for status, response in op["responses"].items():
            for link in response.get("links", {}).values():
                path, method, target = ops[link["operationId"]]
                names = {p["name"] for p in target.get("parameters", [])}
                params = link.get("parameters", {})
                for key in params:
                    assert key.removeprefix("header.") in names, (op_id, link)
                if op_id in answers and answers[op_id].status_code == int(status):
                    body = answers[op_id].json()
                    value = body["id"] if "session_id" in params else body["name"]
                    url = path.replace("{session_id}", value).replace("{name}", value)
                    if method == "get":
                        followed.add(link["operationId"])
                        assert client.get(url).status_code < 300, url
                    elif "requestBody" in link:  # the created object, in a new session
                        assert link["requestBody"] == {"objects": ["$response.body#/name"]}
                        followed.add(link["operationId"])
                        made = client.post(url, json={"objects": [value]})
                        assert made.status_code == 201, made.text
    assert {"get_session", "get_report_json", "get_object", "get_view"} <= followed
    assert "create_session" in followed


def _serve_any_address(tmp_path, env):
    import os
    import subprocess
    import sys

    return subprocess.Popen(
        [sys.executable, "-m", "tactile.cli", "serve", "--host", "0.0.0.0", "--port", "0",
         "--db", str(tmp_path / "any.db")],
        env={**os.environ, **env}, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
    )  # fmt: skip


def test_serving_other_hosts_needs_a_key_unless_open_access_is_set(tmp_path):
    refused = _serve_any_address(tmp_path, {})
    _, err = refused.communicate(timeout=60)
    assert refused.returncode != 0 and b"TACTILE_API_KEY" in err
    (tmp_path / "keys.json").write_text('{"cell-1": "k1", "rig": "k1"}')
    broken = _serve_any_address(tmp_path, {"TACTILE_API_KEYS_FILE": str(tmp_path / "keys.json")})
    _, err = broken.communicate(timeout=60)
    assert broken.returncode != 0 and b"share a key" in err
    keyed = ({"TACTILE_API_KEY": "s3cret"}, {"TACTILE_API_KEYS": '{"cell-1": "k1"}'})
    for env in (*keyed, {"TACTILE_OPEN_ACCESS": "true"}):
        server = _serve_any_address(tmp_path, env)
        try:
            started = False
            for line in server.stderr:
                if b"Application startup complete" in line:
                    started = True
                    break
            assert started, env
        finally:
            server.terminate()
            server.wait(timeout=30)


def test_a_viewer_link_opens_one_session_s_page_and_reads_and_nothing_else(tmp_path):
    key = {"Authorization": "Bearer s3cret"}
    settings = Settings(db_path=str(tmp_path / "v.db"), api_key="s3cret", view_link_ttl_s=60)
    with TestClient(create_app(settings)) as c:
        sid = c.post("/v1/sessions", json=SESSION, headers=key).json()["id"]
        other = c.post("/v1/sessions", json=SESSION, headers=key).json()["id"]
        assert c.get(f"/v1/sessions/{sid}/view").status_code == 401
        assert c.post(f"/v1/sessions/{sid}/view-link").status_code == 401
        link = c.post(f"/v1/sessions/{sid}/view-link", headers=key).json()
        token = {"Authorization": f"Bearer {link['token']}"}
        page = c.get(link["url"])
        assert page.status_code == 200 and page.headers["content-type"].startswith("text/html")
        for read in ("", "/image.json", "/plan?limit=5"):
            assert c.get(f"/v1/sessions/{sid}{read}", headers=token).status_code == 200, read
        # not another session, not a write, not the pictures or the report
        assert c.get(f"/v1/sessions/{other}", headers=token).status_code == 401
        assert c.get(f"/v1/sessions/{other}/view?token={link['token']}").status_code == 401
        touch = {
            "path": {"origin": [0, -200], "direction": [0, 1], "length": 400},
            "contact": None,
        }
        assert (
            c.post(f"/v1/sessions/{sid}/observations", json=touch, headers=token).status_code == 401
        )
        assert c.get(f"/v1/sessions/{sid}/report.json", headers=token).status_code == 401
        assert c.get("/v1/objects", headers=token).status_code == 401
        # a forged or expired token opens nothing
        expires, _, sig = link["token"].partition(".")
        forged = f"{int(expires) + 3600}.{sig}"
        assert (
            c.get(f"/v1/sessions/{sid}", headers={"Authorization": f"Bearer {forged}"}).status_code
            == 401
        )
        from app.view_tokens import make_token

        old = make_token("s3cret", sid, 1)
        assert (
            c.get(f"/v1/sessions/{sid}", headers={"Authorization": f"Bearer {old}"}).status_code
            == 401
        )
    with TestClient(create_app(Settings(db_path=str(tmp_path / "o.db")))) as c:
        sid = c.post("/v1/sessions", json=SESSION).json()["id"]
        assert c.post(f"/v1/sessions/{sid}/view-link").status_code == 409
