"""The session report: residuals against the answer, and its CSV form."""

from __future__ import annotations

import csv
import io

import pytest

from planner.models.outlines import make_stable_pose
from planner.recognition.config import RecognitionConfig
from planner.recognition.session import Session
from planner.report import CSV_COLUMNS, report_csv, session_report
from planner.types import Contact, ObjectModel, Observation, SensingPath, SensorBounds, Workspace

SQUARE = ObjectModel("square", (make_stable_pose([[-20, -20], [20, -20], [20, 20], [-20, 20]]),))
WORKSPACE = Workspace((0.0, 0.0), 100.0)


def touch(origin, direction, point=None, normal=None, length=200.0):
    contact = None if point is None else Contact(point, normal)
    return Observation(SensingPath(origin, direction, length), contact)


def test_a_spurious_contact_and_a_miss_have_their_own_kinds():
    session = Session(
        [SQUARE],
        SensorBounds(0.5, 0.02),
        WORKSPACE,
        RecognitionConfig(max_outliers=1),
        [
            touch((0, -100), (0, 1), (3, -20), (0, -1)),
            touch((100, 0), (-1, 0), (20.2, 4), (1, 0)),
            touch((-100, 0), (1, 0), (-20, 2), (-1, 0)),
            touch((0, 100), (0, -1), (5, 20), (0, 1)),
            # a contact no pose of the square explains with the other four
            touch((100, 90), (-1, 0), (60, 90), (1, 0)),
            touch((-100, 60), (1, 0), length=200.0),  # passes above the square
        ],
    )
    report = session_report(session)
    kinds = [t["kind"] for t in report["touches"]]
    assert kinds == ["contact"] * 4 + ["spurious", "miss"]
    spurious, passed = report["touches"][4], report["touches"][5]
    assert spurious["face"] is None and spurious["distance"] is None
    assert passed["clearance"] == pytest.approx(40.0, abs=1.0)
    for t in report["touches"][:4]:
        assert t["distance"] <= 0.5 + 1e-9 and abs(t["normal_angle"]) <= 0.02 + 1e-9
    rows = list(csv.DictReader(io.StringIO(report_csv(report))))
    assert list(rows[0]) == list(CSV_COLUMNS)
    assert [r["kind"] for r in rows[:-1]] == kinds and rows[-1]["object"] == "square"
