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
