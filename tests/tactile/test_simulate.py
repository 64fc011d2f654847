"""`tactile simulate` and the calibration command (DESIGN §7)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from planner.models.library import dump_objects
from tactile.calibration import (
    calibration_ok,
    reliability_table,
    remaining_records,
    remaining_table,
    touch_records,
)
from tactile.cli import main
from tests.conftest import ELL, WEDGE

JSON_KEYS = {
    "strategy",
    "trials",
    "histogram",
    "mean_touches",
    "max_touches",
    "success_rate",
    "mean_plan_ms",
    "p95_plan_ms",
}


@pytest.fixture(scope="module")
def object_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("objects") / "small.json"
    dump_objects([ELL, WEDGE], path)
    return str(path)


def test_simulate_json_shape_and_plot(object_file, tmp_path, capsys):
    png = tmp_path / "hist.png"
    argv = ["simulate", "--objects", object_file, "--truth", "ell", "--strategy", "pdm"]
    argv += ["--strategy", "thesis", "--trials", "2", "--seed", "4", "--sensor", "ideal"]
    argv += ["--max-touches", "6", "--workers", "1", "--plot", str(png), "--json"]
    assert main(argv) == 0
    out = json.loads(capsys.readouterr().out)
    assert list(out) == ["strategies", "trials"]
    assert {t["strategy"] for t in out["trials"]} == {"pdm", "thesis"}
    assert [s["strategy"] for s in out["strategies"]] == ["pdm", "thesis"]
    for row in out["strategies"]:
        assert set(row) == JSON_KEYS
        assert row["trials"] == 2
        assert list(row["histogram"]) == [str(k) for k in range(1, 11)] + [">10"]
        assert sum(row["histogram"].values()) == pytest.approx(1.0)
        assert 1 <= row["mean_touches"] <= row["max_touches"] <= 6
        assert 0.0 <= row["success_rate"] <= 1.0
        assert row["p95_plan_ms"] >= 0 and row["mean_plan_ms"] >= 0
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_simulate_prints_the_table(object_file, capsys):
    argv = ["simulate", "--objects", object_file, "--strategy", "pdm", "--trials", "1"]
    argv += ["--seed", "2", "--position-error", "0.5", "--normal-error", "0.03"]
    argv += ["--max-touches", "5", "--workers", "1"]
    assert main(argv) == 0
    out = capsys.readouterr().out
    assert "bounds 0.5" in out and out.splitlines()[2].split()[:3] == ["strategy", "1", "2"]


def test_simulate_rejects_a_preset_with_explicit_errors(object_file, capsys):
    argv = ["simulate", "--objects", object_file, "--strategy", "pdm", "--trials", "1"]
    argv += ["--sensor", "thesis_sensor", "--position-error", "1"]
    assert main(argv) == 2
    assert "--sensor" in capsys.readouterr().err


def test_simulate_names_an_unknown_truth(object_file, capsys):
    argv = ["simulate", "--objects", object_file, "--strategy", "pdm", "--truth", "nope"]
    assert main(argv) == 2
    assert "nope" in capsys.readouterr().err


def test_simulate_refuses_a_missing_object_file_and_a_bad_error_disk(object_file, capsys):
    argv = ["simulate", "--objects", "no_such_set.json", "--strategy", "pdm"]
    assert main(argv) == 2
    assert "no_such_set.json" in capsys.readouterr().err
    argv = ["simulate", "--objects", object_file, "--strategy", "pdm", "--error-disk", "-1"]
    assert main(argv) == 2
    assert "error disk" in capsys.readouterr().err


def test_simulate_in_the_thesis_setting(object_file, capsys):
    # the object centred on the safe circle, a fixed error disk: the first probe meets it
    argv = ["simulate", "--objects", object_file, "--truth", "ell", "--strategy", "thesis"]
    argv += ["--trials", "2", "--seed", "1", "--max-touches", "6", "--workers", "1"]
    argv += ["--placement", "centred", "--error-disk", "0.1", "--json"]
    assert main(argv) == 0
    (row,) = json.loads(capsys.readouterr().out)["strategies"]
    assert row["trials"] == 2 and row["histogram"][">10"] < 1.0
    # the thesis' simulations picked at random among the best windows
    argv = [*argv[:-1], "--thesis-choice", "random"]
    assert main(argv) == 0
    assert "thesis picks random" in capsys.readouterr().out
    with pytest.raises(SystemExit):
        main([*argv[:-2], "--thesis-choice", "nearest"])
    assert "--thesis-choice" in capsys.readouterr().err


# -- calibration ----------------------------------------------------------------------------


def test_reliability_table_bins_and_judges():
    rng = np.random.default_rng(0)
    p = rng.uniform(0, 1, 5000)
    calibrated = reliability_table(p, rng.random(5000) < p)
    assert sum(b.count for b in calibrated) == 5000
    assert calibration_ok(calibrated)
    biased = reliability_table(p, rng.random(5000) < p**3)
    assert not calibration_ok(biased)
    few = reliability_table(np.full(20, 0.95), np.zeros(20, bool))
    assert few[-1].count == 20 and few[-1].ok is None and calibration_ok(few)


def test_touch_records_skip_the_opening(sequential_results):
    planned = sum(len(r.p_distinguishing) for r in sequential_results)
    for kind in ("forecast", "model"):
        pred, obs = touch_records(sequential_results, kind)
        assert 0 < len(pred) < planned
        assert np.all((pred >= 0) & (pred <= 1)) and obs.dtype == bool
    with pytest.raises(ValueError, match="prediction"):
        touch_records(sequential_results, "guess")


def test_expected_remaining_is_tabled_against_the_touches_taken(sequential_results):
    """Every planned touch of a localized trial with an expectation, paired with the
    touches the trial took from it on (that one included): the last planned touch
    took one, the first as many as the trial had left."""
    expected, taken, truncated = remaining_records(sequential_results)
    localized = [r for r in sequential_results if r.localized]
    with_e = sum(e is not None for r in localized for e in r.expected_remaining)
    assert len(expected) == len(taken) == len(truncated) == with_e > 0
    assert taken.min() >= 1 and taken.max() <= max(r.touches for r in localized)
    table = remaining_table(expected, taken, truncated)
    assert sum(b.count for b in table) == int((expected >= 1).sum())
    for b in table:
        if b.count:
            assert b.low <= b.mean_expected < b.high and 0 <= b.over <= 1


def test_remaining_table_bins_by_expectation():
    expected = np.array([1.0, 1.2, 2.5, 2.5, 7.0, 40.0])
    taken = np.array([1, 2, 2, 4, 3, 3], dtype=float)
    table = remaining_table(expected, taken, np.array([0, 0, 0, 1, 1, 1], bool))
    counts = {(b.low, b.high): (b.count, b.truncated) for b in table}
    assert counts[(1.0, 1.5)] == (2, 0) and counts[(2.0, 3.0)] == (2, 1)
    assert counts[(5.0, 10.0)] == (1, 1) and counts[(10.0, float("inf"))] == (1, 1)
    first = table[0]
    assert first.mean_expected == pytest.approx(1.1) and first.mean_taken == 1.5
    assert first.over == 0.0 and table[2].over == 0.5
