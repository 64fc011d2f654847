"""Event-sourced recognition session: observations -> state -> plan.

The ordered observations (with the object set, sensor bounds, safe circle and
configuration) are the source of truth; the weighted hypothesis set is derived
from them and cached. :meth:`Session.observe` returns a new session that extends
the interpretation tree of its parent incrementally; :meth:`Session.undo` drops
the last observation.

>>> from planner.models.library import object_from_dict
>>> from planner.types import Contact, Observation, SensingPath
>>> square = object_from_dict({"name": "sq", "outline": [[-1, -1], [1, -1], [1, 1], [-1, 1]]})
>>> s = Session([square], workspace=Workspace((0, 0), 10))
>>> s.status
'awaiting_contact'
>>> s = s.observe(Observation(SensingPath((0, -10), (0, 1), 20), Contact((0, -1), (0, -1))))
>>> s = s.observe(Observation(SensingPath((10, 0), (-1, 0), 20), Contact((1, 0), (1, 0))))
>>> s.status, len(s.hypotheses), len({h.equivalence_class for h in s.hypotheses})
('localized', 4, 1)
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import Literal

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

from planner.errors import InvalidObservationError
from planner.geometry import LENGTH_SLACK, rotation_matrices
from planner.memo import cached_property
from planner.recognition.config import RecognitionConfig
from planner.recognition.evaluate import PoseSamples, evaluate
from planner.recognition.tree import Group, TreeLevel, extend, make_groups
from planner.types import (
    ErrorBound,
    Hypothesis,
    InterpretationId,
    ObjectModel,
    Observation,
    Pose,
    SensorBounds,
    Workspace,
)

__all__ = ["Session", "Status"]

Status = Literal["awaiting_contact", "ambiguous", "localized", "inconsistent"]


@dataclass(frozen=True, eq=False)
class _Derived:
    level: TreeLevel
    candidates: tuple[PoseSamples, ...]


class Session:
    """A recognition in progress. Immutable: `observe` and `undo` return new sessions."""

    def __init__(
        self,
        models: Sequence[ObjectModel],
        sensor: SensorBounds | None = None,
        workspace: Workspace | None = None,
        config: RecognitionConfig | None = None,
        observations: Iterable[Observation] = (),
        *,
        _parent: Session | None = None,
    ) -> None:
        if not models:
            raise InvalidObservationError("a session needs at least one object", field="objects")
        names = [m.name for m in models]
        if len(set(names)) != len(names):
            raise InvalidObservationError("object names must be unique", field="objects")
        self.models: tuple[ObjectModel, ...] = tuple(models)
        self.sensor = sensor or SensorBounds()
        self.workspace = workspace or Workspace()
        self.config = config or RecognitionConfig()
        self.observations: tuple[Observation, ...] = tuple(observations)
        self._parent = _parent
        self._groups: list[Group] = (
            _parent._groups if _parent is not None else make_groups(list(self.models))
        )
        self.length_scale = max(g.stable.centroid_radius for g in self._groups)

    # -- events -----------------------------------------------------------------
    def observe(self, observation: Observation) -> Session:
        """The session after one more observation (the tree is extended, not rebuilt)."""
        return Session(
            self.models,
            self.sensor,
            self.workspace,
            self.config,
            (*self.observations, observation),
            _parent=self,
        )

    def undo(self) -> Session:
        """The session without its last observation."""
        if not self.observations:
            raise InvalidObservationError("there is no observation to undo", field="observations")
        if self._parent is not None:
            return self._parent
        return Session(
            self.models, self.sensor, self.workspace, self.config, self.observations[:-1]
        )

    @property
    def models_by_name(self) -> dict[str, ObjectModel]:
        return {m.name: m for m in self.models}

    @property
    def contacts(self) -> list:
        return [o.contact for o in self.observations if o.contact is not None]

    # -- derived state ------------------------------------------------------------
    @cached_property
    def _derived(self) -> _Derived:
        parent_level: TreeLevel | None
        if self._parent is not None:
            parent_level = self._parent._derived.level
        else:
            prefix = Session(self.models, self.sensor, self.workspace, self.config)
            for obs in self.observations[:-1]:
                prefix = prefix.observe(obs)
            parent_level = prefix._derived.level if self.observations else None
        if parent_level is None:  # no observation at all
            empty = tuple(np.zeros((1, 0), np.int64) for _ in self._groups)
            return _Derived(TreeLevel(rows=empty), ())
        level = parent_level
        last = self.observations[-1]
        contacts = self.contacts
        if last.contact is not None:
            level = extend(level, self._groups, contacts, self.sensor, self.config)
        candidates = []
        rows_kept = []
        for g, (group, rows) in enumerate(zip(self._groups, level.rows, strict=True)):
            cand = evaluate(
                g,
                group,
                rows,
                list(self.observations),
                self.sensor,
                self.workspace,
                self.config,
                self.length_scale,
            )
            latent = (
                np.flatnonzero(~(rows >= 0).any(axis=1)) if rows.shape[1] else np.arange(len(rows))
            )
            keep = np.union1d(np.unique(cand.row), latent)
            remap = np.full(len(rows), -1)
            remap[keep] = np.arange(len(keep))
            rows_kept.append(rows[keep])
            candidates.append(_reindex(cand, remap[cand.row]))
        return _Derived(TreeLevel(tuple(rows_kept), level.pair_cache), tuple(candidates))

    @cached_property
    def hypotheses(self) -> list[Hypothesis]:
        """Weighted hypotheses, most probable first, with equivalence classes."""
        cands = [c for c in self._derived.candidates if len(c.weight)]
        if not cands:
            return []
        weight = np.concatenate([c.weight for c in cands])
        total = weight.sum()
        prob = weight / total if total > 0 else np.full(len(weight), 1 / len(weight))
        classes = self._equivalence(cands)
        class_prob = np.bincount(classes, weights=prob)
        rank = np.empty(len(class_prob), np.int64)
        rank[np.argsort(-class_prob, kind="stable")] = np.arange(len(class_prob))
        out = []
        i = 0
        level = self._derived.level
        for c in cands:
            group = self._groups[c.group]
            rows = level.rows[c.group]
            for k in range(len(c.weight)):
                out.append(
                    Hypothesis(
                        object=group.model.name,
                        stable_pose=group.pose_index,
                        assignment=tuple(int(f) if f >= 0 else None for f in rows[c.row[k]]),
                        pose=Pose(float(c.t[k, 0]), float(c.t[k, 1]), float(c.theta[k])),
                        error_bound=ErrorBound(
                            float(c.d_translation[k]), float(c.d_theta[k]), float(c.eps_t[k])
                        ),
                        probability=float(prob[i]),
                        equivalence_class=int(rank[classes[i]]),
                        interpretation=InterpretationId(c.group, int(c.row[k])),
                    )
                )
                i += 1
        out.sort(key=lambda h: (-h.probability, h.equivalence_class))
        return out

    def _equivalence(self, cands: list[PoseSamples]) -> np.ndarray:
        """Class label per hypothesis: posed outlines that coincide within tolerance.

        Two hypotheses are equivalent when their posed vertex sets are within
        ``max(core eps_t)/2`` of each other (Hausdorff), core eps_t leaving out a
        family sample's cell: samples along one slide family are never merged.
        """
        verts, centroid, tol, group, row, nvert = [], [], [], [], [], []
        for c in cands:
            stable = self._groups[c.group].stable
            R = rotation_matrices(c.theta)
            posed = np.einsum("nij,vj->nvi", R, stable.outline) + c.t[:, None, :]
            verts.extend(posed)
            centroid.append(posed.mean(axis=1))
            tol.append((c.eps_t - c.cell) / 2)
            group.append(np.full(len(c.row), c.group))
            row.append(c.row)
            nvert.extend([len(stable.outline)] * len(c.weight))
        centroid_a = np.concatenate(centroid)
        tol_a = np.concatenate(tol) + 10 * LENGTH_SLACK * self.length_scale
        group_a, row_a = np.concatenate(group), np.concatenate(row)
        nvert_a = np.asarray(nvert)
        n = len(centroid_a)
        pairs = cKDTree(centroid_a).query_pairs(
            r=float(tol_a.max()) * 1.0001, output_type="ndarray"
        )
        if len(pairs):
            i, j = pairs[:, 0], pairs[:, 1]
            same = (group_a[i] == group_a[j]) & (row_a[i] == row_a[j])
            ok = (nvert_a[i] == nvert_a[j]) & ~same
            i, j = i[ok], j[ok]
            keep = np.zeros(len(i), dtype=bool)
            for v in np.unique(nvert_a[i]):
                sel = np.flatnonzero(nvert_a[i] == v)
                a = np.stack([verts[k] for k in i[sel]])
                b = np.stack([verts[k] for k in j[sel]])
                d = np.linalg.norm(a[:, :, None, :] - b[:, None, :, :], axis=-1)
                haus = np.maximum(d.min(axis=2).max(axis=1), d.min(axis=1).max(axis=1))
                keep[sel] = haus <= np.maximum(tol_a[i[sel]], tol_a[j[sel]])
            i, j = i[keep], j[keep]
        else:
            i = j = np.zeros(0, np.int64)
        graph = coo_matrix((np.ones(len(i)), (i, j)), shape=(n, n))
        return connected_components(graph, directed=False)[1]

    @property
    def status(self) -> Status:
        if not self.contacts:
            return "awaiting_contact"
        classes = {h.equivalence_class for h in self.hypotheses}
        if not classes:
            return "inconsistent"
        return "localized" if len(classes) == 1 else "ambiguous"

    def posed_outline(self, hypothesis: Hypothesis) -> np.ndarray:
        """World coordinates of a hypothesis' outline."""
        stable = self.models_by_name[hypothesis.object].stable_poses[hypothesis.stable_pose]
        return hypothesis.pose.apply(stable.outline)


def _reindex(c: PoseSamples, rows: np.ndarray) -> PoseSamples:
    return PoseSamples(
        c.group, rows, c.theta, c.t, c.d_translation, c.d_theta, c.eps_t, c.cell, c.weight
    )
