"""A cheap first guess at what the recognition will conclude of a path (DESIGN §4.15).

The recognition judges a candidate path with one update per predicting class, a
few milliseconds each, so a plan judges a handful of its hundreds of candidates
before its budget ends (:func:`planner.planning.forecast.recognition_ranking`).
Which handful decides the touch. The screen guesses, from the cast alone, how
many classes each predicted outcome leaves: class `j` survives class `k`'s
nominal contact when `j`'s posed outline passes within two position bounds of
it with a face whose normal lies within two normal bounds of the contact's
(a measurement within the bounds of both could then be the one made); a miss
keeps the classes that miss. Where `j` lies is its posed outline, not its own
contact on the same path: the recognition refits every pose to every contact,
so a class turned a little (a curved part's neighbour) slides to explain a
contact its nominal one lies millimetres from, while a class without the bump
the contact is on cannot. The pose bounds are left out: they allow far more
than the refit does (classes 4 mm apart with 15 mm bounds are told apart).
World frame, lengths in the object files' unit.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from planner.compiled import c_array, segment_gap
from planner.geometry import LENGTH_SLACK
from planner.planning.budget import UNIT_US, Budget
from planner.planning.outcomes import Outcomes
from planner.planning.posed_set import PosedSet
from planner.types import SensorBounds

__all__ = ["SCREEN_CLASSES", "SCREEN_FLOOR", "screened_log"]

#: Most classes a screened outcome counts (the most probable; the others are
#: taken to survive every outcome).
SCREEN_CLASSES = 32
#: Units the screen may spend when the plan's budget affords less (half of one
#: predicted update's fixed part).
SCREEN_FLOOR = 4000.0


def screened_log(
    out: Outcomes,
    rows: np.ndarray,
    posed: PosedSet,
    top: np.ndarray,
    weight: np.ndarray,
    sensor: SensorBounds,
    budget: Budget | None = None,
) -> np.ndarray:
    """(n,) the guess at each candidate of `rows`' expected log of the classes
    left: ``sum_k weight(k) log(classes left by k's outcome)`` over the
    predicting classes `top` (their `weight` summing to 1). The `budget` pays for
    each (path, predicting class, counted class' face): the classes counted are
    as many of the most probable (up to `SCREEN_CLASSES`) as it affords, or as
    `SCREEN_FLOOR` units pay for when it affords less (a plan whose budget is
    spent still judges one path, and the screen picks it, for half the cost of
    one predicted update); none when not even the first fits (all zeros: the
    order given stands)."""
    order = np.argsort(-posed.class_weight, kind="stable")[: min(SCREEN_CLASSES, posed.n_classes)]
    members = posed.best_members(order)
    cells = len(rows) * len(top) * np.cumsum(posed.valid[members].sum(axis=1))
    affordable = math.inf if budget is None else budget.affordable("screen_face")
    floor = SCREEN_FLOOR / UNIT_US["screen_face"]
    counted = int(np.searchsorted(cells, max(affordable, floor), side="right"))
    if len(rows) == 0 or counted < 1:
        return np.zeros(len(rows))
    if budget is not None:
        budget.spend("screen_face", float(cells[counted - 1]))
    members = members[:counted]
    predict = posed.best_members(top)
    reach = 2 * sensor.position_error + LENGTH_SLACK
    cos_turn = math.cos(min(2 * sensor.normal_error, math.pi))
    left = _left(
        c_array(np.nan_to_num(out.point[np.ix_(rows, predict)]), float),
        c_array(np.nan_to_num(out.normal[np.ix_(rows, predict)]), float),
        c_array(out.hit[np.ix_(rows, predict)], np.bool_),
        c_array(out.hit[np.ix_(rows, members)], np.bool_),
        c_array(posed.start[members], float),
        c_array(posed.end[members], float),
        c_array(posed.normal[members], float),
        c_array(posed.valid[members], np.bool_),
        reach,
        cos_turn,
    )
    left = left + (posed.n_classes - counted)
    return np.log(np.maximum(left, 1)) @ weight


@numba.njit(cache=True, nogil=True)
def _left(point, normal, hit_k, hit_j, start, end, face_normal, valid, reach, cos_turn):  # type: ignore[no-untyped-def]
    """(n, k) how many of the J classes (faces `start`, `end`, `face_normal`,
    `valid` (J, F)) survive each predicted outcome (`point`, `normal` (n, k, 2),
    `hit_k` (n, k)); `hit_j` (n, J) whether each class' own nominal outcome hits."""
    n, k = hit_k.shape
    n_cls, n_faces = valid.shape
    left = np.zeros((n, k), dtype=np.int64)
    reach_sq = reach * reach
    for c in range(n):
        for i in range(k):
            count = 0
            if not hit_k[c, i]:
                for j in range(n_cls):
                    count += not hit_j[c, j]
                left[c, i] = count
                continue
            px, py = point[c, i, 0], point[c, i, 1]
            nx, ny = normal[c, i, 0], normal[c, i, 1]
            for j in range(n_cls):
                for f in range(n_faces):
                    if not valid[j, f]:
                        continue
                    if nx * face_normal[j, f, 0] + ny * face_normal[j, f, 1] < cos_turn:
                        continue
                    gx, gy = segment_gap(
                        px, py, start[j, f, 0], start[j, f, 1], end[j, f, 0], end[j, f, 1]
                    )
                    if gx * gx + gy * gy <= reach_sq:
                        count += 1
                        break
            left[c, i] = count
    return left
