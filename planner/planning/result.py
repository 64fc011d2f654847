"""What the planner returns: ranked paths with their scores (DESIGN §6 plan fields).

World frame, lengths in the object files' unit, probabilities in [0, 1].
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from planner.types import SensingPath, Workspace

__all__ = ["PLAN_STATUSES", "REFINING", "Plan", "PlannedPath", "opening_path"]

#: Plan-level status, as the session's: a probe is needed first, several
#: classes are left, one class is left, or no hypothesis explains the contacts.
PLAN_STATUSES = ("awaiting_contact", "ambiguous", "localized", "inconsistent")
#: The family of a path offered to shrink the error disks when none is informative.
REFINING = "refining"

_GOLDEN_ANGLE = math.pi * (3 - math.sqrt(5))


@dataclass(frozen=True)
class PlannedPath:
    """One ranked sensing path (world frame) with its scores.

    `family` is one of distinguishing, informative, partial, uninformative, or
    refining (offered only when no path is informative: it tells no hypothesis
    apart but shrinks their error disks to `expected_eps_t`, the class-weighted
    mean disk diameter expected after the touch);
    `expected_remaining` the expected number of touches still needed if this
    path is taken, itself included (None when unknown, e.g. before any contact),
    as the search values it, not calibrated: ``lookahead`` searches it `depth`
    touches deep, a set still open there counted at log |T| over the best gain
    one touch gives now (the worst-case outcome model's), which later touches
    usually beat, so that values above two or three overstate the touches taken
    (measured: README, Calibration; the same in a `truncated` plan, where paths
    the search did not reach keep that estimate); ``optimal``: to the end on
    small sets; the other
    strategies search it `depth` deep only on small sets (at most
    `optimal_max_classes` classes) and otherwise give the one-touch bound, a
    lower bound of the deeper value; `motion_cost` the arc along
    the safe circle from the sensor plus the expected approach length;
    `source` where the candidate came from (opening, probe, random, window,
    intersection, boundary, extra); `p_forecast` the probability of a
    distinguishing measurement as the recognition itself would judge the touch
    (:mod:`planner.planning.forecast`; None where not forecast), against `p_distinguishing`,
    the outcome model's worst-case value, which is sound where it says 1 and
    lower than what happens elsewhere; `height` the probing height (None: the
    default height, DESIGN §4.13)."""

    origin: tuple[float, float]
    direction: tuple[float, float]
    length: float
    aim: tuple[float, float]
    family: str
    p_distinguishing: float
    p_informative: float
    expected_pruning: float
    expected_remaining: float | None
    motion_cost: float
    source: str = "general"
    expected_eps_t: float | None = None
    p_forecast: float | None = None
    scored_by: str = "outcome_model"
    height: float | None = None

    @property
    def path(self) -> SensingPath:
        return SensingPath(self.origin, self.direction, self.length, self.height)


@dataclass(frozen=True)
class Plan:
    """Ranked paths, best first, with the plan-level `status` (one of
    :data:`PLAN_STATUSES`), `truncated` (the budget stopped the search),
    `elapsed_ms`, the `strategy` that ranked them, a `note` when the strategy
    had to deviate or found nothing, and the numbers of candidates and classes;
    `work` (units the plan spent, :mod:`planner.planning.budget`) and
    `stopped_by` (what ended it early: ``"work"``, the deterministic budget;
    ``"time"``, the wall-clock cap; None: nothing)."""

    status: str
    truncated: bool
    elapsed_ms: float
    paths: tuple[PlannedPath, ...]
    strategy: str
    note: str | None = None
    candidates: int = 0
    classes: int = 0
    work: float = 0.0
    stopped_by: str | None = None

    @property
    def best(self) -> PlannedPath | None:
        return self.paths[0] if self.paths else None


def opening_path(
    workspace: Workspace,
    sensor_position: Sequence[float],
    misses: int = 0,
    angle: float | None = None,
    aim: Sequence[float] | None = None,
) -> SensingPath:
    """The probe when nothing is known: from the sensor's place on the safe circle
    through the centre (a chord of length 2R), or through `aim` (the centre of a
    pose prior's region) to where it leaves the circle.

    After `misses` probes that touched nothing, the origin turns by the golden
    angle each time; `angle` (radians about the centre) overrides the origin.

    >>> p = opening_path(Workspace((0.0, 0.0), 100.0), (150.0, 0.0))
    >>> p.origin, p.direction, p.length
    ((100.0, 0.0), (-1.0, -0.0), 200.0)
    """
    centre = np.asarray(workspace.center, dtype=float)
    if angle is None:
        rel = np.asarray(sensor_position, dtype=float) - centre
        angle = (math.atan2(rel[1], rel[0]) if np.any(rel) else 0.0) + misses * _GOLDEN_ANGLE
    unit = np.array([math.cos(angle), math.sin(angle)])
    origin = centre + workspace.radius * unit
    if aim is not None and np.hypot(*(np.asarray(aim, dtype=float) - origin)) > 0:
        # toward the aim, to where the line leaves the circle: t = -2 (o - c).d
        d = np.asarray(aim, dtype=float) - origin
        d = d / np.hypot(*d)
        length = float(-2 * (origin - centre) @ d)
        if length > 0:
            return SensingPath(
                (float(origin[0]), float(origin[1])), (float(d[0]), float(d[1])), length
            )
    return SensingPath(
        (float(origin[0]), float(origin[1])),
        (float(-unit[0]), float(-unit[1])),
        2 * workspace.radius,
    )
