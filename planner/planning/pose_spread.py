"""Where a poorly pinned class may lie: its poses spread over what the touches allow (DESIGN §4.15).

The recognition reports each hypothesis as a fitted pose and a bound. Where the
contacts pin the pose poorly (two contacts on nearly parallel faces: a thin part
that may lie anywhere along tens of millimetres), the fit is one pose of many,
often one that puts a contact beyond the end of its face, and a path aimed at it
misses the part where it really lies. The miss cannot shrink the bound, the
hypotheses stay as they were, and a plan on the fitted poses offers the same
kind of path again: a robot touched air ten times in a row on a set of sixteen
random parts.

For each hypothesis whose translation bound is wide (`SPREAD_FROM` position
bounds), poses are spread over the set consistent with its contacts
(:func:`planner.recognition.consistent.consistent_poses`, the fit among them);
those that put a contact off its finite face, the outline across a path that
missed, or part of it outside the safe circle, are dropped. The plan works on
the one nearest their mean (:func:`recentred`), its bound widened by how far it
moved, so that the outcome model's worst case still covers every pose the bound
allowed; each miss drops the poses it passed through, and the next plan aims
where the part may still be. The recognition's predictions count only on the
share of the poses whose outcome on a path agrees with the planned pose's
(:func:`agreement`).

World frame, lengths in the object files' unit.
"""

from __future__ import annotations

import dataclasses
import functools
from collections.abc import Sequence
from contextlib import AbstractContextManager

import numpy as np

from planner.geometry import LENGTH_SLACK, wrap_angle
from planner.memo import ScopedMemo
from planner.models.tip import grown_models
from planner.planning.outcomes import predict_outcomes
from planner.planning.posed_set import pose_hypotheses
from planner.recognition.consistent import consistent_poses
from planner.recognition.model_check import contacts_on_faces, inside_workspace
from planner.recognition.session import Session
from planner.types import ErrorBound, Hypothesis, Pose

__all__ = [
    "POSES_EACH",
    "SPREAD_FACES",
    "SPREAD_FROM",
    "SPREAD_ROTATIONS",
    "admitted_poses",
    "agreement",
    "recentred",
    "spreads",
]

#: Translation bound, in position bounds, above which a hypothesis' poses are spread.
SPREAD_FROM = 5.0
#: Rotations across the interval the normals allow at which poses are spread
#: (the consistent polygon's corners, its mean, and points between: :func:`_corners`).
SPREAD_ROTATIONS = 4

#: Most poses spread per hypothesis, its fit included.
POSES_EACH = 64
#: Posed faces (poses x faces each) a plan spreads at most: past them, the less
#: probable wide hypotheses are planned at their fits.
SPREAD_FACES = 60_000

#: The spread poses of the hypotheses met during one plan (see :func:`spreads`).
_SPREADS = ScopedMemo("spreads")


def spreads() -> AbstractContextManager[None]:
    """Within it, each hypothesis' poses are spread once (:func:`admitted_poses`)."""
    return _SPREADS.scope()


def _wide(session: Session, hypothesis: Hypothesis) -> bool:
    eps_d = session.bounds.position_error
    return eps_d > 0 and hypothesis.error_bound.translation > SPREAD_FROM * eps_d


def admitted_poses(session: Session, hypothesis: Hypothesis) -> tuple[np.ndarray, np.ndarray]:
    """Poses (theta (M,), t (M, 2)) of `hypothesis` (its fit among them) spread
    over the set consistent with the session's contacts as it assigns them, that
    keep every assigned contact on its finite face, the outline off every path
    that missed (at the default height) and inside the safe circle (when the
    session requires the part there). Empty when none does or the set is
    unbounded (a slide the hypotheses themselves sample)."""
    return _admitted_all(session, [hypothesis])[0]


def _admitted_all(
    session: Session, hypotheses: Sequence[Hypothesis]
) -> list[tuple[np.ndarray, np.ndarray]]:
    """:func:`admitted_poses` of each of `hypotheses`, those not yet spread in this
    plan spread together: one pass per stable pose, one cast of the misses."""
    # keyed by identity for the length of one plan, each entry holding its session
    # and hypothesis (alive, so no key is reused); hashing the hypotheses cost more
    memo = _SPREADS.get()
    memo = {} if memo is None else memo

    def known(h: Hypothesis) -> bool:
        entry = memo.get((id(session), id(h)))
        return entry is not None and entry[0] is session and entry[1] is h

    contacts = [o.contact for o in session.surface_observations if o.contact is not None]
    todo = list({id(h): h for h in hypotheses if not known(h)}.values())
    none = (np.zeros(0), np.zeros((0, 2)))
    for h in todo:
        memo[(id(session), id(h))] = (session, h, none)
    spread = [h for h in todo if len(contacts) >= 2 and len(h.assignment) == len(contacts)]
    groups: dict[tuple[str, int], list[Hypothesis]] = {}
    for h in spread:
        groups.setdefault((h.object, h.stable_pose), []).append(h)
    found = [_spread_group(session, contacts, rows) for rows in groups.values()]
    poses = [(h, th, t) for rows, got in zip(groups.values(), found, strict=True)
             for h, (th, t) in zip(rows, got, strict=True) if len(th)]  # fmt: skip
    missed = [o.path for o in session.observations if o.contact is None and o.path.height is None]
    if poses and missed:
        owner = np.concatenate([np.full(len(th), k) for k, (_, th, _) in enumerate(poses)])
        posed = _posed(
            session,
            [h for h, th, _ in poses for _ in th],
            np.concatenate([th for _, th, _ in poses]),
            np.vstack([t for _, _, t in poses]),
        )
        met = predict_outcomes(
            posed,
            np.array([p.origin for p in missed]),
            np.array([p.direction for p in missed]),
            np.array([p.length for p in missed]),
            session.working_sensor,
        ).hit.any(axis=0)
        poses = [
            (h, th[~met[owner == k]], t[~met[owner == k]]) for k, (h, th, t) in enumerate(poses)
        ]
    for h, th, t in poses:
        memo[(id(session), id(h))] = (session, h, (th, t))
    return [memo[(id(session), id(h))][2] for h in hypotheses]


def _spread_group(
    session: Session, contacts: list, rows: list[Hypothesis]
) -> list[tuple[np.ndarray, np.ndarray]]:
    """The poses of `rows` (one stable pose) spread over their consistent sets,
    kept where every assigned contact lies on its finite face and the part inside
    the safe circle (when the session requires it), the fit first."""
    points = np.array([c.point for c in contacts], dtype=float)
    normals = np.array([c.normal for c in contacts], dtype=float)
    assigned = np.array([[a is not None for a in h.assignment] for h in rows])
    face = np.array([[a if a is not None else 0 for a in h.assignment] for h in rows])
    stable = session.models_by_name[rows[0].object].stable_poses[rows[0].stable_pose]
    faces = stable.all_faces
    eps_d, phi = session.bounds.position_error, session.bounds.normal_error
    fit_theta = np.array([h.pose.theta for h in rows])
    theta, t, valid = consistent_poses(
        points, normals, faces.normal[face], faces.offset[face], assigned, fit_theta, eps_d, phi,
        rotations=SPREAD_ROTATIONS, mixing=_corners,
    )  # fmt: skip
    # the fit first; a row whose set is unbounded (a slide) is not spread
    theta = np.hstack([fit_theta[:, None], theta])
    t = np.concatenate([np.array([[[h.pose.x, h.pose.y]] for h in rows]), t], axis=1)
    valid = np.hstack([valid.any(axis=1, keepdims=True), valid])
    slack = eps_d + LENGTH_SLACK * session.length_scale
    valid &= contacts_on_faces(points, faces, face, assigned, theta, t, slack)
    if session.config.require_inside_workspace:  # the part lies inside the safe circle
        inside = inside_workspace(
            stable.outline, theta.ravel(), t.reshape(-1, 2), np.zeros(theta.size),
            session.workspace, slack,
        )  # fmt: skip
        valid &= inside.reshape(theta.shape)
    out = []
    for k in range(len(rows)):
        keep = np.flatnonzero(valid[k])
        if len(keep) > POSES_EACH:  # evenly thinned, the fit (column 0) kept when valid
            keep = keep[np.linspace(0, len(keep) - 1, POSES_EACH).round().astype(int)]
        out.append((theta[k][keep], t[k][keep]))
    return out


@functools.lru_cache(maxsize=64)
def _corners(vertices: int) -> np.ndarray:
    """Mixing weights over a consistent polygon's candidate vertices (renormalized
    over its true vertices, n of them): each vertex, its mean, and the points
    about a third and two thirds of the way from the mean to each vertex
    (``(2 e_v + 1) / (2 + n)``, ``(6 e_v + 1) / (6 + n)``): a slide's polygon is
    long and thin, and its ends are where a part touched on two nearly parallel
    faces may lie as well as its middle."""
    eye = np.eye(vertices)
    return np.vstack([eye, 6 * eye + 1, 2 * eye + 1, np.ones((1, vertices))])


def _posed(session: Session, hypotheses: Sequence[Hypothesis], theta: np.ndarray, t: np.ndarray):  # type: ignore[no-untyped-def]
    """Each hypothesis' outline at its pose (`theta`, `t` one each), as the planner
    casts it (grown by the ball tip's radius: the session observes its centre)."""
    models = grown_models(session.models_by_name, session.sensor.tip_radius)
    moved = [
        dataclasses.replace(h, pose=Pose(float(x), float(y), float(a)), probability=1.0)
        for h, a, (x, y) in zip(hypotheses, theta, t, strict=True)
    ]
    return pose_hypotheses(moved, models)


def recentred(session: Session, hypotheses: Sequence[Hypothesis]) -> list[Hypothesis]:
    """`hypotheses` with each wide one (the most probable, up to `SPREAD_FACES`
    posed faces) whose fit is no longer possible (a contact off its finite face,
    a missed path through its outline) planned at its admitted pose nearest
    their mean, its bound widened by the move (translation by the shift,
    rotation by the turn, the error disk by twice the farthest displacement of
    its outline): every pose the old bound allowed lies within the new one."""
    out = list(hypotheses)
    by_name = session.models_by_name
    wide, faces = [], 0
    for k, h in enumerate(hypotheses):  # the most probable first, within SPREAD_FACES
        if _wide(session, h):
            faces += POSES_EACH * len(by_name[h.object].stable_poses[h.stable_pose].all_faces)
            if faces > SPREAD_FACES:
                break
            wide.append(k)
    admitted = _admitted_all(session, [hypotheses[k] for k in wide])
    for k, (theta, t) in zip(wide, admitted, strict=True):
        h = hypotheses[k]
        fit_kept = len(theta) and theta[0] == h.pose.theta and (t[0] == (h.pose.x, h.pose.y)).all()
        if not len(theta) or fit_kept:
            continue  # the fit itself is still possible: planned as it is
        stable = by_name[h.object].stable_poses[h.stable_pose]
        lever = float(np.hypot(*np.asarray(stable.outline, dtype=float).T).max())
        turned = wrap_angle(theta - h.pose.theta)
        gap = np.hypot(*(t - t.mean(axis=0)).T) + lever * np.abs(turned - turned.mean())
        m = int(np.argmin(gap))
        shift = float(np.hypot(t[m, 0] - h.pose.x, t[m, 1] - h.pose.y))
        turn = abs(float(turned[m]))
        bound = h.error_bound
        out[k] = dataclasses.replace(
            h,
            pose=Pose(float(t[m, 0]), float(t[m, 1]), h.pose.theta + float(turned[m])),
            error_bound=ErrorBound(
                bound.translation + shift,
                bound.rotation + turn,
                bound.eps_t + 2 * (shift + lever * turn),
            ),
        )
    return out


def agreement(
    session: Session,
    hypotheses: Sequence[Hypothesis],
    planned_hit: np.ndarray,
    origins: np.ndarray,
    directions: np.ndarray,
    lengths: np.ndarray,
) -> np.ndarray:
    """(C, K) for each of C paths (default height) and each of the K session
    `hypotheses` (a class' best member each), the share of its admitted poses
    whose outcome on the path agrees with the planned one (`planned_hit` (C, K):
    both hit or both miss); 1 where the pose is pinned within `SPREAD_FROM`
    position bounds or no pose is admitted."""
    share = np.ones(planned_hit.shape)
    if not len(origins):
        return share
    wide = [k for k, h in enumerate(hypotheses) if _wide(session, h)]
    spread = dict(zip(wide, _admitted_all(session, [hypotheses[k] for k in wide]), strict=True))
    spread = {k: poses for k, poses in spread.items() if len(poses[0]) >= 2}
    if not spread:
        return share
    # every class' poses in one cast
    owner = np.concatenate([np.full(len(theta), k) for k, (theta, _) in spread.items()])
    posed = _posed(
        session,
        [hypotheses[k] for k in owner],
        np.concatenate([theta for theta, _ in spread.values()]),
        np.vstack([t for _, t in spread.values()]),
    )
    hit = predict_outcomes(posed, origins, directions, lengths, session.working_sensor).hit
    for k in spread:
        share[:, k] = (hit[:, owner == k] == planned_hit[:, k : k + 1]).mean(axis=1)
    return share
