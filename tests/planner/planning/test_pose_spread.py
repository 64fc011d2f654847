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
from planner.geometry import rotate, rotation_matrices
from planner.models.library import object_from_dict
from planner.planning import pose_spread
from planner.planning.config import StrategyConfig
from planner.planning.plan import plan_session
from planner.planning.pose_spread import admitted_poses, agreement, recentred
from planner.recognition.config import RecognitionConfig
from planner.recognition.model_check import contacts_on_faces
from planner.recognition.session import Session
from planner.types import Contact, Observation, Pose, SensingPath, SensorBounds, Workspace
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


def _reach(theta, t):
    """The farthest posed outline vertex from the circle's centre, per pose."""
    R = rotation_matrices(theta)
    v = rotate(R, np.asarray(SLIVER.stable_poses[0].outline, dtype=float)) + t[:, None]
    return np.hypot(v[..., 0], v[..., 1]).max(axis=1)


def test_the_poses_spread_keep_the_part_inside_the_safe_circle():
    def spread(radius, inside=True):
        config = RecognitionConfig(require_inside_workspace=inside)
        session = Session([SLIVER], BOUNDS, Workspace((0.0, 0.0), radius), config)
        for o in RECORDED:
            session = session.observe(o)
        return [admitted_poses(session, h) for h in session.hypotheses]

    wide = spread(200.0)
    assert all(len(theta) >= 2 for theta, _ in wide)
    assert max(_reach(*poses).max() for poses in wide) > 150.0  # some reach past 150
    cut = spread(150.0)
    for (theta, t), (all_theta, _) in zip(cut, spread(150.0, inside=False), strict=True):
        assert len(theta) and _reach(theta, t).max() <= 150.0 + BOUNDS.position_error + 1e-6
        assert len(theta) <= len(all_theta)
    assert sum(len(theta) for theta, _ in cut) < sum(len(theta) for theta, _ in wide)


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


def test_near_twins_the_nominal_contacts_cannot_separate_still_get_a_path():
    """Two bars 2.2 mm apart per side, touched on all four faces at 2 mm / 0.1 rad:
    each one's nominal contacts are explained by the other within the bounds, so
    the recognition predicts no change on any path it judged, and nothing refines
    (the plan was empty: the robot stopped). The plan offers the paths where the
    two classes' nominal outcomes lie farthest apart, where a measurement within
    the bounds may still tell them apart."""
    bars = [
        object_from_dict(
            {
                "name": "wide",
                "outline": [[-23.86, -7.0], [23.86, -5.83], [23.86, 5.83], [-23.86, 7.0]],
            }
        ),
        object_from_dict(
            {
                "name": "thin",
                "outline": [[-22.11, -4.78], [22.11, -3.29], [22.11, 3.29], [-22.11, 4.78]],
            }
        ),
    ]
    session = Session(bars, SensorBounds(2.0, 0.1), WORKSPACE)
    for origin, direction, length, contact in [
        ((200.0, 0.0), (-1.0, 0.0), 400.0, None),
        (
            (-59.3769755301123, -190.98265569652247), (0.3420201433256689, 0.9396926207859083),
            399.54622787434346,
            ((26.326239573826093, 43.388481174347625), (-0.30642459863936927, -0.9518949339862575)),
        ),
        (
            (199.8429716183235, -7.92380557295209), (-0.9577161354927661, 0.2877147959643398),
            182.63287042126765,
            ((57.035281299772514, 35.595096039197436), (0.9441222862862204, -0.32959537092877994)),
        ),
        (
            (-162.97190398132918, 115.93169761847032), (0.9424745193490182, -0.3342779986445972),
            384.7005654631408,
            ((13.230056723444363, 55.202669958255626), (-0.9380072139796707, 0.3466157332293161)),
        ),
        (
            (-127.41343974034125, 154.16165338220276), (0.8510875517712297, -0.5250237891944083),
            216.08762561267827,
            ((37.60425400509882, 51.35198324503128), (0.30307130986736996, 0.9529678804321144)),
        ),
    ]:  # fmt: skip
        path = SensingPath(origin, direction, length)
        session = session.observe(Observation(path, None if contact is None else Contact(*contact)))
    assert session.localization.classes == 2
    result = plan_session(session, (0.0, 200.0), StrategyConfig(budget_ms=None), 0)
    assert result.status == "ambiguous" and result.paths, result.note
    assert "farthest apart" in result.note
    assert all(p.p_distinguishing == 0 for p in result.paths)  # nothing is sure
