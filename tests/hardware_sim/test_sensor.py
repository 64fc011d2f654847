"""The strain-gauge touch sensor (thesis App. 3, ch. 5.2) and the preset error bounds."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import signal

from hardware_sim.accuracy import touch_errors
from hardware_sim.arm import ArmParams
from hardware_sim.presets import PRESETS, build_arm
from hardware_sim.sensor import (
    SensorParams,
    StrainGaugeSensor,
    bridge_output,
    force_from_volts,
    volts_from_force,
)
from hardware_sim.world import random_world
from tests.conftest import WORKSPACE, object_set


def angle_between(a: np.ndarray, b: np.ndarray) -> float:
    # unsigned angle = |atan2(a x b, a . b)|
    return abs(math.atan2(a[0] * b[1] - a[1] * b[0], a @ b))


def test_bridge_and_amplifier_follow_appendix_3():
    p = SensorParams()
    # e_i = 8 V, G = 2, bridge factor 2: e0 ~ 8 eps; 313 microstrain -> ~2.5 mV -> ~5 V at gain 2000
    assert bridge_output(np.array(313e-6), p) == pytest.approx(8 * 313e-6, rel=1e-3)
    assert p.gain * bridge_output(np.array(313e-6), p) == pytest.approx(5.0, rel=2e-3)
    # 4 lbf at the tip of a 3 in, 0.375 in aluminium bar: a few hundred microstrain
    assert 150e-6 < 4 * 4.448 * p.strain_per_newton < 313e-6
    forces = np.random.default_rng(0).uniform(-10, 10, (50, 2))
    np.testing.assert_allclose(force_from_volts(volts_from_force(forces, p), p), forces, atol=1e-9)


def test_filter_is_a_3_pole_butterworth_at_25_hz():
    p = SensorParams()
    _, poles, _ = signal.sos2zpk(p.sos)
    assert len(poles[np.abs(poles) > 1e-12]) == 3 and np.all(np.abs(poles) < 1)
    _, h = signal.sosfreqz(p.sos, worN=[25.0, 100.0], fs=p.sample_rate_hz)
    gain_db = 20 * np.log10(np.abs(h))
    assert gain_db[0] == pytest.approx(-3.01, abs=0.05)
    # analog prototype at 4 x the break: -10 log10(1 + 4^6) = -36.1 dB (bilinear: a bit more)
    assert -40.0 < gain_db[1] < -36.0


def test_error_free_chain_measures_the_force_direction():
    s = StrainGaugeSensor(SensorParams(), np.random.default_rng(1))
    rng = np.random.default_rng(2)
    for a in rng.uniform(-math.pi, math.pi, 20):
        d = np.array([math.cos(a), math.sin(a)])
        press = s.press(d, threshold=3.0, ramp=30.0)
        assert angle_between(press.direction, d) < 1e-6
        # the guarded move stops late by the filter lag, never early
        assert 3.0 <= press.peak < 4.0


def test_quantization_and_noise_are_applied():
    p = SensorParams(adc_bits=8, noise=0.01)
    s = StrainGaugeSensor(p, np.random.default_rng(0))
    out = s._chain(np.full((200, 2), 3.0), np.zeros((200, 2)))
    lsb = 2 * p.adc_range / 2**8
    np.testing.assert_allclose(out / lsb, np.round(out / lsb), atol=1e-9)


@pytest.fixture(scope="module")
def thesis_errors():
    return touch_errors("thesis_sensor", object_set("thesis_like"), touches=400, seed=11)


def test_thesis_sensor_normal_error_inside_its_cone(thesis_errors, capsys):
    cone = PRESETS["thesis_sensor"].bounds.normal_error
    assert cone == pytest.approx(math.radians(5.0))
    inside_normal, inside_position = thesis_errors.within()
    assert inside_normal >= 0.99
    assert inside_position == 1.0
    q = thesis_errors.percentiles()
    with capsys.disabled():
        print(
            "\nthesis_sensor normal error (deg) p50/p95/p99/max:",
            " / ".join(f"{v:.2f}" for v in q["normal_deg"]),
            f"over {len(thesis_errors.normal)} touches; position (mm):",
            " / ".join(f"{v:.3f}" for v in q["position"]),
        )
    # a real error distribution, not a degenerate one
    assert np.median(thesis_errors.normal) > math.radians(0.1)


def test_e2_arm_errors_inside_its_bounds():
    e = touch_errors("e2_arm", object_set("thesis_like"), touches=150, seed=5)
    inside_normal, inside_position = e.within()
    assert inside_normal >= 0.99 and inside_position == 1.0
    # the compliant arm really is about an inch off under load
    assert np.median(e.position) > 10.0


@pytest.mark.parametrize("name", sorted(PRESETS))
def test_stated_budget_fits_the_bounds(name):
    preset = PRESETS[name]
    normal = sum(v for k, v in preset.budget.items() if k.startswith("normal."))
    position = sum(v for k, v in preset.budget.items() if k.startswith("position."))
    assert normal <= preset.bounds.normal_error + 1e-12
    assert position <= preset.bounds.position_error + 1e-12


@pytest.mark.parametrize(("name", "since"), [("thesis_sensor", 2.5), ("e2_arm", 3.0)])
def test_recalibration_is_as_recent_as_the_budget_assumes(name, since):
    models = object_set("thesis_like")
    rng = np.random.default_rng(3)
    world = random_world(models, WORKSPACE, rng)
    arm = build_arm(world, name, 3)
    seen = []
    for _ in range(12):
        if arm.execute(world.hitting_path(rng)).hit:
            seen.append(arm.last_press.since_zero)
    assert seen and max(seen) <= since


def _drift_errors(recalibrate: bool) -> np.ndarray:
    preset = PRESETS["thesis_sensor"]
    models = object_set("thesis_like")
    rng = np.random.default_rng(21)
    world = random_world(models, WORKSPACE, rng)
    params = ArmParams(**{**preset.arm.__dict__, "recalibrate": recalibrate})
    sensor = StrainGaugeSensor(preset.sensor, np.random.default_rng(4))
    from hardware_sim.arm import SimulatedArm

    arm = SimulatedArm(world, params, sensor, np.random.default_rng(5))
    errors = []
    for _ in range(25):
        result = arm.execute(world.hitting_path(rng))
        if result.hit:
            c = result.observation.contact
            errors.append(angle_between(np.array(c.normal), np.array(result.true_normal)))
    return np.array(errors)


def test_recalibration_reduces_drift_error():
    without, with_ = _drift_errors(False), _drift_errors(True)
    # zeroed once at power-on, the channels drift through minutes of probing
    assert np.mean(without) > 3 * np.mean(with_)
    assert np.max(with_) <= PRESETS["thesis_sensor"].bounds.normal_error
    assert np.max(without) > PRESETS["thesis_sensor"].bounds.normal_error
