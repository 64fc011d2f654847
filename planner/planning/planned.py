"""A candidate path as a planned path (DESIGN §6): its geometry, the scores the
plan gives it and how the strategy counted the touches after it.

Shared by the plan's assembly (:mod:`planner.planning.plan`) and its refining
paths (:mod:`planner.planning.refining_paths`).
"""

from __future__ import annotations

import numpy as np

from planner.planning.analysis import Analysis
from planner.planning.result import PlannedPath
from planner.planning.scoring import FAMILIES, InformationScores
from planner.planning.strategies import Ranking

__all__ = ["no_ranking", "planned"]


def planned(
    found: Analysis,
    i: int,
    ranking: Ranking,
    family: str | None = None,
    expected_eps_t: float | None = None,
    scores: tuple[InformationScores, int] | None = None,
) -> PlannedPath:
    """Candidate `i` as a planned path; `scores` (information scores, row) replace
    the analysis' own for that path."""
    c = found.candidates
    info, j = scores if scores is not None else (found.info, i)
    return PlannedPath(
        origin=(float(c.origins[i, 0]), float(c.origins[i, 1])),
        direction=(float(c.directions[i, 0]), float(c.directions[i, 1])),
        length=float(c.lengths[i]),
        aim=(float(c.aims[i, 0]), float(c.aims[i, 1])),
        family=family or FAMILIES[int(info.family[j])],
        p_distinguishing=float(info.p_distinguishing[j]),
        p_informative=float(info.p_informative[j]),
        expected_pruning=float(info.expected_pruning[j]),
        expected_remaining=float(ranking.expected_remaining[i]),
        motion_cost=float(found.motion[i]),
        source=str(c.source[i]),
        expected_eps_t=None if expected_eps_t is None else float(expected_eps_t),
        height=c.height_of(i),
    )


def no_ranking(found: Analysis) -> Ranking:
    """The ranking of a single class: nothing to tell apart, no touch left to count."""
    n = len(found.candidates)
    return Ranking(np.zeros(0, dtype=int), np.ones(n), np.ones(n, dtype=bool), False, None)
