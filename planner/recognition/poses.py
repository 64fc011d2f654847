"""Poses of interpretations: rotation gate, pose fit, error bounds and slide-family
samples (DESIGN §4.4, §4.6).

Each step works on K surviving rows at once, of one group (a stable pose of an
object) or of several with their faces in one table (:class:`RowShapes`,
:class:`RowOutlines` say which stable pose each row has): `face` (K, s) the face
each row assigns to each of the s contacts (0 where spurious), `assigned` (K, s)
which contacts it assigns; `points`, `normals` (s, 2) the measured contacts
(world frame).

Interpretations whose faces are all parallel leave the translation free along
the faces: the family's feasible slide interval is sampled at a spacing of about
``eps_t`` (at most `max_family_samples`); each sample's error bound covers half
its cell and its weight carries the cell length.

Lengths in the object files' unit, angles in radians (counter-clockwise
positive); a pose maps model points v to ``R(theta) v + t``.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from planner.geometry import ANGLE_SLACK, rotate, rotation_matrices, wrap_angle
from planner.recognition.config import RecognitionConfig
from planner.recognition.consistent import consistent_set_bounds
from planner.recognition.pose_fit import (
    FitBatch,
    fit_batch,
    noise_scales,
    point_bounds,
    worst_rotation,
)
from planner.types import Faces, StablePose

__all__ = [
    "FitBounds",
    "PoseFit",
    "RowOutlines",
    "RowShapes",
    "SampleBounds",
    "SlideSamples",
    "determined_rows",
    "fit_bounds",
    "fit_poses",
    "fit_poses_of_groups",
    "rotation_gate",
    "sample_bounds",
    "slide_samples",
]

_TURN = np.array([[0.0, -1.0], [1.0, 0.0]])  # +90 degrees


def rotation_gate(
    psi: np.ndarray, face_angle: np.ndarray, assigned: np.ndarray, phi: float
) -> np.ndarray:
    """(K,) can one rotation turn every assigned face normal onto its contact's?

    `psi` (s,) the measured normals' angles (or (K, s), each row's own),
    `face_angle` (K, s) the assigned
    faces' normal angles (model frame), `phi` the normal error bound (radians).
    """
    # rotation gate: every angle(u_j) - angle(n_a) within 2 phi of their circular mean
    delta = wrap_angle(np.atleast_2d(psi) - face_angle)
    mean = np.arctan2((np.sin(delta) * assigned).sum(1), (np.cos(delta) * assigned).sum(1))
    return np.all(
        ~assigned | (np.abs(wrap_angle(delta - mean[:, None])) <= 2 * phi + ANGLE_SLACK), 1
    )


@dataclass(frozen=True, eq=False)
class PoseFit:
    """The fit of K rows (:class:`planner.recognition.pose_fit.FitBatch`) with what
    sampling their slide families needs: `sigma_d` the position scale the rows were
    weighted at, `slide_axis` (K, 2) the face direction e (model frame) a rank-1
    row slides along, `rho` (K,) the lifted scale |(c, s)|, and `model_points`
    (K, s, 2) the contacts' model points at the fit."""

    fit: FitBatch
    sigma_d: float
    slide_axis: np.ndarray
    rho: np.ndarray
    model_points: np.ndarray

    def part(self, rows: slice) -> PoseFit:
        """The fit of some rows (views, not copies)."""
        fit = FitBatch(*(getattr(self.fit, f.name)[rows] for f in dataclasses.fields(FitBatch)))
        return PoseFit(
            fit, self.sigma_d, self.slide_axis[rows], self.rho[rows], self.model_points[rows]
        )


def fit_poses(
    stable: StablePose,
    points: np.ndarray,
    normals: np.ndarray,
    face: np.ndarray,
    assigned: np.ndarray,
    eps_d: float,
    phi: float,
    length_scale: float,
) -> PoseFit:
    """Least-squares pose of every row over its assigned contacts (DESIGN §4.4),
    the bounds' reference point at the outline's centroid; rank-1 rows pinned at
    slide coordinate 0."""
    return fit_poses_of_groups(
        [stable], points, normals, [face], [assigned], eps_d, phi, length_scale
    )


def fit_poses_of_groups(
    stables: Sequence[StablePose],
    points: np.ndarray,
    normals: np.ndarray,
    faces: Sequence[np.ndarray],
    assigned: Sequence[np.ndarray],
    eps_d: float,
    phi: float,
    length_scale: float,
) -> PoseFit:
    """:func:`fit_poses` of the rows of several groups (`faces`, `assigned` (K_g, s)
    per stable pose), stacked in their order, in one pass: every row's fit is its
    own, so each group's rows get the numbers a pass over them alone gives, without
    a pass's fixed cost per group."""
    sigma_d, sigma_phi = noise_scales(eps_d, phi, length_scale)
    counts = [len(f) for f in faces]
    normal = np.concatenate([s.all_faces.normal[f] for s, f in zip(stables, faces, strict=True)])
    offset = np.concatenate([s.all_faces.offset[f] for s, f in zip(stables, faces, strict=True)])
    ref = np.concatenate(
        [np.broadcast_to(s.centroid, (n, 2)) for s, n in zip(stables, counts, strict=True)]
    )
    used = np.concatenate(assigned)
    fit = fit_batch(points, normals, normal, offset, used, ref, sigma_d, sigma_phi)
    # rank-1 families slide along e (model frame): t(s) = t0 + s slide, so a model point v
    # of the sample at s sits where the point v - s e / rho sits at s = 0
    R = rotation_matrices(fit.theta)
    rho = np.hypot(fit.z[:, 0], fit.z[:, 1])
    e = normal[np.arange(len(used)), np.argmax(used, 1)] @ _TURN.T
    per_row = points if points.ndim == 3 else points[None]
    m0 = rotate(R.transpose(0, 2, 1), per_row - fit.t[:, None, :])  # contacts' model points
    return PoseFit(fit=fit, sigma_d=sigma_d, slide_axis=e, rho=rho, model_points=m0)


@dataclass(frozen=True, eq=False)
class RowShapes:
    """What the fit bounds need of each row's stable pose (K rows): the
    `centroid_radius` (K,) and the outline's vertices `extent` (K, P, 2), padded
    with copies of a vertex of the row's own outline (a largest displacement over
    them is the same)."""

    centroid_radius: np.ndarray
    extent: np.ndarray

    @classmethod
    def of(cls, stables: Sequence[StablePose], counts: Sequence[int]) -> RowShapes:
        """`counts[g]` rows of stable pose `stables[g]`, stacked in order."""
        most = max(len(p.extent) for p in stables)
        padded = np.array(
            [np.vstack([p.extent, p.extent[-1:].repeat(most - len(p.extent), 0)]) for p in stables]
        )
        which = np.repeat(np.arange(len(stables)), counts)
        radius = np.array([p.centroid_radius for p in stables], dtype=float)
        return cls(radius[which], padded[which])


@dataclass(frozen=True, eq=False)
class RowOutlines:
    """What the sample bounds need of each row's stable pose (K rows): `points`
    (K, 1 + F, 2) the model origin then every face's start (the outline's
    vertices among them), `ends` (K, F) each face's end face
    (:attr:`~planner.types.StablePose.face_ends`), `first` (K,) where the stable
    pose's faces begin in the table the rows' face numbers index, and
    `centroid_norm` (K,) the centroid's distance from the model origin. Stable
    poses with fewer faces repeat their last face (its start again, itself as its
    end): a largest move over the faces is the same, and no repeated face has two
    bounds crossing along it."""

    points: np.ndarray
    ends: np.ndarray
    first: np.ndarray
    centroid_norm: np.ndarray

    @classmethod
    def of(
        cls, stables: Sequence[StablePose], counts: Sequence[int], start: int = 0
    ) -> RowOutlines:
        """`counts[g]` rows of stable pose `stables[g]`, stacked in order; the
        stable poses' faces stacked in the same order from `start` on."""
        sizes = [len(p.all_faces.start) for p in stables]
        most = max(sizes)
        points = np.zeros((len(stables), 1 + most, 2))
        ends = np.tile(np.arange(most), (len(stables), 1))
        for g, (p, n) in enumerate(zip(stables, sizes, strict=True)):
            points[g, 1 : 1 + n] = p.all_faces.start
            points[g, 1 + n :] = p.all_faces.start[-1]
            ends[g, :n] = p.face_ends
        which = np.repeat(np.arange(len(stables)), counts)
        first = start + np.cumsum([0, *sizes[:-1]])
        norm = np.array([np.hypot(*p.centroid) for p in stables], dtype=float)
        return cls(points[which], ends[which], first[which], norm[which])


@dataclass(frozen=True, eq=False)
class FitBounds:
    """Error bounds of each row's fit at slide coordinate 0 (K rows): `eps_t` the
    error-disk diameter (length), `d_theta` the rotation bound (radians), `margin`
    (K, s) how far each contact may lie beyond its face's ends, and `second` (K,)
    the second-order allowance of the linearization (0 in `thesis` mode)."""

    eps_t: np.ndarray
    d_theta: np.ndarray
    margin: np.ndarray
    second: np.ndarray

    def part(self, rows: slice) -> FitBounds:
        """The bounds of some rows."""
        return FitBounds(self.eps_t[rows], self.d_theta[rows], self.margin[rows], self.second[rows])


def fit_bounds(
    pose: PoseFit,
    shapes: RowShapes,
    assigned: np.ndarray,
    eps_d: float,
    phi: float,
    config: RecognitionConfig,
    slack: float,
) -> FitBounds:
    """Error bounds of the fits (DESIGN §4.4): `linearized`, the worst case of the
    first-order sensitivities to errors within (eps_d, phi), plus a second-order
    allowance; `thesis`, a fixed error disk of `thesis_fraction` of the effective
    diameter. `shapes`: each row's stable pose."""
    fit = pose.fit
    r_c = shapes.centroid_radius
    if config.bound_mode != "thesis":
        d_th = worst_rotation(fit.sens, assigned, eps_d, phi)
        # second-order allowance for the linearization: rotations by up to phi
        second = (phi**2) * r_c + phi * eps_d
        d_th = d_th * (1 + phi) + phi**2
        # first-order worst case at every outline vertex (at s = 0: for the sample spacing)
        moved = point_bounds(fit, shapes.extent, assigned, eps_d, phi)
        eps_t0 = 2 * (moved.max(axis=1) * (1 + phi) + second)
        # a contact's own model point moves by at most this: its slide margin
        at_contact = point_bounds(fit, pose.model_points, assigned, eps_d, phi)
        margin = eps_d + at_contact * (1 + phi) + second[:, None] + slack
    else:
        second = np.zeros(len(fit.theta))
        eps_t0 = config.thesis_fraction * 2 * r_c
        d_th = eps_t0 / (2 * r_c)
        margin = np.broadcast_to((eps_d + eps_t0 / 2 + slack)[:, None], assigned.shape)
    return FitBounds(eps_t=eps_t0, d_theta=d_th, margin=margin, second=second)


def _face_moves(
    ends: np.ndarray,
    face: np.ndarray,
    assigned: np.ndarray,
    linear: np.ndarray,
    consistent: np.ndarray,
) -> np.ndarray:
    """(N, s, 2, 2) how far the start and the end of each contact's face may move,
    by each of the two bounds (`linear`, `consistent` (N, 1 + F): the origin, then
    every face's start; inf where a bound is not known): ``[n, j, bound, end]``.
    `ends` (N, F) each face's end face (:attr:`~planner.types.StablePose.face_ends`
    of the row's stable pose). Each bound is convex along a face, so values
    interpolated between its ends bound its points (the smaller of the two taken
    end by end would not); 0 where the contact is not assigned."""
    on = np.where(assigned, face, 0)
    ends = np.stack([on, np.take_along_axis(ends, on, axis=1)], axis=-1)  # (N, s, 2) vertices
    rows = np.arange(len(face))[:, None, None]
    both = np.stack([linear[rows, 1 + ends], consistent[rows, 1 + ends]], axis=2)
    return np.where(assigned[..., None, None], both, 0.0)


def _outline_move(ends: np.ndarray, linear: np.ndarray, consistent: np.ndarray) -> np.ndarray:
    """(N,) how far any point of the outline may move: the smaller of the two bounds
    at every face's ends, and where the bounds cross along a face (each convex
    along it, both interpolated), the value at the crossing. `ends` (F,) or (N, F)
    each face's end face."""
    lin, con = linear[:, 1:], consistent[:, 1:]
    farthest = np.minimum(lin, con).max(axis=1)
    ends = np.broadcast_to(ends, lin.shape)
    gap = lin - con  # -inf where the consistent bound is not known
    at_end = np.take_along_axis(gap, ends, axis=1)
    cross = np.isfinite(gap) & np.isfinite(at_end) & (gap * at_end < 0)
    if cross.any():
        n, f = np.nonzero(cross)
        e = ends[n, f]
        u = gap[n, f] / (gap[n, f] - gap[n, e])
        value = lin[n, f] + u * (lin[n, e] - lin[n, f])
        np.maximum.at(farthest, n, value)
    return farthest


@dataclass(frozen=True, eq=False)
class SlideSamples:
    """Posed samples of K rows (N samples): `src` (N,) the row of each sample, `s`
    (N,) its slide coordinate (0 for a determined pose), `theta` (N,), `t` (N, 2)
    its pose; per row (K,): `family` (rank 1: the translation slides), `cell` the
    slide cell length of its samples (0 when the pose is determined) and
    `span_scale` the share of the sampled span its nominal span (no margin) is."""

    src: np.ndarray
    s: np.ndarray
    theta: np.ndarray
    t: np.ndarray
    family: np.ndarray
    cell: np.ndarray
    span_scale: np.ndarray

    def part(self, rows: slice, samples: slice) -> SlideSamples:
        """The samples `samples` of the rows `rows` (which drew them), rows
        numbered from the first of `rows`."""
        return SlideSamples(
            self.src[samples] - rows.start,
            self.s[samples],
            self.theta[samples],
            self.t[samples],
            self.family[rows],
            self.cell[rows],
            self.span_scale[rows],
        )


def slide_samples(
    pose: PoseFit,
    faces: Faces,
    face: np.ndarray,
    assigned: np.ndarray,
    margin: np.ndarray,
    eps_t: np.ndarray,
    max_samples: int,
    length_scale: float,
) -> SlideSamples:
    """One sample per determined row; for rank-1 rows (DESIGN §4.6) the slide
    interval keeping every contact on its finite face (widened by `margin` (K, s)),
    cut into at most `max_samples` cells of about `eps_t` (K,), a sample at each
    cell's middle. Rows whose interval is empty get no sample."""
    fit, e, rho, m0 = pose.fit, pose.slide_axis, pose.rho, pose.model_points
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
    nominal = np.clip(nominal, np.minimum(span, eps_t), span)
    span_scale = np.where(span > 0, nominal / np.where(span > 0, span, 1.0), 1.0)
    n = np.where(
        family,
        np.clip(np.ceil(span / np.maximum(eps_t, 1e-12 * length_scale)), 1, max_samples),
        1,
    ).astype(np.int64)
    n = np.where(alive, n, 0)
    cell = np.where(family, span / np.maximum(n, 1), 0.0)

    src = np.repeat(np.arange(len(face)), n)
    offset = np.arange(len(src)) - np.repeat(np.cumsum(n) - n, n)
    s_val = np.where(family[src], s_lo[src] + (offset + 0.5) * cell[src], 0.0)
    theta = fit.theta[src]
    t = fit.t[src] + s_val[:, None] * fit.slide[src]
    return SlideSamples(
        src=src, s=s_val, theta=theta, t=t, family=family, cell=cell, span_scale=span_scale
    )


def determined_rows(fit: FitBatch, src: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The determined (rank-2) rows `det` of a fit and, for the samples drawn from
    them (`src` (N,) the row of each sample), `at` their sample indices and `pos`
    their places in `det` (a rank-2 row has one sample)."""
    det = np.flatnonzero(fit.rank2)
    at = np.flatnonzero(fit.rank2[src])
    pos = np.searchsorted(det, src[at])
    return det, at, pos


@dataclass(frozen=True, eq=False)
class SampleBounds:
    """Error bounds of each sample (N,): `d_translation` the |dt| bound of the pose
    translation, `d_theta` (radians), `eps_t` the error-disk diameter swept along
    the posed outline (its cell included), `feasible`, False where no pose at
    all keeps every contact within its bounds, and `face_move` (N, s, 2, 2) how
    far the start and the end of each contact's posed face may lie from the true
    ones by each of two bounds (:func:`_face_moves`; its cell included; 0 where
    the contact is not assigned)."""

    d_translation: np.ndarray
    d_theta: np.ndarray
    eps_t: np.ndarray
    feasible: np.ndarray
    face_move: np.ndarray

    def part(self, samples: slice) -> SampleBounds:
        """The bounds of some samples."""
        return SampleBounds(*(getattr(self, f.name)[samples] for f in dataclasses.fields(self)))


def sample_bounds(
    pose: PoseFit,
    bounds: FitBounds,
    samples: SlideSamples,
    outlines: RowOutlines,
    faces: Faces,
    points: np.ndarray,
    normals: np.ndarray,
    face: np.ndarray,
    assigned: np.ndarray,
    eps_d: float,
    phi: float,
    config: RecognitionConfig,
    slack: float,
) -> SampleBounds:
    """Error bounds at each sample (DESIGN §4.4, §4.6): the fit's bounds moved to
    the sample's slide coordinate and widened by half its cell; for determined
    poses in `linearized` mode, the smaller of those and the bounds of the set of
    poses consistent with the contacts
    (:func:`planner.recognition.consistent.consistent_set_bounds`). The rows may
    come from several stable poses (`outlines`, their faces stacked in `faces`,
    which `face` (K, s) numbers): each row's bounds are those its own stable pose
    alone gives."""
    fit = pose.fit
    src, s_val, cell = samples.src, samples.s, samples.cell
    e, rho = pose.slide_axis, pose.rho
    eps_t0, d_th, second = bounds.eps_t, bounds.d_theta, bounds.second
    feasible = np.ones(len(src), dtype=bool)
    if config.bound_mode != "thesis":
        # the model origin and every face's start (the outline's vertices among them)
        shift = (s_val / rho[src])[:, None, None] * e[src][:, None, :]
        linear = point_bounds(fit, outlines.points[src] - shift, assigned, eps_d, phi, src)
        linear = linear * (1 + phi) + second[src][:, None]
        consistent = np.full_like(linear, np.inf)  # known for determined poses only
        d_theta = d_th[src]
        # determined poses: the set of poses consistent with every contact is often far
        # smaller than the estimator's worst case (errors do not add up); keep the smaller
        det, at, pos = determined_rows(fit, src)
        if det.size:
            found = consistent_set_bounds(
                points if points.ndim == 2 else points[det],
                normals if normals.ndim == 2 else normals[det],
                faces.normal[face[det]],
                faces.offset[face[det]],
                assigned[det],
                fit.theta[det],
                fit.t[det],
                outlines.points[det],
                eps_d,
                phi,
            )
            consistent[at] = found.moved[pos] + slack
            d_theta[at] = np.minimum(d_theta[at], found.dtheta[pos] + ANGLE_SLACK)
            # no pose keeps every contact within its bounds: the interpretation is out
            feasible[at] &= found.feasible[pos]
        ends = outlines.ends[src]
        eps_t = 2 * _outline_move(ends, linear, consistent) + cell[src]
        d_translation = np.minimum(linear[:, 0], consistent[:, 0]) + cell[src] / 2
        local = face[src] - outlines.first[src][:, None]
        face_move = _face_moves(ends, local, assigned[src], linear, consistent)
        face_move += np.where(assigned[src], cell[src][:, None] / 2, 0.0)[..., None, None]
    else:
        eps_t = eps_t0[src] + cell[src]
        d_translation = eps_t0[src] / 2 + outlines.centroid_norm[src] * d_th[src] + cell[src] / 2
        d_theta = d_th[src]
        face_move = np.where(assigned[src], eps_t[:, None] / 2, 0.0)[..., None, None]
        face_move = np.repeat(np.repeat(face_move, 2, axis=2), 2, axis=3)
    return SampleBounds(
        d_translation=d_translation,
        d_theta=d_theta,
        eps_t=eps_t,
        feasible=feasible,
        face_move=face_move,
    )
