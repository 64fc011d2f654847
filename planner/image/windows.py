"""Rays, windows and the thesis' paths on the grid MII (DESIGN §4.9; thesis §4.3.5, App. 2).

From the target point of each intersection area of a
:class:`~planner.image.grid.GridMII`, rays are swept in 1 degree steps, every
ray records the blocking strengths it crosses, and runs of rays whose summed
strength stays within an admitted strength are the windows. Each window is
bisected; the admitted strength is raised until windows open. Paths are mapped
back to the world (App. 2 inverse), start on the safe circle and are ordered
by the thesis' CHOOSE rule.

Grid coordinates are those of :mod:`planner.image.grid` (continuous, 1-based);
the mapping is a uniform scale plus a shift, so ray angles (radians,
counter-clockwise from the x axis) are the same in grid and world.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from planner.errors import PlanningNotPossibleError
from planner.geometry import wrap_angle
from planner.image.grid import RAY_STEP, GridMII, build_grid
from planner.types import Hypothesis, ObjectModel, SensingPath, Workspace

__all__ = ["RaySweep", "ThesisPath", "choose", "sweep_rays", "thesis_paths", "windows"]


@dataclass(frozen=True, eq=False)
class RaySweep:
    """Blocking met by rays from one target: `angles` (K,) radians, and per ray the
    summed strength of the separate blocking runs crossed (`total`), the largest
    run (`largest`) and the number of runs (`runs`)."""

    angles: np.ndarray
    total: np.ndarray
    largest: np.ndarray
    runs: np.ndarray


def sweep_rays(grid: GridMII, target: np.ndarray, angles: np.ndarray) -> RaySweep:
    """Follow rays from `target` (grid coordinates) at `angles` (radians) to the grid edge.

    A run of consecutive blocking cells along a ray is one blocking boundary
    crossed (thesis §4.3.5); its strength is the largest value in the run. The
    ray's `total` sums its runs: ``1 - total`` bounds P(DM) from below, and with a
    single run it is Theorem 2's value.
    """
    angles = np.atleast_1d(np.asarray(angles, dtype=float))
    size = grid.mapping.size
    r = np.arange(0.0, size * math.sqrt(2.0) + RAY_STEP, RAY_STEP)
    pts = (
        np.asarray(target, dtype=float)[None, None, :]
        + r[None, :, None] * np.stack([np.cos(angles), np.sin(angles)], axis=1)[:, None, :]
    )
    cell = np.floor(pts - 0.5).astype(int)  # cell k covers [k + 0.5, k + 1.5)
    ok = np.all((cell >= 0) & (cell < size), axis=-1)
    values = np.where(
        ok,
        grid.strength[np.clip(cell[..., 0], 0, size - 1), np.clip(cell[..., 1], 0, size - 1)],
        0.0,
    )
    blocked = values > 0
    starts = blocked & ~np.pad(blocked, ((0, 0), (1, 0)))[:, :-1]
    flat_blocked, flat_values = blocked.ravel(), values.ravel()
    run_id = np.cumsum(starts.ravel())[flat_blocked] - 1
    n_runs = int(starts.sum())
    total = np.zeros(len(angles))
    largest = np.zeros(len(angles))
    runs = starts.sum(axis=1)
    if n_runs:
        run_max = np.zeros(n_runs)
        np.maximum.at(run_max, run_id, flat_values[flat_blocked])
        ray_of_run = np.repeat(np.arange(len(angles)), runs)
        total = np.bincount(ray_of_run, weights=run_max, minlength=len(angles)).astype(float)
        np.maximum.at(largest, ray_of_run, run_max)
    return RaySweep(angles, np.round(total, 9), np.round(largest, 9), runs)


def windows(open_rays: np.ndarray) -> list[tuple[int, int]]:
    """Circular runs of open rays as (first index, count); the whole circle is (0, K).

    >>> windows(np.array([True, False, False, True, True, False, True]))
    [(3, 2), (6, 2)]
    """
    open_rays = np.asarray(open_rays, dtype=bool)
    n = len(open_rays)
    if open_rays.all():
        return [(0, n)]
    shift = int(np.argmin(open_rays))  # a closed ray
    rolled = np.roll(open_rays, -shift).astype(np.int8)
    edges = np.diff(np.concatenate([[0], rolled, [0]]))
    first, stop = np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)
    return [(int((a + shift) % n), int(b - a)) for a, b in zip(first, stop, strict=True)]


@dataclass(frozen=True)
class ThesisPath:
    """One thesis path: a window's bisector into an intersection area.

    `path` starts on the safe circle and ends at `aim` (the area's target point,
    world frame). `family` is ``"distinguishing"`` (no blocking boundary crossed,
    Theorem 1) or ``"sub-optimal"``; `admitted_strength` is the level at which
    the window opened and `level` its rank among the levels; `strength` is the
    summed blocking strength on the bisector ray (``1 - strength`` bounds P(DM)),
    `crossings` the number of blocking runs on it. `window` is the range of
    approach-ray angles (radians, from the target outward, counter-clockwise; the
    end exceeds 2 pi when the window wraps past 0); `motion_cost` the arc
    along the safe circle from the sensor to the path origin (the CHOOSE key).
    """

    path: SensingPath
    aim: tuple[float, float]
    family: str
    level: int
    admitted_strength: float
    strength: float
    crossings: int
    window: tuple[float, float]
    area: int
    motion_cost: float


def _origin_on_circle(aim: np.ndarray, u: np.ndarray, workspace: Workspace) -> float:
    """Distance r > 0 with |aim + r u - c| = R."""
    rel = aim - np.asarray(workspace.center)
    b = float(rel @ u)
    # r = -b + sqrt(b^2 - (|rel|^2 - R^2))
    return -b + math.sqrt(b * b - (float(rel @ rel) - workspace.radius**2))


def thesis_paths(
    hypotheses: Sequence[Hypothesis],
    models: Mapping[str, ObjectModel] | Iterable[ObjectModel],
    workspace: Workspace,
    sensor_position: Sequence[float],
    size: int = 70,
    *,
    corners: bool = True,
    angle_tolerance: float | None = None,
    grid: GridMII | None = None,
) -> list[ThesisPath]:
    """The thesis' candidate paths, best first (DESIGN §4.9, thesis §4.3.5, CHOOSE).

    For each intersection area, rays from its target are swept in 1 degree
    steps. The admitted strength is raised through the distinct ray strengths,
    starting at 0 (the distinguishing family); at each level every window that
    newly opens is bisected into one path. Paths are sorted by admitted
    strength, then by the CHOOSE rule: nearest origin on the safe circle (arc
    length) to `sensor_position`. World frame throughout; an empty list when the
    grid has no intersection area. Pass `grid` to reuse a built grid.

    >>> from planner.models.outlines import make_stable_pose
    >>> from planner.types import ErrorBound, Pose
    >>> sq = ObjectModel("sq", (make_stable_pose([[0, 0], [2, 0], [2, 1], [0, 1]]),))
    >>> hs = [Hypothesis("sq", 0, (), Pose(x, 0, 0), ErrorBound(0, 0, 0), 0.5,
    ...                  equivalence_class=i) for i, x in enumerate([0.0, 1.0])]
    >>> best = thesis_paths(hs, [sq], Workspace((1.5, 0.5), 10.0), (11.5, 0.5), size=40)[0]
    >>> best.family, bool(best.path.direction[0] < -0.99), round(best.path.origin[0], 1)
    ('distinguishing', True, 11.5)
    """
    grid = grid or build_grid(
        hypotheses, models, size, corners=corners, angle_tolerance=angle_tolerance
    )
    centre = np.asarray(workspace.center, dtype=float)
    sensor = np.asarray(sensor_position, dtype=float)
    sensor_angle = math.atan2(*(sensor - centre)[::-1])
    aims = grid.world_targets()
    if len(aims) and np.any(np.hypot(*(aims - centre).T) >= workspace.radius):
        raise PlanningNotPossibleError(
            "an intersection area lies outside the safe circle", field="workspace"
        )
    step = math.radians(1.0)
    angles = np.arange(360) * step
    found: list[tuple[int, float, float, float, tuple[float, float]]] = []
    for area, target in enumerate(grid.targets):
        sweep = sweep_rays(grid, target, angles)
        for level in np.unique(sweep.total):
            for first, count in windows(sweep.total <= level):
                rays = (first + np.arange(count)) % 360
                if sweep.total[rays].max() < level:
                    continue  # opened at a lower level already
                if count == 360:
                    aim = aims[area]
                    theta = math.atan2(*(sensor - aim)[::-1])
                else:
                    # bisect the window's included angle
                    theta = float((first + (count - 1) / 2.0) * step)
                span = (float(first * step), float((first + count - 1) * step))
                found.append((area, float(level), theta, 0.0, span))
    if not found:
        return []
    thetas = np.array([f[2] for f in found])
    along = np.zeros(len(found))
    crossings = np.zeros(len(found), dtype=int)
    for area in {f[0] for f in found}:
        sel = np.array([f[0] == area for f in found])
        sweep = sweep_rays(grid, grid.targets[area], thetas[sel])
        along[sel], crossings[sel] = sweep.total, sweep.runs
    levels = np.unique([f[1] for f in found])
    out = []
    for (area, level, theta, _, span), strength, runs in zip(found, along, crossings, strict=True):
        u = np.array([math.cos(theta), math.sin(theta)])
        aim = aims[area]
        r = _origin_on_circle(aim, u, workspace)
        origin = aim + r * u
        arc = workspace.radius * abs(
            float(wrap_angle(math.atan2(*(origin - centre)[::-1]) - sensor_angle))
        )
        out.append(
            ThesisPath(
                path=SensingPath(tuple(origin), tuple(-u), r),
                aim=(float(aim[0]), float(aim[1])),
                family="distinguishing" if level == 0 else "sub-optimal",
                level=int(np.searchsorted(levels, level)),
                admitted_strength=level,
                strength=float(strength),
                crossings=int(runs),
                window=span,
                area=area + 1,
                motion_cost=arc,
            )
        )
    out.sort(key=lambda p: (p.admitted_strength, p.motion_cost))
    return out


def choose(paths: Sequence[ThesisPath]) -> ThesisPath:
    """The thesis' CHOOSE rule: in the lowest admitted strength, the path whose
    origin on the safe circle is nearest the sensor (smallest `motion_cost`)."""
    if not paths:
        raise PlanningNotPossibleError("no thesis path to choose from", field="paths")
    return min(paths, key=lambda p: (p.admitted_strength, p.motion_cost))
