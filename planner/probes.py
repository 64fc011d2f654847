"""Paths a strategy brings of its own (world frame, lengths in the object files' unit).

The opening probe before any contact (from the sensor's place toward the
centre; ``random``: from a random place), the thesis' second probe orthogonal
to the first contact normal (thesis §3.1, Exp. II), random draws aimed at the
centre of the union area (thesis Exp. I), and the thesis' grid windows from
:func:`planner.grid.thesis_paths`.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING

import numpy as np

from planner.candidates import Candidates, paths_through, union_centre
from planner.errors import PlanningNotPossibleError
from planner.plans import PlannedPath, opening_path
from planner.posed import PosedSet
from planner.scoring import motion_cost
from planner.types import Contact, Hypothesis, ObjectModel, SensorBounds, Workspace

if TYPE_CHECKING:
    from planner.strategies import StrategyConfig

__all__ = ["opening_probe", "strategy_paths"]


def opening_probe(
    config: StrategyConfig,
    workspace: Workspace,
    sensor_position: Sequence[float],
    misses: int,
    rng: np.random.Generator,
) -> PlannedPath:
    """Before any contact: toward the centre from the sensor's place (``random``:
    from a random place)."""
    angle = float(rng.uniform(-math.pi, math.pi)) if config.name == "random" else None
    path = opening_path(workspace, sensor_position, misses, angle)
    # motion: the arc to the origin plus the way to the centre
    cost = motion_cost(
        np.array([path.origin]), np.array([workspace.radius]), workspace, sensor_position
    )[0]
    # nothing is known yet: any contact teaches something, none can be predicted
    return PlannedPath(
        origin=path.origin,
        direction=path.direction,
        length=path.length,
        aim=(float(workspace.center[0]), float(workspace.center[1])),
        family="informative",
        p_distinguishing=0.0,
        p_informative=1.0,
        expected_pruning=0.0,
        expected_remaining=None,
        motion_cost=float(cost),
        source="opening",
    )


def _chords(aim: np.ndarray, angles: np.ndarray, workspace: Workspace, source: str) -> Candidates:
    """Paths from origins on the safe circle (at `angles` about the centre) through
    `aim` to the far side of the circle."""
    centre = np.asarray(workspace.center, dtype=float)
    origins = centre + workspace.radius * np.stack([np.cos(angles), np.sin(angles)], axis=1)
    span = aim - origins
    dist = np.hypot(*span.T)
    d = span / np.maximum(dist, 1e-300)[:, None]
    # a chord from o along unit d on the circle |x - c| = R has length 2 d.(c - o)
    lengths = 2 * np.einsum("nk,nk->n", d, centre - origins)
    ok = (dist > 1e-9 * workspace.radius) & (lengths > 1e-9 * workspace.radius)
    return Candidates(
        origins[ok],
        d[ok],
        lengths[ok],
        np.repeat(aim[None], ok.sum(), 0),
        np.full(int(ok.sum()), source, dtype="<U12"),
    )


def strategy_paths(
    config: StrategyConfig,
    hypotheses: Sequence[Hypothesis],
    models: Mapping[str, ObjectModel],
    posed: PosedSet,
    contacts: Sequence[Contact],
    workspace: Workspace,
    sensor: SensorBounds,
    sensor_position: Sequence[float],
    rng: np.random.Generator,
) -> Candidates:
    """Candidates a strategy brings of its own: random draws, thesis probes and windows."""
    parallel = _parallel(contacts, sensor)
    if config.name == "random" or (config.name == "thesis" and parallel > 1):
        # thesis Exp. I: a random origin on the safe circle, aimed at the union area's centre
        draws = config.random_draws if config.name == "random" else 1
        angles = rng.uniform(-math.pi, math.pi, draws)
        return _chords(union_centre(posed), angles, workspace, "random")
    if config.name != "thesis":
        return Candidates.empty()
    if parallel == 1:
        return _orthogonal_probe(contacts[0], posed, workspace, sensor_position)
    from planner.grid import thesis_paths  # lazy: the grid brings scipy.ndimage

    # windows in CHOOSE order: admitted blocking strength, then nearest origin
    try:
        windows = thesis_paths(hypotheses, models, workspace, sensor_position, config.grid_size)
    except PlanningNotPossibleError:  # e.g. an intersection area outside the safe circle
        return Candidates.empty()  # the thesis strategy then falls back, saying so
    return Candidates.from_paths(
        [w.path for w in windows],
        source="window",
        aims=np.array([w.aim for w in windows]).reshape(-1, 2),
    )


def _parallel(contacts: Sequence[Contact], sensor: SensorBounds) -> int:
    """Number of contacts when all their normals are parallel (within 2 phi), else 0."""
    if not contacts:
        return 0
    normals = np.array([c.normal for c in contacts])
    cos_tol = math.cos(2 * sensor.normal_error + 1e-6)
    return len(contacts) if np.all(np.abs(normals @ normals[0]) >= cos_tol) else 0


def _orthogonal_probe(
    contact: Contact, posed: PosedSet, workspace: Workspace, sensor_position: Sequence[float]
) -> Candidates:
    """Thesis §3.1: the second probe runs orthogonal to the first contact normal,
    across the envelope of translations, through the depth of the union's centre."""
    n, p = np.asarray(contact.normal), np.asarray(contact.point)
    depth = max(float((p - union_centre(posed)) @ n), 1e-6 * workspace.radius)
    aim = p - depth * n
    both = np.array([[-n[1], n[0]], [n[1], -n[0]]])
    origins, _, chord = paths_through(np.repeat(aim[None], 2, 0), both, workspace)
    ok = np.isfinite(chord)
    if not ok.any():
        return Candidates.empty()
    cost = motion_cost(np.nan_to_num(origins), np.zeros(2), workspace, sensor_position)
    i = int(np.argmin(np.where(ok, cost, np.inf)))
    return Candidates(
        origins[i : i + 1],
        both[i : i + 1],
        chord[i : i + 1],
        aim[None],
        np.array(["probe"], dtype="<U12"),
    )
