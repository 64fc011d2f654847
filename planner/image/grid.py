"""Grid multi-interpretation image and the thesis' paths (DESIGN §4.9; thesis §4.3, App. 2, 4).

The MII is mapped onto a B x B grid (App. 2) with room for the grown faces,
every grown face is filled, and MGRID holds ``1`` on any face plus the degree
of the blocking boundaries there (eq. 4.3, or its corner-free variant). A
weighted twin, `strength`, holds the summed class weights of the blocking
boundaries (thesis §3.1.3). Intersection areas are labelled with
:func:`scipy.ndimage.label`; from a target point in each, rays are swept in
1 degree steps, every ray records the blocking strengths it crosses, and runs
of rays whose summed strength stays within an admitted strength are the
windows. Each window is bisected; the admitted strength is raised until
windows open. Paths are mapped back to the world and start on the safe circle.

Grid coordinates follow the thesis: continuous, 1-based, x along the first
array axis and y along the second (``mgrid[i, j]`` is cell ``I = i + 1``,
``J = j + 1``, centred on grid coordinate ``(i + 1, j + 1)``). The mapping is
a uniform scale plus a shift, so angles are the same in grid and world.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass

import numpy as np
import shapely
from scipy import ndimage

from planner.errors import PlanningNotPossibleError
from planner.geometry import wrap_angle
from planner.image.vector import (
    EXACT_TOLERANCE,
    hypothesis_weights,
    model_map,
    normal_groups,
    posed_faces,
    posed_polygon,
)
from planner.types import Hypothesis, ObjectModel, SensingPath, Workspace

__all__ = [
    "GridMII",
    "GridMapping",
    "RaySweep",
    "ThesisPath",
    "build_grid",
    "choose",
    "sweep_rays",
    "thesis_paths",
    "windows",
]

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

    >>> from planner.geometry import make_stable_pose
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

    # App. 4 membership: a cell is in the IA when its centre is inside every outline
    centres = mapping.cell_centres().reshape(-1, 2)
    candidates = np.arange(len(centres))
    for h in hypotheses:
        polygon = posed_polygon(h, models)
        keep = shapely.contains_xy(polygon, centres[candidates, 0], centres[candidates, 1])
        candidates = candidates[keep]
    inside = np.zeros(size * size, dtype=bool)
    inside[candidates] = True
    inside = inside.reshape(shape)
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


@dataclass(frozen=True, eq=False)
class RaySweep:
    """Blocking met by rays from one target: `angles` (K,) radians, and per ray the
    summed strength of the separate blocking runs crossed (`total`), the largest
    run (`largest`) and the number of runs (`runs`)."""

    angles: np.ndarray
    total: np.ndarray
    largest: np.ndarray
    runs: np.ndarray


def sweep_rays(grid: GridMII, target: np.ndarray, angles: np.ndarray) -> RaySweep:
    """Follow rays from `target` (grid coordinates) at `angles` (radians) to the grid edge.

    A run of consecutive blocking cells along a ray is one blocking boundary
    crossed (thesis §4.3.5); its strength is the largest value in the run. The
    ray's `total` sums its runs: ``1 - total`` bounds P(DM) from below, and with a
    single run it is Theorem 2's value.
    """
    angles = np.atleast_1d(np.asarray(angles, dtype=float))
    size = grid.mapping.size
    r = np.arange(0.0, size * math.sqrt(2.0) + RAY_STEP, RAY_STEP)
    pts = (
        np.asarray(target, dtype=float)[None, None, :]
        + r[None, :, None] * np.stack([np.cos(angles), np.sin(angles)], axis=1)[:, None, :]
    )
    cell = np.floor(pts - 0.5).astype(int)  # cell k covers [k + 0.5, k + 1.5)
    ok = np.all((cell >= 0) & (cell < size), axis=-1)
    values = np.where(
        ok,
        grid.strength[np.clip(cell[..., 0], 0, size - 1), np.clip(cell[..., 1], 0, size - 1)],
        0.0,
    )
    blocked = values > 0
    starts = blocked & ~np.pad(blocked, ((0, 0), (1, 0)))[:, :-1]
    flat_blocked, flat_values = blocked.ravel(), values.ravel()
    run_id = np.cumsum(starts.ravel())[flat_blocked] - 1
    n_runs = int(starts.sum())
    total = np.zeros(len(angles))
    largest = np.zeros(len(angles))
    runs = starts.sum(axis=1)
    if n_runs:
        run_max = np.zeros(n_runs)
        np.maximum.at(run_max, run_id, flat_values[flat_blocked])
        ray_of_run = np.repeat(np.arange(len(angles)), runs)
        total = np.bincount(ray_of_run, weights=run_max, minlength=len(angles)).astype(float)
        np.maximum.at(largest, ray_of_run, run_max)
    return RaySweep(angles, np.round(total, 9), np.round(largest, 9), runs)


def windows(open_rays: np.ndarray) -> list[tuple[int, int]]:
    """Circular runs of open rays as (first index, count); the whole circle is (0, K).

    >>> windows(np.array([True, False, False, True, True, False, True]))
    [(3, 2), (6, 2)]
    """
    open_rays = np.asarray(open_rays, dtype=bool)
    n = len(open_rays)
    if open_rays.all():
        return [(0, n)]
    shift = int(np.argmin(open_rays))  # a closed ray
    rolled = np.roll(open_rays, -shift).astype(np.int8)
    edges = np.diff(np.concatenate([[0], rolled, [0]]))
    first, stop = np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)
    return [(int((a + shift) % n), int(b - a)) for a, b in zip(first, stop, strict=True)]


@dataclass(frozen=True)
class ThesisPath:
    """One thesis path: a window's bisector into an intersection area.

    `path` starts on the safe circle and ends at `aim` (the area's target point,
    world frame). `family` is ``"distinguishing"`` (no blocking boundary crossed,
    Theorem 1) or ``"sub-optimal"``; `admitted_strength` is the level at which
    the window opened and `level` its rank among the levels; `strength` is the
    summed blocking strength on the bisector ray (``1 - strength`` bounds P(DM)),
    `crossings` the number of blocking runs on it. `window` is the range of
    approach-ray angles (radians, from the target outward, counter-clockwise; the
    end exceeds 2 pi when the window wraps past 0); `motion_cost` the arc
    along the safe circle from the sensor to the path origin (the CHOOSE key).
    """

    path: SensingPath
    aim: tuple[float, float]
    family: str
    level: int
    admitted_strength: float
    strength: float
    crossings: int
    window: tuple[float, float]
    area: int
    motion_cost: float


def _origin_on_circle(aim: np.ndarray, u: np.ndarray, workspace: Workspace) -> float:
    """Distance r > 0 with |aim + r u - c| = R."""
    rel = aim - np.asarray(workspace.center)
    b = float(rel @ u)
    # r = -b + sqrt(b^2 - (|rel|^2 - R^2))
    return -b + math.sqrt(b * b - (float(rel @ rel) - workspace.radius**2))


def thesis_paths(
    hypotheses: Sequence[Hypothesis],
    models: Mapping[str, ObjectModel] | Iterable[ObjectModel],
    workspace: Workspace,
    sensor_position: Sequence[float],
    size: int = 70,
    *,
    corners: bool = True,
    angle_tolerance: float | None = None,
    grid: GridMII | None = None,
) -> list[ThesisPath]:
    """The thesis' candidate paths, best first (DESIGN §4.9, thesis §4.3.5, CHOOSE).

    For each intersection area, rays from its target are swept in 1 degree
    steps. The admitted strength is raised through the distinct ray strengths,
    starting at 0 (the distinguishing family); at each level every window that
    newly opens is bisected into one path. Paths are sorted by admitted
    strength, then by the CHOOSE rule: nearest origin on the safe circle (arc
    length) to `sensor_position`. World frame throughout; an empty list when the
    grid has no intersection area. Pass `grid` to reuse a built grid.

    >>> from planner.geometry import make_stable_pose
    >>> from planner.types import ErrorBound, Pose
    >>> sq = ObjectModel("sq", (make_stable_pose([[0, 0], [2, 0], [2, 1], [0, 1]]),))
    >>> hs = [Hypothesis("sq", 0, (), Pose(x, 0, 0), ErrorBound(0, 0, 0), 0.5,
    ...                  equivalence_class=i) for i, x in enumerate([0.0, 1.0])]
    >>> best = thesis_paths(hs, [sq], Workspace((1.5, 0.5), 10.0), (11.5, 0.5), size=40)[0]
    >>> best.family, bool(best.path.direction[0] < -0.99), round(best.path.origin[0], 1)
    ('distinguishing', True, 11.5)
    """
    grid = grid or build_grid(
        hypotheses, models, size, corners=corners, angle_tolerance=angle_tolerance
    )
    centre = np.asarray(workspace.center, dtype=float)
    sensor = np.asarray(sensor_position, dtype=float)
    sensor_angle = math.atan2(*(sensor - centre)[::-1])
    aims = grid.world_targets()
    if len(aims) and np.any(np.hypot(*(aims - centre).T) >= workspace.radius):
        raise PlanningNotPossibleError(
            "an intersection area lies outside the safe circle", field="workspace"
        )
    step = math.radians(1.0)
    angles = np.arange(360) * step
    found: list[tuple[int, float, float, float, tuple[float, float]]] = []
    for area, target in enumerate(grid.targets):
        sweep = sweep_rays(grid, target, angles)
        for level in np.unique(sweep.total):
            for first, count in windows(sweep.total <= level):
                rays = (first + np.arange(count)) % 360
                if sweep.total[rays].max() < level:
                    continue  # opened at a lower level already
                if count == 360:
                    aim = aims[area]
                    theta = math.atan2(*(sensor - aim)[::-1])
                else:
                    # bisect the window's included angle
                    theta = float((first + (count - 1) / 2.0) * step)
                span = (float(first * step), float((first + count - 1) * step))
                found.append((area, float(level), theta, 0.0, span))
    if not found:
        return []
    thetas = np.array([f[2] for f in found])
    along = np.zeros(len(found))
    crossings = np.zeros(len(found), dtype=int)
    for area in {f[0] for f in found}:
        sel = np.array([f[0] == area for f in found])
        sweep = sweep_rays(grid, grid.targets[area], thetas[sel])
        along[sel], crossings[sel] = sweep.total, sweep.runs
    levels = np.unique([f[1] for f in found])
    out = []
    for (area, level, theta, _, span), strength, runs in zip(found, along, crossings, strict=True):
        u = np.array([math.cos(theta), math.sin(theta)])
        aim = aims[area]
        r = _origin_on_circle(aim, u, workspace)
        origin = aim + r * u
        arc = workspace.radius * abs(
            float(wrap_angle(math.atan2(*(origin - centre)[::-1]) - sensor_angle))
        )
        out.append(
            ThesisPath(
                path=SensingPath(tuple(origin), tuple(-u), r),
                aim=(float(aim[0]), float(aim[1])),
                family="distinguishing" if level == 0 else "sub-optimal",
                level=int(np.searchsorted(levels, level)),
                admitted_strength=level,
                strength=float(strength),
                crossings=int(runs),
                window=span,
                area=area + 1,
                motion_cost=arc,
            )
        )
    out.sort(key=lambda p: (p.admitted_strength, p.motion_cost))
    return out


def choose(paths: Sequence[ThesisPath]) -> ThesisPath:
    """The thesis' CHOOSE rule: in the lowest admitted strength, the path whose
    origin on the safe circle is nearest the sensor (smallest `motion_cost`)."""
    if not paths:
        raise PlanningNotPossibleError("no thesis path to choose from", field="paths")
    return min(paths, key=lambda p: (p.admitted_strength, p.motion_cost))
