"""The `tactile` command line: bench output shape, import-mesh, clear errors."""

from __future__ import annotations

import json

import pytest
import trimesh

from app.cli import main


def test_bench_json_reports_every_set_and_error_case(capsys):
    assert main(["bench", "--sets", "symmetric", "--trials", "2", "--json"]) == 0
    rows = json.loads(capsys.readouterr().out)["recognition"]
    assert [r["set"] for r in rows] == ["symmetric", "symmetric"]
    for r in rows:
        assert len(r["hypotheses_after"]) == 3 and len(r["classes_after"]) == 3
        assert all(c <= h for c, h in zip(r["classes_after"], r["hypotheses_after"], strict=True))
        assert r["update_p95_ms"] >= r["update_p50_ms"] > 0


def test_bench_planning_reports_plan_times_after_0_to_3_touches(capsys):
    argv = ["bench", "--sets", "symmetric", "--planning", "--no-recognition", "--json"]
    assert main([*argv, "--plan-trials", "1", "--strategies", "pdm", "pruning"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert "recognition" not in out
    rows = out["planning"]
    assert [(r["position_error"], r["touches"]) for r in rows] == [
        (e, k) for e in (0.0, 1.0) for k in range(4)
    ]
    for r in rows:
        assert r["set"] == "symmetric" and r["trials"] == 1
        assert set(r["p50_ms"]) == set(r["p95_ms"]) == {"pdm", "pruning"}
        assert all(r["p95_ms"][s] >= r["p50_ms"][s] > 0 for s in ("pdm", "pruning"))
        assert r["classes"] <= r["hypotheses"] <= r["hypotheses_max"]
    assert rows[0]["hypotheses"] == 0 and rows[1]["candidates"] > 0


def test_import_mesh_writes_an_object_file(tmp_path, capsys):
    mesh_path = tmp_path / "box.stl"
    trimesh.creation.box(extents=(40, 60, 100)).export(mesh_path)
    out = tmp_path / "box.json"
    assert main(["import-mesh", str(mesh_path), "--height", "8", "--out", str(out)]) == 0
    data = json.loads(out.read_text())
    poses = data["objects"][0]["stable_poses"]
    assert len(poses) == 3
    assert sum(p["probability"] for p in poses) == pytest.approx(1.0)


def test_import_mesh_errors_name_the_field(tmp_path, capsys):
    mesh_path = tmp_path / "box.stl"
    trimesh.creation.box(extents=(40, 60, 100)).export(mesh_path)
    assert main(["import-mesh", str(mesh_path), "--height", "500"]) == 2
    assert "height" in capsys.readouterr().err
