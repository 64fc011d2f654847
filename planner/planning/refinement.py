"""Pose refinement: how far a sensing path would shrink the hypotheses' error disks.

A path is informative (DESIGN §4.12) when some outcome removes a hypothesis.
With measurement error there are states where none is: the error disks of the
remaining hypotheses (``eps_t``, DESIGN §4.4) are wider than the features that
tell them apart (a 5 degree normal error leaves a 100 mm block's disk near
20 mm after two touches, wider than a 15 mm bump). Then the useful touch is the
one that localizes best: a contact on a face not parallel to the ones touched
fixes the slide of a family, and a contact far along a face already touched
pins the rotation. Every hypothesis predicts where a path meets it (the
outcome model, :mod:`planner.planning.outcomes`); adding that contact to the
hypothesis' own and bounding the pose again, with the recognition's bounds
(:mod:`planner.recognition.pose_fit`, :mod:`planner.recognition.consistent`),
gives the disk it would have after the touch.

World frame, lengths in the object files' unit, angles in radians.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from planner.geometry import vertex_turns
from planner.planning.bitsets import SurvivorTable
from planner.planning.candidates import Candidates
from planner.planning.confusability import class_bits
from planner.planning.outcomes import OutcomeConfig, Outcomes, predict_outcomes
from planner.planning.posed_set import PosedSet
from planner.planning.scoring import InformationScores, information_scores
from planner.planning.survivors import pin_families
from planner.recognition.consistent import consistent_set_bounds
from planner.recognition.pose_fit import fit_batch, noise_scales, point_bounds, worst_rotation
from planner.types import Contact, Hypothesis, ObjectModel, SensorBounds, StablePose

__all__ = ["Refinement", "refinement", "scores_after"]

#: Rotations sampled by the consistent-set sweep when predicting (as the recognition does).
_SWEEP_SAMPLES = 25
#: Turn (radians) at a vertex up to which a hit near it counts for refinement: a
#: curve drawn with 16 faces per half turn turns 11.25 degrees at each vertex, a
#: chamfer 45.
SMOOTH_TURN = math.pi / 8
#: Most (path, hypothesis) rows bounded in one call (the sweep's memory).
_MAX_ROWS = 6000


@dataclass(frozen=True, eq=False)
class Refinement:
    """Predicted error disks after each path.

    `before` (K,) the disk diameter of each class' most probable member now;
    `after` (C, K) the same after path c (unchanged where the path misses it, meets
    it at an uncertain place, or leaves its pose undetermined), `rotation` (C, K)
    the rotation bound after path c; `expected` (C,) the class-weighted mean of
    `after`, and `current` that of `before`."""

    before: np.ndarray
    after: np.ndarray
    rotation: np.ndarray
    expected: np.ndarray
    current: float


def refinement(
    hypotheses: Sequence[Hypothesis],
    models: Mapping[str, ObjectModel],
    posed: PosedSet,
    outcomes: Outcomes,
    contacts: Sequence[Contact],
    sensor: SensorBounds,
) -> Refinement:
    """Error disk of each class' most probable hypothesis after each path.

    The predicted contact is the nominal first hit (point and posed face normal,
    exact); hits near a vertex, grazing or at the path's end are not credited.
    """
    eps_d, phi = sensor.position_error, sensor.normal_error
    C = outcomes.face.shape[0]
    order = np.lexsort((-posed.weight, posed.cls))
    first = np.ones(len(order), dtype=bool)
    first[1:] = posed.cls[order][1:] != posed.cls[order][:-1]
    reps = order[first]  # one per class, in class order
    before = posed.eps_t[reps]
    after = np.broadcast_to(before, (C, len(reps))).copy()
    rotation = np.broadcast_to(posed.rotation[reps], (C, len(reps))).copy()
    sure = outcomes.hit[:, reps] & ~outcomes.uncertain[:, reps]
    # on a drawn curve every hit lies near a vertex: where the faces there turn
    # little, the contact is much as predicted whichever face it lands on
    smooth = _smooth_hits(hypotheses, models, outcomes, reps, max(phi, SMOOTH_TURN))
    sure |= outcomes.hit[:, reps] & smooth & ~_uncertain_besides_vertices(outcomes, reps)
    if contacts and (eps_d > 0 or phi > 0) and sure.any():
        P0 = np.array([c.point for c in contacts], dtype=float)
        U0 = np.array([c.normal for c in contacts], dtype=float)
        scale = max(p.centroid_radius for m in models.values() for p in m.stable_poses)
        sigma_d, sigma_phi = noise_scales(eps_d, phi, scale)
        by_pose: dict[tuple[str, int], list[int]] = {}
        for k, h in enumerate(reps):
            hyp = hypotheses[int(h)]
            by_pose.setdefault((hyp.object, hyp.stable_pose), []).append(k)
        budget = _MAX_ROWS
        for (name, pose_index), ks in by_pose.items():
            stable = models[name].stable_poses[pose_index]
            faces = stable.all_faces  # outcome faces index every layer's, as assignments do
            c_idx, k_pos = np.nonzero(sure[:, ks])
            if budget <= 0 or not len(c_idx):
                continue
            c_idx, k_pos = c_idx[:budget], k_pos[:budget]
            budget -= len(c_idx)
            k_idx = np.asarray(ks)[k_pos]
            h_idx = reps[k_idx]
            old = np.array(
                [[-1 if f is None else f for f in hypotheses[int(h)].assignment] for h in h_idx]
            ).reshape(len(h_idx), len(contacts))
            face = np.concatenate([old, outcomes.face[c_idx, h_idx][:, None]], axis=1)
            assigned = face >= 0
            face = np.maximum(face, 0)
            points = np.concatenate(
                [np.broadcast_to(P0, (len(c_idx), *P0.shape)), outcomes.point[c_idx, h_idx, None]],
                axis=1,
            )
            normals = np.concatenate(
                [np.broadcast_to(U0, (len(c_idx), *U0.shape)), outcomes.normal[c_idx, h_idx, None]],
                axis=1,
            )
            ref = np.broadcast_to(stable.centroid, (len(c_idx), 2))
            fit = fit_batch(
                points,
                normals,
                faces.normal[face],
                faces.offset[face],
                assigned,
                ref,
                sigma_d,
                sigma_phi,
            )
            det = np.flatnonzero(fit.rank2)
            if not det.size:
                continue
            # the recognition's bounds (planner.recognition), on determined rows
            second = phi**2 * stable.centroid_radius + phi * eps_d
            moved = point_bounds(fit, stable.extent, assigned, eps_d, phi, det) * (1 + phi)
            swept = consistent_set_bounds(
                points[det],
                normals[det],
                faces.normal[face[det]],
                faces.offset[face[det]],
                assigned[det],
                fit.theta[det],
                fit.t[det],
                stable.extent,
                eps_d,
                phi,
                samples=_SWEEP_SAMPLES,
            )
            eps_t = 2 * np.minimum(moved + second, swept.moved).max(axis=1)
            d_theta = worst_rotation(fit.sens[det], assigned[det], eps_d, phi)
            d_theta = np.minimum(d_theta * (1 + phi) + phi**2, swept.dtheta)
            rows = (c_idx[det], k_idx[det])
            after[rows] = np.minimum(after[rows], eps_t)
            rotation[rows] = np.minimum(rotation[rows], d_theta)
    weight = posed.class_weight
    return Refinement(before, after, rotation, after @ weight, float(before @ weight))


def smooth_faces(stable: StablePose, turn: float) -> np.ndarray:
    """(F,) over `stable.all_faces`: does the outline turn by at most `turn`
    (radians) at both ends of the face (a face of a finely drawn curve)?"""
    out = []
    for layer in stable.layers:
        for ring in (layer.outline, *layer.holes):
            at = vertex_turns(ring)  # face k runs from vertex k to k + 1
            out.append((at <= turn) & (np.roll(at, -1) <= turn))
    return np.concatenate(out)


def _smooth_hits(
    hypotheses: Sequence[Hypothesis],
    models: Mapping[str, ObjectModel],
    outcomes: Outcomes,
    reps: np.ndarray,
    turn: float,
) -> np.ndarray:
    """(C, K) does path c hit representative k on a face of a smooth run?"""
    out = np.zeros((outcomes.face.shape[0], len(reps)), dtype=bool)
    cache: dict[tuple[str, int], np.ndarray] = {}
    for k, h in enumerate(reps):
        hyp = hypotheses[int(h)]
        key = (hyp.object, hyp.stable_pose)
        if key not in cache:
            cache[key] = smooth_faces(models[key[0]].stable_poses[key[1]], turn)
        face = outcomes.face[:, h]
        ok = face >= 0
        out[ok, k] = cache[key][face[ok]]
    return out


def _uncertain_besides_vertices(outcomes: Outcomes, reps: np.ndarray) -> np.ndarray:
    """(C, K) the outcome may differ from the nominal one for a reason other than
    a vertex near the contact or passed on the way, or other faces near the path
    past it (a stretch counts only when it is open to any face)."""
    o = outcomes
    return (o.grazing | o.near_miss | o.end_of_path | o.shallow | o.open_stretch)[:, reps]


def scores_after(
    hypotheses: Sequence[Hypothesis],
    posed: PosedSet,
    refine: Refinement,
    candidates: Candidates,
    index: int,
    sensor: SensorBounds,
    config: OutcomeConfig,
) -> InformationScores:
    """Information scores (one row) of candidate `index` of `candidates` under the
    outcome model with the disks and rotation bounds each class is predicted to
    have once the touch is made (each class' best member's)."""
    cls = posed.cls
    after = dataclasses.replace(
        posed, eps_t=refine.after[index][cls], rotation=refine.rotation[index][cls]
    )
    path = candidates.subset([index])
    outcome = predict_outcomes(after, path.origins, path.directions, path.lengths, sensor, config)
    bits = pin_families(
        hypotheses, after, outcome, class_bits(after, outcome, sensor, config), sensor
    )
    return information_scores(SurvivorTable.from_bits(bits, after.class_weight))
