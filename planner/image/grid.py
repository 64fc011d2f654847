"""Grid multi-interpretation image (DESIGN §4.9; thesis §4.3.2-4.3.4, App. 2, App. 4).

The MII is mapped onto a B x B grid (App. 2) with room for the grown faces,
every grown face is filled, and MGRID holds ``1`` on any face plus the degree
of the blocking boundaries there (eq. 4.3, or its corner-free variant). A
weighted twin, `strength`, holds the summed class weights of the blocking
boundaries (thesis §3.1.3). Intersection areas are labelled with
:func:`scipy.ndimage.label` and each gets a target point (App. 4: the centroid
when it lies in the area, else the cell farthest from the area's border). The
rays, windows and thesis paths swept from those targets are in
:mod:`planner.image.windows`.

Grid coordinates follow the thesis: continuous, 1-based, x along the first
array axis and y along the second (``mgrid[i, j]`` is cell ``I = i + 1``,
``J = j + 1``, centred on grid coordinate ``(i + 1, j + 1)``). The mapping is
a uniform scale plus a shift, so angles are the same in grid and world.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass

import numpy as np
import shapely
from scipy import ndimage

from planner.errors import PlanningNotPossibleError
from planner.image.faces import (
    EXACT_TOLERANCE,
    PosedFaces,
    hypothesis_weights,
    model_map,
    normal_groups,
    posed_faces,
    posed_polygon,
)
from planner.types import Hypothesis, ObjectModel

__all__ = ["GridMII", "GridMapping", "build_grid"]


#: Spacing (cells) of the samples taken along each swept ray.
RAY_STEP = 0.25
#: Cells of grid kept per chunk of faces when filling (bounds memory).
_CHUNK_CELLS = 1_000_000


@dataclass(frozen=True)
class GridMapping:
    """App. 2 mapping between world and grid coordinates.

    ``A = Delta (B - 2) / (Delta + 2 eps_t)`` so that the MII plus a growth margin
    of ``eps_t A / Delta + 1`` cells on each side fills the B x B grid (solving the
    thesis' ``A = B - 2 (eps_t A / Delta + 1)``; its printed ``B + 2`` would overflow).

    >>> m = GridMapping.fit(np.array([[0.0, 0.0], [10.0, 5.0]]), eps_t=0.0, size=12)
    >>> m.forward([[0.0, 0.0], [10.0, 5.0]]).tolist()
    [[1.0, 1.0], [11.0, 6.0]]
    >>> m.inverse(m.forward([[3.0, 4.0]])).round(12).tolist()
    [[3.0, 4.0]]
    """

    x_min: float
    y_min: float
    delta: float
    eps_t: float
    size: int

    @classmethod
    def fit(cls, points: np.ndarray, eps_t: float, size: int) -> GridMapping:
        """Mapping for world points (N, 2) with error disk diameter `eps_t`, B = `size`."""
        points = np.asarray(points, dtype=float)
        lo, hi = points.min(axis=0), points.max(axis=0)
        # Delta = max(dX_max, dY_max)
        delta = float(max(hi - lo))
        if not delta > 0:
            raise PlanningNotPossibleError("the image has no extent", field="hypotheses")
        return cls(float(lo[0]), float(lo[1]), delta, max(float(eps_t), 0.0), int(size))

    @property
    def a(self) -> float:
        # A = Delta (B - 2) / (Delta + 2 eps_t)
        return self.delta * (self.size - 2) / (self.delta + 2.0 * self.eps_t)

    @property
    def scale(self) -> float:
        """Cells per world length unit, A / Delta."""
        return self.a / self.delta

    def forward_matrix(self) -> np.ndarray:
        """Homogeneous world -> grid matrix, thesis eq. A4."""
        s = self.scale
        return np.array(
            [
                [s, 0.0, s * (self.eps_t - self.x_min) + 1.0],
                [0.0, s, s * (self.eps_t - self.y_min) + 1.0],
                [0.0, 0.0, 1.0],
            ]
        )

    def inverse_matrix(self) -> np.ndarray:
        """Homogeneous grid -> world matrix, thesis eq. A5."""
        r = 1.0 / self.scale
        return np.array(
            [
                [r, 0.0, -self.eps_t - r + self.x_min],
                [0.0, r, -self.eps_t - r + self.y_min],
                [0.0, 0.0, 1.0],
            ]
        )

    def forward(self, points: np.ndarray | Sequence[Sequence[float]]) -> np.ndarray:
        """World points (N, 2) to continuous grid coordinates (N, 2)."""
        m = self.forward_matrix()
        return np.asarray(points, dtype=float) @ m[:2, :2].T + m[:2, 2]

    def inverse(self, points: np.ndarray | Sequence[Sequence[float]]) -> np.ndarray:
        """Continuous grid coordinates (N, 2) to world points (N, 2)."""
        m = self.inverse_matrix()
        return np.asarray(points, dtype=float) @ m[:2, :2].T + m[:2, 2]

    def cell_centres(self) -> np.ndarray:
        """World coordinates of every cell centre, (B, B, 2) indexed [i, j]."""
        k = np.arange(1, self.size + 1, dtype=float)
        gx, gy = np.meshgrid(k, k, indexing="ij")
        return self.inverse(np.stack([gx, gy], axis=-1).reshape(-1, 2)).reshape(
            self.size, self.size, 2
        )


@dataclass(frozen=True, eq=False)
class GridMII:
    """The MII on a grid; arrays are (B, B) indexed ``[i, j]`` (x, y).

    `mgrid`: 1 on any grown face plus the blocking degree (eq. 4.3 or the
    corner-free variant); `strength`: summed class weights of the blocking
    boundaries; `faces`: filled grown faces (at least the cells a face passes
    through); `inside`: cell centre inside every posed outline; `ia`: inside and
    off every face grown by its true ``eps_t`` (the thesis' IA cells; with zero
    error the one-cell drawing width removes nothing); `labels`: IA components 1..n;
    `targets` (n, 2): the target point of each area in grid coordinates.
    """

    mapping: GridMapping
    hypotheses: tuple[Hypothesis, ...]
    class_weights: np.ndarray
    mgrid: np.ndarray
    strength: np.ndarray
    faces: np.ndarray
    inside: np.ndarray
    ia: np.ndarray
    labels: np.ndarray
    targets: np.ndarray
    corners: bool

    @property
    def n_areas(self) -> int:
        return len(self.targets)

    @property
    def cell_size(self) -> float:
        """World length of one cell side."""
        return 1.0 / self.mapping.scale

    def world_targets(self) -> np.ndarray:
        """Target points (n, 2) in the world frame."""
        return self.mapping.inverse(self.targets) if len(self.targets) else np.zeros((0, 2))


def _fill(
    g0: np.ndarray, g1: np.ndarray, half_width: np.ndarray, half_ext: np.ndarray, size: int
) -> np.ndarray:
    """Cells (k, B, B) whose centre lies in each grown face rectangle (grid coords)."""
    k = np.arange(1, size + 1, dtype=float)
    cx, cy = k[None, :, None], k[None, None, :]
    mid = 0.5 * (g0 + g1)
    edge = g1 - g0
    half_len = 0.5 * np.hypot(edge[:, 0], edge[:, 1])
    t = edge / np.maximum(2.0 * half_len, 1e-300)[:, None]
    dx, dy = cx - mid[:, 0, None, None], cy - mid[:, 1, None, None]
    # along = t·(c - m), across = n·(c - m) with n = (t_y, -t_x)
    along = dx * t[:, 0, None, None] + dy * t[:, 1, None, None]
    across = dx * t[:, 1, None, None] - dy * t[:, 0, None, None]
    return (np.abs(along) <= (half_len + half_ext)[:, None, None]) & (
        np.abs(across) <= half_width[:, None, None]
    )


def _draw_faces(
    faces: PosedFaces,
    groups: np.ndarray,
    mapping: GridMapping,
    class_weights: np.ndarray,
    corners: bool,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Fill every face and add the blocking of each normal group (thesis §4.3.4, eq. 4.3).

    `groups` labels the faces' normal groups. Returns, each (B, B) indexed
    ``[i, j]``: the cells on any face drawn at least one cell wide, the cells on
    any face grown by its true ``eps_t``, MGRID (1 on any face plus the blocking
    degree) and the summed class weights of the blocking boundaries.
    """
    size = mapping.size
    g0, g1 = mapping.forward(faces.start), mapping.forward(faces.end)
    true_half = 0.5 * faces.eps_t * mapping.scale
    # a face covers at least the cells it passes through, widened by one ray step
    floor = 0.5 * (np.abs(faces.normal[:, 0]) + np.abs(faces.normal[:, 1])) + RAY_STEP
    drawn_half = np.maximum(true_half, floor)

    shape = (size, size)
    any_face = np.zeros(shape, dtype=bool)
    grown = np.zeros(shape, dtype=bool)
    degree = np.zeros(shape, dtype=np.int32)
    strength = np.zeros(shape, dtype=float)
    chunk = max(1, _CHUNK_CELLS // (size * size))
    for g in np.unique(groups):
        idx = np.flatnonzero(groups == g)
        idx = idx[np.argsort(faces.klass[idx], kind="stable")]
        classes = np.unique(faces.klass[idx])
        cover = np.zeros((len(classes), *shape), dtype=bool)
        for lo in range(0, len(idx), chunk):
            part = idx[lo : lo + chunk]
            masks = _fill(g0[part], g1[part], drawn_half[part], drawn_half[part], size)
            any_face |= masks.any(axis=0)
            if np.any(true_half[part] > 0):
                grown |= _fill(g0[part], g1[part], true_half[part], true_half[part], size).any(0)
            row = np.searchsorted(classes, faces.klass[part])
            starts = np.flatnonzero(np.r_[True, row[1:] != row[:-1]])
            cover[row[starts]] |= np.logical_or.reduceat(masks, starts, axis=0)
        # WGRID: classes of this normal covering each cell (a class counts once)
        wgrid = cover.sum(axis=0)
        weighted = np.tensordot(class_weights[classes], cover, axes=1)
        blocking = wgrid >= 2
        if corners:
            # MGRID(I, J) = MGRID(I, J) + MAX(0, WGRID(I, J) - 1)   (eq. 4.3)
            degree += np.maximum(0, wgrid - 1)
            strength += np.where(blocking, weighted, 0.0)
        else:
            # corner-free: replace when larger instead of adding
            degree = np.maximum(degree, wgrid - 1)
            strength = np.maximum(strength, np.where(blocking, weighted, 0.0))
    mgrid = any_face.astype(np.int32) + degree
    return any_face, grown, mgrid, strength


def _inside_every_outline(
    hypotheses: Sequence[Hypothesis], models: Mapping[str, ObjectModel], mapping: GridMapping
) -> np.ndarray:
    """Cells (B, B) whose centre lies inside every posed outline."""
    size = mapping.size
    # App. 4 membership: a cell is in the IA when its centre is inside every outline
    centres = mapping.cell_centres().reshape(-1, 2)
    candidates = np.arange(len(centres))
    for h in hypotheses:
        polygon = posed_polygon(h, models)
        keep = shapely.contains_xy(polygon, centres[candidates, 0], centres[candidates, 1])
        candidates = candidates[keep]
    inside = np.zeros(size * size, dtype=bool)
    inside[candidates] = True
    return inside.reshape((size, size))


def build_grid(
    hypotheses: Sequence[Hypothesis],
    models: Mapping[str, ObjectModel] | Iterable[ObjectModel],
    size: int = 70,
    *,
    corners: bool = True,
    angle_tolerance: float | None = None,
) -> GridMII:
    """Build the grid MII of a hypothesis set (thesis §4.3.2-4.3.4, App. 2, App. 4).

    `size` is B (cells per side, the thesis used 70). `corners` keeps eq. 4.3's
    summed "zones of confusion" where blocking boundaries of different normals
    overlap; ``corners=False`` is the thesis' corner-free variant (the larger
    value is kept instead of the sum; the printed variant compares MGRID, which
    holds 1 + degree, with WGRID - 1: here MGRID is 1 + degree throughout).
    Faces are drawn at least one cell wide. Normals group within `angle_tolerance`
    (default: twice the largest rotation error bound, plus 1e-7).

    >>> from planner.models.outlines import make_stable_pose
    >>> from planner.types import ErrorBound, Pose
    >>> sq = ObjectModel("sq", (make_stable_pose([[0, 0], [2, 0], [2, 1], [0, 1]]),))
    >>> hs = [Hypothesis("sq", 0, (), Pose(x, 0, 0), ErrorBound(0, 0, 0), 0.5,
    ...                  equivalence_class=i) for i, x in enumerate([0.0, 1.0])]
    >>> g = build_grid(hs, [sq], size=32)
    >>> g.n_areas, float(g.strength.max())
    (1, 1.0)
    """
    if not isinstance(size, int | np.integer) or isinstance(size, bool) or size < 8:
        raise PlanningNotPossibleError("grid size must be an integer >= 8", field="size")
    size = int(size)
    models = model_map(models)
    hypotheses = tuple(hypotheses)
    _, _, class_weights = hypothesis_weights(hypotheses)
    faces = posed_faces(hypotheses, models)
    eps_t = max(h.error_bound.eps_t for h in hypotheses)
    mapping = GridMapping.fit(np.concatenate([faces.start, faces.end]), eps_t, size)
    if angle_tolerance is None:
        angle_tolerance = EXACT_TOLERANCE + 2.0 * max(h.error_bound.rotation for h in hypotheses)
    groups = normal_groups(faces, angle_tolerance)

    any_face, grown, mgrid, strength = _draw_faces(faces, groups, mapping, class_weights, corners)
    inside = _inside_every_outline(hypotheses, models, mapping)
    ia = inside & ~grown
    labels, n_areas = ndimage.label(ia)
    return GridMII(
        mapping=mapping,
        hypotheses=hypotheses,
        class_weights=class_weights,
        mgrid=mgrid,
        strength=strength,
        faces=any_face,
        inside=inside,
        ia=ia,
        labels=labels,
        targets=_targets(labels, n_areas),
        corners=corners,
    )


def _targets(labels: np.ndarray, n_areas: int) -> np.ndarray:
    """Centroid of each area when its cell lies in the area, else the deepest cell."""
    if n_areas == 0:
        return np.zeros((0, 2))
    index = np.arange(1, n_areas + 1)
    # centroid: x = sum x_i / n, y = sum y_i / n over the area's cells (eq. A5-1)
    centroid = np.array(ndimage.center_of_mass(labels > 0, labels, index)).reshape(-1, 2)
    cell = np.rint(centroid).astype(int)
    at = labels[cell[:, 0], cell[:, 1]]
    depth = ndimage.distance_transform_edt(labels > 0)
    deepest = np.array(ndimage.maximum_position(depth, labels, index), dtype=float).reshape(-1, 2)
    target = np.where((at == index)[:, None], centroid, deepest)
    return target + 1.0  # array index -> 1-based grid coordinate
