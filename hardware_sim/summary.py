"""The Table 4.1 analog from trial results: per strategy, the share of trials needing
1, 2, ..., 10 and more than 10 touches (unlocalized trials count as "> 10"), mean and
max touches (an unlocalized trial is charged `max_touches`), success rate (localized,
right object and pose within the hypothesis' own error bound), and planning time per step.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from hardware_sim.experiments import TrialResult

__all__ = ["BINS", "StrategySummary", "format_table", "histogram", "summarize"]

#: Table 4.1 columns: 1, 2, ..., 10 touches, then more than 10.
BINS = (*(str(k) for k in range(1, 11)), ">10")


@dataclass(frozen=True)
class StrategySummary:
    """One row of the Table 4.1 analog (shares in [0, 1], times in ms)."""

    strategy: str
    trials: int
    histogram: dict[str, float]
    mean_touches: float
    max_touches: int
    success_rate: float
    mean_plan_ms: float
    p95_plan_ms: float

    def as_dict(self) -> dict[str, Any]:
        """The ``tactile simulate --json`` form of one strategy (DESIGN §7)."""
        return {
            "strategy": self.strategy,
            "trials": self.trials,
            "histogram": dict(self.histogram),
            "mean_touches": self.mean_touches,
            "max_touches": self.max_touches,
            "success_rate": self.success_rate,
            "mean_plan_ms": self.mean_plan_ms,
            "p95_plan_ms": self.p95_plan_ms,
        }


def histogram(touches: Sequence[int], localized: Sequence[bool]) -> dict[str, float]:
    """Share of trials per Table 4.1 column: "1" ... "10", ">10" (unlocalized
    trials count as ">10"); the shares sum to 1."""
    counts = dict.fromkeys(BINS, 0)
    for t, ok in zip(touches, localized, strict=True):
        counts[str(t) if ok and 1 <= t <= 10 else ">10"] += 1
    n = max(len(touches), 1)
    return {k: v / n for k, v in counts.items()}


def summarize(
    results: Sequence[TrialResult], strategies: Sequence[str], max_touches: int
) -> list[StrategySummary]:
    """One Table 4.1 row per strategy, in the given order."""
    rows = []
    for name in strategies:
        rs = [r for r in results if r.strategy == name]
        if not rs:
            continue
        # an unlocalized trial is charged the whole touch budget
        charged = np.array([r.touches if r.localized else max_touches for r in rs])
        times = np.concatenate([np.asarray(r.plan_ms, dtype=float) for r in rs] + [np.zeros(0)])
        rows.append(
            StrategySummary(
                strategy=name,
                trials=len(rs),
                histogram=histogram([r.touches for r in rs], [r.localized for r in rs]),
                mean_touches=float(charged.mean()),
                max_touches=int(charged.max()),
                success_rate=float(np.mean([r.success for r in rs])),
                mean_plan_ms=float(times.mean()) if len(times) else 0.0,
                p95_plan_ms=float(np.percentile(times, 95)) if len(times) else 0.0,
            )
        )
    return rows


def format_table(rows: Sequence[StrategySummary]) -> str:
    """The Table 4.1 layout: percent of trials per number of touches, then stats."""
    head = f"{'strategy':10s} " + " ".join(f"{b:>4s}" for b in BINS)
    head += "   mean  max  success  plan ms mean/p95"
    lines = [head]
    for r in rows:
        cells = " ".join(f"{100 * r.histogram[b]:4.0f}" for b in BINS)
        lines.append(
            f"{r.strategy:10s} {cells}  {r.mean_touches:5.2f} {r.max_touches:4d}  "
            f"{100 * r.success_rate:6.1f}%  {r.mean_plan_ms:7.1f} / {r.p95_plan_ms:.1f}"
        )
    return "\n".join(lines)
