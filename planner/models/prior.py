"""The prior over the true object and its pose, as the planner assumes it (DESIGN §4.7).

Object by its prior (equal by default), stable pose by its probability,
orientation uniform, and position uniform among those keeping the whole outline
inside the safe circle (the circle is all that is known of where the object
lies). Hypothesis weights are posteriors under this prior, so a simulation
that draws its true worlds from it is one where predicted probabilities can be
checked against frequencies. World frame, lengths in the object files' unit,
angles in radians.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from planner.errors import PlannerError
from planner.geometry import LENGTH_SLACK, rotate, rotation_matrices
from planner.types import ObjectModel, StablePose, Workspace

__all__ = ["draw_poses", "draw_stable_poses"]

#: Most posed vertices held at once while testing drawn poses.
_POSED_VERTICES = 1_000_000


def draw_stable_poses(
    models: Sequence[ObjectModel], n: int, rng: np.random.Generator
) -> list[tuple[int, int]]:
    """`n` draws of (object index, stable pose index) from the priors."""
    prior = np.array([m.prior if m.prior is not None else 1.0 for m in models], dtype=float)
    which = rng.choice(len(models), size=n, p=prior / prior.sum())
    pose = np.zeros(n, dtype=int)
    for i in np.unique(which):
        at = np.flatnonzero(which == i)
        probs = np.array([p.probability for p in models[int(i)].stable_poses])
        pose[at] = rng.choice(len(probs), size=len(at), p=probs / probs.sum())
    return [(int(i), int(j)) for i, j in zip(which, pose, strict=True)]


def draw_poses(
    stable: StablePose, workspace: Workspace, n: int, rng: np.random.Generator
) -> tuple[np.ndarray, np.ndarray]:
    """`n` poses (theta (n,), t (n, 2)) of one stable pose: orientation uniform,
    position uniform among those keeping every vertex inside the safe circle
    (``v_world = R(theta) v + t``), by rejection in batches.

    >>> from planner.models.outlines import make_stable_pose
    >>> sq = make_stable_pose([[-1, -1], [1, -1], [1, 1], [-1, 1]])
    >>> theta, t = draw_poses(sq, Workspace((0, 0), 3), 100, np.random.default_rng(0))
    >>> bool(np.all(np.hypot(*t.T) <= 3 - 1))   # the corners stay inside
    True
    """
    centre = np.asarray(workspace.center, dtype=float)
    R = workspace.radius
    if stable.radius > 2 * R:
        raise PlannerError("the object does not fit in the safe circle", field="workspace.radius")
    theta_out, t_out = [np.zeros(0)], [np.zeros((0, 2))]
    have = 0
    for _ in range(1000):
        if have >= n:
            break
        m = max(64, 4 * (n - have))
        theta = rng.uniform(-np.pi, np.pi, m)
        r, a = R * np.sqrt(rng.random(m)), rng.uniform(-np.pi, np.pi, m)
        t = r[:, None] * np.stack([np.cos(a), np.sin(a)], axis=1)  # relative to the centre
        ok = _inside(stable, theta, t, R * (1 - LENGTH_SLACK))
        theta_out.append(theta[ok])
        t_out.append(t[ok] + centre)
        have += int(ok.sum())
    if have < n:
        raise PlannerError("no pose of the object fits in the safe circle", field="workspace")
    return np.concatenate(theta_out)[:n], np.concatenate(t_out)[:n]


def _inside(stable: StablePose, theta: np.ndarray, t: np.ndarray, limit: float) -> np.ndarray:
    """(m,) every vertex of the outline posed at (theta, t) lies within `limit` of the
    origin. A pose whose farthest vertex cannot reach the limit passes unposed; the
    others are posed a bounded number of vertices at a time."""
    ok = np.hypot(t[:, 0], t[:, 1]) + stable.radius <= limit
    near = np.flatnonzero(~ok)
    step = max(1, _POSED_VERTICES // len(stable.outline))
    for k in range(0, len(near), step):
        at = near[k : k + step]
        posed = rotate(rotation_matrices(theta[at]), stable.outline) + t[at, None]
        ok[at] = np.all(np.hypot(posed[..., 0], posed[..., 1]) <= limit, axis=1)
    return ok
