"""Interpretation tree: face assignments of the contacts (DESIGN §4.3).

Depth = number of contacts; branches = the faces of every stable pose of every
object, plus an optional "spurious" branch (face -1) for at most `max_outliers`
contacts. A contact may also be folded (entry ``-2 - f``): rows that differ only in
which of a few neighbouring faces f, f + 1, ... of one ring it lies on become one
row that leaves it unassigned (:func:`fold_runs`). A new contact extends each
surviving partial interpretation only: constraint checks first (table lookups,
:mod:`planner.recognition.constraints`), then the model check on the fitted pose
(:mod:`planner.recognition.evaluate`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import shapely

from planner.arrays import row_labels
from planner.memo import SharedCache, array_key, cached_property
from planner.recognition.config import RecognitionConfig
from planner.recognition.constraints import (
    ConstraintTables,
    extend_feasibility,
    pair_columns,
    shared_tables,
    unary_feasibility,
)
from planner.recognition.crossing import ring_edges, segments_meet
from planner.types import Contact, ObjectModel, SensorBounds, StablePose

__all__ = [
    "FOLD_ROWS",
    "Group",
    "TreeLevel",
    "extend",
    "extend_many",
    "face_of",
    "fold_runs",
    "make_groups",
]


@dataclass(frozen=True, eq=False)
class Group:
    """One stable pose of one object: a subtree of the interpretation tree."""

    object_index: int
    model: ObjectModel
    pose_index: int
    prior: float

    @property
    def stable(self) -> StablePose:
        return self.model.stable_poses[self.pose_index]

    @cached_property
    def tables(self) -> ConstraintTables:
        """The tables of every layer's faces together: contacts at different
        heights constrain each other as faces of one rigid pose do."""
        return shared_tables(self.stable.all_faces)

    def crossed(self, segments: np.ndarray, tol: float, layer: int = 0) -> np.ndarray:
        """Which `segments` ((N, 4) rows ``x0, y0, x1, y1``, model frame) meet the
        outline of `layer` shrunk by `tol` (a tolerance bucket): cross it, touch it
        or lie inside. The shrunk outlines' edges are kept for the process
        (:data:`SHRUNK_EDGES`): sessions on the same parts shrink each once."""
        key = (self._layer_keys[layer], tol)
        edges = _shrunk.get(key, lambda: _shrunk_edges(self.stable.layers[layer].shape, tol))
        return segments_meet(segments, edges)

    @cached_property
    def _layer_keys(self) -> list[bytes]:
        """Each layer's outline and holes as a key (its numbers' digest)."""
        return [array_key((layer.outline, *layer.holes)) for layer in self.stable.layers]

    def __getstate__(self) -> dict:
        """Pickled without what it derives from its stable pose (the constraint tables
        are nine tenths of a curved part's session snapshot; a restored group finds
        them again, shared between sessions)."""
        state = dict(self.__dict__)
        state.pop("tables", None)
        state.pop("_layer_keys", None)
        return state


#: Edges of shrunk outlines the process keeps (a few megabytes; a part shrunk at
#: every tolerance step holds tens of thousands).
SHRUNK_EDGES = 250_000


def _shrunk_edges(shape: shapely.Geometry, tol: float) -> np.ndarray:
    """The ring edges of `shape` shrunk by `tol` (mitred corners)."""
    return ring_edges(shape.buffer(-tol, join_style="mitre") if tol > 0 else shape)


_shrunk: SharedCache[np.ndarray] = SharedCache(SHRUNK_EDGES, len)


def make_groups(models: list[ObjectModel]) -> list[Group]:
    """One group per stable pose; prior = P(object) x P(stable pose | object)."""
    weights = np.array([m.prior if m.prior is not None else 1.0 for m in models])
    weights = weights / weights.sum()
    groups = []
    for i, model in enumerate(models):
        pose_total = sum(p.probability for p in model.stable_poses)
        for j, pose in enumerate(model.stable_poses):
            groups.append(Group(i, model, j, float(weights[i] * pose.probability / pose_total)))
    return groups


@dataclass(frozen=True, eq=False)
class TreeLevel:
    """Surviving partial interpretations per group: rows (K, depth) of face indices (-1 =
    spurious)."""

    rows: tuple[np.ndarray, ...]


def extend(
    level: TreeLevel,
    groups: list[Group],
    contacts: list[Contact],
    bounds: SensorBounds,
    config: RecognitionConfig,
    height: float | None = None,
) -> TreeLevel:
    """Extend every surviving row by the newest contact, made at probing `height`
    (constraint checks only): it may lie only on faces of the layer at that height."""
    *before, new = contacts
    return extend_many(level, groups, before, [new], bounds, config, [height])[0]


def extend_many(
    level: TreeLevel,
    groups: list[Group],
    before: list[Contact],
    news: list[Contact],
    bounds: SensorBounds,
    config: RecognitionConfig,
    heights: list[float | None],
) -> list[TreeLevel]:
    """:func:`extend` of `level` by each of several newest contacts (`news`, made
    at `heights`) after the same contacts `before` (a plan's predictions): the
    rows each extension gives alone. Per group, the checks of every row against
    each new contact's faces (the pair numbers the same for every stable pose:
    :func:`~planner.recognition.constraints.pair_columns`), then a spurious
    branch for the rows that may call one more contact spurious."""
    columns = [pair_columns([*before, new]) for new in news]
    out: list[list[np.ndarray]] = [[] for _ in news]
    for group, rows in zip(groups, level.rows, strict=True):
        unary: dict[tuple, np.ndarray] = {}
        ok = np.empty((len(news), len(rows), len(group.stable.all_faces.start)), dtype=bool)
        for b, (new, height) in enumerate(zip(news, heights, strict=True)):
            key = (height, new.normal_z)
            if key not in unary:
                unary[key] = unary_feasibility(group.stable, new, config.normal_z_error, height)
            ok[b] = extend_feasibility(
                group.tables, rows, [*before, new], unary[key], bounds.position_error,
                bounds.normal_error, columns[b],
            )  # fmt: skip
        which, parent, face = np.nonzero(ok)
        grown = np.column_stack([rows[parent], face])
        outliers = (rows == -1).sum(axis=1)
        spare = np.flatnonzero(outliers < config.max_outliers)
        spurious = [np.column_stack([rows[spare], np.full(spare.size, -1)])] if spare.size else []
        ends = np.searchsorted(which, np.arange(len(news) + 1))
        for b in range(len(news)):
            mine = grown[ends[b] : ends[b + 1]]
            out[b].append(np.concatenate([mine, *spurious]).astype(np.int64))
    return [TreeLevel(rows=tuple(x)) for x in out]


#: Rows of one group past which the rows that differ only in the neighbouring face of
#: one contact are folded into one (DESIGN §4.3): every contact near the end of a
#: chord of a finely drawn curve fits two chords, and without folding the rows of a
#: curved part double with such contacts (an ellipse touched 37 times held 19,068).
#: Folding past fewer rows keeps a long session's late updates near its first ones
#: (README, update time against earlier observations).
FOLD_ROWS = 32
#: Contacts a row keeps assigned besides the one folded: they pin its pose (three
#: contacts with their normals fix a planar pose; one more keeps it fixed when one of
#: them lies near a face's end).
FOLD_PINNED = 4
#: Most faces (first to last, one ring) the rows folded at one contact may name.
FOLD_SPAN = 3


def face_of(entry: int) -> int | None:
    """The face a row's entry names: the face itself, the first face of a folded
    contact, None for a spurious one."""
    if entry >= 0:
        return entry
    return None if entry == -1 else -2 - entry


def fold_runs(rows: np.ndarray, ring: np.ndarray, limit: int = FOLD_ROWS) -> np.ndarray:
    """`rows` (K, s) of one group with contacts folded, once they are more than `limit`.

    Rows equal but for one contact, which they put on faces of one ring no more than
    `FOLD_SPAN` apart (or a fold of them), become one row leaving that contact
    unassigned (entry ``-2 - f``, f the first of those faces), when the row keeps
    `FOLD_PINNED` other contacts assigned. Sound: a row without a contact's
    constraint admits every pose the rows it replaces admit, so the true pose
    survives in it whenever it would in one of them; it is checked against the
    other contacts and the free space as any row. The fold costs that contact's
    part in the bound while the others pin the pose.

    >>> pin = list(range(0, 2 * FOLD_PINNED, 2))  # contacts on faces 0, 2, 4, ...
    >>> rows = np.array([[*pin, 30], [*pin, 31], [*pin, 35]])
    >>> [row[-1] for row in fold_runs(rows, np.zeros(40, int), limit=2).tolist()]
    [-32, 35]
    """
    if len(rows) <= limit or rows.shape[1] <= FOLD_PINNED:
        return rows
    for c in range(rows.shape[1]):
        col = rows[:, c]
        face = np.where(col >= 0, col, -2 - col)
        others = (rows >= 0).sum(axis=1) - (col >= 0)
        idx = np.flatnonzero((col != -1) & (others >= FOLD_PINNED))
        if len(idx) < 2:
            continue
        # the rows alike but for this contact, by the face they name: a run of faces
        # each next to the one before (one ring) is one fold
        group = row_labels(np.delete(rows[idx], c, axis=1))
        f = face[idx]
        order = np.lexsort((f, group))
        idx, g, f = idx[order], group[order], f[order]
        start = np.r_[
            True, (g[1:] != g[:-1]) | (f[1:] - f[:-1] > 1) | (ring[f[1:]] != ring[f[:-1]])
        ]
        run = np.cumsum(start) - 1
        last = np.r_[np.flatnonzero(start)[1:], len(f)] - 1  # each run's last row
        width = f[last] - f[start]  # per run: its last face less its first
        fold = (np.bincount(run)[run] > 1) & (width[run] < FOLD_SPAN)
        if not fold.any():
            continue
        rows = rows.copy()
        lead = idx[fold & start]
        rows[lead, c] = -2 - f[fold & start]
        keep = np.ones(len(rows), dtype=bool)
        keep[idx[fold & ~start]] = False
        rows = rows[keep]
    return rows
