"""Everything known about the candidate paths before a strategy chooses (DESIGN §4.10-4.12).

:func:`analyse` builds the candidates (the strategy's own first, then the general
set), casts them against every posed hypothesis, turns the outcomes into class
survivor sets and scores them. World frame, lengths in the object files' unit.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from planner.models.heights import canonical_height, probing_heights
from planner.planning.bitsets import SurvivorTable
from planner.planning.budget import Budget
from planner.planning.candidate_generation import generate_candidates
from planner.planning.candidates import Candidates
from planner.planning.config import StrategyConfig
from planner.planning.confusability import class_bits
from planner.planning.feature_aims import feature_candidates
from planner.planning.outcomes import Outcomes, predict_outcomes
from planner.planning.posed_set import PosedSet, pose_hypotheses
from planner.planning.probes import strategy_paths
from planner.planning.scoring import InformationScores, information_scores, motion_cost
from planner.planning.survivors import pin_families, repeated_paths
from planner.types import Hypothesis, ObjectModel, Observation, SensingPath, SensorBounds, Workspace

__all__ = ["Analysis", "analyse", "as_generator", "models_by_name"]

#: Fewest candidates per block when a time budget splits the outcome passes, and
#: fewest candidates x hypotheses per block.
_BLOCK = 16
_BLOCK_ELEMENTS = 4096
#: Faces per hypothesis up to which an outcome cell costs the reference `outcome_cell`
#: (the shared polygon sets); beyond it the cost grows with the faces.
_REFERENCE_FACES = 12


@dataclass(frozen=True, eq=False)
class Analysis:
    """Everything known about the candidates before a strategy chooses.

    `posed` hypotheses, `candidates` (C paths), their `outcomes`, the class
    survivor `table`, the information scores `info` and `motion` cost (C,);
    `truncated` when the time budget left candidates out."""

    posed: PosedSet
    candidates: Candidates
    outcomes: Outcomes
    table: SurvivorTable
    info: InformationScores
    motion: np.ndarray
    truncated: bool = False


def as_generator(rng: np.random.Generator | int | None) -> np.random.Generator:
    """`rng` itself when it is a generator, else a generator seeded with it (None: 0)."""
    return rng if isinstance(rng, np.random.Generator) else np.random.default_rng(rng or 0)


def models_by_name(models: Mapping[str, ObjectModel] | Sequence[ObjectModel]) -> dict:
    """The object models keyed by name, whether given as a mapping or a sequence."""
    return dict(models) if isinstance(models, Mapping) else {m.name: m for m in models}


def analyse(
    hypotheses: Sequence[Hypothesis],
    models: Mapping[str, ObjectModel] | Sequence[ObjectModel],
    sensor: SensorBounds,
    workspace: Workspace,
    sensor_position: Sequence[float],
    config: StrategyConfig | None = None,
    rng: np.random.Generator | int | None = None,
    *,
    observations: Sequence[Observation] = (),
    extra_paths: Sequence[SensingPath] = (),
    budget: Budget | None = None,
) -> Analysis:
    """Candidates (the strategy's own first, then `extra_paths`, then the general
    set), their predicted outcomes, survivor sets and scores (world frame).

    With a `budget`, outcomes are worked out block by block of candidates and
    stop (`truncated`) once it passes; the first block is always done."""
    config = config or StrategyConfig()
    gen = as_generator(rng)
    by_name = models_by_name(models)
    budget = budget or Budget()
    posed = pose_hypotheses(hypotheses, by_name)
    contacts = [o.contact for o in observations if o.contact is not None]
    own = strategy_paths(
        config, hypotheses, by_name, posed, contacts, workspace, sensor, sensor_position, gen
    )
    parts = []
    for k, height in enumerate(probing_heights(by_name.values())):
        at = posed if height is None else pose_hypotheses(hypotheses, by_name, height)
        extra = [own, Candidates.from_paths(list(extra_paths))] if k == 0 else []
        parts.append(
            _at_height(
                hypotheses, at, height, extra, workspace, sensor, sensor_position, config, gen,
                observations, budget, layer_offsets(hypotheses, by_name, height), by_name,
            )
        )  # fmt: skip
    cands = Candidates.concat([p[0] for p in parts])
    found = Outcomes.concat([p[1] for p in parts])
    truncated = any(p[3] for p in parts)
    table = SurvivorTable.from_bits(np.concatenate([p[2] for p in parts]), posed.class_weight)
    motion = motion_cost(cands.origins, found.travel @ posed.weight, workspace, sensor_position)
    info = information_scores(table)
    return Analysis(posed, cands, found, table, info, motion, truncated)


def layer_offsets(
    hypotheses: Sequence[Hypothesis], models: Mapping[str, ObjectModel], height: float | None
) -> np.ndarray:
    """(H,) where the faces of the layer at `height` start among each hypothesis'
    stable pose's `all_faces` (0 at the default height)."""
    if height is None:
        return np.zeros(len(hypotheses), dtype=np.int64)
    start = {
        (name, k): p.layer_start(height)
        for name, m in models.items()
        for k, p in enumerate(m.stable_poses)
    }
    return np.array([start[h.object, h.stable_pose] for h in hypotheses], dtype=np.int64)


def _at_height(
    hypotheses: Sequence[Hypothesis],
    posed: PosedSet,
    height: float | None,
    extra: list[Candidates],
    workspace: Workspace,
    sensor: SensorBounds,
    sensor_position: Sequence[float],
    config: StrategyConfig,
    gen: np.random.Generator,
    observations: Sequence[Observation],
    budget: Budget,
    offsets: np.ndarray,
    models: Mapping[str, ObjectModel],
) -> tuple[Candidates, Outcomes, np.ndarray, bool]:
    """Candidates at one probing height (`posed`: the hypotheses' outlines there),
    their outcomes (faces numbered as in each stable pose's `all_faces`), class
    survivor bits, and whether the budget cut them short."""
    features = feature_candidates(posed, workspace, sensor, config.candidates.feature_paths)
    cands = generate_candidates(
        posed,
        workspace,
        sensor,
        config.candidates,
        gen,
        sensor_position=sensor_position,
        extra=Candidates.concat([*extra, features]),
        budget=None if budget.unlimited else budget,
    ).at_height(height)
    here = [o for o in observations if canonical_height(models.values(), o.path.height) == height]
    fresh = np.flatnonzero(~repeated_paths(cands, here, posed, sensor))
    if 0 < len(fresh) < len(cands):
        cands = cands.subset(fresh)
    outcomes: list[Outcomes] = []
    bits: list[np.ndarray] = []
    # anytime: candidates in blocks, best first (the strategy's own, extra, general);
    # when the budget runs out, the blocks done so far are the candidates
    size = max(_BLOCK, _BLOCK_ELEMENTS // len(posed))
    # a cell costs more where the hypotheses have more faces than the reference sets
    per_cell = max(1.0, posed.valid.sum() / max(len(posed), 1) / _REFERENCE_FACES)
    if budget.unlimited:
        block = len(cands)
    else:  # the first block too keeps to what the budget has left (at least one path)
        block = max(1, budget.at_most("outcome_cell", size, per_cell * len(posed)))
    lo = 0
    while lo < len(cands) or not outcomes:
        take = max(block, 1)
        if outcomes:  # past the first block, none starts that the budget cannot pay for
            if budget.exhausted():
                break
            take = budget.at_most("outcome_cell", take, per_cell * len(posed))
            if take < 1:
                break
        part = cands.subset(np.arange(lo, min(lo + take, len(cands))))
        lo += take
        out = predict_outcomes(
            posed, part.origins, part.directions, part.lengths, sensor, config.outcome
        )
        budget.spend("outcome_cell", len(part) * len(posed) * per_cell)
        bits.append(
            pin_families(
                hypotheses,
                posed,
                out,
                class_bits(posed, out, sensor, config.outcome),
                sensor,
            )
        )
        if offsets.any():
            out = dataclasses.replace(out, face=np.where(out.face >= 0, out.face + offsets, -1))
        outcomes.append(out)
    found = Outcomes.concat(outcomes)
    truncated = len(found.hit) < len(cands)
    return cands.subset(np.arange(len(found.hit))), found, np.concatenate(bits), truncated
