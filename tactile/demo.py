"""One recognition of a randomly posed object over HTTP, printed step by step.

:func:`run_demo` drives the simulated arm against a running service (its base
URL) through :class:`hardware_sim.http_service.HttpService`: it creates a session
on the object set, plans, touches and observes until the session is localized or
the touch limit, prints each step, writes the service's picture of the session,
and says whether the object and its pose were found. ``tactile demo`` starts the
service for it (``tactile.cli``).
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import TextIO

import httpx
import numpy as np

from hardware_sim.api_client import Client
from hardware_sim.client import Recognition, Step, outline_distance, run_recognition
from hardware_sim.http_service import HttpService, ServiceError
from hardware_sim.presets import Preset, build_arm, explicit_preset, resolve_preset
from hardware_sim.world import random_world
from planner.models.library import load_objects
from planner.types import Workspace

__all__ = ["SENSORS", "demo_preset", "run_demo"]

#: ``--sensor`` choices: the demo's bounded errors (1 mm, 3 degrees) or a hardware preset.
SENSORS = ("bounded", "ideal", "thesis_sensor")
WORKSPACE = Workspace((0.0, 0.0), 200.0)
STRATEGY = {"name": "lookahead", "depth": 2, "budget_ms": 1000}
#: Slack (length) on the pose check, as in the experiments.
POSE_SLACK = 1e-6


def demo_preset(sensor: str) -> Preset:
    """`bounded`: contact point within 1 mm and normal within 3 degrees, uniformly;
    otherwise the named hardware preset (:data:`hardware_sim.presets.PRESETS`)."""
    if sensor == "bounded":
        return explicit_preset(1.0, math.radians(3.0))
    return resolve_preset(sensor)


def _num(value: float | None) -> str:
    # + 0.0 turns a rounded -0.0 into 0.0
    return "-" if value is None or not math.isfinite(value) else f"{round(value, 2) + 0.0:.2f}"


def _step_line(number: int, step: Step) -> str:
    path, contact = step.observation.path, step.observation.contact
    what = (
        "miss"
        if contact is None
        else f"contact ({contact.point[0]:.1f}, {contact.point[1]:.1f}) "
        f"normal {math.degrees(contact.normal_angle):.0f} deg"
    )
    # the recognition's own forecast, where it was made: what to act on when the
    # outcome model's worst case says 0
    p = step.advice.p_forecast
    forecast = "" if p is None else f" (forecast {_num(p)})"
    return (
        f"touch {number}: path from ({path.origin[0]:.1f}, {path.origin[1]:.1f}) "
        f"direction ({_num(path.direction[0])}, {_num(path.direction[1])}) "
        f"[P(DM) {_num(step.advice.p_distinguishing)}{forecast}, "
        f"E[touches] {_num(step.advice.expected_remaining)}] -> {what}; "
        f"{step.update.hypotheses} hypotheses in {step.update.classes} classes, "
        f"status {step.update.status}"
    )


def run_demo(
    base_url: str,
    objects: str,
    seed: int,
    max_touches: int,
    out: TextIO,
    picture: Path,
    sensor: str = "bounded",
    client: Client | None = None,
    report: Path | None = None,
) -> int:
    """Recognize one random object of `objects` (an object file) through the service
    at `base_url`; write the session's picture to `picture` (.png or .svg) and, given
    `report`, the session's report there (.csv: CSV, else JSON).

    Exit code 0 when localized with the right object and stable pose and the true
    outline within the estimate's error disk (eps_t / 2), as the experiments judge."""
    fmt = picture.suffix.lower().lstrip(".")
    if fmt not in ("png", "svg"):
        raise ValueError(f"picture must end in .png or .svg, not {picture.name!r}")
    models = load_objects(objects)
    preset = demo_preset(sensor)
    world = random_world(models, WORKSPACE, np.random.default_rng(seed))
    arm = build_arm(world, preset, seed)
    b = preset.bounds
    print(f"service: {base_url}", file=out)
    print(f"objects: {', '.join(m.name for m in models)}", file=out)
    print(
        f"sensor: {sensor} ({preset.description}), bounds {b.position_error:g} and "
        f"{math.degrees(b.normal_error):g} deg; strategy {STRATEGY['name']} "
        f"(depth {STRATEGY['depth']}, {STRATEGY['budget_ms']} ms)",
        file=out,
    )
    print(
        f"truth: {world.model.name} (stable pose {world.pose_index}) at x={world.pose.x:.1f} "
        f"y={world.pose.y:.1f} theta={math.degrees(world.pose.theta):.1f} deg",
        file=out,
    )
    client = client or Client(base_url=base_url, timeout=httpx.Timeout(60.0))
    service = HttpService.create(
        client,
        models,
        b,
        WORKSPACE,
        sensor_position=arm.position,
        strategy={**STRATEGY, "seed": seed},
    )
    view = f"{base_url}{service.view_path()}"
    print(f"session: {service.session_id}", file=out)
    numbered = iter(range(1, max_touches + 1))
    rec = run_recognition(
        service, arm, max_touches, on_step=lambda s: print(_step_line(next(numbered), s), file=out)
    )
    ok = _verdict(rec, models, world, out)
    try:
        picture.write_bytes(service.picture(fmt))
        print(f"picture: {picture}", file=out)
    except ServiceError as exc:
        print(f"no picture: {exc}", file=out)
    if report is not None:
        report.write_bytes(service.report("csv" if report.suffix.lower() == ".csv" else "json"))
        print(f"report: {report}", file=out)
    print(f"live view: {view}", file=out)
    return 0 if ok else 1


def _verdict(rec: Recognition, models: list, world, out: TextIO) -> bool:
    if rec.status != "localized" or not rec.estimates:
        print(f"not localized after {rec.touches} touches ({rec.status})", file=out)
        return False
    best = rec.estimates[0]
    error = outline_distance(models, best, world.model.name, world.pose_index, world.pose)
    shift = math.hypot(best.pose.x - world.pose.x, best.pose.y - world.pose.y)
    right = best.object == world.model.name and best.stable_pose == world.pose_index
    within = error <= best.eps_t / 2 + POSE_SLACK
    print(
        f"localized after {rec.touches} touches: {best.object} (stable pose {best.stable_pose}) "
        f"at x={best.pose.x:.1f} y={best.pose.y:.1f} "
        f"theta={math.degrees(best.pose.theta):.1f} deg; outline {_num(error)} from the truth "
        f"(bound eps_t/2 = {best.eps_t / 2:.2f}), translation {shift:.2f} "
        f"(bound {_num(best.translation)}): {'correct' if right and within else 'WRONG'}",
        file=out,
    )
    return right and within
