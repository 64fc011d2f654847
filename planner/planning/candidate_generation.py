"""The general set of candidate sensing paths (DESIGN §4.10).

The general set aims at points inside the intersection area (IA) from origins
spread around the safe circle (:mod:`planner.planning.intersection_aims`), and at
points just inside faces where the hypotheses' boundaries differ (low blocking
strength, :mod:`planner.planning.boundary_aims`), approaching them head on and at
two oblique angles. Extra paths (thesis windows, strategy probes) are passed in
and always kept. Duplicates (same direction and line offset within a
resolution) are dropped, keeping the first in priority order: extra, IA,
boundary; beyond the configured count the rest is subsampled. World frame,
lengths in the object files' unit, angles in radians.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from planner.errors import PlannerError
from planner.geometry import LENGTH_SLACK
from planner.planning.boundary_aims import boundary_aims
from planner.planning.candidates import Candidates, paths_through
from planner.planning.intersection_aims import intersection_aims
from planner.types import SensorBounds, Workspace

if TYPE_CHECKING:
    from planner.planning.budget import Budget
    from planner.planning.posed_set import PosedSet

__all__ = ["CandidateConfig", "candidate_cap", "generate_candidates"]


@dataclass(frozen=True)
class CandidateConfig:
    """Size and resolution of the general candidate set.

    `count` caps the general candidates (extra paths come on top) for up to
    `full_size_hypotheses` hypotheses; beyond, the cap shrinks as the square of
    their ratio (not below `min_count`), since the outcome and confusability
    passes cost candidates x hypotheses^2;
    `origins` is the number of origins spread on the safe circle for each IA aim;
    `intersection_aims`, `boundary_aims` the number of aim points of each kind;
    `oblique` (radians) the extra approach angles of boundary aims (0 and +-oblique);
    `angle_step` (radians) and `offset_step` (length; None = radius / 200) the
    dedupe resolution; `grid` the sample grid (per side) used to find IA points;
    `face_samples` the points per face examined for differing boundaries;
    `feature_paths` caps the paths aimed at the features that tell the most
    probable classes apart (:mod:`planner.planning.feature_aims`; 0: none).
    """

    count: int = 256
    full_size_hypotheses: int = 64
    min_count: int = 48
    origins: int = 24
    intersection_aims: int = 6
    boundary_aims: int = 48
    oblique: float = 0.5
    angle_step: float = math.radians(1.0)
    offset_step: float | None = None
    grid: int = 24
    face_samples: int = 3
    feature_paths: int = 24

    def __post_init__(self) -> None:
        names = ("count", "min_count", "origins", "intersection_aims", "boundary_aims")
        for name in (*names, "face_samples", "full_size_hypotheses", "feature_paths"):
            if getattr(self, name) < 0:
                raise PlannerError("must be >= 0", field=f"candidates.{name}")
        if self.grid < 2:
            raise PlannerError("must be >= 2", field="candidates.grid")
        if not (0 <= self.oblique < math.pi / 2):
            raise PlannerError("must lie in [0, pi/2)", field="candidates.oblique")
        if not self.angle_step > 0 or (self.offset_step is not None and not self.offset_step > 0):
            raise PlannerError("dedupe steps must be > 0", field="candidates.angle_step")


def generate_candidates(
    posed: PosedSet,
    workspace: Workspace,
    sensor: SensorBounds,
    config: CandidateConfig | None = None,
    rng: np.random.Generator | None = None,
    *,
    sensor_position: Sequence[float] | None = None,
    extra: Candidates | None = None,
    budget: Budget | None = None,
) -> Candidates:
    """The candidate paths for a posed hypothesis set (world frame).

    IA aims get `config.origins` origins spread on the safe circle (the first at
    the sensor's place); paths end at the aim, inside every outline. Boundary
    aims sit just inside a face (by twice the largest tolerance) and are
    approached head on and at +-`config.oblique`. Extra paths are kept whole and
    first; the general ones are deduped and, beyond `config.count`, subsampled
    with `rng`. With a `budget`, the aims are sized to the work it has left and
    spend what they do.
    """
    config = config or CandidateConfig()
    rng = rng if rng is not None else np.random.default_rng(0)
    centre = np.asarray(workspace.center, dtype=float)
    sensor_xy = (
        centre + np.array([workspace.radius, 0.0]) if sensor_position is None else sensor_position
    )
    rel = np.asarray(sensor_xy, dtype=float) - centre
    start_angle = math.atan2(rel[1], rel[0]) if np.any(rel) else 0.0
    parts = []

    ia = intersection_aims(posed, config.intersection_aims, config.grid, budget)
    if len(ia) and config.origins:
        origins = _ring_points(workspace, config.origins, start_angle)
        o = np.repeat(origins[None], len(ia), axis=0).reshape(-1, 2)
        a = np.repeat(ia, len(origins), axis=0)
        span = a - o
        length = np.hypot(*span.T)
        ok = length > LENGTH_SLACK * workspace.radius
        parts.append(_make(o[ok], span[ok] / length[ok, None], length[ok], a[ok], "intersection"))

    points, normals = boundary_aims(
        posed, sensor, config.boundary_aims, config.face_samples, rng, budget
    )
    if len(points):
        inset = 2 * (2 * sensor.position_error + posed.eps_t.max()) + 5e-3 * workspace.radius
        aims = points - inset * normals
        turns = [0.0, config.oblique, -config.oblique] if config.oblique > 0 else [0.0]
        for turn in turns:
            c, s = math.cos(turn), math.sin(turn)
            d = -normals @ np.array([[c, s], [-s, c]])
            o, to_aim, _ = paths_through(aims, d, workspace)
            ok = np.isfinite(to_aim) & (to_aim > LENGTH_SLACK * workspace.radius)
            parts.append(_make(o[ok], d[ok], to_aim[ok], aims[ok], "boundary"))

    extra = extra if extra is not None else Candidates.empty()
    merged = Candidates.concat([extra, *parts])
    merged = merged.subset(_dedupe(merged, workspace, config, keep=len(extra)))
    n_general = len(merged) - len(extra)
    cap = candidate_cap(config, len(posed))
    if n_general > cap:
        pick = np.sort(rng.choice(n_general, cap, replace=False)) + len(extra)
        merged = merged.subset(np.concatenate([np.arange(len(extra)), pick]))
    return merged


def candidate_cap(config: CandidateConfig, n_hypotheses: int) -> int:
    """How many general candidates to keep for `n_hypotheses` hypotheses.

    >>> candidate_cap(CandidateConfig(), 50), candidate_cap(CandidateConfig(), 128)
    (256, 64)
    """
    ratio = min(1.0, config.full_size_hypotheses / max(n_hypotheses, 1))
    # cost ~ candidates x hypotheses^2: keep it near the full-size budget
    return min(config.count, max(config.min_count, int(config.count * ratio * ratio)))


def _ring_points(workspace: Workspace, count: int, start_angle: float) -> np.ndarray:
    """`count` points evenly spread on the safe circle, the first at `start_angle` (radians)."""
    angles = start_angle + 2 * np.pi * np.arange(count) / max(count, 1)
    return np.asarray(workspace.center) + workspace.radius * np.stack(
        [np.cos(angles), np.sin(angles)], axis=1
    )


def _dedupe(
    c: Candidates, workspace: Workspace, config: CandidateConfig, keep: int = 0
) -> np.ndarray:
    """Indices of the first path of each (direction, line offset) cell, in order;
    the first `keep` paths are kept whatever their cell."""
    if len(c) == 0:
        return np.zeros(0, dtype=int)
    offset_step = config.offset_step or workspace.radius / 200
    angle = np.arctan2(c.directions[:, 1], c.directions[:, 0])
    n_steps = max(1, round(2 * math.pi / config.angle_step))
    k_angle = np.round(angle / config.angle_step).astype(np.int64) % n_steps
    rel = c.origins - np.asarray(workspace.center)
    offset = c.directions[:, 0] * rel[:, 1] - c.directions[:, 1] * rel[:, 0]
    k_offset = np.round(offset / offset_step).astype(np.int64)
    _, first = np.unique(np.stack([k_angle, k_offset], axis=1), axis=0, return_index=True)
    return np.union1d(np.arange(keep), first)


def _make(
    o: np.ndarray, d: np.ndarray, length: np.ndarray, aims: np.ndarray, source: str
) -> Candidates:
    """Paths from arrays (origins, unit directions, lengths, aims), all from `source`."""
    return Candidates(o, d, length, aims, np.full(len(length), source, dtype="<U12"))
