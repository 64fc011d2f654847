"""A real `tactile serve` process: acknowledged observations survive SIGKILL.

The server runs on 127.0.0.1 with a port it picks itself. A client posts
observations (one contact, then misses) and records each acknowledged one;
the server is killed with SIGKILL while the client is still posting; a new
server on the same database (a SQLite file, a PostgreSQL database) must hold
every acknowledged observation, in order (plus at most the one that was in flight).
"""

from __future__ import annotations

import json
import socket
import threading

import httpx
import pytest

from app.serve import bind_socket, bind_sockets
from app.supervisor import reuse_port_supported
from tactile.server import Server
from tests.app.api_support import BOTTOM, SQUARE, WORKSPACE, miss


def _signature(obs: dict) -> tuple:
    return (tuple(round(v, 6) for v in obs["path"]["origin"]), obs["contact"] is not None)


def test_acknowledged_observations_survive_sigkill(db_target):
    db = db_target
    acked: list[tuple] = []
    stop = threading.Event()
    with Server(db) as server:
        base = server.url
        with httpx.Client(base_url=base, timeout=30) as http:
            body = {"objects": [SQUARE], "workspace": WORKSPACE, "strategy": {"name": "pdm"}}
            sid = http.post("/v1/sessions", json=body).json()["id"]
            first = http.post(f"/v1/sessions/{sid}/observations", json=BOTTOM)
            assert first.status_code == 201
            acked.append(_signature(BOTTOM))

            def post_until_killed() -> None:
                k = 0
                while not stop.is_set():
                    obs = miss(k)
                    try:
                        r = http.post(f"/v1/sessions/{sid}/observations", json=obs)
                    except httpx.TransportError:
                        return  # the server died under us: this one is not acknowledged
                    if r.status_code == 201:
                        acked.append(_signature(obs))
                    k += 1

            writer = threading.Thread(target=post_until_killed)
            writer.start()
            while len(acked) < 25 and writer.is_alive():
                writer.join(0.01)
            server.kill()  # SIGKILL: no shutdown, no flush
            stop.set()
            writer.join(30)

    assert len(acked) >= 25
    with Server(db) as again, httpx.Client(base_url=again.url, timeout=30) as http:
        state = http.get(f"/v1/sessions/{sid}").json()
        stored = [_signature(o) for o in state["observations"]]
        assert stored[: len(acked)] == acked
        assert len(stored) - len(acked) in (0, 1)  # at most the one in flight
        assert state["version"] == len(stored) + 1
        assert state["status"] == "ambiguous"
        # the restarted service still takes observations on the recovered session
        r = http.post(f"/v1/sessions/{sid}/observations", json=miss(10_000))
        assert r.status_code == 201
        rid = r.headers["x-request-id"]
    # JSON log lines; the request's lines carry its id
    logged = [json.loads(line) for line in again.lines if line.startswith("{")]
    assert len(logged) == len(again.lines)
    access = [e for e in logged if e.get("event") == "request"]
    assert access and all(e.get("request_id") for e in access)
    assert any(e["request_id"] == rid and e["status"] == 201 for e in access)


def test_serve_with_two_workers_shares_the_database(db_target):
    db = db_target
    with Server(db, "--workers", "2") as server, httpx.Client(base_url=server.url) as http:
        sid = http.post("/v1/sessions", json={"objects": [SQUARE]}).json()["id"]
        for k in range(6):  # new connections spread over both workers
            with httpx.Client(base_url=server.url) as fresh:
                r = fresh.post(f"/v1/sessions/{sid}/observations", json=miss(k))
                assert r.status_code == 201
        assert len(http.get(f"/v1/sessions/{sid}").json()["observations"]) == 6
        metrics = http.get("/metrics").text
        assert "http_requests_total" in metrics


def test_serve_prepares_a_new_database_before_its_workers_start(tmp_path):
    """Several workers each open the database at startup; on a new SQLite file two
    creating it at once had the second find it locked and fail to start, and the
    supervisor then stopped the whole service. `tactile serve` creates it first."""
    import sqlite3

    from app.serve import _prepare_database
    from app.settings import Settings

    db = tmp_path / "new.db"
    _prepare_database(Settings(db_path=db))
    with sqlite3.connect(db) as conn:
        assert conn.execute("PRAGMA journal_mode").fetchone()[0] == "wal"
        tables = {row[0] for row in conn.execute("SELECT name FROM sqlite_master")}
    assert {"sessions", "observations"} <= tables


def test_bound_socket_gives_accepted_connections_tcp_nodelay():
    """uvicorn #3149: the socket `tactile serve` binds carries TCP_NODELAY to its connections."""
    listener = bind_socket("127.0.0.1", 0)
    try:
        assert listener.getsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY)
        with socket.create_connection(listener.getsockname()[:2]):
            conn, _ = listener.accept()
            with conn:
                assert conn.getsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY)
    finally:
        listener.close()


@pytest.mark.skipif(not reuse_port_supported(), reason="no SO_REUSEPORT here")
def test_each_worker_socket_takes_its_share_and_the_port_stays_one_services():
    # several workers listen on sockets of their own on one port: the kernel spreads
    # new connections over them (one shared socket gave a burst of them to one worker)
    listeners = bind_sockets("127.0.0.1", 0, 2)
    try:
        ports = {s.getsockname()[1] for s in listeners}
        assert len(ports) == 1
        port = ports.pop()
        # a second service on the same port fails, as it does with one socket
        with pytest.raises(OSError):
            bind_sockets("127.0.0.1", port, 2)
        with pytest.raises(OSError):
            bind_socket("127.0.0.1", port)
        clients = [socket.create_connection(("127.0.0.1", port)) for _ in range(32)]
        taken = []
        for listener in listeners:
            listener.setblocking(False)
            count = 0
            while True:
                try:
                    conn, _ = listener.accept()
                except BlockingIOError:
                    break
                conn.close()
                count += 1
            taken.append(count)
        for c in clients:
            c.close()
        assert sum(taken) == 32
        assert min(taken) > 0  # all on one socket: 2 chances in 2**32
    finally:
        for listener in listeners:
            listener.close()


class _FakeWorker:
    """What the supervisor asks of a worker process."""

    def __init__(self, alive: bool, exitcode: int | None = None) -> None:
        self.alive, self.exitcode, self.pid = alive, exitcode, 0

    def is_alive(self, timeout: float = 5) -> bool:
        return self.alive

    def kill(self) -> None:
        pass

    def join(self) -> None:
        pass


@pytest.fixture
def supervisor():
    """A two-worker supervisor of `tactile serve` (its signal handlers put back after)."""
    import signal

    import uvicorn
    from uvicorn.supervisors.multiprocess import SIGNALS

    from app.supervisor import per_worker_supervisor

    saved = {sig: signal.getsignal(sig) for sig in SIGNALS}
    sockets = [socket.socket(), socket.socket()]
    try:
        config = uvicorn.Config("app.main:create_app", factory=True, workers=2)
        found = per_worker_supervisor(config, sockets)
        if found is None:
            pytest.skip("the installed uvicorn's supervisor has another shape")
        yield found
    finally:
        for sig, handler in saved.items():
            signal.signal(sig, handler)
        for s in sockets:
            s.close()


def test_a_worker_failing_to_start_while_another_serves_is_started_again(supervisor):
    from uvicorn.config import STARTUP_FAILURE

    from app.supervisor import START_RETRIES

    spawned = []

    def spawn(idx):
        spawned.append(idx)
        return _FakeWorker(False, STARTUP_FAILURE)

    supervisor._spawn = spawn
    supervisor.processes = [_FakeWorker(True), _FakeWorker(False, STARTUP_FAILURE)]
    for _ in range(START_RETRIES):
        supervisor.keep_subprocess_alive()
        assert not supervisor.should_exit.is_set()
    supervisor.keep_subprocess_alive()  # one failure too many within the window: stop
    assert supervisor.should_exit.is_set()
    assert spawned == [1] * START_RETRIES


def test_a_worker_failing_to_start_with_none_serving_stops_the_service(supervisor):
    from uvicorn.config import STARTUP_FAILURE

    supervisor._spawn = lambda idx: pytest.fail("a broken app must not be started again")
    supervisor.processes = [_FakeWorker(False), _FakeWorker(False, STARTUP_FAILURE)]
    supervisor.processes[0].exitcode = STARTUP_FAILURE
    supervisor.keep_subprocess_alive()
    assert supervisor.should_exit.is_set()
