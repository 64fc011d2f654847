"""Posed faces, hypothesis weights and normal groups (DESIGN §4.8; thesis §3.1.3, §4.2.3).

Every hypothesis places its object's outline (and holes) in the world; the
faces of all of them are collected as flat arrays (:class:`PosedFaces`) with
the owning hypothesis, its equivalence class and its error disk diameter.
Hypothesis weights are the normalized probabilities, and a class counts once
with the summed weight of its members (thesis §3.1.3). Faces are grouped by
outward normal within an angular tolerance (:func:`normal_groups`), and with
error each face becomes its grown rectangle (thesis §4.2.3: widened by
``eps_t``, lengthened by ``eps_t / 2`` at each end, i.e. a square-capped buffer
of ``eps_t / 2``; :func:`grown_faces`).

All coordinates are world-frame lengths in the unit of the object files;
angles are radians, counter-clockwise positive.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass

import numpy as np
import shapely

from planner.errors import InvalidModelError, PlanningNotPossibleError
from planner.types import Hypothesis, ObjectModel

__all__ = [
    "PosedFaces",
    "cluster_sorted",
    "grown_faces",
    "hypothesis_weights",
    "model_map",
    "normal_groups",
    "posed_faces",
    "posed_outline",
    "posed_polygon",
]

#: Relative tolerance (of the MII's extent) used when every error bound is zero.
EXACT_TOLERANCE = 1e-7


def model_map(models: Mapping[str, ObjectModel] | Iterable[ObjectModel]) -> dict[str, ObjectModel]:
    """Models by name; accepts a mapping or any iterable of :class:`ObjectModel`."""
    if isinstance(models, Mapping):
        return dict(models)
    return {m.name: m for m in models}


def _stable_pose(h: Hypothesis, models: Mapping[str, ObjectModel]):
    model = models.get(h.object)
    if model is None:
        raise InvalidModelError(f"no object model named {h.object!r}", field="models")
    if not 0 <= h.stable_pose < len(model.stable_poses):
        raise InvalidModelError(
            f"object {h.object!r} has no stable pose {h.stable_pose}", field="hypotheses"
        )
    return model.stable_poses[h.stable_pose]


def posed_outline(
    h: Hypothesis, models: Mapping[str, ObjectModel]
) -> tuple[np.ndarray, tuple[np.ndarray, ...]]:
    """World-frame outline (N, 2) and holes of hypothesis `h`.

    >>> from planner.models.outlines import make_stable_pose
    >>> from planner.types import ErrorBound, Pose
    >>> sq = ObjectModel("sq", (make_stable_pose([[0, 0], [1, 0], [1, 1], [0, 1]]),))
    >>> h = Hypothesis("sq", 0, (), Pose(2.0, 0.0, 0.0), ErrorBound(0, 0, 0), 1.0)
    >>> posed_outline(h, {"sq": sq})[0][0].tolist()
    [2.0, 0.0]
    """
    pose = _stable_pose(h, models)
    return h.pose.apply(pose.outline), tuple(h.pose.apply(r) for r in pose.holes)


def posed_polygon(h: Hypothesis, models: Mapping[str, ObjectModel]) -> shapely.Polygon:
    """The posed outline of `h` as a shapely polygon (world frame)."""
    outline, holes = posed_outline(h, models)
    return shapely.Polygon(outline, list(holes))


@dataclass(frozen=True, eq=False)
class PosedFaces:
    """Every face of every hypothesis in the world frame, as flat arrays of length F.

    `start`, `end`, `normal` (outward unit) are (F, 2); `offset` is ``n·start``;
    `hypothesis` indexes the hypothesis list, `klass` the equivalence classes
    (renumbered 0..C-1); `eps_t` is the owning hypothesis' error disk diameter.
    """

    start: np.ndarray
    end: np.ndarray
    normal: np.ndarray
    offset: np.ndarray
    length: np.ndarray
    hypothesis: np.ndarray
    klass: np.ndarray
    eps_t: np.ndarray

    def __len__(self) -> int:
        return len(self.length)

    @property
    def angle(self) -> np.ndarray:
        return np.arctan2(self.normal[:, 1], self.normal[:, 0])


def hypothesis_weights(
    hypotheses: Sequence[Hypothesis],
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Normalized weights w(h), class index per hypothesis (0..C-1), class weights w(k).

    Classes come from ``equivalence_class``; a class counts once with the summed
    weight of its members.
    """
    if not hypotheses:
        raise PlanningNotPossibleError("no hypotheses to build an image from", field="hypotheses")
    p = np.array([h.probability for h in hypotheses], dtype=float)
    if not np.all(np.isfinite(p)) or np.any(p < 0) or p.sum() <= 0:
        raise PlanningNotPossibleError(
            "hypothesis probabilities must be finite, >= 0 and not all zero", field="hypotheses"
        )
    # w(h) = p(h) / sum_g p(g)
    weights = p / p.sum()
    _, klass = np.unique([h.equivalence_class for h in hypotheses], return_inverse=True)
    klass = klass.reshape(-1)
    # w(k) = sum_{h in k} w(h)
    class_weights = np.bincount(klass, weights=weights)
    return weights, klass, class_weights


def posed_faces(
    hypotheses: Sequence[Hypothesis], models: Mapping[str, ObjectModel] | Iterable[ObjectModel]
) -> PosedFaces:
    """Collect the posed faces of all hypotheses (world frame, outline and holes)."""
    models = model_map(models)
    _, klass, _ = hypothesis_weights(hypotheses)
    pairs = [(h, _stable_pose(h, models).faces) for h in hypotheses]
    # v_world = R(theta) v_model + t;  n_world = R(theta) n_model
    start = np.concatenate([h.pose.apply(f.start) for h, f in pairs])
    end = np.concatenate([h.pose.apply(f.end) for h, f in pairs])
    normal = np.concatenate([f.normal @ h.pose.rotation().T for h, f in pairs])
    hyp = np.repeat(np.arange(len(hypotheses)), [len(f) for _, f in pairs])
    eps = np.array([h.error_bound.eps_t for h in hypotheses], dtype=float)[hyp]
    edge = end - start
    return PosedFaces(
        start=start,
        end=end,
        normal=normal,
        offset=np.einsum("ij,ij->i", normal, start),
        length=np.hypot(edge[:, 0], edge[:, 1]),
        hypothesis=hyp,
        klass=klass[hyp],
        eps_t=np.maximum(eps, 0.0),
    )


def cluster_sorted(values: np.ndarray, tolerance: float, *, circular: bool = False) -> np.ndarray:
    """Cluster 1-D values so that every cluster spans at most `tolerance`.

    Values are visited in sorted order and a new cluster starts when a value lies
    more than `tolerance` beyond the first value of the current cluster (so no
    chaining across a fan of small steps). With `circular` the values are angles
    in radians and the sweep starts after the widest gap, so no cluster straddles
    the +-pi seam. Returns a cluster label per value (0..K-1).

    >>> cluster_sorted(np.array([0.0, 0.05, 1.0, 0.02]), 0.1).tolist()
    [0, 0, 1, 0]
    """
    values = np.asarray(values, dtype=float)
    if values.size == 0:
        return np.zeros(0, dtype=int)
    order = np.argsort(values, kind="stable")
    ordered = values[order]
    if circular:
        gaps = np.diff(np.append(ordered, ordered[0] + 2 * np.pi))
        first = (int(np.argmax(gaps)) + 1) % len(ordered)
        order = np.roll(order, -first)
        ordered = np.unwrap(values[order])
    labels_sorted = np.empty(len(order), dtype=int)
    label, anchor = 0, ordered[0]
    for k, v in enumerate(ordered):  # one pass over faces, never over pairs
        if v - anchor > tolerance:
            label, anchor = label + 1, v
        labels_sorted[k] = label
    labels = np.empty_like(labels_sorted)
    labels[order] = labels_sorted
    return labels


def normal_groups(faces: PosedFaces, angle_tolerance: float) -> np.ndarray:
    """Group faces whose outward normals agree within `angle_tolerance` (radians)."""
    return cluster_sorted(faces.angle, angle_tolerance, circular=True)


def grown_faces(faces: PosedFaces, floor: float = 0.0) -> np.ndarray:
    """Grown rectangle of every face: square-capped buffer of ``max(eps_t, floor) / 2``."""
    lines = shapely.linestrings(np.stack([faces.start, faces.end], axis=1))
    # widened by eps_t, lengthened by eps_t / 2 at each end (thesis §4.2.3)
    half = 0.5 * np.maximum(faces.eps_t, floor)
    return shapely.buffer(lines, half, cap_style="square", join_style="mitre")
