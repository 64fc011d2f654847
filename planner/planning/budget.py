"""The time a plan may take: a deadline every stage of planning checks (DESIGN §4.12)."""

from __future__ import annotations

import time
from dataclasses import dataclass

__all__ = ["Deadline", "OutOfTimeError"]


class OutOfTimeError(Exception):
    """Raised inside the search when the deadline passes."""


@dataclass(frozen=True)
class Deadline:
    """A point in `time.perf_counter()` seconds after which search stops (inf: never)."""

    end: float = float("inf")

    @classmethod
    def after_ms(cls, budget_ms: float | None) -> Deadline:
        if budget_ms is None:
            return cls()
        return cls(time.perf_counter() + budget_ms / 1000.0)

    def expired(self) -> bool:
        return time.perf_counter() > self.end

    def check(self) -> None:
        if time.perf_counter() > self.end:
            raise OutOfTimeError
