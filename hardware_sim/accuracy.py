"""Measured contact errors of a hardware preset, against its stated bounds.

Random worlds from an object set, random paths aimed at the object, and for
every contact the angle between measured and true outward normal (rad) and the
distance between measured and true contact point (length unit).

    python -m hardware_sim.accuracy --objects thesis_like --touches 2000
"""

from __future__ import annotations

import argparse
import math
import sys
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from hardware_sim.presets import PRESETS, Preset, build_arm, resolve_preset
from hardware_sim.world import random_world
from planner.geometry import ANGLE_SLACK
from planner.models.library import load_objects
from planner.types import ObjectModel, Workspace

__all__ = ["TouchErrors", "main", "touch_errors"]


@dataclass(frozen=True, eq=False)
class TouchErrors:
    """Per-contact errors: `normal` (rad, unsigned angle between measured and true
    normal), `position` (length), with the preset's `bounds`."""

    preset: Preset
    normal: np.ndarray
    position: np.ndarray

    def within(self) -> tuple[float, float]:
        """Share of contacts inside the normal bound and inside the position bound."""
        b = self.preset.bounds
        slack = ANGLE_SLACK
        return (
            float(np.mean(self.normal <= b.normal_error + slack)),
            float(np.mean(self.position <= b.position_error + slack)),
        )

    def percentiles(self, q: Sequence[float] = (50, 95, 99, 100)) -> dict[str, list[float]]:
        """Percentiles of the normal error (degrees) and position error (length)."""
        return {
            "normal_deg": [float(v) for v in np.degrees(np.percentile(self.normal, q))],
            "position": [float(v) for v in np.percentile(self.position, q)],
        }


def touch_errors(
    preset: str | Preset,
    models: Sequence[ObjectModel],
    touches: int = 1000,
    seed: int = 0,
    workspace: Workspace | None = None,
    touches_per_world: int = 10,
) -> TouchErrors:
    """Collect at least `touches` contacts: a fresh world and arm every
    `touches_per_world` probes (the arm warms up over its probes, as in a trial)."""
    p = resolve_preset(preset)
    ws = workspace or Workspace((0.0, 0.0), 200.0)
    rng = np.random.default_rng(seed)
    normal: list[float] = []
    position: list[float] = []
    world_index = 0
    while len(normal) < touches:
        world = random_world(list(models), ws, rng)
        arm = build_arm(world, p, np.random.SeedSequence(seed, spawn_key=(world_index,)))
        world_index += 1
        for _ in range(touches_per_world):
            result = arm.execute(world.hitting_path(rng))
            if result.true_point is None or result.true_normal is None:
                continue
            c = result.observation.contact
            if c is None:  # pragma: no cover - a true contact always gives a measured one
                continue
            err = math.atan2(c.normal[1], c.normal[0]) - math.atan2(
                result.true_normal[1], result.true_normal[0]
            )
            # unsigned angle: |wrap(measured - true)|
            normal.append(abs((err + math.pi) % (2 * math.pi) - math.pi))
            position.append(math.dist(c.point, result.true_point))
    return TouchErrors(p, np.asarray(normal), np.asarray(position))


def main(argv: Sequence[str] | None = None) -> int:
    """Print the error distribution of every preset (or the chosen ones)."""
    parser = argparse.ArgumentParser(prog="python -m hardware_sim.accuracy", description=__doc__)
    parser.add_argument("--objects", default="thesis_like")
    parser.add_argument("--sensor", action="append", choices=sorted(PRESETS))
    parser.add_argument("--touches", type=int, default=2000)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args(argv)
    models = load_objects(args.objects)
    print(
        "preset         touches  normal error deg p50/p95/p99/max (bound)  inside  "
        "position p50/p95/p99/max (bound)  inside"
    )
    for name in args.sensor or list(PRESETS):
        e = touch_errors(name, models, args.touches, args.seed)
        q = e.percentiles()
        inside_n, inside_p = e.within()
        b = e.preset.bounds
        n = "/".join(f"{v:.2f}" for v in q["normal_deg"])
        pos = "/".join(f"{v:.3f}" for v in q["position"])
        print(
            f"{name:14s} {len(e.normal):7d}  {n:>24s} ({math.degrees(b.normal_error):g})  "
            f"{100 * inside_n:6.2f}%  {pos:>26s} ({b.position_error:g})  {100 * inside_p:6.2f}%"
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
