"""Hypotheses moved into the world frame as padded face arrays (DESIGN §2 "posed outline").

A hypothesis' posed outline is ``pose.apply(stable_pose.outline)`` (holes
likewise); here every hypothesis' faces are stacked into (H, F) arrays, padded
to the largest face count, so that ray casting and point tests run over all
hypotheses in one numpy pass. World frame, lengths in the object files' unit.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from planner.errors import PlannerError
from planner.geometry import rotate, rotation_matrices
from planner.types import Hypothesis, ObjectModel

__all__ = ["CHUNK_ELEMENTS", "PosedSet", "contains_points", "pose_hypotheses"]

#: The most point x hypothesis x face cells one pass over posed outlines holds at once.
CHUNK_ELEMENTS = 1_000_000


@dataclass(frozen=True, eq=False)
class PosedSet:
    """Posed faces of H hypotheses padded to F faces, in the world frame.

    `start`, `end`, `normal` are (H, F, 2); `length`, `prev`, `next`, `valid` are
    (H, F) (`prev[h, f]` is the face sharing f's start vertex, `next[h, f]` the one
    sharing its end vertex); `eps_t`, `rotation` (error bounds), `weight`
    (normalized probability) and `cls` (equivalence class index 0..K-1) are (H,);
    `class_weight` is (K,) and `class_ids` holds the callers' class labels.
    `rings[h]` is the posed outline and holes of hypothesis h. `touched` (H, s, 2)
    is the posed normal of the face each hypothesis assigns each contact to (of any
    probing height's layer; NaN for a spurious contact).
    """

    start: np.ndarray
    end: np.ndarray
    normal: np.ndarray
    length: np.ndarray
    prev: np.ndarray
    next: np.ndarray
    valid: np.ndarray
    eps_t: np.ndarray
    rotation: np.ndarray
    weight: np.ndarray
    cls: np.ndarray
    class_ids: np.ndarray
    class_weight: np.ndarray
    rings: tuple[tuple[np.ndarray, tuple[np.ndarray, ...]], ...]
    touched: np.ndarray

    def __len__(self) -> int:
        return len(self.weight)

    @property
    def n_classes(self) -> int:
        return len(self.class_weight)

    def best_members(self, classes: np.ndarray) -> np.ndarray:
        """The most probable hypothesis of each of `classes` (ties: the first), in
        one pass: hypotheses ordered by class, then weight, then index.

        >>> import types
        >>> p = types.SimpleNamespace(cls=np.array([1, 0, 1, 0]), weight=np.array([.1, .2, .3, .2]))
        >>> PosedSet.best_members(p, np.array([1, 0])).tolist()
        [2, 1]
        """
        order = np.lexsort((np.arange(len(self.cls)), -self.weight, self.cls))
        return order[np.searchsorted(self.cls[order], classes)]

    @cached_property
    def scale(self) -> float:
        """A length of the order of the scene (for relative numerical floors; computed
        once: a round part with holes holds a million posed faces)."""
        return float(max(1.0, np.abs(self.start[self.valid]).max(initial=0.0)))


def pose_hypotheses(
    hypotheses: Sequence[Hypothesis],
    models: Mapping[str, ObjectModel],
    height: float | None = None,
) -> PosedSet:
    """Move every hypothesis' outline at probing `height` (None: the default
    height) into the world frame, as padded face arrays.

    Probabilities are normalized to sum to 1; equivalence classes are renumbered
    0..K-1 in increasing order of their labels.
    """
    if not hypotheses:
        raise PlannerError("needs at least one hypothesis", field="hypotheses")
    keys: dict[tuple[str, int], int] = {}
    model_of = np.empty(len(hypotheses), dtype=int)
    for i, h in enumerate(hypotheses):
        if h.object not in models:
            raise PlannerError(f"unknown object {h.object!r}", field=f"hypotheses[{i}].object")
        if not 0 <= h.stable_pose < len(models[h.object].stable_poses):
            raise PlannerError("no such stable pose", field=f"hypotheses[{i}].stable_pose")
        model_of[i] = keys.setdefault((h.object, h.stable_pose), len(keys))
    whole = [models[name].stable_poses[sp] for name, sp in keys]
    poses = [p.layer(height) for p in whole]
    n_faces = max(len(p.faces) for p in poses)
    shape = (len(poses), n_faces)
    m_start, m_end, m_normal = (np.zeros((*shape, 2)) for _ in range(3))
    m_length = np.ones(shape)
    m_prev, m_next = (np.tile(np.arange(n_faces), (len(poses), 1)) for _ in range(2))
    m_valid = np.zeros(shape, dtype=bool)
    for m, pose in enumerate(poses):
        faces = pose.faces
        f = len(faces)
        m_start[m, :f], m_end[m, :f], m_normal[m, :f] = faces.start, faces.end, faces.normal
        m_length[m, :f], m_valid[m, :f] = faces.length, True
        for ring in np.unique(faces.ring):
            idx = np.flatnonzero(faces.ring == ring)
            m_next[m, idx], m_prev[m, idx] = np.roll(idx, -1), np.roll(idx, 1)
    theta = np.array([h.pose.theta for h in hypotheses])
    shift = np.array([[h.pose.x, h.pose.y] for h in hypotheses])
    rot = rotation_matrices(theta)
    # v_world = R(theta) v_model + t
    start = rotate(rot, m_start[model_of]) + shift[:, None, :]
    end = rotate(rot, m_end[model_of]) + shift[:, None, :]
    normal = rotate(rot, m_normal[model_of])
    weight = np.array([max(h.probability, 0.0) for h in hypotheses], dtype=float)
    total = weight.sum()
    if not math.isfinite(total) or total <= 0:
        raise PlannerError("probabilities must sum to a positive number", field="hypotheses")
    weight = weight / total
    class_ids, cls = np.unique([h.equivalence_class for h in hypotheses], return_inverse=True)
    return PosedSet(
        start=start,
        end=end,
        normal=normal,
        length=m_length[model_of],
        prev=m_prev[model_of],
        next=m_next[model_of],
        valid=m_valid[model_of],
        eps_t=_bounded([h.error_bound.eps_t for h in hypotheses], 1e3 * _extent(start)),
        rotation=_bounded([h.error_bound.rotation for h in hypotheses], math.pi),
        weight=weight,
        cls=cls,
        class_ids=class_ids,
        class_weight=np.bincount(cls, weights=weight, minlength=len(class_ids)),
        rings=_rings(poses, model_of, rot, shift),
        touched=_touched(hypotheses, whole, model_of, rot),
    )


def _touched(
    hypotheses: Sequence[Hypothesis], poses: list, model_of: np.ndarray, rot: np.ndarray
) -> np.ndarray:
    """(H, s, 2) posed normal of each assigned face (NaN: spurious)."""
    width = max(len(h.assignment) for h in hypotheses)
    assigned = np.full((len(hypotheses), width), -1, dtype=np.int64)
    for i, h in enumerate(hypotheses):
        assigned[i, : len(h.assignment)] = [-1 if f is None else f for f in h.assignment]
    out = np.full((*assigned.shape, 2), np.nan)
    for m, pose in enumerate(poses):
        mine = np.flatnonzero(model_of == m)
        normals = pose.all_faces.normal[np.maximum(assigned[mine], 0)]  # (k, s, 2)
        out[mine] = rotate(rot[mine], normals)
    out[assigned < 0] = np.nan
    return out


def _rings(poses: list, model_of: np.ndarray, rot: np.ndarray, shift: np.ndarray) -> tuple:
    """Each hypothesis' posed outline and holes, the hypotheses of one stable pose
    moved together."""
    out: list = [None] * len(model_of)
    for m, pose in enumerate(poses):
        mine = np.flatnonzero(model_of == m)
        # v_world = v_model R(theta)^T + t, as Pose.apply
        moved = [
            np.asarray(ring, dtype=float)[None] @ np.swapaxes(rot[mine], -1, -2) + shift[mine, None]
            for ring in (pose.outline, *pose.holes)
        ]
        for k, i in enumerate(mine):
            out[i] = (moved[0][k], tuple(ring[k] for ring in moved[1:]))
    return tuple(out)


def contains_points(posed: PosedSet, points: np.ndarray) -> np.ndarray:
    """(M, H) bool: is each world point inside each posed outline (holes excluded)?

    Even-odd crossing count of a ray toward +x over all faces, points in chunks of at
    most :data:`CHUNK_ELEMENTS` point x hypothesis x face cells.
    """
    pts = np.asarray(points, dtype=float).reshape(-1, 2)
    n_hyp, n_faces = posed.start.shape[:2]
    step = max(1, CHUNK_ELEMENTS // max(1, n_hyp * n_faces))
    parts = [_inside(posed, pts[i : i + step]) for i in range(0, len(pts), step)]
    return np.concatenate(parts) if parts else np.zeros((0, n_hyp), dtype=bool)


def _inside(posed: PosedSet, points: np.ndarray) -> np.ndarray:
    q = points[:, None, None, :]
    s, e = posed.start[None], posed.end[None]
    straddle = (s[..., 1] > q[..., 1]) != (e[..., 1] > q[..., 1])
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        x_cross = s[..., 0] + (q[..., 1] - s[..., 1]) * (e[..., 0] - s[..., 0]) / (
            e[..., 1] - s[..., 1]
        )
    crossing = straddle & (q[..., 0] < x_cross) & posed.valid[None]
    return (np.count_nonzero(crossing, axis=-1) % 2) == 1


def _extent(points: np.ndarray) -> float:
    return float(max(1.0, np.ptp(points.reshape(-1, 2), axis=0).max()))


def _bounded(values: Sequence[float], ceiling: float) -> np.ndarray:
    """Error bounds as an array; unknown (NaN) or unbounded ones become `ceiling`
    (larger than anything in the scene: confusable with everything)."""
    out = np.abs(np.asarray(values, dtype=float))
    return np.where(np.isfinite(out), np.minimum(out, ceiling), ceiling)
