"""Hardware presets and the error bounds the planner must be told about.

Each :class:`Preset` is an arm, a sensor model, and the :class:`SensorBounds`
a planner session must be configured with for that hardware. The bounds are the
worst-case sum of the modelled error sources (the error budget in each preset's
`budget`), so bounded-error pruning stays sound; the only unbounded terms are
Gaussian electronic noise and the drift random walk, kept far below the budget
(tests measure the distribution, and `thesis_sensor` keeps >= 99 % of its
normals inside the 5 degree cone).

Presets (lengths in mm, the unit of the shipped object sets):

- ``ideal``: exact contacts (rigid arm, exact sensor); bounds (0, 0).
- ``thesis_sensor``: the strain-gauge sensor of App. 3 on a stiff, accurate arm
  with the recalibration routine: about a 5 degree normal error cone (ch. 5.2);
  bounds (1 mm, 5 deg).
- ``e2_arm``: the same sensor on the compliant Argonne E2 master/slave arm
  (ch. 5.1): about 1 inch of position error under load, about 10 degrees of
  normal error; bounds (25.4 mm, 10 deg).
- :func:`explicit_preset`: bounded uniform noise of given size (``--position-error``,
  ``--normal-error``): positions uniform in a disk, normals uniform in +-phi.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Literal

import numpy as np

from hardware_sim.arm import ArmParams, SimulatedArm
from hardware_sim.sensor import (
    BoundedSensor,
    ExactSensor,
    ForceSensor,
    SensorParams,
    StrainGaugeSensor,
)
from hardware_sim.world import World
from planner.types import SensorBounds

__all__ = ["PRESETS", "Preset", "build_arm", "explicit_preset", "resolve_preset"]

SensorKind = Literal["exact", "strain_gauge", "bounded"]


@dataclass(frozen=True)
class Preset:
    """A hardware configuration: `arm` parameters, the sensor model (`sensor_kind`
    with `sensor` parameters for the strain-gauge model), and `bounds`, the
    error bounds the planner session must use. `budget` lists the worst-case
    contribution of each error source (length unit or radians)."""

    name: str
    bounds: SensorBounds
    arm: ArmParams
    sensor_kind: SensorKind
    sensor: SensorParams | None = None
    budget: dict[str, float] = field(default_factory=dict)
    description: str = ""


# The electronics of App. 3 (8 V excitation, gauge factor 2, bridge factor 2, gain
# 2000, 3-pole Butterworth at 25 Hz) with a 12-bit +-10 V A/D (the Analogic AD5400),
# amplifier drift after the thermal transients of ch. 5.2, mains interference.
THESIS_ELECTRONICS = SensorParams(
    noise=0.005,
    hum=0.2,
    adc_bits=12,
    drift_transient=0.3,
    drift_tau=120.0,
    drift_walk=0.001,
    gain_mismatch=0.02,
    misalignment=math.radians(1.25),
)


def _sensor_normal(since_zero: float) -> dict[str, float]:
    """Worst-case normal error (rad) of the sensor itself with >= 0.62 V of signal
    (3 N): misalignment, gain mismatch g (at most g rad, at 45 degrees), and the
    residual channel offsets `since_zero` s after a recalibration (transient slope
    0.3 V / 120 s, 4 sigma of the 1 mV/sqrt(s) walk, half an A/D step, 1 mV of
    filtered hum and noise)."""
    e = THESIS_ELECTRONICS
    lsb = 2 * e.adc_range / 2 ** (e.adc_bits or 12)
    # per-channel offset: A/tau t + 4 sigma sqrt(t) + lsb/2 + 1 mV
    offset = (
        e.drift_transient / e.drift_tau * since_zero
        + 4 * e.drift_walk * math.sqrt(since_zero)
        + lsb / 2
        + 0.001
    )
    return {
        "normal.misalignment": e.misalignment,
        "normal.gain_mismatch": e.gain_mismatch,
        # both channels off: the force vector moves by sqrt(2) offset over 0.62 V
        "normal.electronics": math.atan(math.sqrt(2) * offset / 0.62),
    }


_THESIS_ARM = ArmParams(
    recalibrate=True,
    threshold=3.0,
    stiffness=15.0,
    touch_speed=2.0,
    tip_radius=3.0,
    vertex_zone=0.2,
    backlash=math.radians(0.5),
    thermal_position=0.1,
    thermal_angle=math.radians(0.05),
    reading_noise=0.02,
)

# E2: about 1 inch of hand deflection under ~1 lbf (k ~ 4.45 N / 25.4 mm), wrist
# play, potentiometer drift after ~10 minutes of use (ch. 5.1)
_E2_ARM = ArmParams(
    recalibrate=True,
    threshold=3.0,
    stiffness=0.175,
    touch_speed=10.0,
    tip_radius=3.0,
    vertex_zone=2.0,
    backlash=math.radians(8.0),
    thermal_position=4.0,
    thermal_angle=math.radians(1.0),
    reading_noise=0.5,
)

PRESETS: dict[str, Preset] = {
    "ideal": Preset(
        "ideal",
        SensorBounds(0.0, 0.0),
        ArmParams(),
        "exact",
        description="exact contacts: rigid arm, exact sensor",
    ),
    "thesis_sensor": Preset(
        "thesis_sensor",
        SensorBounds(1.0, math.radians(5.0)),
        _THESIS_ARM,
        "strain_gauge",
        THESIS_ELECTRONICS,
        budget={
            **_sensor_normal(2.5),
            "normal.backlash": _THESIS_ARM.backlash / 2,
            "normal.thermal": _THESIS_ARM.thermal_angle,
            # deflection: (threshold + filter-lag overshoot < 1 N) / stiffness
            "position.deflection": 4.0 / _THESIS_ARM.stiffness,
            # ball centre moved back along a normal off by <= 5 deg: 2 r sin(phi / 2)
            "position.tip": 2 * 3.0 * math.sin(math.radians(5.0) / 2),
            "position.thermal": _THESIS_ARM.thermal_position,
            "position.vertex": _THESIS_ARM.vertex_zone,
            "position.reading": _THESIS_ARM.reading_noise,
        },
        description="strain-gauge sensor (App. 3) on a stiff arm, recalibrated: ~5 deg cone",
    ),
    "e2_arm": Preset(
        "e2_arm",
        SensorBounds(25.4, math.radians(10.0)),
        _E2_ARM,
        "strain_gauge",
        THESIS_ELECTRONICS,
        budget={
            **_sensor_normal(3.0),
            "normal.backlash": _E2_ARM.backlash / 2,
            "normal.thermal": _E2_ARM.thermal_angle,
            "position.deflection": 3.1 / _E2_ARM.stiffness,
            "position.tip": 2 * 3.0 * math.sin(math.radians(10.0) / 2),
            "position.thermal": _E2_ARM.thermal_position,
            "position.vertex": _E2_ARM.vertex_zone,
            "position.reading": _E2_ARM.reading_noise,
        },
        description="the compliant E2 arm (ch. 5.1): ~1 inch and ~10 deg",
    ),
}


def explicit_preset(position_error: float, normal_error: float, tip_radius: float = 0.0) -> Preset:
    """Bounded uniform noise: the contact point uniform in a disk of radius
    `position_error` (length unit), the normal turned uniformly in
    +-`normal_error` (rad); the bounds are exactly these. With a ball tip of
    `tip_radius` the arm reports the ball's centre (within `position_error`) and
    the session is told the radius."""
    bounds = SensorBounds(position_error, normal_error, tip_radius)
    tip = f", {tip_radius:g} ball" if tip_radius else ""
    return Preset(
        f"bounded({position_error:g}, {math.degrees(normal_error):g} deg{tip})",
        bounds,
        ArmParams(reading_noise=position_error, tip_radius=tip_radius, report_centre=True),
        "bounded",
        description="uniform bounded noise",
    )


def resolve_preset(preset: str | Preset) -> Preset:
    """A preset by name (one of :data:`PRESETS`) or the preset itself."""
    if isinstance(preset, Preset):
        return preset
    try:
        return PRESETS[preset]
    except KeyError:
        raise ValueError(f"unknown sensor preset {preset!r}; one of {sorted(PRESETS)}") from None


def build_arm(
    world: World,
    preset: str | Preset,
    seed: int | np.random.SeedSequence = 0,
    start_angle: float = 0.0,
) -> SimulatedArm:
    """The arm and sensor of `preset` around `world`, seeded (arm and sensor draw
    from independent streams)."""
    p = resolve_preset(preset)
    seq = seed if isinstance(seed, np.random.SeedSequence) else np.random.SeedSequence(seed)
    # children derived from the key, not spawned: the same seed always gives the same streams
    arm_seq, sensor_seq = (
        np.random.SeedSequence(seq.entropy, spawn_key=(*seq.spawn_key, k)) for k in (0, 1)
    )
    sensor_rng = np.random.default_rng(sensor_seq)
    sensor: ForceSensor
    if p.sensor_kind == "exact":
        sensor = ExactSensor()
    elif p.sensor_kind == "bounded":
        sensor = BoundedSensor(p.bounds.normal_error, sensor_rng)
    else:
        sensor = StrainGaugeSensor(p.sensor or SensorParams(), sensor_rng)
    return SimulatedArm(world, p.arm, sensor, np.random.default_rng(arm_seq), start_angle)
