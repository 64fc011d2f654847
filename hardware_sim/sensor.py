"""The 2-D strain-gauge touch sensor of the thesis (ch. 5.2, Appendix 3).

An aluminium cantilever (length L = 3 in, diameter D = 0.375 in) held upright by
the wrist, with a ball bearing at its tip. A lateral tip force F (sensor frame:
x, y across the finger, z along it) bends the bar; two Wheatstone bridges at the
base, each with two active gauges (bridge factor 2), see the two bending moments
``M = F L``. Signal chain per channel (App. 3, Figure A3-3):

    strain      eps = M (D/2) / (E I),  I = pi D^4 / 64
    bridge      e0  = b e_i G eps / (4 + 2 G eps)       (e_i = 8 V, G = 2, b = 2)
    amplifier   v   = gain e0 + drift + noise + hum     (gain = 2000)
    filter      3-pole Butterworth low-pass, 25 Hz (scipy.signal, sampled signal)
    A/D         clip to +-range, quantize to `adc_bits`

The measured outward normal is the direction of the lateral force: the object
pushes the tip along its outward surface normal (the bearing rejects friction).
Channel drift (a warm-up transient plus a random walk, per channel) is removed by
the recalibration routine: back off, :meth:`StrainGaugeSensor.zero` at no load,
touch again (the arm in :mod:`hardware_sim.arm` runs it).

Units: SI inside this module (N, m, V, s, rad). Directions are unit 2-vectors
in the sensor frame (x, y across the finger, counter-clockwise angles).

>>> import numpy as np
>>> s = StrainGaugeSensor(SensorParams(), np.random.default_rng(0))
>>> press = s.press(np.array([0.0, 1.0]), threshold=3.0, ramp=30.0)
>>> np.round(press.direction, 9).tolist(), press.peak >= 3.0
([0.0, 1.0], True)
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import cached_property
from typing import Protocol

import numpy as np
from scipy import signal

__all__ = [
    "BoundedSensor",
    "ExactSensor",
    "ForceSensor",
    "Press",
    "SensorParams",
    "StrainGaugeSensor",
    "bridge_output",
    "force_from_volts",
    "volts_from_force",
]


@dataclass(frozen=True)
class SensorParams:
    """Parameters of the strain-gauge sensor and its electronics (SI units).

    Geometry and material: `length` (m, tip to gauges), `diameter` (m),
    `youngs_modulus` (Pa). Bridge: `excitation` (V), `gauge_factor`,
    `bridge_factor` (active gauges per bridge). Amplifier: `gain` (V/V),
    `noise` (V rms per sample at the amplifier output, white), `hum` (V
    amplitude of `hum_hz` mains interference at the output). Filter:
    `filter_order` poles of Butterworth low-pass at `cutoff_hz`, sampled at
    `sample_rate_hz`. A/D: `adc_bits` (None: no quantization) over
    +-`adc_range` V. Drift per channel: a warm-up transient
    ``A (1 - exp(-t / drift_tau))`` with A uniform in +-`drift_transient` (V) and a
    random walk of `drift_walk` V/sqrt(s). Build errors (fixed per sensor):
    channel gain error uniform in +-`gain_mismatch` (relative), gauge axis
    misalignment uniform in +-`misalignment` (rad). Reading: after the force
    threshold is met the arm dwells `settle` s and the last `average` s of
    samples are averaged; :meth:`StrainGaugeSensor.zero` averages `zero_time` s.
    """

    length: float = 3 * 0.0254
    diameter: float = 0.375 * 0.0254
    youngs_modulus: float = 69e9
    excitation: float = 8.0
    gauge_factor: float = 2.0
    bridge_factor: float = 2.0
    gain: float = 2000.0
    noise: float = 0.0
    hum: float = 0.0
    hum_hz: float = 60.0
    cutoff_hz: float = 25.0
    filter_order: int = 3
    sample_rate_hz: float = 1000.0
    adc_bits: int | None = None
    adc_range: float = 10.0
    drift_transient: float = 0.0
    drift_tau: float = 120.0
    drift_walk: float = 0.0
    gain_mismatch: float = 0.0
    misalignment: float = 0.0
    settle: float = 0.25
    average: float = 0.1
    zero_time: float = 0.5

    def __post_init__(self) -> None:
        if not 0 < self.cutoff_hz < self.sample_rate_hz / 2:
            raise ValueError("cutoff_hz must lie below the Nyquist frequency")
        if self.average > self.settle:
            raise ValueError("the averaging window must fit in the dwell (average <= settle)")

    @cached_property
    def sos(self) -> np.ndarray:
        """Second-order sections of the Butterworth low-pass (digital, at the sample rate)."""
        return signal.butter(
            self.filter_order, self.cutoff_hz, btype="low", fs=self.sample_rate_hz, output="sos"
        )

    @property
    def strain_per_newton(self) -> float:
        """Strain at the gauges per newton of tip force: ``eps / F = L (D/2) / (E I)``."""
        # I = pi D^4 / 64 (round bar)
        inertia = math.pi * self.diameter**4 / 64
        # eps = M (D/2) / (E I), M = F L  (App. 3, eq. A3-1)
        return self.length * (self.diameter / 2) / (self.youngs_modulus * inertia)


def bridge_output(strain: np.ndarray, params: SensorParams) -> np.ndarray:
    """Bridge output voltage (V) for gauge strain: ``e0 = b e_i G eps / (4 + 2 G eps)``."""
    g, eps = params.gauge_factor, np.asarray(strain, dtype=float)
    # e0 = b e_i G eps / (4 + 2 G eps)  (App. 3; b = 2 active gauges per bridge)
    return params.bridge_factor * params.excitation * g * eps / (4 + 2 * g * eps)


def volts_from_force(force: np.ndarray, params: SensorParams) -> np.ndarray:
    """Noise-free amplifier output (V) of both channels for sensor-frame tip forces (N),
    shape (..., 2) -> (..., 2)."""
    return params.gain * bridge_output(np.asarray(force) * params.strain_per_newton, params)


def force_from_volts(volts: np.ndarray, params: SensorParams) -> np.ndarray:
    """Invert the nominal chain: amplifier output (V, zero-corrected) -> tip force (N)."""
    e0 = np.asarray(volts, dtype=float) / params.gain
    g, k = params.gauge_factor, params.bridge_factor * params.excitation
    # e0 (4 + 2 G eps) = k G eps  =>  eps = 4 e0 / (G (k - 2 e0))
    strain = 4 * e0 / (g * (k - 2 * e0))
    return strain / params.strain_per_newton


@dataclass(frozen=True)
class Press:
    """One touch as the sensor saw it: `direction` (unit, sensor frame) of the
    measured lateral force, `force` (N, measured magnitude), `peak` (N, the true
    force the arm reached: threshold plus the overshoot of the filter lag),
    `duration` (s, from first contact to the reading) and `since_zero` (s from
    the middle of the last zero calibration to the middle of the reading window;
    0 for sensors without drift)."""

    direction: np.ndarray
    force: float
    peak: float
    duration: float
    since_zero: float = 0.0


class ForceSensor(Protocol):
    """What the arm needs from a touch sensor."""

    def press(self, direction: np.ndarray, threshold: float, ramp: float) -> Press:
        """Push with a force growing at `ramp` N/s along the unit sensor-frame
        `direction` until the measured force passes `threshold` N; read it."""
        ...

    def zero(self) -> float:
        """Calibrate at no load; returns the seconds it took."""
        ...

    def advance(self, seconds: float) -> None:
        """Let time pass (the electronics drift while the arm moves)."""
        ...


class ExactSensor:
    """The `ideal` sensor: the true force direction, no lag, no drift."""

    def press(self, direction: np.ndarray, threshold: float, ramp: float) -> Press:
        return Press(np.asarray(direction, dtype=float), threshold, threshold, threshold / ramp)

    def zero(self) -> float:
        return 0.0

    def advance(self, seconds: float) -> None:
        return None


@dataclass
class BoundedSensor:
    """Bounded-noise sensor: the direction turned by an angle uniform in
    +-`normal_error` (rad), the explicit ``--normal-error`` model."""

    normal_error: float
    rng: np.random.Generator = field(default_factory=lambda: np.random.default_rng(0))

    def press(self, direction: np.ndarray, threshold: float, ramp: float) -> Press:
        delta = self.rng.uniform(-self.normal_error, self.normal_error)
        c, s = math.cos(delta), math.sin(delta)
        d = np.asarray(direction, dtype=float)
        turned = np.array([c * d[0] - s * d[1], s * d[0] + c * d[1]])
        return Press(turned, threshold, threshold, threshold / ramp)

    def zero(self) -> float:
        return 0.0

    def advance(self, seconds: float) -> None:
        return None


class StrainGaugeSensor:
    """The cantilever, its two bridges, amplifiers, filters and A/D (App. 3).

    Stateful because the hardware is: a clock (s since power-on), the drift
    state of both channels and the zero reference of the last calibration.
    All randomness comes from `rng` (build errors are drawn here, once).
    """

    def __init__(self, params: SensorParams, rng: np.random.Generator) -> None:
        self.params = params
        self.rng = rng
        self.clock = 0.0
        p = params
        self._transient = rng.uniform(-p.drift_transient, p.drift_transient, 2)
        self._walk = np.zeros(2)
        self._gain = 1.0 + rng.uniform(-p.gain_mismatch, p.gain_mismatch, 2)
        mis = rng.uniform(-p.misalignment, p.misalignment, 2)
        # gauge axes: channel a nominally along x, channel b along y (sensor frame)
        angles = np.array([0.0, math.pi / 2]) + mis
        self._axes = np.stack([np.cos(angles), np.sin(angles)], axis=1)
        self._zero = np.zeros(2)
        self._zero_clock = 0.0

    # -- electronics --------------------------------------------------------------
    def _disturbance(self, n: int) -> tuple[np.ndarray, np.ndarray]:
        """Drift + white noise + mains hum (V) for the next `n` samples, (n, 2), and
        the random-walk part of the drift at each sample (n, 2)."""
        p = self.params
        dt = 1.0 / p.sample_rate_hz
        t = self.clock + dt * np.arange(n)
        # offset(t) = A (1 - exp(-t / tau)) + W(t), W a random walk of drift_walk V/sqrt(s)
        steps = p.drift_walk * math.sqrt(dt) * self.rng.standard_normal((n, 2))
        walk = self._walk + np.cumsum(steps, axis=0)
        transient = self._transient * (1.0 - np.exp(-t / p.drift_tau))[:, None]
        noise = p.noise * self.rng.standard_normal((n, 2))
        phase = self.rng.uniform(0, 2 * math.pi)
        hum = p.hum * np.sin(2 * math.pi * p.hum_hz * t + phase)[:, None]
        return transient + walk + noise + hum, walk

    def _chain(self, force: np.ndarray, disturbance: np.ndarray) -> np.ndarray:
        """Sampled sensor-frame force (n, 2) N -> digitized filtered outputs (n, 2) V."""
        p = self.params
        # moment seen by each bridge: the force component along its gauge axis
        along = force @ self._axes.T
        analog = self._gain * volts_from_force(along, p) + disturbance
        # the filter ran at steady state on the first sample's level before this window
        zi = signal.sosfilt_zi(p.sos)[:, :, None] * analog[0][None, None, :]
        filtered, _ = signal.sosfilt(p.sos, analog, axis=0, zi=zi)
        if p.adc_bits is None:
            return filtered
        lsb = 2 * p.adc_range / 2**p.adc_bits
        # A/D: clip to the range, round to the nearest code
        return np.round(np.clip(filtered, -p.adc_range, p.adc_range - lsb) / lsb) * lsb

    def _consume(self, walk: np.ndarray, n: int) -> None:
        """Move the clock past `n` samples; the walk continues from its n-th value."""
        self.clock += n / self.params.sample_rate_hz
        self._walk = walk[n - 1]

    # -- operations ---------------------------------------------------------------
    def advance(self, seconds: float) -> None:
        """Let `seconds` pass with the sensor unloaded (the arm moves)."""
        if seconds <= 0:
            return
        # the random walk over a long interval: one Gaussian step of variance sigma^2 dt
        self._walk = self._walk + self.params.drift_walk * math.sqrt(
            seconds
        ) * self.rng.standard_normal(2)
        self.clock += seconds

    def zero(self) -> float:
        """Average `zero_time` s of no-load samples into the zero reference; returns
        the seconds spent."""
        p = self.params
        n = max(round(p.zero_time * p.sample_rate_hz), 1)
        dist, walk = self._disturbance(n)
        out = self._chain(np.zeros((n, 2)), dist)
        self._zero = out.mean(axis=0)
        self._zero_clock = self.clock + 0.5 * n / p.sample_rate_hz
        self._consume(walk, n)
        return n / p.sample_rate_hz

    def press(self, direction: np.ndarray, threshold: float, ramp: float) -> Press:
        """Force ``f(t) = ramp t`` along `direction` (sensor frame) until the measured
        force magnitude passes `threshold`; then hold it `settle` s and average the
        last `average` s (`threshold` N, `ramp` N/s). Raises RuntimeError when the
        threshold is never met (drift pushing the reading away from the force)."""
        if not (math.isfinite(ramp) and ramp > 0 and threshold > 0):
            raise ValueError("press needs a finite ramp > 0 (a finite arm stiffness) and threshold")
        p = self.params
        fs = p.sample_rate_hz
        n_settle = max(round(p.settle * fs), 1)
        n_avg = max(round(p.average * fs), 1)
        # enough samples to reach the threshold through the filter lag, then dwell
        n_ramp = math.ceil((threshold / ramp + 10.0 / p.cutoff_hz) * fs) + 1
        n = n_ramp + n_settle
        dist, walk = self._disturbance(n)
        unit = np.asarray(direction, dtype=float)
        magnitude = ramp * np.arange(n) / fs
        # pass 1: the guarded move stops at the first sample whose measured force passes
        out = self._chain(magnitude[:, None] * unit, dist)
        measured = np.hypot(*force_from_volts(out - self._zero, p).T)
        over = np.flatnonzero(measured[:n_ramp] >= threshold)
        if not len(over):
            raise RuntimeError("contact force never reached the threshold")
        k = int(over[0])
        # pass 2: the arm holds the force it had when it stopped (causal filter: same
        # samples up to k), dwells, and the reading averages the end of the dwell
        held = np.minimum(magnitude, magnitude[k])[: k + 1 + n_settle]
        out = self._chain(held[:, None] * unit, dist[: k + 1 + n_settle])
        volts = out[-n_avg:].mean(axis=0) - self._zero
        force = force_from_volts(volts, p)
        self._consume(walk, k + 1 + n_settle)
        size = float(np.hypot(*force))
        return Press(
            force / max(size, 1e-300),
            size,
            float(magnitude[k]),
            (k + 1 + n_settle) / fs,
            self.clock - 0.5 * p.average - self._zero_clock,
        )
