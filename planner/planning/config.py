"""How to plan: the strategy and its settings, as a session's JSON gives them (DESIGN §4.12, §6)."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field, fields
from typing import Any

from planner.errors import PlannerError
from planner.planning.candidate_generation import CandidateConfig
from planner.planning.outcomes import OutcomeConfig

__all__ = ["DEFAULT_WORK", "STRATEGIES", "THESIS_CHOICES", "StrategyConfig"]

STRATEGIES = (
    "random",
    "thesis",
    "pdm",
    "pruning",
    "lookahead",
    "optimal",
    # the published peers, on the same candidates and outcome model (planner.planning.peers)
    "ec2",
    "infogain",
    "pomcp",
)
THESIS_CHOICES = ("choose", "random")
#: The default work budget: about 400 ms of planning on the reference machine (its
#: wall-clock cap, `budget_ms`, defaults to well above that: a safety net only).
DEFAULT_WORK = 400_000.0


@dataclass(frozen=True)
class StrategyConfig:
    """How to plan: strategy `name`, lookahead `depth` (touches), `budget_work`
    (units of work, :mod:`planner.planning.budget`; None: unlimited; it covers the
    whole plan: outcomes, search, forecast, and makes the plan the same on any
    machine under any load), `budget_ms` (a wall-clock cap on the same, a safety
    net only; None: none),
    `optimal_max_classes` (the most classes ``optimal`` solves exactly, and the
    most for which strategies that do not search still score their paths `depth`
    touches deep), `max_paths` in the ranked list,
    `motion_weight` (touches per unit of motion length in the combined
    objective; 0 = motion only breaks ties), `random_draws` (origins drawn at
    once by ``random``), `grid_size` (B of the thesis' B x B grid),
    `thesis_choice` (how ``thesis`` picks among the windows of the lowest admitted
    strength: ``choose``, the nearest origin, as the thesis' hardware did (ch. 5),
    or ``random``, as its simulations did (§4.3.6)), and the candidate and outcome
    settings. `forecast` is how many of the ranked paths a session-aware caller
    has the recognition forecast (:mod:`planner.planning.forecast`; 0: none).
    `simulations` is the ``pomcp`` strategy's budget (Monte-Carlo simulations per
    plan; the work budget may stop it sooner)."""

    name: str = "lookahead"
    depth: int = 2
    budget_ms: float | None = 1500.0
    budget_work: float | None = DEFAULT_WORK
    optimal_max_classes: int = 12
    max_paths: int = 5
    motion_weight: float = 0.0
    random_draws: int = 16
    grid_size: int = 70
    thesis_choice: str = "choose"
    forecast: int = 1
    simulations: int = 1000
    candidates: CandidateConfig = field(default_factory=CandidateConfig)
    outcome: OutcomeConfig = field(default_factory=OutcomeConfig)

    def __post_init__(self) -> None:
        if self.name not in STRATEGIES:
            raise PlannerError(
                f"unknown strategy; one of {list(STRATEGIES)}", field="strategy.name"
            )
        for name in ("depth", "max_paths", "random_draws", "grid_size", "simulations"):
            if getattr(self, name) < 1:
                raise PlannerError("must be >= 1", field=f"strategy.{name}")
        if self.thesis_choice not in THESIS_CHOICES:
            raise PlannerError(
                f"must be one of {list(THESIS_CHOICES)}", field="strategy.thesis_choice"
            )
        if self.forecast < 0:
            raise PlannerError("must be >= 0", field="strategy.forecast")
        if self.optimal_max_classes < 1:
            raise PlannerError("must be >= 1", field="strategy.optimal_max_classes")
        if self.budget_ms is not None and not (
            self.budget_ms > 0 and math.isfinite(self.budget_ms)
        ):
            raise PlannerError("must be a finite number > 0", field="strategy.budget_ms")
        if self.budget_work is not None and not (
            self.budget_work > 0 and math.isfinite(self.budget_work)
        ):
            raise PlannerError("must be a finite number > 0", field="strategy.budget_work")
        if not (math.isfinite(self.motion_weight) and self.motion_weight >= 0):
            raise PlannerError("must be a finite number >= 0", field="strategy.motion_weight")

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> StrategyConfig:
        """From the session's JSON, e.g. ``{"name": "lookahead", "depth": 2, "budget_ms": 500}``."""
        known = {f.name for f in fields(cls)}
        unknown = set(data) - known
        if unknown:
            raise PlannerError(f"unknown keys {sorted(unknown)}", field="strategy")
        values = dict(data)
        try:
            if isinstance(values.get("candidates"), Mapping):
                values["candidates"] = CandidateConfig(**values["candidates"])
            if isinstance(values.get("outcome"), Mapping):
                values["outcome"] = OutcomeConfig(**values["outcome"])
            return cls(**values)
        except TypeError as exc:  # unknown nested keys, or a value of the wrong type
            raise PlannerError(f"invalid strategy settings: {exc}", field="strategy") from exc
