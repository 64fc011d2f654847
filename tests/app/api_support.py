"""Shared pieces of the HTTP service tests: settings, in-process clients, shapes, touches.

The square (side 2, centred) and the rectangle (4 x 2) stand in a safe circle
of radius 10; the touches below are exact contacts on the square at the origin.
"""

from __future__ import annotations

import os
import queue
import re
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from fastapi.testclient import TestClient

from app.main import create_app
from app.settings import Settings

ROOT = Path(__file__).resolve().parents[2]
SQUARE = {"name": "square", "outline": [[-1, -1], [1, -1], [1, 1], [-1, 1]]}
RECT = {"name": "rect", "outline": [[-2, -1], [2, -1], [2, 1], [-2, 1]]}
WORKSPACE = {"center": [0, 0], "radius": 10}
SENSOR = {"position_error": 0.01, "normal_error": 0.02}
FAST_STRATEGY = {"name": "pdm", "depth": 1, "budget_ms": 200}


def observation(origin, direction, point=None, normal=None, length=20.0) -> dict[str, Any]:
    contact = None if point is None else {"point": list(point), "normal": list(normal)}
    return {
        "path": {"origin": list(origin), "direction": list(direction), "length": length},
        "contact": contact,
    }


#: From below onto the bottom face, from the right onto the right face.
BOTTOM = observation((0, -10), (0, 1), (0, -1), (0, -1))
RIGHT = observation((10, 0), (-1, 0), (1, 0), (1, 0))
#: A contact no object placement explains after BOTTOM and RIGHT.
IMPOSSIBLE = observation((-10, 0), (1, 0), (5, 0), (1, 0))


def miss(k: int) -> dict[str, Any]:
    """A path that touched nothing; `k` makes it recognizable (its origin's y)."""
    return observation((-10, -9 + 0.001 * k), (0, 1), length=1.0)


def test_settings(tmp_path: Path, **overrides: Any) -> Settings:
    values: dict[str, Any] = {"db_path": tmp_path / "tactile.db", "log_level": "warning"}
    values.update(overrides)
    return Settings(**values)


test_settings.__test__ = False  # type: ignore[attr-defined]  # a helper, not a test


@contextmanager
def api(tmp_path: Path, **overrides: Any) -> Iterator[TestClient]:
    """An in-process client with the app's lifespan running."""
    app = create_app(test_settings(tmp_path, **overrides))
    with TestClient(app) as client:
        yield client


def create_session(client: TestClient, objects=None, **body: Any) -> dict[str, Any]:
    payload = {
        "objects": objects if objects is not None else [SQUARE, RECT],
        "sensor": SENSOR,
        "workspace": WORKSPACE,
        "strategy": FAST_STRATEGY,
        **body,
    }
    r = client.post("/v1/sessions", json=payload)
    assert r.status_code == 201, r.text
    return r.json()


def is_problem(response: Any, status: int | None = None) -> bool:
    """A 4xx/5xx answered as RFC 9457 problem+json with the minimal members."""
    if status is not None and response.status_code != status:
        return False
    if not response.headers.get("content-type", "").startswith("application/problem+json"):
        return False
    body = response.json()
    return {"type", "title", "status"} <= set(body) and body["status"] == response.status_code


# -- a real `tactile serve` process -------------------------------------------------------------
class Server:
    """`tactile serve` in a subprocess on 127.0.0.1 and a port it picked itself.

    A thread keeps reading the server's log (stderr) so that it never blocks on a
    full pipe; the lines are kept in `lines`."""

    def __init__(self, db: Path, *args: str, env: dict[str, str] | None = None) -> None:
        self.db = db
        self.args = args
        self.env = {**os.environ, "TACTILE_LOG_LEVEL": "info", **(env or {})}
        self.proc: subprocess.Popen[bytes] | None = None
        self.port = 0
        self.lines: list[str] = []
        self._queue: queue.Queue[str | None] = queue.Queue()

    def _drain(self) -> None:
        assert self.proc is not None and self.proc.stderr is not None
        for raw in self.proc.stderr:
            line = raw.decode(errors="replace").rstrip()
            self.lines.append(line)
            self._queue.put(line)
        self._queue.put(None)

    def start(self, timeout: float = 30.0) -> Server:
        cmd = [sys.executable, "-m", "tactile.cli", "serve", "--host", "127.0.0.1", "--port", "0"]
        self.proc = subprocess.Popen(
            [*cmd, "--db", str(self.db), *self.args],
            cwd=ROOT,
            env=self.env,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.PIPE,
        )
        threading.Thread(target=self._drain, daemon=True).start()
        deadline = time.monotonic() + timeout
        started = 0
        args = list(self.args)
        workers = int(args[args.index("--workers") + 1]) if "--workers" in args else 1
        while started < workers:
            try:
                line = self._queue.get(timeout=max(deadline - time.monotonic(), 0.01))
            except queue.Empty:
                line = None
            if line is None:
                self.kill()
                raise RuntimeError("server did not start:\n" + "\n".join(self.lines[-20:]))
            if not self.port and (m := re.search(r'"port": (\d+)', line)):
                self.port = int(m.group(1))
            started += "Application startup complete" in line
        return self

    @property
    def url(self) -> str:
        return f"http://127.0.0.1:{self.port}"

    def kill(self, sig: int = signal.SIGKILL) -> None:
        if self.proc is not None and self.proc.poll() is None:
            self.proc.send_signal(sig)
            try:
                self.proc.wait(timeout=30)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait(timeout=30)

    def __enter__(self) -> Server:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.kill(signal.SIGTERM)
