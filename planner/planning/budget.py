"""What a plan may do: work counted in units, with a wall-clock cap (DESIGN §4.12).

A plan is a function of the session, its strategy and its seed, never of how
busy the machine is: every stage of planning counts the work it does (outcome
cells, search nodes, recognition updates in prediction) and stops at the same
point on any machine under any load. One unit is about a microsecond of this
code on the 2-core reference machine, so a work budget reads like a time budget
on that machine (see :data:`UNIT_US`). The wall-clock cap (``budget_ms``) stays
as a safety net only: when it bites, the plan says so (`stopped_by` "time"), and
only then can the same request give another plan.

>>> b = Budget(work=5000)
>>> b.spend("search_node", 10); b.exhausted()
False
>>> b.spend("outcome_cell", 1000); b.exhausted(), b.stopped_by
(True, 'work')
"""

from __future__ import annotations

import math
import time
from collections import Counter

__all__ = ["UNIT_US", "Budget", "OutOfBudgetError"]

#: The reference cost of one item of each kind of work, in units (~microseconds on the
#: reference machine), measured on plans of the shared object sets after 1-3 touches
#: (means; single items vary by 2-3x either way): one candidate x hypothesis outcome
#: cell (candidate generation, cast, survivors), one node of the lookahead search, one
#: leaf set valued one touch deep, and one recognition update in a forecast or a
#: recognition-ranked path: a fixed part and a part per hypothesis it carries. The
#: aims of candidate generation: a (point, face) pair examined for a boundary aim,
#: a posed face put into the intersection area, a grid point x posed face of it. One
#: posed face a screened outcome is measured against (path x predicting class x
#: counted class x face, :mod:`planner.planning.screen`).
UNIT_US: dict[str, float] = {
    "outcome_cell": 13.0,
    "search_node": 200.0,
    "leaf_set": 200.0,
    "recognition_update": 8000.0,
    "recognition_hypothesis": 100.0,
    "simulated_touch": 5.0,
    "aim_pair": 0.4,
    "aim_face": 5.0,
    "aim_cell": 0.008,
    "screen_face": 0.006,
}


class OutOfBudgetError(Exception):
    """Raised inside the search when the budget is spent."""


class Budget:
    """Units of work a plan may spend (inf: unlimited), and a wall-clock cap in ms
    (None: none). `spent` counts items of each kind; `stopped_by` says what ended
    the plan early: ``"work"``, ``"time"`` or None."""

    def __init__(self, work: float | None = None, cap_ms: float | None = None) -> None:
        self.work = math.inf if work is None else float(work)
        self.end = math.inf if cap_ms is None else time.perf_counter() + cap_ms / 1000.0
        self.spent: Counter[str] = Counter()
        self.units = 0.0
        self.stopped_by: str | None = None

    @property
    def unlimited(self) -> bool:
        return math.isinf(self.work) and math.isinf(self.end)

    def spend(self, kind: str, count: float = 1.0) -> None:
        self.spent[kind] += count
        self.units += UNIT_US[kind] * count

    def raise_to(self, work: float | None) -> None:
        """Allow `work` units in all (None: unlimited); a stop by work is lifted."""
        self.work = math.inf if work is None else float(work)
        if self.stopped_by == "work" and self.units <= self.work:
            self.stopped_by = None

    def affordable(self, kind: str) -> float:
        """How many more items of `kind` the work budget allows (inf: unlimited);
        the stages that can be told their cost in advance size themselves by it."""
        return max(0.0, self.work - self.units) / UNIT_US[kind]

    def at_most(self, kind: str, wanted: int, per: float = 1.0) -> int:
        """How many of `wanted` steps, each `per` items of `kind`, the work budget
        pays for: all of them when it can (always when unlimited), else the whole
        number it can.

        >>> Budget().at_most("outcome_cell", 7), Budget(work=0).at_most("outcome_cell", 7)
        (7, 0)
        >>> Budget(work=3.5 * UNIT_US["outcome_cell"]).at_most("outcome_cell", 7)
        3
        """
        affordable = self.affordable(kind) / per
        return wanted if affordable >= wanted else int(affordable)

    def spend_updates(self, count: int, hypotheses: float) -> None:
        """`count` recognition updates of a session carrying `hypotheses` hypotheses."""
        self.spend("recognition_update", count)
        self.spend("recognition_hypothesis", count * hypotheses)

    def affords_updates(self, count: int, hypotheses: float) -> bool:
        """Whether all of `count` recognition updates of a session carrying
        `hypotheses` hypotheses would start within the work budget (each starts
        while the units spent are within it). A stage that is worth nothing unless
        it finishes asks first; when the answer is no, the budget counts as stopped
        by work, as if the stage had run out, and no work is spent on it.

        >>> b = Budget(work=20_000)
        >>> b.affords_updates(3, 10.0), b.affords_updates(4, 10.0), b.stopped_by
        (True, False, 'work')
        """
        each = UNIT_US["recognition_update"] + hypotheses * UNIT_US["recognition_hypothesis"]
        if self.units + max(count - 1, 0) * each <= self.work:
            return True
        self.stopped_by = self.stopped_by or "work"
        return False

    def steps_affordable(self, count: int, hypotheses: float) -> float:
        """How many steps of `count` recognition updates each (of a session carrying
        `hypotheses` hypotheses), taken one after another, start within the work
        budget: a step starts while the units spent are within it (inf: unlimited).

        >>> Budget(work=20_000).steps_affordable(1, 10.0), Budget().steps_affordable(2, 1.0)
        (3, inf)
        """
        each = count * (
            UNIT_US["recognition_update"] + hypotheses * UNIT_US["recognition_hypothesis"]
        )
        room = self.work - self.units
        if math.isinf(room):
            return math.inf
        return math.floor(room / each) + 1 if room >= 0 else 0

    def exhausted(self) -> bool:
        """True once the work is spent or the cap passed (and from then on)."""
        if self.stopped_by is None:
            if self.units > self.work:
                self.stopped_by = "work"
            elif time.perf_counter() > self.end:
                self.stopped_by = "time"
        return self.stopped_by is not None

    def check(self, kind: str, count: float = 1.0) -> None:
        """Spend, then raise :class:`OutOfBudgetError` if nothing is left."""
        self.spend(kind, count)
        if self.exhausted():
            raise OutOfBudgetError
