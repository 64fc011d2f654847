"""Several hosts on one database: any host serves any session, from its snapshot.

In process, two apps on one store stand for two hosts; then two real `tactile serve`
processes share one PostgreSQL database while 8 robots spread their requests over
both and one host is killed with SIGKILL half-way.
"""

from __future__ import annotations

import threading
import time

import httpx
import pytest

import app.convert
from tactile.server import Server
from tests.app.api_support import BOTTOM, RIGHT, SQUARE, WORKSPACE, api, miss

ROBOTS = 8
TOUCHES = 12


def test_a_host_that_never_saw_a_session_resumes_it_from_its_snapshot(
    db_target, tmp_path, monkeypatch
):
    body = {"objects": [SQUARE], "workspace": WORKSPACE, "strategy": {"name": "pdm"}}
    with api(tmp_path, db=db_target) as first:
        sid = first.post("/v1/sessions", json=body).json()["id"]
        for obs in (BOTTOM, RIGHT, miss(1)):
            assert first.post(f"/v1/sessions/{sid}/observations", json=obs).status_code == 201
        expected = first.get(f"/v1/sessions/{sid}").json()

    def no_replay(record):
        raise AssertionError("the session was replayed from its first observation")

    monkeypatch.setattr(app.convert, "build_session", no_replay)
    with api(tmp_path, db=db_target) as second:
        assert second.get(f"/v1/sessions/{sid}").json() == expected
        r = second.post(f"/v1/sessions/{sid}/observations", json=miss(2))  # and goes on
        assert r.status_code == 201 and r.json()["version"] == expected["version"] + 1
        assert second.get(f"/v1/sessions/{sid}/plan").status_code == 200
        # an undo goes back to the snapshot before the last one
        last = f"/v1/sessions/{sid}/observations/last"
        undone = second.delete(last, headers={"If-Match": f'"{r.json()["version"]}"'}).json()
        assert undone["observations"] == expected["observations"]
        assert undone["hypotheses"] == expected["hypotheses"]


def _robot(robot: int, sid: str, hosts: list[Server], acked: list[int]) -> None:
    """One robot's touches, each sent with If-Match and an Idempotency-Key and retried
    on the other host while a host is down (a replayed answer counts as the ack)."""
    etag = '"1"'
    clients = [httpx.Client(timeout=30) for _ in hosts]
    try:
        for k in range(TOUCHES):
            key = f"robot{robot}-touch{k}"
            attempt = robot + k
            deadline = time.monotonic() + 60
            while True:
                assert time.monotonic() < deadline, f"{key} never acknowledged"
                host = attempt % len(hosts)
                attempt += 1
                try:
                    r = clients[host].post(
                        f"{hosts[host].url}/v1/sessions/{sid}/observations",
                        json=miss(1000 * robot + k),
                        headers={"If-Match": etag, "Idempotency-Key": key},
                    )
                except httpx.TransportError:
                    time.sleep(0.05)
                    continue  # that host is down: the other one takes it
                if r.status_code in (502, 503, 504):
                    time.sleep(float(r.headers.get("retry-after", 0.1)))
                    continue
                assert r.status_code == 201, (r.status_code, r.text)
                etag = r.headers["etag"]
                acked.append(k)
                break
    finally:
        for c in clients:
            c.close()


def test_two_hosts_on_postgresql_survive_one_of_them_killed(postgres_url):
    hosts = [Server(postgres_url).start(), Server(postgres_url).start()]
    try:
        body = {"objects": [SQUARE], "workspace": WORKSPACE, "strategy": {"name": "pdm"}}
        sids = [
            httpx.post(f"{hosts[r % 2].url}/v1/sessions", json=body).json()["id"]
            for r in range(ROBOTS)
        ]
        acked: list[list[int]] = [[] for _ in range(ROBOTS)]
        robots = [
            threading.Thread(target=_robot, args=(r, sids[r], hosts, acked[r]))
            for r in range(ROBOTS)
        ]
        for t in robots:
            t.start()
        while sum(map(len, acked)) < ROBOTS * TOUCHES // 2:
            time.sleep(0.01)
        hosts[0].kill()  # SIGKILL half-way: requests in flight there get no answer
        for t in robots:
            t.join(120)
        assert not any(t.is_alive() for t in robots)
        hosts[0] = Server(postgres_url).start()  # it comes back
        for r, sid in enumerate(sids):
            assert acked[r] == list(range(TOUCHES))
            want = [round(-9 + 0.001 * (1000 * r + k), 4) for k in range(TOUCHES)]
            for host in hosts:  # the same, exactly once and in order, from both hosts
                state = httpx.get(f"{host.url}/v1/sessions/{sid}").json()
                seen = [round(o["path"]["origin"][1], 4) for o in state["observations"]]
                assert seen == want, (host.url, r)
                assert state["version"] == TOUCHES + 1
    finally:
        for host in hosts:
            host.kill()


def test_serve_refuses_a_database_url_it_cannot_use():
    server = Server("mysql://u@h/db")
    with pytest.raises(RuntimeError, match="unsupported database URL"):
        server.start(timeout=30)
