"""The `tactile` command line: bench output shape, import-mesh, the demo, clear errors."""

from __future__ import annotations

import json
import math
import re
from xml.etree import ElementTree

import numpy as np
import pytest
import trimesh

from tactile.cli import main


def test_bench_json_reports_every_set_and_error_case(capsys):
    assert main(["bench", "--sets", "symmetric", "--trials", "2", "--growth", "5", "--json"]) == 0
    rows = json.loads(capsys.readouterr().out)["recognition"]
    assert [r["set"] for r in rows] == ["symmetric", "symmetric"]
    for r in rows:
        assert list(r["update_ms_by_n"]) == ["1", "2", "5"]  # JSON keys
        assert all(v > 0 for v in r["update_ms_by_n"].values())
        assert len(r["hypotheses_after"]) == 3 and len(r["classes_after"]) == 3
        assert all(c <= h for c, h in zip(r["classes_after"], r["hypotheses_after"], strict=True))
        assert r["update_p95_ms"] >= r["update_p50_ms"] > 0


def test_bench_without_exact_sensing_times_the_error_case_only(capsys):
    argv = ["bench", "--sets", "symmetric", "--trials", "2", "--no-exact", "--json"]
    assert main(argv) == 0
    rows = json.loads(capsys.readouterr().out)["recognition"]
    assert [(r["position_error"], r["normal_error_deg"]) for r in rows] == [(1.0, 3.0)]


def test_bench_replays_keep_the_counts_and_the_shortest_times(capsys):
    argv = ["bench", "--sets", "symmetric", "--trials", "3", "--no-exact", "--json"]
    assert main(argv) == 0
    once = json.loads(capsys.readouterr().out)["recognition"][0]
    assert main([*argv, "--repeat", "3"]) == 0
    replayed = json.loads(capsys.readouterr().out)["recognition"][0]
    # the same worlds and touches: the same hypotheses; times are only measured
    assert replayed["hypotheses_after"] == once["hypotheses_after"]
    assert replayed["classes_after"] == once["classes_after"]
    assert replayed["update_p95_ms"] >= replayed["update_p50_ms"] > 0


def test_bench_planning_reports_plan_times_and_work_after_0_to_3_touches(capsys):
    argv = ["bench", "--sets", "symmetric", "--planning", "--no-recognition", "--json"]
    assert (
        main([*argv, "--plan-trials", "1", "--plan-touches", "3", "--strategies", "pdm", "pruning"])
        == 0
    )
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
        assert set(r["work"]) == set(r["capped"]) == {"pdm", "pruning"}
    assert rows[0]["hypotheses"] == 0 and rows[1]["candidates"] > 0
    assert any(r["work"]["pdm"] > 0 for r in rows[1:])  # (localized plans do no work)


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


def _demo(tmp_path, capsys, *argv: str) -> tuple[int, list[str]]:
    code = main(["demo", *argv])
    return code, capsys.readouterr().out.splitlines()


def test_demo_recognizes_over_http_and_writes_the_picture(tmp_path, capsys):
    picture = tmp_path / "demo.png"
    code, lines = _demo(tmp_path, capsys, "--out", str(picture))
    assert code == 0, "\n".join(lines)
    assert lines[0].startswith("service: http://127.0.0.1:")
    assert any(line.startswith("truth: ") for line in lines)
    touches = [line for line in lines if line.startswith("touch ")]
    assert touches and touches[0].startswith("touch 1: path from (200.0, 0.0) direction")
    for line in touches:
        assert "P(DM)" in line and "E[touches]" in line and "hypotheses in" in line
        assert "-> contact (" in line or "-> miss;" in line
    assert "status localized" in touches[-1]
    verdict = next(line for line in lines if line.startswith("localized after"))
    assert verdict.endswith(": correct")
    assert f"picture: {picture}" in lines
    view = next(line for line in lines if line.startswith("live view: "))
    assert re.fullmatch(r"live view: http://127\.0\.0\.1:\d+/v1/sessions/[0-9a-f-]{36}/view", view)
    assert picture.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_demo_with_an_ideal_sensor_writes_svg(tmp_path, capsys):
    picture = tmp_path / "demo.svg"
    code, lines = _demo(tmp_path, capsys, "--sensor", "ideal", "--seed", "3", "--out", str(picture))
    assert code == 0, "\n".join(lines)
    assert "bounds 0 and 0 deg" in lines[2]
    root = ElementTree.fromstring(picture.read_bytes())
    assert root.tag == "{http://www.w3.org/2000/svg}svg"


def test_demo_refuses_a_picture_it_cannot_write(capsys):
    with pytest.raises(SystemExit):
        main(["demo", "--out", "demo.gif"])
    assert "--out" in capsys.readouterr().err


def test_demo_that_runs_out_of_touches_exits_1(tmp_path, capsys):
    code, lines = _demo(tmp_path, capsys, "--max-touches", "1", "--out", str(tmp_path / "d.png"))
    assert code == 1
    assert any(line.startswith("not localized after 1 touches") for line in lines)


def test_demo_with_objects_the_service_refuses_names_the_limit(tmp_path, capsys):
    # a zigzag of 600 vertices: nothing to simplify, past the worked ring limit
    ring = [
        [(40 - 3 * (k % 2)) * math.cos(a), (40 - 3 * (k % 2)) * math.sin(a)]
        for k, a in enumerate(np.linspace(0, 2 * math.pi, 600, endpoint=False))
    ]
    path = tmp_path / "big.json"
    path.write_text(json.dumps({"objects": [{"name": "big", "outline": ring}]}))
    assert main(["demo", "--objects", str(path), "--out", str(tmp_path / "d.png")]) == 2
    err = capsys.readouterr().err
    assert "422" in err and "max_worked_vertices" in err and "500" in err


def test_import_mesh_slices_at_several_heights(tmp_path):
    mesh_path = tmp_path / "cube.stl"
    trimesh.creation.box(extents=(40, 40, 40)).export(mesh_path)
    out = tmp_path / "cube.json"
    argv = ["import-mesh", str(mesh_path), "--heights", "5", "15", "30", "--out", str(out)]
    assert main(argv) == 0
    poses = json.loads(out.read_text())["objects"][0]["stable_poses"]
    assert all([s["height"] for s in p["slices"]] == [5.0, 15.0, 30.0] for p in poses)
    assert main(["import-mesh", str(mesh_path)]) == 2
