"""Shared pieces of the HTTP service tests: settings, in-process clients, shapes, touches.

The square (side 2, centred) and the rectangle (4 x 2) stand in a safe circle
of radius 10; the touches below are exact contacts on the square at the origin.
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from fastapi.testclient import TestClient

from app.main import create_app
from app.settings import Settings

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
