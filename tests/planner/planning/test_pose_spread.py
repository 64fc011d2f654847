"""A part pinned along one direction only (two contacts on nearly parallel faces) is
planned where the touches still allow it to lie, not where its fit puts it.

The session below is one a client met over HTTP on a set of sixteen random parts:
a thin part touched on its two long faces (3 degrees from parallel) was fitted
tens of millimetres along them, with a contact beyond the end of its face. The
plans aimed at the fit; ten paths in a row missed, none of them changed the
hypotheses, and the eleventh plan offered nothing.
"""

from __future__ import annotations

import numpy as np

from hardware_sim.world import World
from planner.models.library import object_from_dict
from planner.planning import pose_spread
from planner.planning.config import StrategyConfig
from planner.planning.plan import plan_session
from planner.planning.pose_spread import admitted_poses, agreement, recentred
from planner.recognition.model_check import contacts_on_faces
from planner.recognition.session import Session
from planner.types import Contact, Observation, Pose, SensingPath, SensorBounds
from tests.conftest import WORKSPACE

SLIVER = object_from_dict(
    {
        "name": "sliver",
        "outline": [
            [-24.86, 32.06], [-17.76, 12.8], [-27.31, 8.05],
            [6.94, -22.6], [20.13, -22.37], [28.24, -10.51],
        ],
    }
)  # fmt: skip
TRUTH = Pose(83.60862422378892, 76.8964379307823, 1.555794072479551)
BOUNDS = SensorBounds(1.0, 0.05)
RECORDED = [
    Observation(SensingPath((200.0, 0.0), (-1.0, 0.0), 400.0), None),
    Observation(
        SensingPath((-184.91893179950094, 76.19047619047622), (1.0, 0.0), 369.8378635990019),
        Contact((71.34590060532459, 75.68776122811904), (-0.7553938853304704, 0.6552709958523545)),
    ),
    Observation(
        SensingPath(
            (196.53919046181767, 37.04519688992574),
            (-0.988478525296241, 0.15136117411069688),
            377.3351293083869,
        ),
        Contact((80.26837415585828, 55.14528603294158), (0.7677579614193139, -0.6407399727481183)),
    ),
]


def touched() -> Session:
    session = Session([SLIVER], BOUNDS, WORKSPACE)
    for o in RECORDED:
        session = session.observe(o)
    return session


def test_the_fit_of_a_poorly_pinned_part_is_moved_where_it_may_lie():
    session = touched()
    wide = [h for h in session.hypotheses if h.error_bound.translation > 20]
    assert wide, "the contacts pin the sliver along its long faces only"
    faces = SLIVER.stable_poses[0].all_faces
    points = np.array([c.point for c in session.contacts])
    for h, moved in zip(session.hypotheses, recentred(session, session.hypotheses), strict=True):
        theta, _ = admitted_poses(session, h)
        assert len(theta) >= 2
        shift = np.hypot(moved.pose.x - h.pose.x, moved.pose.y - h.pose.y)
        # the fit put a contact off its finite face: the plan works elsewhere
        assert shift > 1.0
        # every pose the old bound allowed lies within the new one
        assert moved.error_bound.translation >= h.error_bound.translation + shift - 1e-9
        assert moved.error_bound.eps_t >= h.error_bound.eps_t + 2 * shift - 1e-9
        face = np.array([[a for a in h.assignment]])
        on = contacts_on_faces(
            points,
            faces,
            face,
            np.ones_like(face, dtype=bool),
            np.array([[moved.pose.theta, h.pose.theta]]),
            np.array([[[moved.pose.x, moved.pose.y], [h.pose.x, h.pose.y]]]),
            BOUNDS.position_error + 1e-6,
        )
        assert on.tolist() == [[True, False]]


def test_the_poses_spread_are_bounded_in_advance(monkeypatch):
    session = touched()
    faces = len(SLIVER.stable_poses[0].all_faces)
    monkeypatch.setattr(pose_spread, "SPREAD_FACES", pose_spread.POSES_EACH * faces)
    moved = recentred(session, session.hypotheses)
    assert moved[0] != session.hypotheses[0]  # the most probable is spread
    assert moved[1:] == list(session.hypotheses[1:])  # the budget ends before the next
    monkeypatch.setattr(pose_spread, "SPREAD_FACES", 0)
    assert recentred(session, session.hypotheses) == list(session.hypotheses)


def test_a_prediction_counts_only_where_the_part_may_lie():
    session = touched()
    h = session.hypotheses[0]
    _, t = admitted_poses(session, h)
    # paths across the direction the poses spread along, from one end of it to the other
    along = t[np.argmax(t @ [1.0, 1.0])] - t[np.argmin(t @ [1.0, 1.0])]
    along /= np.hypot(*along)
    across = np.array([-along[1], along[0]])
    offsets = np.linspace(-80.0, 80.0, 33)
    aims = t.mean(axis=0) + offsets[:, None] * along
    share = agreement(
        session,
        [h],
        np.ones((len(offsets), 1), dtype=bool),  # as if the planned pose were hit on each
        aims - 150 * across,
        np.tile(across, (len(offsets), 1)),
        np.full(len(offsets), 300.0),
    )[:, 0]
    assert ((share > 0) & (share < 1)).any()  # only some of the poses lie on such a path
    assert share[0] == 0 and share[-1] == 0  # beyond either end: none does
    assert share.max() == 1  # across the middle: every one


def test_a_poorly_pinned_part_is_found_without_touching_air_again_and_again():
    session = touched()
    world = World(SLIVER, 0, TRUTH, WORKSPACE)
    rng = np.random.default_rng(0)
    where, misses = (200.0, 0.0), 0
    for k in range(4):
        result = plan_session(session, where, StrategyConfig(budget_ms=None), k)
        if result.status == "localized":
            break
        assert result.paths, result.note
        path = result.paths[0].path
        observation, _ = world.execute(path, BOUNDS, rng)
        misses += observation.contact is None
        session = session.observe(observation)
        where = tuple(np.add(path.origin, np.multiply(path.direction, path.length)))
    assert session.status == "localized"
    assert misses <= 1
