"""Model check and free-space check of posed samples (DESIGN §4.5).

With the fitted pose: each contact lies on its assigned FINITE face within
``eps_d + eps_t/2`` and its measured normal within ``phi + |dtheta|`` of the
face's posed normal (:func:`model_check`); the path up to each contact (less
``eps_d``), and every missed path whole, stays outside the posed outline shrunk
by ``eps_t/2`` (:func:`free_space_check`); optionally the posed outline lies
inside the safe circle (:func:`inside_workspace`).

World frame, lengths in the object files' unit, angles in radians; a pose maps
model points v to ``R(theta) v + t``.
"""

from __future__ import annotations

import math

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
from planner.recognition.tree import Group
from planner.types import Faces, Observation, Workspace

__all__ = ["clear_paths", "free_space_check", "inside_workspace", "model_check"]


def model_check(
    faces: Faces,
    face: np.ndarray,
    assigned: np.ndarray,
    points: np.ndarray,
    psi: np.ndarray,
    theta: np.ndarray,
    t: np.ndarray,
    eps_t: np.ndarray,
    d_theta: np.ndarray,
    eps_d: float,
    phi: float,
    slack: float,
) -> np.ndarray:
    """(N,) does every assigned contact fit its posed face? Each contact (`points`
    (s, 2), measured normal angles `psi` (s,)) within ``eps_d + eps_t/2 + slack`` of
    its FINITE face (the segment, not its line) and its normal within
    ``phi + d_theta`` of the face's posed normal.

    `face`, `assigned` (N, s): each sample's face per contact and which contacts it
    assigns (spurious ones are not checked); `theta` (N,), `t` (N, 2) the poses;
    `eps_t`, `d_theta` (N,) their error bounds.
    """
    # each contact on its finite posed face, normal within phi + dtheta
    Rs = rotation_matrices(theta)
    start = np.einsum("nij,nsj->nsi", Rs, faces.start[face]) + t[:, None, :]
    end = np.einsum("nij,nsj->nsi", Rs, faces.end[face]) + t[:, None, :]
    dist = point_segment_distance(points[None], start, end)
    ok = np.all(~assigned | (dist <= eps_d + eps_t[:, None] / 2 + slack), axis=1)
    ang = np.abs(wrap_angle(psi[None, :] - theta[:, None] - faces.angle[face]))
    ok &= np.all(~assigned | (ang <= phi + d_theta[:, None] + ANGLE_SLACK), axis=1)
    return ok


def inside_workspace(
    outline: np.ndarray,
    theta: np.ndarray,
    t: np.ndarray,
    eps_t: np.ndarray,
    workspace: Workspace,
    slack: float,
) -> np.ndarray:
    """(N,) does the posed `outline` (model frame, (V, 2)) lie inside the safe
    circle, within ``eps_t/2 + slack``, for each pose (`theta` (N,), `t` (N, 2))?"""
    Rs = rotation_matrices(theta)
    verts = np.einsum("nij,vj->nvi", Rs, outline) + t[:, None, :]
    reach = np.hypot(*(verts - np.asarray(workspace.center)).transpose(2, 0, 1)).max(1)
    return reach <= workspace.radius + eps_t / 2 + slack


def free_space_check(
    group: Group,
    observations: list[Observation],
    assigned: np.ndarray,
    theta: np.ndarray,
    t: np.ndarray,
    eps_t: np.ndarray,
    keep: np.ndarray,
    eps_d: float,
    slack: float,
) -> np.ndarray:
    """`keep` (N,) and, for each pose (`theta` (N,), `t` (N, 2)), every path clear
    of the posed outline shrunk by ``eps_t/2 + slack``: up to each contact the
    sample assigns (`assigned` (N, s)), less ``eps_d + slack``, and each missed path
    whole. Samples `keep` leaves out are not checked (they stay False)."""
    # free space: path up to each contact (less eps_d), and each missed path whole
    floor = max(slack, LENGTH_SLACK)
    shrink = eps_t / 2 + slack
    return clear_paths(group, observations, assigned, theta, t, shrink, keep, eps_d + slack, floor)


def clear_paths(
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
            layer = group.stable.layer_index(obs.path.height)
            keep[idx] &= _free_space_ok(
                group, theta[idx], t[idx], shrink[idx], o, d, reach_len, floor, layer
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
    layer: int = 0,
) -> np.ndarray:
    """Does the segment origin -> origin + length*direction avoid the posed outline
    of `layer` (the path's height) shrunk by `shrink` (per sample)? Checked in the
    model frame, vectorized."""
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
        ok[idx] = ~shapely.intersects(lines[idx], group.shrunk(float(value), layer))
    return ok
