"""Paths a strategy brings of its own (world frame, lengths in the object files' unit).

The opening probe before any contact (from the sensor's place toward the
centre; ``random``: from a random place), the thesis' second probe orthogonal
to the first contact normal (thesis §3.1, Exp. II), random draws aimed at the
centre of the union area (thesis Exp. I), and the thesis' grid windows from
:func:`planner.image.windows.thesis_paths`.
"""

from __future__ import annotations

import math
from collections import Counter
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import shapely

from planner.errors import PlanningNotPossibleError
from planner.geometry import (
    LENGTH_SLACK,
    point_segment_distance,
    rotate,
    rotation_matrices,
    signed_area,
)
from planner.memo import SharedCache, array_key
from planner.models.prior import draw_poses, draw_stable_poses
from planner.planning.candidates import Candidates, paths_through
from planner.planning.intersection_aims import union_centre
from planner.planning.posed_set import PosedSet
from planner.planning.result import PlannedPath, opening_path
from planner.planning.scoring import motion_cost
from planner.recognition.crossing import ring_edges, segments_meet
from planner.types import (
    Contact,
    Hypothesis,
    ObjectModel,
    SensingPath,
    SensorBounds,
    Workspace,
)

if TYPE_CHECKING:
    from planner.planning.config import StrategyConfig

__all__ = ["opening_probe", "search_chord", "strategy_paths"]


def opening_probe(
    config: StrategyConfig,
    models: Mapping[str, ObjectModel],
    workspace: Workspace,
    sensor_position: Sequence[float],
    missed: Sequence[SensingPath],
    rng: np.random.Generator,
    prior_center: Sequence[float] | None = None,
) -> PlannedPath:
    """Before any contact. The first probe runs from the sensor's place through the
    centre (``random``: from a random place, every time); after `missed` paths, the
    chord most likely to meet the object (:func:`search_chord`). With a pose prior's
    region, the first probe runs through its centre."""
    aim = (float(workspace.center[0]), float(workspace.center[1]))
    if config.name == "random":
        path = opening_path(workspace, sensor_position, angle=float(rng.uniform(-math.pi, math.pi)))
    elif not missed and prior_center is not None:
        path = opening_path(workspace, sensor_position, aim=prior_center)
        aim = (float(prior_center[0]), float(prior_center[1]))
    elif not missed:
        path = opening_path(workspace, sensor_position)
    else:
        path, aim = search_chord(models, workspace, missed, sensor_position)
    cost = motion_cost(
        np.array([path.origin]), np.array([path.length / 2]), workspace, sensor_position
    )[0]
    # nothing is known yet: any contact teaches something, none can be predicted
    return PlannedPath(
        origin=path.origin,
        direction=path.direction,
        length=path.length,
        aim=aim,
        family="informative",
        p_distinguishing=0.0,
        p_informative=1.0,
        expected_pruning=0.0,
        expected_remaining=None,
        motion_cost=float(cost),
        source="opening",
    )


def search_chord(
    models: Mapping[str, ObjectModel],
    workspace: Workspace,
    missed: Sequence[SensingPath],
    sensor_position: Sequence[float],
    samples: int = 4096,
    angles: int = 36,
    offsets: int = 41,
) -> tuple[SensingPath, tuple[float, float]]:
    """The chord of the safe circle most likely to meet the object after `missed` paths.

    Prior: the object (by its prior), stable pose (by its probability), orientation
    uniform, position uniform among those keeping it inside the safe circle, as
    `samples` fixed draws. A draw that one of the `missed` paths would have met is
    ruled out; while fewer than a quarter of `samples` survive, a further fixed
    batch is drawn (up to `SEARCH_BATCHES`), so that after many misses the chord
    is not chosen on a handful of draws. A chord (normal angle a, offset rho from
    the centre) meets a draw's outline exactly when rho lies strictly between the
    outline's least and greatest projection on the normal; the chord meeting the
    most surviving draws wins (ties: the least motion from the sensor's place).
    With no draw left (the prior was wrong), chords through the centre turn by the
    golden angle per miss.
    Returns the path (origin on the circle, through to the far side) and its midpoint.

    >>> from planner.models.library import object_from_dict
    >>> sq = object_from_dict({"name": "sq", "outline": [[-5, -5], [5, -5], [5, 5], [-5, 5]]})
    >>> first = SensingPath((50.0, 0.0), (-1.0, 0.0), 100.0)
    >>> path, aim = search_chord({"sq": sq}, Workspace((0, 0), 50), [first], (50, 0))
    >>> abs(aim[1]) > 5 or abs(aim[0]) > 5   # off the band the first chord swept
    True
    """
    centre = np.asarray(workspace.center, dtype=float)
    R = workspace.radius
    alpha = np.arange(angles) * math.pi / angles
    normal = np.stack([np.cos(alpha), np.sin(alpha)], axis=1)  # (A, 2)
    lo, hi = _prior_extents(models, workspace, missed, normal, samples)  # (N, A)
    if not len(lo):
        return opening_path(workspace, sensor_position, len(missed)), (
            float(centre[0]),
            float(centre[1]),
        )
    rho = np.linspace(-R, R, offsets + 2)[1:-1]  # (O,)
    # share of the surviving draws met, lo < rho < hi: as lo < hi, the draws with
    # lo < rho less those with hi <= rho (counted on each angle's sorted extents)
    below = np.stack([np.searchsorted(v, rho, side="left") for v in np.sort(lo.T, axis=1)])
    past = np.stack([np.searchsorted(v, rho, side="right") for v in np.sort(hi.T, axis=1)])
    score = ((below - past) / len(lo)).ravel()  # (A * O,)
    a_idx, o_idx = np.divmod(np.arange(score.size), len(rho))
    half = np.sqrt(R**2 - rho[o_idx] ** 2)
    n = normal[a_idx]
    t = np.stack([-n[:, 1], n[:, 0]], axis=1)
    mid = centre + rho[o_idx, None] * n
    # both ways along each chord: origin at one end, heading to the other
    origins = np.concatenate([mid - half[:, None] * t, mid + half[:, None] * t])
    heading = np.concatenate([t, -t])
    cost = motion_cost(origins, np.concatenate([half, half]), workspace, sensor_position)
    best = int(np.lexsort((cost, -np.concatenate([score, score])))[0])
    k = best % len(score)
    path = SensingPath(
        (float(origins[best, 0]), float(origins[best, 1])),
        (float(heading[best, 0]), float(heading[best, 1])),
        float(2 * half[k]),
    )
    return path, (float(mid[k, 0]), float(mid[k, 1]))


def _prior_extents(
    models: Mapping[str, ObjectModel],
    workspace: Workspace,
    missed: Sequence[SensingPath],
    normal: np.ndarray,
    samples: int,
) -> tuple[np.ndarray, np.ndarray]:
    """Least and greatest projection (N, A) on each `normal` (A, 2), relative to the
    centre, of the prior draws of the posed outline that no `missed` path meets.

    A missed path is tested against the outline in the object's frame, for the
    draws it passes near (the free-space check's compiled test: it meets the
    outline when it crosses or touches an edge or lies inside); the extents are
    the draws' own, kept with them."""
    a = np.array([p.origin for p in missed], dtype=float).reshape(-1, 2)  # (M, 2) a -> b
    b = a + np.array([np.multiply(p.length, p.direction) for p in missed]).reshape(-1, 2)
    lo, hi = [], []
    alive = 0
    # after many misses few draws survive and the chord chosen on them is a guess:
    # further fixed batches are drawn until a quarter of one batch survives
    for batch in range(SEARCH_BATCHES):
        if batch and alive >= samples // 4:
            break
        for draws in _prior_draws(models, workspace, samples, normal, batch):
            theta, t = draws.theta, draws.t
            met = np.zeros(len(theta), dtype=bool)
            for start, end in zip(a, b, strict=True):
                # only a path passing within the farthest vertex's reach of the origin can meet
                near = np.flatnonzero(point_segment_distance(t, start, end) <= draws.radius)
                ends = np.stack([start - t[near], end - t[near]], axis=1)  # (k, 2, 2)
                # world offsets into the object's frame
                local = rotate(rotation_matrices(-theta[near]), ends).reshape(-1, 4)
                met[near] |= segments_meet(local, draws.edges)
            lo.append(draws.lo[~met])
            hi.append(draws.hi[~met])
            alive += int((~met).sum())
    return np.concatenate(lo), np.concatenate(hi)


def _support(outline: np.ndarray, phi: np.ndarray) -> np.ndarray:
    """The support function of `outline` at angles `phi` (any shape): the greatest
    projection of its vertices on the unit vector at each angle, found on the convex
    hull by the angle of its faces' outward normals (exact, log of the hull's size).

    >>> sq = np.array([[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]])
    >>> np.round(_support(sq, np.array([0.0, np.pi / 4, np.pi])), 6).tolist()
    [1.0, 1.414214, 1.0]
    """
    hull = _hull(outline)  # counter-clockwise, no repeated vertex
    edge = np.roll(hull, -1, axis=0) - hull
    beta = np.arctan2(-edge[:, 0], edge[:, 1])  # outward normal of face i (hull[i] -> hull[i+1])
    first = int(np.argmin(beta))
    beta = np.roll(beta, -first)  # increasing from its least
    order = (np.arange(len(hull)) + first) % len(hull)
    # vertex i + 1 is extreme between the normals of faces i and i + 1
    x = np.mod(phi - beta[0], 2 * math.pi) + beta[0]
    k = order[(np.searchsorted(beta, x, side="left") - 1) % len(hull)]
    best = hull[(k + 1) % len(hull)]
    return best[..., 0] * np.cos(phi) + best[..., 1] * np.sin(phi)


def _hull(outline: np.ndarray) -> np.ndarray:
    """The convex hull's vertices of `outline`, counter-clockwise."""
    ring = np.asarray(shapely.MultiPoint(outline).convex_hull.exterior.coords)[:-1]
    return ring[::-1] if signed_area(ring) < 0 else ring


@dataclass(frozen=True, eq=False)
class _Draws:
    """Prior draws of one stable pose: its outline's ring `edges` (E, 4) and farthest
    vertex's distance from the model origin (`radius`), the poses
    ``v_world = R(theta) v + t`` (n,) and (n, 2), and each posed outline's least and
    greatest projection (n, A) on the normals, relative to the centre."""

    edges: np.ndarray
    radius: float
    theta: np.ndarray
    t: np.ndarray
    lo: np.ndarray
    hi: np.ndarray


#: Most batches of prior draws the search after misses judges its chords on.
SEARCH_BATCHES = 8

#: Prior draws per (objects' numbers, safe circle, count, batch, normals), for the process:
#: every session on the same parts makes the same fixed draws (a service rebuilds
#: the parts per session, so their identities would never match). A few numbers
#: per draw and normal, whatever the outline; bounded by their total (4 million
#: numbers, 32 MB: a dozen sets of parts at the default 4,096 draws).
_DRAWS: SharedCache[list[_Draws]] = SharedCache(
    4_000_000,
    lambda groups: sum(g.lo.size + g.hi.size + 3 * g.theta.size + g.edges.size for g in groups),
)


def _prior_draws(
    models: Mapping[str, ObjectModel],
    workspace: Workspace,
    samples: int,
    normal: np.ndarray,
    batch: int = 0,
) -> list[_Draws]:
    """`samples` fixed draws of the pose from the prior (the `batch`-th such set),
    grouped by stable pose, with their extents on each `normal` (A, 2) (the convex
    hull's support function)."""
    items = list(models.values())
    weights = [[1.0 if m.prior is None else m.prior] for m in items]
    weights += [[p.probability for p in m.stable_poses] for m in items]
    outlines = [p.outline for m in items for p in m.stable_poses]
    counts = [len(items), *(len(m.stable_poses) for m in items)]
    where = [[*workspace.center, workspace.radius, samples, batch], counts, normal]
    key = array_key([*map(np.asarray, where + weights), *outlines])

    def draw() -> list[_Draws]:
        rng = np.random.default_rng(batch)  # fixed draws: the plan is a function of its inputs
        drawn = Counter(draw_stable_poses(items, samples, rng))
        centre = np.asarray(workspace.center, dtype=float)
        alpha = np.arctan2(normal[:, 1], normal[:, 0])  # (A,)
        groups = []
        for (i, j), n in sorted(drawn.items()):
            stable = items[i].stable_poses[j]
            theta, t = draw_poses(stable, workspace, n, rng)
            # projection of R(theta) v + t - centre on n_a: h(alpha_a - theta) + (t - centre).n_a
            phi = alpha[None, :] - theta[:, None]  # (n, A)
            shift = (t - centre) @ normal.T
            lo = shift - _support(stable.outline, phi + math.pi)
            hi = shift + _support(stable.outline, phi)
            edges = ring_edges(shapely.Polygon(stable.outline))
            groups.append(_Draws(edges, stable.radius, theta, t, lo, hi))
        return groups

    return _DRAWS.get(key, draw)


def _chords(aim: np.ndarray, angles: np.ndarray, workspace: Workspace, source: str) -> Candidates:
    """Paths from origins on the safe circle (at `angles` about the centre) through
    `aim` to the far side of the circle."""
    centre = np.asarray(workspace.center, dtype=float)
    origins = centre + workspace.radius * np.stack([np.cos(angles), np.sin(angles)], axis=1)
    span = aim - origins
    dist = np.hypot(*span.T)
    d = span / np.maximum(dist, 1e-300)[:, None]
    # a chord from o along unit d on the circle |x - c| = R has length 2 d.(c - o)
    lengths = 2 * np.einsum("nk,nk->n", d, centre - origins)
    ok = (dist > LENGTH_SLACK * workspace.radius) & (lengths > LENGTH_SLACK * workspace.radius)
    return Candidates(
        origins[ok],
        d[ok],
        lengths[ok],
        np.repeat(aim[None], ok.sum(), 0),
        np.full(int(ok.sum()), source, dtype="<U12"),
    )


def strategy_paths(
    config: StrategyConfig,
    hypotheses: Sequence[Hypothesis],
    models: Mapping[str, ObjectModel],
    posed: PosedSet,
    contacts: Sequence[Contact],
    workspace: Workspace,
    sensor: SensorBounds,
    sensor_position: Sequence[float],
    rng: np.random.Generator,
) -> Candidates:
    """Candidates a strategy brings of its own: random draws, thesis probes and windows."""
    parallel = _parallel(contacts, sensor)
    if config.name == "random" or (config.name == "thesis" and parallel > 1):
        # thesis Exp. I: a random origin on the safe circle, aimed at the union area's centre
        draws = config.random_draws if config.name == "random" else 1
        angles = rng.uniform(-math.pi, math.pi, draws)
        return _chords(union_centre(posed), angles, workspace, "random")
    if config.name != "thesis":
        return Candidates.empty()
    if parallel == 1:
        return _orthogonal_probe(contacts[0], posed, workspace, sensor_position)
    from planner.image.windows import thesis_paths

    # windows in CHOOSE order: admitted blocking strength, then nearest origin
    try:
        windows = thesis_paths(hypotheses, models, workspace, sensor_position, config.grid_size)
    except PlanningNotPossibleError:  # e.g. an intersection area outside the safe circle
        return Candidates.empty()  # the thesis strategy then falls back, saying so
    return Candidates.from_paths(
        [w.path for w in windows],
        source="window",
        aims=np.array([w.aim for w in windows]).reshape(-1, 2),
        tier=np.array([w.level for w in windows], dtype=int),
    )


def _parallel(contacts: Sequence[Contact], sensor: SensorBounds) -> int:
    """Number of contacts when all their normals are parallel (within 2 phi), else 0."""
    if not contacts:
        return 0
    normals = np.array([c.normal for c in contacts])
    cos_tol = math.cos(2 * sensor.normal_error + 1e-6)
    return len(contacts) if np.all(np.abs(normals @ normals[0]) >= cos_tol) else 0


def _orthogonal_probe(
    contact: Contact, posed: PosedSet, workspace: Workspace, sensor_position: Sequence[float]
) -> Candidates:
    """Thesis §3.1: the second probe runs orthogonal to the first contact normal,
    across the envelope of translations, through the depth of the union's centre."""
    n, p = np.asarray(contact.normal), np.asarray(contact.point)
    depth = max(float((p - union_centre(posed)) @ n), 1e-6 * workspace.radius)
    aim = p - depth * n
    both = np.array([[-n[1], n[0]], [n[1], -n[0]]])
    origins, _, chord = paths_through(np.repeat(aim[None], 2, 0), both, workspace)
    ok = np.isfinite(chord)
    if not ok.any():
        return Candidates.empty()
    cost = motion_cost(np.nan_to_num(origins), np.zeros(2), workspace, sensor_position)
    i = int(np.argmin(np.where(ok, cost, np.inf)))
    return Candidates(
        origins[i : i + 1],
        both[i : i + 1],
        chord[i : i + 1],
        aim[None],
        np.array(["probe"], dtype="<U12"),
    )
