"""Interpretation tree: observations -> posed, weighted hypotheses (DESIGN §4.3-4.7).

Depth = number of contacts; branches = the faces of every stable pose of every
object, plus an optional "spurious" branch (face -1) for at most `max_outliers`
contacts. A new contact extends each surviving partial interpretation only:
constraint checks first (table lookups, :mod:`planner.recognition.constraints`), then the
model check on the fitted pose (:mod:`planner.recognition.pose_fit`): every contact on its FINITE
face within ``eps_d + eps_t/2`` and its normal within ``phi + |dtheta|``; the path
up to each contact (less ``eps_d``), and every missed path whole, outside the
posed outline shrunk by ``eps_t/2``; optionally the outline inside the safe circle.

Interpretations whose faces are all parallel leave the translation free along
the faces: the family's feasible slide interval is sampled at a spacing of about
``eps_t`` (at most `max_family_samples`); each sample's error bound covers half
its cell and its weight carries the cell length.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Literal

import numpy as np
import shapely

from planner.geometry import (
    ANGLE_SLACK,
    LENGTH_SLACK,
    SHARE_SLACK,
    point_segment_distance,
    rotation_matrices,
    wrap_angle,
)
from planner.memo import cached_property
from planner.recognition.consistent import (
    consistent_poses,
    consistent_set_bounds,
    consistent_volume,
)
from planner.recognition.constraints import (
    ConstraintTables,
    build_tables,
    pair_feasibility,
    unary_feasibility,
)
from planner.recognition.pose_fit import fit_batch, noise_scales, point_bounds, worst_case_bounds
from planner.types import Contact, ObjectModel, Observation, SensorBounds, StablePose, Workspace

__all__ = ["Group", "PoseSamples", "RecognitionConfig", "TreeLevel", "evaluate", "extend"]


@dataclass(frozen=True)
class RecognitionConfig:
    """Knobs of recognition; the defaults follow DESIGN §4."""

    max_outliers: int = 0
    outlier_probability: float = 0.05
    bound_mode: Literal["linearized", "thesis"] = "linearized"
    thesis_fraction: float = 0.10
    likelihood: Literal["bounded", "gaussian"] = "bounded"
    max_family_samples: int = 16
    require_inside_workspace: bool = True
    normal_z_error: float = 0.1

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
        return build_tables(self.stable.faces)

    def shrunk(self, tol: float) -> shapely.Geometry:
        """The model outline shrunk by `tol` (cached per tolerance bucket), prepared."""
        cache = self.__dict__.setdefault("_shrunk", {})
        if tol not in cache:
            geom = (
                self.stable.shape.buffer(-tol, join_style="mitre") if tol > 0 else self.stable.shape
            )
            shapely.prepare(geom)
            cache[tol] = geom
        return cache[tol]


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
    spurious), plus the pair-feasibility matrices computed so far, keyed (group, j, k)."""

    rows: tuple[np.ndarray, ...]
    pair_cache: dict[tuple[int, int, int], np.ndarray] = field(default_factory=dict)


def extend(
    level: TreeLevel,
    groups: list[Group],
    contacts: list[Contact],
    bounds: SensorBounds,
    config: RecognitionConfig,
) -> TreeLevel:
    """Extend every surviving row by the newest contact (constraint checks only)."""
    k = len(contacts) - 1
    new = contacts[k]
    cache = dict(level.pair_cache)
    out = []
    for g, (group, rows) in enumerate(zip(groups, level.rows, strict=True)):
        F = len(group.stable.faces)
        ok = np.broadcast_to(
            unary_feasibility(group.stable, new, config.normal_z_error), (len(rows), F)
        ).copy()
        for j in range(k):
            key = (g, j, k)
            if key not in cache:
                cache[key] = pair_feasibility(
                    group.tables, contacts[j], new, bounds.position_error, bounds.normal_error
                )
            col = rows[:, j]
            ok &= np.where(col[:, None] >= 0, cache[key][np.maximum(col, 0)], True)
        parent, face = np.nonzero(ok)
        grown = [np.column_stack([rows[parent], face])]
        outliers = (rows < 0).sum(axis=1)
        spare = np.flatnonzero(outliers < config.max_outliers)
        if spare.size:
            grown.append(np.column_stack([rows[spare], np.full(spare.size, -1)]))
        out.append(np.concatenate(grown).astype(np.int64))
    return TreeLevel(rows=tuple(out), pair_cache=cache)


@dataclass(frozen=True, eq=False)
class PoseSamples:
    """Posed samples of the surviving interpretations of one group (arrays, length N)."""

    group: int
    row: np.ndarray  # index into the group's rows
    theta: np.ndarray
    t: np.ndarray  # (N, 2)
    d_translation: np.ndarray  # |dt| bound of the pose translation
    d_theta: np.ndarray
    eps_t: np.ndarray
    cell: np.ndarray  # slide cell length of a family sample (0 when the pose is determined)
    weight: np.ndarray  # unnormalized posterior weight


_TURN = np.array([[0.0, -1.0], [1.0, 0.0]])  # +90 degrees
#: Least share of the consistent set a determined pose keeps in its weight.
_FITNESS_FLOOR = 1e-6


def _no_samples(group_index: int) -> PoseSamples:
    none = np.zeros(0)
    return PoseSamples(
        group_index, np.zeros(0, np.int64), none, np.zeros((0, 2)), none, none, none, none, none
    )


def _fitness(
    P: np.ndarray,
    U: np.ndarray,
    faces,
    face: np.ndarray,
    assigned: np.ndarray,
    theta: np.ndarray,
    t: np.ndarray,
    eps_d: float,
    phi: float,
) -> np.ndarray:
    """(K,) volume of the poses consistent with the contacts as measured, over
    that with the same contacts moved onto the fitted pose's faces: 1 when the
    contacts fit exactly, less as they lie nearer the edges of their bounds.
    The bounded-error likelihood (uniform errors) is that volume; the pose's
    Laplace volume carries the geometry, this ratio the residuals. 1 where the
    volume is not known (exact sensing, unbounded, or empty when centred). Never
    below `_FITNESS_FLOOR`: a weight, not a test (a pose consistent only between
    the sampled rotations keeps a small weight; pruning is the bounds' business)."""
    normal, offset = faces.normal[face], faces.offset[face]  # (K, s, 2), (K, s)
    # the fitted pose's faces in the world: n_w . y = d + n_w . t
    n_w = np.einsum("kij,ksj->ksi", rotation_matrices(theta), normal)
    d_w = offset + np.einsum("ksi,ki->ks", n_w, t)
    resid = np.einsum("ksi,si->ks", n_w, P) - d_w
    centred = P[None] - resid[..., None] * n_w
    measured = consistent_volume(P, U, normal, offset, assigned, theta, eps_d, phi)
    ideal = consistent_volume(centred, n_w, normal, offset, assigned, theta, eps_d, phi)
    known = np.isfinite(measured) & np.isfinite(ideal) & (ideal > 0)
    ratio = np.clip(measured / np.where(known, ideal, 1.0), _FITNESS_FLOOR, 1.0)
    return np.where(known, ratio, 1.0)


def _admitted_share(
    group: Group,
    observations: list[Observation],
    P: np.ndarray,
    face: np.ndarray,
    assigned: np.ndarray,
    theta: np.ndarray,
    t: np.ndarray,
    valid: np.ndarray,
    eps_d: float,
    floor: float,
) -> np.ndarray:
    """(K,) share of the poses spread over each row's consistent set (`theta`,
    `t`, `valid`: (K, M), (K, M, 2), (K, M)) whose contacts lie within eps_d of
    their FINITE faces and whose paths (up to each contact less eps_d, or whole
    when missed) stay out of the outline: the model check without the pose's
    error allowance. It weighs, it does not prune (at least `_FITNESS_FLOOR`;
    1 where no pose is spread)."""
    K, M = valid.shape
    faces = group.stable.faces
    R = rotation_matrices(theta.reshape(-1)).reshape(K, M, 2, 2)
    start = np.einsum("kmij,ksj->kmsi", R, faces.start[face]) + t[:, :, None, :]
    end = np.einsum("kmij,ksj->kmsi", R, faces.end[face]) + t[:, :, None, :]
    dist = point_segment_distance(P[None, None], start, end)  # (K, M, s)
    good = valid & np.all(~assigned[:, None, :] | (dist <= eps_d + floor), axis=-1)
    clear = _clear_paths(
        group,
        observations,
        np.repeat(assigned, M, axis=0),
        theta.reshape(-1),
        t.reshape(-1, 2),
        np.full(K * M, floor),
        good.reshape(-1),
        eps_d,
        floor,
    )
    good = clear.reshape(K, M)
    count = valid.sum(axis=1)
    share = good.sum(axis=1) / np.maximum(count, 1)
    return np.where(count > 0, np.maximum(share, _FITNESS_FLOOR), 1.0)


def _clear_paths(
    group: Group,
    observations: list[Observation],
    assigned: np.ndarray,
    theta: np.ndarray,
    t: np.ndarray,
    shrink: np.ndarray,
    keep: np.ndarray,
    back: float,
    floor: float,
) -> np.ndarray:
    """`keep` (N,) and, for each pose (`theta`, `t`, N rows), every path clear of
    the posed outline shrunk by `shrink`: up to each contact the row assigns
    (`assigned` (N, s)), less `back`, and each missed path whole."""
    keep = keep.copy()
    contact_col = 0
    for obs in observations:
        o, d = np.asarray(obs.path.origin), np.asarray(obs.path.direction)
        if obs.contact is None:
            reach_len = obs.path.length
            check = keep.copy()
        else:
            reach_len = float((np.asarray(obs.contact.point) - o) @ d) - back
            check = keep & assigned[:, contact_col]
            contact_col += 1
        idx = np.flatnonzero(check)
        if idx.size:
            keep[idx] &= _free_space_ok(
                group, theta[idx], t[idx], shrink[idx], o, d, reach_len, floor
            )
    return keep


def _tol_bucket(tol: np.ndarray, floor: float) -> np.ndarray:
    """Round tolerances UP onto a geometric grid (sound: a larger shrink is more lenient)."""
    tol = np.maximum(tol, floor)
    return floor * 1.15 ** np.ceil(np.log(tol / floor) / math.log(1.15) - SHARE_SLACK)


def _free_space_ok(
    group: Group,
    theta: np.ndarray,
    t: np.ndarray,
    shrink: np.ndarray,
    origin: np.ndarray,
    direction: np.ndarray,
    length: float,
    floor: float,
) -> np.ndarray:
    """Does the segment origin -> origin + length*direction avoid the posed outline
    shrunk by `shrink` (per sample)? Checked in the model frame, vectorized."""
    if length <= 0:
        return np.ones(len(theta), dtype=bool)
    R = rotation_matrices(theta)
    a = np.einsum("nji,nj->ni", R, origin - t)
    b = np.einsum("nji,nj->ni", R, origin + length * direction - t)
    lines = shapely.linestrings(np.stack([a, b], axis=1))
    bucket = _tol_bucket(shrink, floor)
    ok = np.ones(len(theta), dtype=bool)
    for value in np.unique(bucket):
        idx = np.flatnonzero(bucket == value)
        ok[idx] = ~shapely.intersects(lines[idx], group.shrunk(float(value)))
    return ok


def evaluate(
    group_index: int,
    group: Group,
    rows: np.ndarray,
    observations: list[Observation],
    bounds: SensorBounds,
    workspace: Workspace,
    config: RecognitionConfig,
    length_scale: float,
) -> PoseSamples:
    """Fit, sample and model-check every row of one group against all observations."""
    eps_d, phi = bounds.position_error, bounds.normal_error
    stable = group.stable
    faces = stable.faces
    slack = LENGTH_SLACK * length_scale * 10
    contact_obs = [o for o in observations if o.contact is not None]
    assigned = rows >= 0
    keep = np.flatnonzero(assigned.any(axis=1)) if rows.size else np.zeros(0, np.int64)
    if keep.size == 0 or not contact_obs:
        return _no_samples(group_index)
    rows, assigned = rows[keep], assigned[keep]
    face = np.maximum(rows, 0)
    P = np.array([o.contact.point for o in contact_obs])  # type: ignore[union-attr]
    U = np.array([o.contact.normal for o in contact_obs])  # type: ignore[union-attr]
    psi = np.arctan2(U[:, 1], U[:, 0])

    # rotation gate: every angle(u_j) - angle(n_a) within 2 phi of their circular mean
    delta = wrap_angle(psi[None, :] - faces.angle[face])
    mean = np.arctan2((np.sin(delta) * assigned).sum(1), (np.cos(delta) * assigned).sum(1))
    gate = np.all(
        ~assigned | (np.abs(wrap_angle(delta - mean[:, None])) <= 2 * phi + ANGLE_SLACK), 1
    )
    rows, assigned, face, keep = rows[gate], assigned[gate], face[gate], keep[gate]
    if rows.shape[0] == 0:
        return _no_samples(group_index)

    sigma_d, sigma_phi = noise_scales(eps_d, phi, length_scale)
    ref = np.broadcast_to(stable.centroid, (len(rows), 2))
    fit = fit_batch(P, U, faces.normal[face], faces.offset[face], assigned, ref, sigma_d, sigma_phi)
    r_c = stable.centroid_radius
    # rank-1 families slide along e (model frame): t(s) = t0 + s slide, so a model point v
    # of the sample at s sits where the point v - s e / rho sits at s = 0
    R = rotation_matrices(fit.theta)
    rho = np.hypot(fit.z[:, 0], fit.z[:, 1])
    e = faces.normal[face[np.arange(len(rows)), np.argmax(assigned, 1)]] @ _TURN.T
    m0 = np.einsum("kji,ksj->ksi", R, P[None] - fit.t[:, None, :])  # contacts' model points
    origin_and_outline = np.vstack([[0.0, 0.0], stable.outline])
    linearized = config.bound_mode != "thesis"
    if linearized:
        _, d_th = worst_case_bounds(fit.sens, assigned, eps_d, phi)
        # second-order allowance for the linearization: rotations by up to phi
        second = (phi**2) * r_c + phi * eps_d
        d_th = d_th * (1 + phi) + phi**2
        # first-order worst case at every outline vertex (at s = 0: for the sample spacing)
        moved = point_bounds(fit, stable.outline, assigned, eps_d, phi)
        eps_t0 = 2 * (moved.max(axis=1) * (1 + phi) + second)
        # a contact's own model point moves by at most this: its slide margin
        at_contact = point_bounds(fit, m0, assigned, eps_d, phi)
        margin = eps_d + at_contact * (1 + phi) + second + slack
    else:
        eps_t0 = np.full(len(rows), config.thesis_fraction * 2 * r_c)
        d_th = eps_t0 / (2 * r_c)
        margin = np.broadcast_to((eps_d + eps_t0 / 2 + slack)[:, None], assigned.shape)

    # rank-1 families: feasible slide interval (each contact on its finite face), sampled
    fdir = faces.direction[face]
    mu0 = np.einsum("ksi,ksi->ks", m0 - faces.start[face], fdir)
    rate = np.einsum("ki,ksi->ks", e, fdir) / rho[:, None]  # d mu / d s (= ±1/rho)
    lo_mu, hi_mu = -margin, faces.length[face] + margin
    with np.errstate(divide="ignore", invalid="ignore"):
        s_a, s_b = (lo_mu - mu0) / rate, (hi_mu - mu0) / rate
    s_lo = np.where(assigned, np.minimum(s_a, s_b), -np.inf).max(1)
    s_hi = np.where(assigned, np.maximum(s_a, s_b), np.inf).min(1)
    family = ~fit.rank2
    alive = fit.rank2 | (s_hi >= s_lo)
    span = np.where(family & alive, s_hi - s_lo, 0.0)
    # the family's weight carries its nominal span (no margin); the margin only places samples
    with np.errstate(divide="ignore", invalid="ignore"):
        n_a, n_b = (0.0 - mu0) / rate, (faces.length[face] - mu0) / rate
    nominal = np.where(assigned, np.maximum(n_a, n_b), np.inf).min(1) - np.where(
        assigned, np.minimum(n_a, n_b), -np.inf
    ).max(1)
    nominal = np.clip(nominal, np.minimum(span, eps_t0), span)
    span_scale = np.where(span > 0, nominal / np.where(span > 0, span, 1.0), 1.0)
    n = np.where(
        family,
        np.clip(
            np.ceil(span / np.maximum(eps_t0, 1e-12 * length_scale)), 1, config.max_family_samples
        ),
        1,
    ).astype(np.int64)
    n = np.where(alive, n, 0)
    cell = np.where(family, span / np.maximum(n, 1), 0.0)

    src = np.repeat(np.arange(len(rows)), n)
    offset = np.arange(len(src)) - np.repeat(np.cumsum(n) - n, n)
    s_val = np.where(family[src], s_lo[src] + (offset + 0.5) * cell[src], 0.0)
    theta = fit.theta[src]
    t = fit.t[src] + s_val[:, None] * fit.slide[src]
    ok = np.ones(len(src), dtype=bool)
    fitness = np.ones(len(src))  # determined poses: share of the consistent set the errors left
    spread, spread_rows = None, None  # poses spread over each determined row's consistent set
    if linearized:
        shift = (s_val / rho[src])[:, None, None] * e[src][:, None, :]
        moved = point_bounds(fit, origin_and_outline[None] - shift, assigned, eps_d, phi, src)
        moved = moved * (1 + phi) + second
        d_theta = d_th[src]
        # determined poses: the set of poses consistent with every contact is often far
        # smaller than the estimator's worst case (errors do not add up); keep the smaller
        det = np.flatnonzero(fit.rank2)
        if det.size:
            found = consistent_set_bounds(
                P,
                U,
                faces.normal[face[det]],
                faces.offset[face[det]],
                assigned[det],
                fit.theta[det],
                fit.t[det],
                origin_and_outline,
                eps_d,
                phi,
            )
            at = np.flatnonzero(fit.rank2[src])  # rank-2 rows have one sample each
            pos = np.searchsorted(det, src[at])
            moved[at] = np.minimum(moved[at], found.moved[pos] + slack)
            d_theta[at] = np.minimum(d_theta[at], found.dtheta[pos] + ANGLE_SLACK)
            # no pose keeps every contact within its bounds: the interpretation is out
            ok[at] &= found.feasible[pos]
            fitness[at] = _fitness(
                P, U, faces, face[det], assigned[det], fit.theta[det], fit.t[det], eps_d, phi
            )[pos]
            spread = consistent_poses(
                P,
                U,
                faces.normal[face[det]],
                faces.offset[face[det]],
                assigned[det],
                fit.theta[det],
                eps_d,
                phi,
            )
            spread_rows = (at, pos)
        eps_t = 2 * moved[:, 1:].max(axis=1) + cell[src]
        d_translation = moved[:, 0] + cell[src] / 2
    else:
        eps_t = eps_t0[src] + cell[src]
        d_translation = eps_t0[src] / 2 + np.hypot(*stable.centroid) * d_th[src] + cell[src] / 2
        d_theta = d_th[src]

    # model check: each contact on its finite posed face, normal within phi + dtheta
    Rs = rotation_matrices(theta)
    f_src = face[src]
    start = np.einsum("nij,nsj->nsi", Rs, faces.start[f_src]) + t[:, None, :]
    end = np.einsum("nij,nsj->nsi", Rs, faces.end[f_src]) + t[:, None, :]
    dist = point_segment_distance(P[None], start, end)
    a_src = assigned[src]
    ok &= np.all(~a_src | (dist <= eps_d + eps_t[:, None] / 2 + slack), axis=1)
    ang = np.abs(wrap_angle(psi[None, :] - theta[:, None] - faces.angle[f_src]))
    ok &= np.all(~a_src | (ang <= phi + d_theta[:, None] + ANGLE_SLACK), axis=1)

    # optional: the posed outline inside the safe circle
    if config.require_inside_workspace:
        verts = np.einsum("nij,vj->nvi", Rs, stable.outline) + t[:, None, :]
        reach = np.hypot(*(verts - np.asarray(workspace.center)).transpose(2, 0, 1)).max(1)
        ok &= reach <= workspace.radius + eps_t / 2 + slack

    # free space: path up to each contact (less eps_d), and each missed path whole
    floor = max(slack, LENGTH_SLACK)
    shrink = eps_t / 2 + slack
    ok = _clear_paths(group, observations, a_src, theta, t, shrink, ok, eps_d + slack, floor)

    # determined poses: the share of their consistent set that also keeps every
    # contact on its finite face and every path clear of the outline, exactly
    if spread is not None:
        at, pos = spread_rows
        live = np.flatnonzero(ok[at])
        if live.size:
            fitness[at[live]] *= _admitted_share(
                group,
                observations,
                P,
                face[src[at[live]]],
                assigned[src[at[live]]],
                spread[0][pos[live]],
                spread[1][pos[live]],
                spread[2][pos[live]],
                eps_d,
                floor,
            )

    # weight = prior x incidence likelihood x pose volume (x Gaussian residual term)
    world_n = np.einsum("nij,nsj->nsi", Rs, faces.normal[f_src])
    dirs = np.array([o.path.direction for o in contact_obs])
    incidence = np.where(a_src, np.abs(np.einsum("nsi,si->ns", world_n, dirs)), 1.0).prod(1)
    volume = np.sqrt(np.maximum(np.linalg.det(fit.cov), 0.0))[src]
    volume = np.where(family[src], volume * cell[src] * span_scale[src] / sigma_d, volume)
    weight = group.prior * incidence * volume * fitness
    weight *= config.outlier_probability ** (~a_src).sum(axis=1)
    if config.likelihood == "gaussian":
        weight *= np.exp(-0.5 * fit.chi2[src])

    sel = np.flatnonzero(ok & (weight > 0))
    return PoseSamples(
        group=group_index,
        row=keep[src[sel]],
        theta=theta[sel],
        t=t[sel],
        d_translation=d_translation[sel],
        d_theta=d_theta[sel],
        eps_t=eps_t[sel],
        cell=cell[src[sel]],
        weight=weight[sel],
    )
