"""GET /v1/sessions/{id}/report.json and report.csv: each touch with its residuals, the
answer with its bound, probability and status."""

from __future__ import annotations

import csv
import io
import math

import jsonschema
import pytest

from app.answers import ReportOut
from tests.app.api_support import BOTTOM, RIGHT, SENSOR, api, create_session, is_problem, miss


@pytest.fixture
def client(tmp_path):
    with api(tmp_path) as c:
        yield c


def _session_with_touches(client):
    sid = create_session(client)["id"]
    url = f"/v1/sessions/{sid}"
    for body in (BOTTOM, miss(1), RIGHT):
        assert client.post(f"{url}/observations", json=body).status_code == 201
    return url


def test_the_report_validates_against_its_schema_and_residuals_lie_within_the_sensor(client):
    url = _session_with_touches(client)
    r = client.get(f"{url}/report.json")
    assert r.status_code == 200 and r.headers["etag"] == '"4"'
    report = r.json()
    jsonschema.validate(report, ReportOut.model_json_schema())
    state = client.get(url).json()
    assert report["status"] == state["status"] and report["version"] == state["version"]
    assert [t["kind"] for t in report["touches"]] == ["contact", "miss", "contact"]
    best = state["hypotheses"][0]
    result = report["result"]
    assert result["object"] == best["object"] and result["pose"] == best["pose"]
    assert result["classes"] == state["class_count"]
    assert result["bound"] == state["localization"]["bound"]
    for touch, face in zip(
        [t for t in report["touches"] if t["contact"]], best["assignment"], strict=True
    ):
        assert touch["face"] == face
        # the answer explains each contact within the sensor's bounds
        assert touch["distance"] <= SENSOR["position_error"] + 1e-9
        assert abs(touch["normal_angle"]) <= SENSOR["normal_error"] + 1e-9
    assert report["touches"][1]["clearance"] > 0  # the miss passed the answer by


def test_the_csv_parses_with_the_standard_library_and_says_what_the_json_says(client):
    url = _session_with_touches(client)
    report = client.get(f"{url}/report.json").json()
    r = client.get(f"{url}/report.csv")
    assert r.status_code == 200 and r.headers["content-type"].startswith("text/csv")
    rows = list(csv.DictReader(io.StringIO(r.text)))
    assert [row["row"] for row in rows] == ["touch"] * 3 + ["result"]
    for row, touch in zip(rows, report["touches"], strict=False):
        assert row["kind"] == touch["kind"] and int(row["index"]) == touch["index"]
        assert float(row["origin_x"]) == touch["path"]["origin"][0]
        if touch["distance"] is None:
            assert row["distance"] == "" and row["point_x"] == ""
        else:
            assert float(row["distance"]) == touch["distance"]
            assert float(row["normal_angle"]) == touch["normal_angle"]
    final, result = rows[-1], report["result"]
    assert final["status"] == report["status"] and final["object"] == result["object"]
    assert float(final["theta"]) == result["pose"]["theta"]
    assert math.isclose(float(final["class_probability"]), result["class_probability"])


def test_a_report_before_any_contact_has_no_answer_and_unknown_sessions_404(client):
    sid = create_session(client)["id"]
    report = client.get(f"/v1/sessions/{sid}/report.json").json()
    assert report["status"] == "awaiting_contact" and report["touches"] == []
    assert report["result"] is None
    jsonschema.validate(report, ReportOut.model_json_schema())
    rows = list(csv.DictReader(io.StringIO(client.get(f"/v1/sessions/{sid}/report.csv").text)))
    assert len(rows) == 1 and rows[0]["row"] == "result" and rows[0]["object"] == ""
    unknown = "/v1/sessions/00000000-0000-0000-0000-000000000007/report.json"
    assert is_problem(client.get(unknown), 404)
