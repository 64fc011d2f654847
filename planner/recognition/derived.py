"""A session's derived state: the rows of the interpretation tree its checks kept,
their posed samples, and the rows the next observation extends.

:func:`derived_state` turns one evaluation (:func:`~planner.recognition.evaluate.
evaluate_groups`) into it; :func:`derive_together` evaluates the predictions of
one session in a single pass (a plan asks the recognition what each of a handful
of touches would leave, each a few rows: the fixed cost of an evaluation, not its
rows, was most of each one) and gives each prediction the state it would have
derived alone.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from planner.arrays import row_labels
from planner.recognition.config import RecognitionConfig
from planner.recognition.evaluate import PoseSamples, Variants, evaluate_groups
from planner.recognition.tree import Group, TreeLevel, extend_many, fold_runs
from planner.types import Observation, SensorBounds, Workspace

__all__ = [
    "Derived",
    "derive_together",
    "derived_state",
    "empty_state",
    "interpretation_labels",
]


@dataclass(frozen=True, eq=False)
class Derived:
    """The checked rows of the tree (`level`), their posed samples, and the rows the
    next observation extends (`ahead`: the level with its contacts folded where the
    rows of a group multiply, :func:`~planner.recognition.tree.fold_runs`)."""

    level: TreeLevel
    candidates: tuple[PoseSamples, ...]
    ahead: TreeLevel


def empty_state(groups: Sequence[Group]) -> Derived:
    """The state before any observation: one empty row per group."""
    empty = TreeLevel(rows=tuple(np.zeros((1, 0), np.int64) for _ in groups))
    return Derived(empty, (), empty)


def derived_state(
    groups: Sequence[Group], level: TreeLevel, found: Sequence[PoseSamples]
) -> Derived:
    """The state the evaluation `found` of the rows of `level` leaves: the rows with
    a sample (and those that assign no contact yet), the samples renumbered onto
    them, and those rows folded for the next observation."""
    candidates = []
    rows_kept = []
    for rows, cand in zip(level.rows, found, strict=True):
        kept = ~(rows >= 0).any(axis=1)  # rows that assign no contact yet stay
        kept[cand.row] = True
        keep = np.flatnonzero(kept)
        remap = np.full(len(rows), -1)
        remap[keep] = np.arange(len(keep))
        rows_kept.append(rows[keep])
        candidates.append(renumbered(cand, remap[cand.row]))
    ahead = [fold_runs(r, g.stable.all_faces.ring) for r, g in zip(rows_kept, groups, strict=True)]
    return Derived(TreeLevel(tuple(rows_kept)), tuple(candidates), TreeLevel(tuple(ahead)))


def derive_together(
    groups: Sequence[Group],
    ahead: TreeLevel,
    observations: list[Observation],
    last: Sequence[Observation],
    bounds: SensorBounds,
    workspace: Workspace,
    config: RecognitionConfig,
    length_scale: float,
) -> tuple[list[TreeLevel], list[Derived]]:
    """The grown tree and the state of each of several predictions, in one
    evaluation: prediction b observes `observations` and then its contact
    `last[b]`, extending the rows `ahead` of the session they follow
    (:func:`~planner.recognition.tree.extend_many`). Every row is evaluated
    against its own prediction's observations
    (:class:`~planner.recognition.evaluate.Variants`), so each state is the one the
    prediction derives alone, bit for bit. `config` leaves the residual fitness
    out (as a prediction does)."""
    before = [o.contact for o in observations if o.contact is not None]
    news = [o.contact for o in last]
    heights = [o.path.height for o in last]
    levels = extend_many(ahead, list(groups), before, news, bounds, config, heights)
    counts = np.array([[len(r) if r.size else 0 for r in lv.rows] for lv in levels])  # (B, G)
    rows = [
        np.concatenate([lv.rows[g] for lv, n in zip(levels, counts[:, g], strict=True) if n])
        if counts[:, g].any()
        else levels[0].rows[g][:0]
        for g in range(len(groups))
    ]
    of_rows = [np.repeat(np.arange(len(levels)), counts[:, g]) for g in range(len(groups))]
    found = evaluate_groups(
        groups, rows, observations, bounds, workspace, config, length_scale,
        variants=Variants(last, of_rows),
    )  # fmt: skip
    starts = np.cumsum(counts, axis=0) - counts  # each prediction's first row per group
    out = []
    for b, level in enumerate(levels):
        mine = []
        for g, cand in enumerate(found):
            lo, hi = starts[b, g], starts[b, g] + counts[b, g]
            sel = np.flatnonzero((cand.row >= lo) & (cand.row < hi))
            mine.append(_selected(cand, sel, lo))
        out.append(derived_state(groups, level, mine))
    return levels, out


def renumbered(c: PoseSamples, rows: np.ndarray) -> PoseSamples:
    """The samples `c` with their rows numbered `rows`."""
    return PoseSamples(
        c.group, rows, c.theta, c.t, c.d_translation, c.d_theta, c.eps_t, c.cell, c.weight
    )


def _selected(c: PoseSamples, sel: np.ndarray, first: int) -> PoseSamples:
    """The samples `sel` of `c`, their rows counted from row `first`."""
    return PoseSamples(
        c.group, c.row[sel] - first, c.theta[sel], c.t[sel], c.d_translation[sel],
        c.d_theta[sel], c.eps_t[sel], c.cell[sel], c.weight[sel],
    )  # fmt: skip


def interpretation_labels(cands: Sequence[PoseSamples]) -> np.ndarray:
    """One label per hypothesis naming the interpretation (group, row) it was posed
    from: the samples of one slide family share it."""
    pairs = np.concatenate([np.column_stack([np.full(len(c.row), c.group), c.row]) for c in cands])
    return row_labels(pairs)
