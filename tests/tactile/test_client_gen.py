"""The generated HTTP client: in step with the schema, and usable against the service."""

from __future__ import annotations

import filecmp
import json

from fastapi.testclient import TestClient

from app.main import create_app
from app.settings import Settings
from hardware_sim.api_client import Client
from hardware_sim.api_client.api.observations import add_observation
from hardware_sim.api_client.api.plan import get_plan
from hardware_sim.api_client.api.sessions import create_session, get_session
from hardware_sim.api_client.models import ObservationIn, Problem, SessionCreate
from tactile.client_gen import CLIENT_DIR, generate_client
from tests.conftest import DATA


def _differences(a, b, prefix=""):
    cmp = filecmp.dircmp(a, b, ignore=["__pycache__"])
    out = [f"{prefix}{n}" for n in cmp.left_only + cmp.right_only + cmp.diff_files]
    for name, sub in cmp.subdirs.items():
        out += _differences(sub.left, sub.right, f"{prefix}{name}/")
    return out


def test_committed_client_matches_the_schema(tmp_path):
    fresh = tmp_path / "api_client"
    generate_client(fresh)
    differences = _differences(CLIENT_DIR, fresh)
    assert not differences, f"regenerate the client with `make client`: {differences}"


def test_client_runs_a_recognition_step_and_types_problems(tmp_path):
    app = create_app(Settings(db_path=str(tmp_path / "c.db")))
    objects = json.loads((DATA / "symmetric.json").read_text())["objects"]
    with TestClient(app) as http:
        client = Client(base_url="http://testserver").set_httpx_client(http)
        body = SessionCreate.from_dict(
            {
                "objects": [o for o in objects if o["name"] == "square"],
                "sensor": {"position_error": 0.5, "normal_error": 0.03},
                "workspace": {"center": [0, 0], "radius": 200},
                "sensor_position": [200, 0],
                "strategy": {"name": "pdm", "budget_ms": 300},
            }
        )
        session = create_session.sync(client=client, body=body)
        sid = session.id
        plan = get_plan.sync(session_id=sid, client=client, limit=3)
        assert plan.paths and plan.status.value == "awaiting_contact"
        for touch in (
            {
                "path": {"origin": [0, -200], "direction": [0, 1], "length": 400},
                "contact": {"point": [5, -40], "normal": [0, -1]},
            },
            {
                "path": {"origin": [200, 10], "direction": [-1, 0], "length": 400},
                "contact": {"point": [40, 10], "normal": [1, 0]},
            },
        ):
            state = add_observation.sync(
                session_id=sid, client=client, body=ObservationIn.from_dict(touch)
            )
        assert state.status.value == "localized"
        again = get_session.sync(session_id=sid, client=client)
        assert again.version == state.version and len(again.hypotheses) == 4
        bad = add_observation.sync(
            session_id=sid,
            client=client,
            body=ObservationIn.from_dict(
                {"path": {"origin": [0, 0], "direction": [0, 0], "length": 1}, "contact": None}
            ),
        )
        assert isinstance(bad, Problem) and bad.status == 422
