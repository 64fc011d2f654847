"""Interpretations -> posed, weighted hypotheses (DESIGN §4.4-4.7).

:func:`evaluate_groups` takes the surviving rows of every group of the
interpretation tree (:mod:`planner.recognition.tree`) through the steps of the
DESIGN, each a function of its own; steps 1-4, 5's model check and 7 run over the
rows of all groups at once, the rest group by group (:func:`evaluate`: one group):

1. rotation gate and pose fit (§4.4, :mod:`planner.recognition.poses`);
2. error bounds of the fit (§4.4);
3. slide-family samples of under-constrained rows (§4.6);
4. error bounds of each sample (§4.4, §4.6);
5. model check: every contact on its FINITE face within ``eps_d + eps_t/2`` and
   its normal within ``phi + |dtheta|``; optionally the posed outline inside the
   safe circle (§4.5, :mod:`planner.recognition.model_check`);
6. free-space check: the path up to each contact (less ``eps_d``), and every
   missed path whole, outside the posed outline shrunk by ``eps_t/2`` (§4.5);
7. weights (§4.7, :mod:`planner.recognition.weights`).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from planner.geometry import LENGTH_SLACK, wrap_angle
from planner.recognition.config import RecognitionConfig
from planner.recognition.model_check import (
    PathVariants,
    free_space_check,
    inside_workspace,
    model_check,
)
from planner.recognition.poses import (
    RowOutlines,
    RowShapes,
    SampleBounds,
    SlideSamples,
    fit_bounds,
    fit_poses_of_groups,
    rotation_gate,
    sample_bounds,
    slide_samples,
)
from planner.recognition.tree import Group
from planner.recognition.weights import residual_fitness, weights
from planner.types import Faces, Observation, PosePrior, SensorBounds, StablePose, Workspace

__all__ = ["PoseSamples", "Variants", "evaluate", "evaluate_groups"]


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


def _no_samples(group_index: int) -> PoseSamples:
    none = np.zeros(0)
    return PoseSamples(
        group_index, np.zeros(0, np.int64), none, np.zeros((0, 2)), none, none, none, none, none
    )


def within_prior(
    prior: PosePrior, stable: StablePose, theta: np.ndarray, t: np.ndarray, bound: Any, slack: float
) -> np.ndarray:
    """(N,) bool: can each pose (theta (N,), t (N, 2)) be the true one under `prior`?
    Sound: a pose is dropped only when its whole error bound lies outside the prior."""
    ok = np.ones(len(theta), dtype=bool)
    d_t, d_theta = np.asarray(bound.d_translation), np.asarray(bound.d_theta)
    if prior.center is not None and prior.radius is not None:
        # centroid c = R(theta) c_model + t, uncertain by d_t + d_theta |c_model|
        c = np.asarray(stable.centroid, dtype=float)
        cos, sin = np.cos(theta), np.sin(theta)
        cx = cos * c[0] - sin * c[1] + t[:, 0]
        cy = sin * c[0] + cos * c[1] + t[:, 1]
        reach = prior.radius + d_t + d_theta * float(np.hypot(*c)) + slack
        ok &= np.hypot(cx - prior.center[0], cy - prior.center[1]) <= reach
    if prior.theta is not None:
        lo, hi = prior.theta
        mid, half = (lo + hi) / 2, (hi - lo) / 2
        ok &= np.abs(wrap_angle(theta - mid)) <= half + d_theta + 1e-12
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
    (out,) = evaluate_groups(
        [group], [rows], observations, bounds, workspace, config, length_scale, [group_index]
    )
    return out


@dataclass(frozen=True, eq=False)
class Variants:
    """Observation lists alike but for their last observation, evaluated in one pass
    (a plan's predictions: :meth:`~planner.recognition.session.Session.predict_many`):
    `last` (B,) each list's last observation (every one a contact), `of_rows` per
    group which list each of its rows observes."""

    last: Sequence[Observation]
    of_rows: Sequence[np.ndarray]


@dataclass(frozen=True, eq=False)
class _Contacts:
    """The contacts of the observations (s of them): `points`, `normals` (s, 2), the
    normals' angles `psi` (s,) and the `directions` (s, 2) of the paths that met
    them; given variants, each row's own: (K, s, 2) and (K, s)."""

    points: np.ndarray
    normals: np.ndarray
    psi: np.ndarray
    directions: np.ndarray

    @classmethod
    def of(cls, observations: list[Observation], variants: Variants | None = None) -> _Contacts:
        if variants is not None:  # the shared contacts read once, then each row's own
            shared = cls.of(observations)
            last = cls.of(list(variants.last))  # one contact each
            row = np.concatenate(variants.of_rows).astype(np.int64)

            def then(f: str) -> np.ndarray:
                head, own = getattr(shared, f), getattr(last, f)[row, None]
                return np.concatenate([np.broadcast_to(head, (len(row), *head.shape)), own], 1)

            return cls(*(then(f) for f in _FIELDS))
        contacts = [o.contact for o in observations if o.contact is not None]
        normals = np.array([c.normal for c in contacts], dtype=float).reshape(-1, 2)
        return cls(
            np.array([c.point for c in contacts], dtype=float).reshape(-1, 2),
            normals,
            np.arctan2(normals[:, 1], normals[:, 0]),
            np.array(
                [o.path.direction for o in observations if o.contact is not None], dtype=float
            ).reshape(-1, 2),
        )

    @property
    def shared(self) -> bool:
        """One set of contacts for every row."""
        return self.psi.ndim == 1

    def rows(self, at: np.ndarray | slice) -> _Contacts:
        """The contacts of some rows (all of them, when shared)."""
        if self.shared:
            return self
        return _Contacts(*(getattr(self, f)[at] for f in _FIELDS))


_FIELDS = ("points", "normals", "psi", "directions")


@dataclass(frozen=True, eq=False)
class _Gated:
    """The rows of one group that assign a contact and pass the rotation gate:
    `keep` their indices among the group's rows, `face` and `assigned` (K, s), and
    `spurious` (K, s) the contacts they call spurious (a folded contact is unassigned
    but not spurious: :func:`~planner.recognition.tree.fold_runs`), and `at` (K,)
    their places among the rows of every group, stacked."""

    keep: np.ndarray
    face: np.ndarray
    assigned: np.ndarray
    spurious: np.ndarray
    at: np.ndarray


def _gated(
    groups: Sequence[Group], rows: Sequence[np.ndarray], psi: np.ndarray, phi: float
) -> list[_Gated | None]:
    """Step 1's gate on every group's `rows` in one pass: per group its rows that
    assign a contact and pass it (None when no row is left). `psi` (s,), or (K, s)
    for every row of the groups stacked."""
    out: list[_Gated | None] = [None] * len(groups)
    sizes = [len(r) if r.size else 0 for r in rows]
    if not sum(sizes):
        return out
    every = np.concatenate([r for r, n in zip(rows, sizes, strict=True) if n])
    angles = [g.stable.all_faces.angle for g in groups]
    moved = np.repeat(np.cumsum([0, *map(len, angles[:-1])]), sizes)
    assigned = every >= 0
    face = np.maximum(every, 0)
    gate = rotation_gate(psi, np.concatenate(angles)[face + moved[:, None]], assigned, phi)
    gate &= assigned.any(axis=1)
    start = 0
    for g, n in enumerate(sizes):
        keep = np.flatnonzero(gate[start : start + n])
        if keep.size:
            at = keep + start
            out[g] = _Gated(keep, face[at], assigned[at], every[at] == -1, at)
        start += n
    return out


def evaluate_groups(
    groups: Sequence[Group],
    rows: Sequence[np.ndarray],
    observations: list[Observation],
    bounds: SensorBounds,
    workspace: Workspace,
    config: RecognitionConfig,
    length_scale: float,
    indices: Sequence[int] | None = None,
    variants: Variants | None = None,
) -> list[PoseSamples]:
    """:func:`evaluate` of every group (its `rows` each, numbered by `indices`,
    default their places). The rotation gate, the fit, its bounds, the slide
    samples, the model check, the safe circle, the free space and the weights run
    over the rows of all groups in one pass, face numbers moved into one table;
    the sample bounds over consecutive groups of about as many faces (each row
    padded with its own outline's copies); the consistent sets' volumes and spread
    poses group by group (their polygons' padding decides their last bits). Each
    row gets the numbers a pass over its group alone gives.

    Given `variants`, each row observes `observations` and then its variant's last
    observation, and gets the numbers a pass over its own observations gives (the
    residual fitness, which a prediction leaves out, is not run)."""
    indices = range(len(groups)) if indices is None else indices
    out = [_no_samples(g) for g in indices]
    if variants is None and all(o.contact is None for o in observations):
        return out
    if variants is not None and config.residual_fitness and config.bound_mode != "thesis":
        raise ValueError("observation variants are evaluated without the residual fitness")
    contacts = _Contacts.of(observations, variants)
    eps_d, phi = bounds.position_error, bounds.normal_error
    slack = LENGTH_SLACK * length_scale * 10
    gated = _gated(groups, rows, contacts.psi, phi)
    live = [k for k, x in enumerate(gated) if x is not None]
    if not live:
        return out
    stack = _Stack.of([groups[k] for k in live], [gated[k] for k in live])  # type: ignore[misc]
    contacts = contacts.rows(stack.at)
    P, U = contacts.points, contacts.normals
    stables = [g.stable for g in stack.groups]
    pose = fit_poses_of_groups(
        stables, P, U, stack.local_faces, stack.assigned_parts, eps_d, phi, length_scale
    )
    face, assigned = stack.face, stack.assigned
    fit_bound = fit_bounds(
        pose, RowShapes.of(stables, stack.counts), assigned, eps_d, phi, config, slack
    )
    samples = slide_samples(
        pose,
        stack.faces,
        face,
        assigned,
        fit_bound.margin,
        fit_bound.eps_t,
        config.max_family_samples,
        length_scale,
    )
    parts = stack.parts(samples.src)
    # the bounds of consecutive stable poses with about as many faces in one pass
    sizes = [len(g.all_faces.start) for g in stables]
    bound = _joined_bounds(
        [
            sample_bounds(
                pose.part(rs), fit_bound.part(rs), samples.part(rs, ss),
                RowOutlines.of(stables[gs], stack.counts[gs], sum(sizes[: gs.start])),
                stack.faces, contacts.rows(rs).points, contacts.rows(rs).normals, face[rs],
                assigned[rs], eps_d, phi, config, slack,
            )
            for gs, rs, ss in _similar_runs(parts, sizes)
        ]
    )  # fmt: skip
    src, theta, t, eps_t = samples.src, samples.theta, samples.t, bound.eps_t
    f_src, a_src = face[src], assigned[src]
    ok = bound.feasible & model_check(
        stack.faces, f_src, a_src, contacts.rows(src).points, contacts.rows(src).psi, theta, t,
        bound.face_move, bound.d_theta, eps_d, phi, slack,
    )  # fmt: skip
    ok = _outline_checks(
        stack, observations, samples, bound, ok, workspace, config, eps_d, slack, variants
    )
    fitness = residual_fitness(
        stack.groups, parts, stack.faces, observations, pose, samples, P, U, stack.face,
        stack.assigned, ok, eps_d, phi, config, slack,
        workspace if config.require_inside_workspace else None,
    )  # fmt: skip
    prior = np.array([g.prior for g in stack.groups])[stack.group[src]]
    weight = weights(
        prior, pose, samples, stack.faces, f_src, a_src, contacts.rows(src).directions, fitness,
        config,
        stack.spurious[src],
    )  # fmt: skip
    keep = stack.keep[src]
    for j, (_, ss) in enumerate(parts):
        sel = np.flatnonzero(ok[ss] & (weight[ss] > 0)) + ss.start
        out[live[j]] = PoseSamples(
            indices[live[j]], keep[sel], theta[sel], t[sel], bound.d_translation[sel],
            bound.d_theta[sel], eps_t[sel], samples.cell[src[sel]], weight[sel],
        )  # fmt: skip
    return out


@dataclass(frozen=True, eq=False)
class _Stack:
    """The gated rows of several groups stacked in group order (K rows): each
    group's faces in one table (`faces`, the group's face numbers moved past the
    faces of the groups before it: `face` (K, s)), `assigned` and `spurious` (K, s),
    `keep` (K,) each row's index among its group's rows, `group` (K,) its place in `groups`,
    `at` (K,) its place among the rows of every group, stacked;
    per group its rows' `counts`, its own face numbers and assignments."""

    groups: list[Group]
    counts: list[int]
    local_faces: list[np.ndarray]
    assigned_parts: list[np.ndarray]
    faces: Faces
    face: np.ndarray
    assigned: np.ndarray
    spurious: np.ndarray
    keep: np.ndarray
    group: np.ndarray
    at: np.ndarray

    @classmethod
    def of(cls, groups: list[Group], gated: list[_Gated]) -> _Stack:
        tables = [g.stable.all_faces for g in groups]
        counts = [len(x.face) for x in gated]
        moved = np.cumsum([0] + [len(f) for f in tables[:-1]])
        faces = Faces(
            *(
                np.concatenate([getattr(f, n.name) for f in tables])
                for n in dataclasses.fields(Faces)
            )
        )
        return cls(
            groups,
            counts,
            [x.face for x in gated],
            [x.assigned for x in gated],
            faces,
            np.concatenate([x.face + m for x, m in zip(gated, moved, strict=True)]),
            np.concatenate([x.assigned for x in gated]),
            np.concatenate([x.spurious for x in gated]),
            np.concatenate([x.keep for x in gated]),
            np.repeat(np.arange(len(groups)), counts),
            np.concatenate([x.at for x in gated]),
        )

    def parts(self, src: np.ndarray) -> list[tuple[slice, slice]]:
        """Each group's rows and the samples they drew (`src` (N,) the row of each
        sample, ascending), both in group order."""
        row_ends = np.cumsum(self.counts)
        sample_ends = np.searchsorted(src, row_ends)
        return [
            (slice(r1 - n, r1), slice(s0, s1))
            for n, r1, s0, s1 in zip(
                self.counts, row_ends, np.r_[0, sample_ends[:-1]], sample_ends, strict=True
            )
        ]


#: Stable poses whose face counts lie within this ratio share a pass of the
#: sample bounds (each row is padded to the most faces of its pass).
SIMILAR_FACES = 2.0


def _similar_runs(
    parts: list[tuple[slice, slice]], sizes: list[int]
) -> list[tuple[slice, slice, slice]]:
    """Consecutive groups (`parts`: each one's rows and samples) whose face counts
    `sizes` lie within `SIMILAR_FACES` of each other, merged: (groups, rows,
    samples) of each run."""
    runs, start, lo, hi = [], 0, sizes[0], sizes[0]
    for j in range(1, len(parts) + 1):
        if j < len(parts) and max(hi, sizes[j]) <= SIMILAR_FACES * min(lo, sizes[j]):
            lo, hi = min(lo, sizes[j]), max(hi, sizes[j])
            continue
        rows = slice(parts[start][0].start, parts[j - 1][0].stop)
        runs.append((slice(start, j), rows, slice(parts[start][1].start, parts[j - 1][1].stop)))
        if j < len(parts):
            start, lo, hi = j, sizes[j], sizes[j]
    return runs


def _joined_bounds(parts: list[SampleBounds]) -> SampleBounds:
    return SampleBounds(
        *(
            np.concatenate([getattr(p, f.name) for p in parts])
            for f in dataclasses.fields(SampleBounds)
        )
    )


def _outline_checks(
    stack: _Stack,
    observations: list[Observation],
    samples: SlideSamples,
    bound: SampleBounds,
    ok: np.ndarray,
    workspace: Workspace,
    config: RecognitionConfig,
    eps_d: float,
    slack: float,
    variants: Variants | None = None,
) -> np.ndarray:
    """Steps 5-6, which need each sample's outline: the safe circle and the prior,
    and the free space (each sample's own last path, given `variants`); `ok` (N,) of
    the samples. The safe circle and the free space take every group's samples in
    one pass."""
    src, theta, t, eps_t = samples.src, samples.theta, samples.t, bound.eps_t
    which = stack.group[src]
    outlines = [g.stable.outline for g in stack.groups]
    if config.require_inside_workspace:
        ok = ok & inside_workspace(outlines, theta, t, eps_t, workspace, slack, which)
    if config.prior is not None:
        ok = ok.copy()
        for g, group in enumerate(stack.groups):
            at = np.flatnonzero(which == g)
            ok[at] &= within_prior(
                config.prior, group.stable, theta[at], t[at], bound.part(at), slack
            )
    paths = None
    if variants is not None:
        paths = PathVariants(variants.last, np.concatenate(variants.of_rows)[stack.at][src])
    return free_space_check(
        stack.groups, observations, stack.assigned[src], theta, t, eps_t, ok, eps_d, slack, which,
        paths,
    )  # fmt: skip
