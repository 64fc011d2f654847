"""Weights of posed samples (DESIGN §4.7).

weight = prior x incidence likelihood x pose volume x residual fitness (x the
Gaussian residual term in `gaussian` mode) x outlier probability per spurious
contact. The prior is P(object) x P(stable pose | object); a contact on face a
from a path with direction `dir` is likelier the squarer the hit, ``|dir·n_a|``;
the pose volume is the Laplace volume of the fit (a slide family's carries its
cell); the residual fitness is the bounded-error likelihood of the contacts, the
share of the poses consistent with them that the errors left
(:mod:`planner.recognition.consistent`).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from planner.geometry import LENGTH_SLACK, rotation_matrices
from planner.recognition.config import RecognitionConfig
from planner.recognition.consistent import consistent_poses, consistent_volume
from planner.recognition.model_check import clear_paths, contacts_on_faces, inside_workspace
from planner.recognition.poses import PoseFit, SlideSamples, determined_rows
from planner.recognition.tree import Group
from planner.types import Faces, Observation, Workspace

__all__ = ["residual_fitness", "weights"]

#: Least share of the consistent set a determined pose keeps in its weight.
_FITNESS_FLOOR = 1e-6


def residual_fitness(
    groups: Sequence[Group],
    parts: Sequence[tuple[slice, slice]],
    faces: Faces,
    observations: list[Observation],
    pose: PoseFit,
    samples: SlideSamples,
    points: np.ndarray,
    normals: np.ndarray,
    face: np.ndarray,
    assigned: np.ndarray,
    ok: np.ndarray,
    eps_d: float,
    phi: float,
    config: RecognitionConfig,
    slack: float,
    workspace: Workspace | None = None,
) -> np.ndarray:
    """(N,) bounded-error likelihood of each sample's contacts, in (0, 1].

    Determined poses in `linearized` mode: the volume of the poses consistent with
    the contacts as measured over that with the contacts moved onto the fitted
    faces, times, for samples the checks kept (`ok` (N,)), the share of that set
    which also keeps every contact on its finite face, every path clear of the
    outline and, given the `workspace`, the part inside the safe circle (the
    prior puts it there: a set mostly outside it is mostly impossible). 1 for
    slide-family samples, in `thesis` mode and where the `config` leaves it out
    (a prediction).

    The rows come from `groups`: `parts` gives each one's rows and samples, in
    order; `faces` holds the groups' faces stacked in that order, which `face`,
    `assigned` (K, s), the rows the samples were drawn from, number. The
    consistent sets' volumes and spread poses are measured group by group (their
    polygons are padded to the most slabs of a pass, and that padding decides
    their last bits); the share of the spread poses the checks admit, for every
    group at once."""
    fitness = np.ones(len(samples.src))  # determined poses: share of the set the errors left
    if config.bound_mode == "thesis" or not config.residual_fitness:
        return fitness
    found: list[tuple[int, np.ndarray, tuple[np.ndarray, ...]]] = []
    for g, (rs, ss) in enumerate(parts):
        fit = pose.part(rs).fit
        det, at, pos = determined_rows(fit, samples.src[ss] - rs.start)
        if det.size == 0:
            continue
        f, a, theta = face[rs][det], assigned[rs][det], fit.theta[det]
        fitness[ss.start + at] = _fitness(
            points, normals, faces, f, a, theta, fit.t[det], eps_d, phi
        )[pos]
        # determined poses: the share of their consistent set that also keeps every
        # contact on its finite face and every path clear of the outline, exactly
        live = np.flatnonzero(ok[ss][at])
        if live.size:
            # poses spread over each determined row's consistent set
            spread = consistent_poses(
                points, normals, faces.normal[f], faces.offset[f], a, theta, eps_d, phi
            )
            found.append((g, ss.start + at[live], tuple(x[pos[live]] for x in spread)))
    if found:
        at = np.concatenate([x[1] for x in found])
        which = np.concatenate([np.full(len(x[1]), x[0]) for x in found])
        theta, t, valid = (np.concatenate([x[2][k] for x in found]) for k in range(3))
        rows = samples.src[at]
        fitness[at] *= _admitted_share(
            groups, which, observations, points, faces, face[rows], assigned[rows], theta, t,
            valid, eps_d, max(slack, LENGTH_SLACK), workspace,
        )  # fmt: skip
    return fitness


def weights(
    prior: float,
    pose: PoseFit,
    samples: SlideSamples,
    faces: Faces,
    face: np.ndarray,
    assigned: np.ndarray,
    directions: np.ndarray,
    fitness: np.ndarray,
    config: RecognitionConfig,
    spurious: np.ndarray | None = None,
) -> np.ndarray:
    """(N,) unnormalized posterior weight of each sample.

    `prior` of the group; `face`, `assigned` (N, s) each sample's faces and which
    contacts it assigns; `directions` (s, 2) the unit directions of the paths that
    met the contacts (or (N, s, 2), each sample's own); `fitness` (N,) from
    :func:`residual_fitness`; `spurious` (N, s) the contacts it calls spurious,
    each weighed by the outlier probability (default: every contact it leaves
    unassigned; a folded one is not spurious).
    """
    fit, src = pose.fit, samples.src
    Rs = rotation_matrices(samples.theta)
    # weight = prior x incidence likelihood x pose volume (x Gaussian residual term)
    world_n = np.einsum("nij,nsj->nsi", Rs, faces.normal[face])
    spec = "nsi,si->ns" if directions.ndim == 2 else "nsi,nsi->ns"
    incidence = np.where(assigned, np.abs(np.einsum(spec, world_n, directions)), 1.0).prod(1)
    volume = np.sqrt(np.maximum(np.linalg.det(fit.cov), 0.0))[src]
    family, cell, span_scale = samples.family[src], samples.cell[src], samples.span_scale[src]
    volume = np.where(family, volume * cell * span_scale / pose.sigma_d, volume)
    weight = prior * incidence * volume * fitness
    spurious = ~assigned if spurious is None else spurious
    weight *= config.outlier_probability ** spurious.sum(axis=1)
    if config.likelihood == "gaussian":
        weight *= np.exp(-0.5 * fit.chi2[src])
    return weight


def _fitness(
    P: np.ndarray,
    U: np.ndarray,
    faces: Faces,
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
    groups: Sequence[Group],
    which: np.ndarray,
    observations: list[Observation],
    P: np.ndarray,
    faces: Faces,
    face: np.ndarray,
    assigned: np.ndarray,
    theta: np.ndarray,
    t: np.ndarray,
    valid: np.ndarray,
    eps_d: float,
    floor: float,
    workspace: Workspace | None = None,
) -> np.ndarray:
    """(K,) share of the poses spread over each row's consistent set (`theta`,
    `t`, `valid`: (K, M), (K, M, 2), (K, M)) whose contacts lie within eps_d of
    their FINITE faces (`face` numbering `faces`), whose paths (up to each
    contact less eps_d, or whole when missed) stay out of the outline of the
    row's group (`which` (K,) into `groups`) and, given the `workspace`, whose
    outline lies inside the safe circle: the model check without the pose's
    error allowance. It weighs, it does not prune (at least `_FITNESS_FLOOR`;
    1 where no pose is spread)."""
    K, M = valid.shape
    good = valid & contacts_on_faces(P, faces, face, assigned, theta, t, eps_d + floor)
    each = np.repeat(which, M)
    if workspace is not None:
        outlines = [g.stable.outline for g in groups]
        inside = inside_workspace(
            outlines, theta.reshape(-1), t.reshape(-1, 2), np.zeros(K * M), workspace, floor, each
        )
        good &= inside.reshape(K, M)
    clear = clear_paths(
        groups,
        observations,
        np.repeat(assigned, M, axis=0),
        theta.reshape(-1),
        t.reshape(-1, 2),
        np.full(K * M, floor),
        good.reshape(-1),
        eps_d,
        floor,
        each,
    )
    good = clear.reshape(K, M)
    count = valid.sum(axis=1)
    share = good.sum(axis=1) / np.maximum(count, 1)
    return np.where(count > 0, np.maximum(share, _FITNESS_FLOOR), 1.0)
