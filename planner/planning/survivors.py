"""Where the outcome model must follow what the recognition will do (DESIGN §4.11).

The outcome model predicts, per path and hypothesis, what a touch would measure
and which hypotheses would survive it. Two things the recognition does are not
visible in single outcomes and are applied here, both in the world frame:

- a slide family (touched faces all parallel, DESIGN §4.6) is re-fitted as one
  determined pose once a contact lands on a face not parallel to them, so its
  samples are told apart by such a path (:func:`pin_families`);
- an observation already made has been checked against every hypothesis still
  standing, so a path repeating it measures nothing new (:func:`repeated_paths`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from planner.arrays import row_labels
from planner.geometry import ANGLE_SLACK, LENGTH_SLACK
from planner.planning.candidates import Candidates
from planner.planning.outcomes import Outcomes
from planner.planning.posed_set import PosedSet
from planner.types import Hypothesis, Observation, SensorBounds

__all__ = ["pin_families", "repeated_paths"]


def pin_families(
    hypotheses: Sequence[Hypothesis],
    posed: PosedSet,
    outcomes: Outcomes,
    bits: np.ndarray,
    sensor: SensorBounds,
) -> np.ndarray:
    """Survivor bits (C, K, W) with the samples of one slide family told apart
    where a path pins the family.

    A family (touched faces all parallel, DESIGN §4.6) is sampled along its slide,
    one class per sample. When a path meets two samples surely (no alternative
    outcome, :attr:`Outcomes.uncertain`) on the same face, not parallel to the touched ones, the
    contact fixes the slide: the family becomes one determined pose, the sample
    the truth is, and the other sample does not survive as a class of its own.
    Their disks (which carry the sample spacing) would otherwise call them
    confusable, and the touch that ends the family would never look
    distinguishing.
    """
    # a family: one interpretation (object, stable pose, faces touched, all parallel)
    tol = math.sin(2 * sensor.normal_error + 1e-6)
    assigned = np.array([[-1 if a is None else a for a in h.assignment] for h in hypotheses])
    if assigned.size == 0:
        return bits
    on = assigned >= 0
    first = np.argmax(on, axis=1)
    rows = np.arange(len(hypotheses))
    n = np.nan_to_num(posed.touched)  # (H, s, 2)
    u = n[rows, first]  # (H, 2): a touched face's posed normal
    cross = np.abs(n[..., 0] * u[:, None, 1] - n[..., 1] * u[:, None, 0])
    parallel = on.any(axis=1) & np.all(~on | (cross <= tol), axis=1)
    ident: dict[tuple, int] = {}
    label = [
        ident.setdefault((h.interpretation, h.object, h.stable_pose), len(ident))
        for h in hypotheses
    ]
    family = np.where(parallel, row_labels(np.column_stack([label, assigned])), -1)
    members = np.bincount(posed.cls, minlength=posed.n_classes)
    # classes of one hypothesis, sampled from a family with siblings
    solo = (members[posed.cls] == 1) & (family >= 0)
    siblings = np.unique(family[solo], return_counts=True)
    shared = siblings[0][siblings[1] > 1]
    if not len(shared):
        return bits
    # every ordered pair (a, b) of samples of one shared family, all families at once
    hs = np.flatnonzero(solo & np.isin(family, shared))
    hs = hs[np.argsort(family[hs], kind="stable")]
    starts = np.searchsorted(family[hs], shared)
    sizes = np.diff(np.append(starts, len(hs)))
    a, b = _pairs_within_runs(starts, sizes)
    a, b = hs[a], hs[b]
    # a path pins a sample where it surely meets a face not parallel to its family's
    un = u[hs[np.repeat(starts, sizes)]]  # (S, 2): each sample's family's touched normal
    hit_n = outcomes.normal[:, hs]  # (C, S, 2)
    sure = outcomes.hit[:, hs] & ~outcomes.uncertain[:, hs]
    pins = sure & (np.abs(hit_n[..., 0] * un[:, 1] - hit_n[..., 1] * un[:, 0]) > tol)
    pinned = np.zeros(len(hypotheses), dtype=np.int64)
    pinned[hs] = np.arange(len(hs))
    ia, ib = pinned[a], pinned[b]
    # on path c, sample a's class no longer survives with sample b's class
    same = (outcomes.face[:, a] == outcomes.face[:, b]) & pins[:, ia] & pins[:, ib]
    c, m = np.nonzero(same)
    k = posed.cls
    bit = np.left_shift(np.uint64(1), (k[b[m]] % 64).astype(np.uint64))
    bits = bits.copy()
    np.bitwise_and.at(bits, (c, k[a[m]], k[b[m]] // 64), ~bit)
    return bits


def _pairs_within_runs(starts: np.ndarray, sizes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Every ordered pair (i, j), i != j, of places within each run (run r holds
    places ``starts[r] .. starts[r] + sizes[r] - 1``)."""
    n = sizes * sizes
    run = np.repeat(np.arange(len(sizes)), n)
    at = np.arange(int(n.sum())) - np.repeat(np.cumsum(n) - n, n)
    i = starts[run] + at // sizes[run]
    j = starts[run] + at % sizes[run]
    keep = i != j
    return i[keep], j[keep]


def repeated_paths(
    cands: Candidates,
    observations: Sequence[Observation],
    posed: PosedSet,
    sensor: SensorBounds,
) -> np.ndarray:
    """(C,) bool: does each candidate repeat a path already taken?

    A candidate repeats an observation when it runs the same way (directions
    within ``2 phi``) along the same line (within ``2 eps_d + min eps_t / 2`` of the
    observed contact, or of a missed path's point nearest the candidate's aim).
    Every hypothesis still standing agreed with that observation within its
    tolerances, so the repeat can only measure it again: it teaches nothing the
    outcome model could count on (with errors, taking it again loops).
    """
    out = np.zeros(len(cands), dtype=bool)
    if not len(cands) or not observations:
        return out
    eps_d, phi = sensor.position_error, sensor.normal_error
    reach = 2 * eps_d + float(posed.eps_t.min()) / 2 + LENGTH_SLACK * posed.scale
    d = cands.directions
    for obs in observations:
        o, u = np.asarray(obs.path.origin), np.asarray(obs.path.direction)
        same_way = d @ u >= np.cos(2 * phi + ANGLE_SLACK)
        if obs.contact is not None:
            x = np.broadcast_to(np.asarray(obs.contact.point, dtype=float), d.shape)
        else:  # the missed path's point nearest each candidate's aim
            along = np.clip((cands.aims - o) @ u, 0.0, obs.path.length)
            x = o + along[:, None] * u
        rel = x - cands.origins
        off = np.abs(rel[:, 0] * d[:, 1] - rel[:, 1] * d[:, 0])
        out |= same_way & (off <= reach)
    return out
