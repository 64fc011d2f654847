"""Scores of candidate paths (DESIGN §4.12).

Inputs are a :class:`~planner.planning.bitsets.SurvivorTable` (survivor sets over
equivalence classes, one per path and truth class, with class weights) and,
for the motion cost, the paths' origins and expected travel. Probabilities are
over equivalence classes; lengths are in the object files' unit.

The expected number of remaining touches, E(S), and the exact ``optimal``
dynamic programme live in :mod:`planner.planning.search`.

>>> import numpy as np
>>> from planner.planning.bitsets import SurvivorTable
>>> eye = np.eye(2, dtype=bool)
>>> table = SurvivorTable.from_matrix(np.stack([eye, ~eye | eye]), np.array([0.5, 0.5]))
>>> s = information_scores(table)
>>> s.p_distinguishing.tolist(), [FAMILIES[f] for f in s.family]
([1.0, 0.0], ['distinguishing', 'uninformative'])
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from planner.geometry import SHARE_SLACK, wrap_angle
from planner.planning.bitsets import SurvivorTable, pack_bits, popcount, weighted_count
from planner.types import Workspace

__all__ = [
    "FAMILIES",
    "InformationScores",
    "combined_objective",
    "family_codes",
    "information_scores",
    "motion_cost",
]

#: Path families, best first (thesis §3.1): index = family code.
FAMILIES = ("distinguishing", "informative", "partial", "uninformative")
DISTINGUISHING, INFORMATIVE, PARTIAL, UNINFORMATIVE = range(4)

#: Probabilities within this of 1 (or 0) count as 1 (or 0) for the families.
FAMILY_TOLERANCE = SHARE_SLACK


@dataclass(frozen=True, eq=False)
class InformationScores:
    """Per-path scores (C,): `p_distinguishing`, `p_informative`,
    `expected_pruning` (probability mass expected to be removed) and `family`
    (codes into :data:`FAMILIES`)."""

    p_distinguishing: np.ndarray
    p_informative: np.ndarray
    expected_pruning: np.ndarray
    family: np.ndarray

    @property
    def informative(self) -> np.ndarray:
        """(C,) bool: paths of any family but `uninformative`."""
        return self.family != UNINFORMATIVE


def family_codes(p_distinguishing: np.ndarray, p_informative: np.ndarray) -> np.ndarray:
    """Family of each path: distinguishing (P(DM) = 1, Theorem 1), informative
    (something is learned whatever happens), partial, uninformative (never choose)."""
    p_dm, p_inf = np.asarray(p_distinguishing), np.asarray(p_informative)
    return np.select(
        [p_dm >= 1 - FAMILY_TOLERANCE, p_inf >= 1 - FAMILY_TOLERANCE, p_inf > FAMILY_TOLERANCE],
        [DISTINGUISHING, INFORMATIVE, PARTIAL],
        default=UNINFORMATIVE,
    )


def information_scores(table: SurvivorTable, state: np.ndarray | None = None) -> InformationScores:
    """P(DM), P(informative), expected pruning and family of every path, in one pass
    over the survivor bitsets.

    `state` (bool over classes, default all) restricts the hypothesis set S;
    weights are conditional on S.
    """
    in_state = np.ones(table.n_classes, bool) if state is None else np.asarray(state, bool)
    state_bits = pack_bits(in_state)
    sets = table.bits[:, in_state] & state_bits
    w = table.weight[in_state]
    w = w / w.sum() if w.sum() > 0 else np.full(len(w), 1 / max(len(w), 1))
    w_all = np.zeros(table.n_classes)
    w_all[in_state] = w
    # w(S_P(h)): probability mass surviving truth h
    surviving = weighted_count(sets, w_all)
    # p_distinguishing(P) = sum_h w(h) [S_P(h) within the class of h]
    p_dm = (popcount(sets) == 1).astype(float) @ w
    # p_informative(P) = sum_h w(h) [S_P(h) != S]
    p_inf = np.any(sets != state_bits, axis=-1).astype(float) @ w
    # expected pruning = sum_h w(h) (1 - w(S_P(h)))
    pruning = (1.0 - surviving) @ w
    return InformationScores(p_dm, p_inf, np.clip(pruning, 0.0, 1.0), family_codes(p_dm, p_inf))


def motion_cost(
    origins: np.ndarray,
    travel: np.ndarray,
    workspace: Workspace,
    sensor_position: Sequence[float],
) -> np.ndarray:
    """Length the sensor moves for each path: the arc along the safe circle from
    the sensor's place (its angle about the centre) to the path origin, plus the
    expected approach `travel` along the path (length unit)."""
    centre = np.asarray(workspace.center, dtype=float)
    rel = np.asarray(sensor_position, dtype=float) - centre
    here = math.atan2(rel[1], rel[0]) if np.any(rel) else 0.0
    o = np.asarray(origins, dtype=float) - centre
    # arc = R |wrap(angle(origin) - angle(sensor))|
    arc = workspace.radius * np.abs(wrap_angle(np.arctan2(o[:, 1], o[:, 0]) - here))
    return arc + np.asarray(travel, dtype=float)


def combined_objective(
    information_cost: np.ndarray, motion: np.ndarray, motion_weight: float
) -> np.ndarray:
    """Cost to minimize: the strategy's information cost (in touches, e.g.
    expected remaining touches or 1 - P(DM)) plus `motion_weight` touches per
    unit of motion length."""
    # objective = information_cost + motion_weight * motion_cost
    return np.asarray(information_cost, dtype=float) + motion_weight * np.asarray(motion)
