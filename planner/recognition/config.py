"""Knobs of recognition: outliers, error-bound mode, likelihood, slide-family sampling
(DESIGN §4.3-4.7)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

from planner.types import PosePrior

__all__ = ["RecognitionConfig"]


@dataclass(frozen=True)
class RecognitionConfig:
    """Knobs of recognition; the defaults follow DESIGN §4. `prior`: where the object
    is known to lie (:class:`~planner.types.PosePrior`; None: anywhere in the safe
    circle). `residual_fitness` False leaves the residual fitness out of the weights
    (:mod:`planner.recognition.weights`): what a predicted observation asks of the
    recognition (which interpretations survive, their classes) does not need it."""

    max_outliers: int = 0
    outlier_probability: float = 0.05
    bound_mode: Literal["linearized", "thesis"] = "linearized"
    thesis_fraction: float = 0.10
    likelihood: Literal["bounded", "gaussian"] = "bounded"
    max_family_samples: int = 16
    require_inside_workspace: bool = True
    normal_z_error: float = 0.1
    prior: PosePrior | None = None
    residual_fitness: bool = True

    def __post_init__(self) -> None:
        if self.max_outliers < 0:
            raise ValueError("max_outliers must be >= 0")
        if self.max_family_samples < 1:
            raise ValueError("max_family_samples must be >= 1")
        if self.bound_mode not in ("linearized", "thesis"):
            raise ValueError("bound_mode must be 'linearized' or 'thesis'")
        if self.likelihood not in ("bounded", "gaussian"):
            raise ValueError("likelihood must be 'bounded' or 'gaussian'")
        if not (0 < self.thesis_fraction < 1):
            raise ValueError("thesis_fraction (the error disk) must lie in (0, 1)")
