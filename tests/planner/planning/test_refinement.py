"""Pose refinement when nothing is informative, repeated paths, and the search
for the object before the first contact."""

from __future__ import annotations

import math

import numpy as np
import pytest
import shapely

from hardware_sim.world import random_world
from planner.codec import plan_to_dict
from planner.planning.analysis import analyse
from planner.planning.candidates import Candidates
from planner.planning.config import STRATEGIES, StrategyConfig
from planner.planning.plan import plan
from planner.planning.probes import search_chord
from planner.planning.refinement import refinement
from planner.planning.result import REFINING, opening_path
from planner.planning.survivors import repeated_paths
from planner.recognition.session import Session
from planner.types import Contact, Observation, SensingPath, SensorBounds
from tests.conftest import WORKSPACE, object_set

BUMP = object_set("thesis_like")
SENSOR = SensorBounds(1.0, math.radians(5))


def _stuck_session() -> Session:
    """bump_block at the origin, touched on its bottom, right and top faces, the
    bottom and top contacts only 10 mm apart: the rotation is known to about the
    normal error, the disks (~23 mm) swamp the 15 mm bump, no path tells the four
    classes apart."""
    s = Session(BUMP, SENSOR, WORKSPACE)
    for origin, direction, point, normal in [
        ((20, -200), (0, 1), (20, 0), (0, -1)),
        ((200, 70), (-1, 0), (100, 70), (1, 0)),
        ((10, 200), (0, -1), (10, 80), (0, 1)),
    ]:
        s = s.observe(Observation(SensingPath(origin, direction, 400), Contact(point, normal)))
    return s


@pytest.fixture(scope="module")
def stuck() -> Session:
    return _stuck_session()


def test_the_scene_has_no_informative_path(stuck):
    found = analyse(
        stuck.hypotheses, BUMP, SENSOR, WORKSPACE, (200.0, 0.0), observations=stuck.observations
    )
    assert found.table.n_classes > 1
    assert not found.info.informative.any()


@pytest.mark.parametrize("name", STRATEGIES)
def test_plan_refines_the_pose_when_nothing_is_informative(stuck, name):
    before = max(h.error_bound.eps_t for h in stuck.hypotheses)
    result = plan(
        stuck.hypotheses,
        BUMP,
        SENSOR,
        WORKSPACE,
        (200.0, 0.0),
        StrategyConfig(name=name),
        0,
        observations=stuck.observations,
    )
    assert result.status == "ambiguous" and result.paths
    assert "refining the pose" in (result.note or "")
    best = result.paths[0]
    assert best.family == REFINING
    assert best.expected_eps_t is not None and best.expected_eps_t < 0.6 * before
    assert plan_to_dict(result, 1)["paths"][0]["expected_eps_t"] == pytest.approx(
        best.expected_eps_t
    )


def test_the_refining_touch_shrinks_the_disk_as_predicted(stuck):
    # execute the best refining path on the true object (the first class' pose) exactly
    result = plan(
        stuck.hypotheses, BUMP, SENSOR, WORKSPACE, (200.0, 0.0), observations=stuck.observations
    )
    best = result.paths[0]
    truth = shapely.Polygon(BUMP[0].stable_poses[0].outline)
    end = np.add(best.origin, np.multiply(best.length, best.direction))
    hit = shapely.intersection(truth.exterior, shapely.LineString([best.origin, end]))
    points = np.array(shapely.get_coordinates(hit))
    first = points[np.argmin((points - best.origin) @ np.asarray(best.direction))]
    faces = BUMP[0].stable_poses[0].faces
    on = np.argmin(
        [
            shapely.LineString([a, b]).distance(shapely.Point(first))
            for a, b in zip(faces.start, faces.end, strict=True)
        ]
    )
    after = stuck.observe(Observation(best.path, Contact(tuple(first), tuple(faces.normal[on]))))
    mine = [h for h in after.hypotheses if h.object == "bump_block"]
    assert min(h.error_bound.eps_t for h in mine) < 0.6 * min(
        h.error_bound.eps_t for h in stuck.hypotheses
    )


def test_refinement_credits_nothing_to_a_path_that_misses(stuck):
    away = Candidates.from_paths([SensingPath((-200.0, -190.0), (1.0, 0.0), 400.0)])
    found = analyse(
        stuck.hypotheses,
        BUMP,
        SENSOR,
        WORKSPACE,
        (200.0, 0.0),
        observations=stuck.observations,
        extra_paths=[SensingPath(away.origins[0], away.directions[0], 400.0)],
    )
    i = int(np.flatnonzero(found.candidates.source == "extra")[0])
    assert not found.outcomes.hit[i].any()
    ref = refinement(
        stuck.hypotheses,
        {m.name: m for m in BUMP},
        found.posed,
        found.outcomes,
        stuck.contacts,
        SENSOR,
    )
    np.testing.assert_array_equal(ref.after[i], ref.before)
    assert ref.expected[i] == pytest.approx(ref.current)
    assert ref.expected.min() < ref.current


def test_repeated_paths_are_recognized(stuck):
    taken = stuck.observations[1].path
    o, d = np.asarray(taken.origin), np.asarray(taken.direction)
    turn = math.radians(20)
    rot = np.array([[math.cos(turn), -math.sin(turn)], [math.sin(turn), math.cos(turn)]])
    cands = Candidates.from_paths(
        [
            taken,  # the same path
            SensingPath((o[0], o[1] + 3), taken.direction, taken.length),  # 3 mm aside
            SensingPath((o[0], o[1] + 60), taken.direction, taken.length),  # far aside
            SensingPath(taken.origin, tuple(rot @ d), taken.length),  # another way
            SensingPath(tuple(o + 400 * d), tuple(-d), taken.length),  # the other way
        ]
    )
    found = analyse(
        stuck.hypotheses, BUMP, SENSOR, WORKSPACE, (200.0, 0.0), observations=stuck.observations
    )
    flags = repeated_paths(cands, stuck.observations, found.posed, SENSOR)
    assert flags.tolist() == [True, True, False, False, False]


def _hit_share(path: SensingPath, worlds) -> float:
    return float(np.mean([w.polygon().intersects(_line(path)) for w in worlds]))


def _line(path: SensingPath) -> shapely.LineString:
    return shapely.LineString(
        [path.origin, np.add(path.origin, np.multiply(path.length, path.direction))]
    )


@pytest.mark.parametrize("name", ["thesis_like", "workshop", "table_poses"])
def test_search_after_misses_meets_the_object_more_often(name):
    # independent worlds that the first probe (through the centre) missed: the
    # search chord meets more of them than turning about the centre would
    models = object_set(name)
    by_name = {m.name: m for m in models}
    rng = np.random.default_rng(11)
    first = opening_path(WORKSPACE, (200.0, 0.0))
    worlds = [random_world(models, WORKSPACE, rng) for _ in range(800)]
    left = [w for w in worlds if not w.polygon().intersects(_line(first))]
    assert len(left) > 200
    chord, _ = search_chord(by_name, WORKSPACE, [first], (200.0, 0.0))
    turned = opening_path(WORKSPACE, (200.0, 0.0), misses=1)
    assert _hit_share(chord, left) > _hit_share(turned, left) + 0.05
    # and after the search chord missed too
    left2 = [w for w in left if not w.polygon().intersects(_line(chord))]
    third, _ = search_chord(by_name, WORKSPACE, [first, chord], (200.0, 0.0))
    turned2 = opening_path(WORKSPACE, (200.0, 0.0), misses=2)
    assert _hit_share(third, left2) > _hit_share(turned2, left2) + 0.05


def test_opening_search_falls_back_when_the_prior_is_exhausted():
    # misses along every chord of a fine fan: no prior draw is left
    fan = [opening_path(WORKSPACE, (200.0, 0.0), angle=a) for a in np.linspace(0, math.pi, 90)]
    fan += [SensingPath((x, -200.0), (0.0, 1.0), 400.0) for x in np.linspace(-190, 190, 40)]
    chord, aim = search_chord({m.name: m for m in BUMP}, WORKSPACE, fan, (200.0, 0.0))
    assert aim == (0.0, 0.0)
    assert math.hypot(*chord.origin) == pytest.approx(WORKSPACE.radius)


def _stadium_touched_on_its_sides():
    """The shared stadium (straight sides 80 long, round ends drawn with short
    faces) touched on its straight sides and once where a round end meets one:
    one class, its slide along the sides known only to about 10."""
    from planner.recognition.session import Session
    from planner.types import Contact, Observation, SensingPath, SensorBounds, Workspace
    from tests.conftest import object_set

    stadium = [m for m in object_set("curved") if m.name == "stadium"]
    session = Session(stadium, SensorBounds(1.0, math.radians(3)), Workspace((0, 0), 200))
    a = math.radians(-75)
    end = (40 + 25 * math.cos(a), 25 * math.sin(a)), (math.cos(a), math.sin(a))
    for p, n in [((-20, -25), (0, -1)), ((25, -25), (0, -1)), ((0, 25), (0, 1)), end]:
        p, n = np.array(p, dtype=float), np.array(n, dtype=float)
        path = SensingPath(tuple(p + 150 * n), tuple(-n), 300.0)
        session = session.observe(Observation(path, Contact(tuple(p), tuple(n))))
    return session


def test_a_curved_end_is_touched_to_pin_a_slide(monkeypatch):
    """Every hit on a drawn curve lies near a vertex; where the faces turn little,
    refinement credits it: the plan touches the round end, where before it found
    no path and the robot stopped."""
    from planner.planning import refinement as refine_module
    from planner.planning.config import StrategyConfig
    from planner.planning.plan import plan_session

    session = _stadium_touched_on_its_sides()
    assert session.localization.missing == ("accuracy",)
    config = StrategyConfig(budget_ms=None)
    plan = plan_session(session, (200.0, 0.0), config, 0)
    assert plan.paths and plan.paths[0].family == "refining"
    assert abs(plan.paths[0].aim[0]) > 35.0  # at a round end, not mid-side
    # without the credit, the hits on the round end do not count: a weaker path
    monkeypatch.setattr(refine_module, "SMOOTH_TURN", 0.0)
    blind = plan_session(session, (200.0, 0.0), config, 0)
    assert not blind.paths or blind.paths[0].expected_eps_t > plan.paths[0].expected_eps_t + 1.0


def _stadium_touched_twice():
    """A world of the shared curved set (the stadium, seen in a simulated trial)
    touched twice near one end of a straight side: one class, but the part can
    still slide about 30 along its sides, and every contact that would pin it is
    uncertain for the outcome model."""
    from planner.types import Workspace
    from tests.conftest import object_set

    models = [m for m in object_set("curved") if len(m.stable_poses[0].outline) <= 500]
    session = Session(models, SensorBounds(1.0, 0.05), Workspace((0, 0), 200))
    for origin, direction, length, point, normal in [
        ((200.0, 0.0), (-1.0, 0.0), 400.0, (49.336, -0.487), (0.98726, -0.15913)),
        (
            (51.764, -193.185), (-0.217495, 0.976062), 215.489,
            (22.966, -61.463), (0.90255, -0.43059),
        ),
    ]:  # fmt: skip
        path = SensingPath(origin, direction, length)
        session = session.observe(Observation(path, Contact(point, normal)))
    return session


def test_the_recognition_refines_where_the_outcome_model_is_unsure(monkeypatch):
    """One class short of the accuracy and no contact sure for the outcome model
    (its credit for contacts on a drawn curve taken away, as for a part of sharp
    corners): the plan still offers refining paths, ranked on the bound the
    recognition predicts (before, the plan was empty and the robot stopped).
    Observing the first path's predicted contact gives the predicted bound, within
    the accuracy."""
    from planner.planning import pose_spread
    from planner.planning import refinement as refine_module
    from planner.planning.analysis import models_by_name
    from planner.planning.plan import plan_session

    monkeypatch.setattr(refine_module, "SMOOTH_TURN", 0.0)
    # the plan works on the fitted pose (moved where the contacts allow it, the
    # stadium's disk would change and, with it, what the outcome model is sure of)
    monkeypatch.setattr(pose_spread, "SPREAD_FROM", math.inf)
    session = _stadium_touched_twice()
    where = session.localization
    assert where.classes == 1 and where.missing == ("accuracy",)
    assert where.bound.translation > 3 * session.accuracy.translation
    found = plan_session(session, (200.0, 0.0), StrategyConfig(budget_ms=None), 0)
    assert found.paths, found.note
    first = found.paths[0]
    assert first.family == REFINING and first.scored_by == "recognition"
    assert "recognition's predictions" in (found.note or "")
    # the nominal contact of the class' best member on that path, observed
    best = session.hypotheses[0]
    models = models_by_name(session.models)
    stable = models[best.object].stable_poses[best.stable_pose]
    outline = shapely.LinearRing(best.pose.apply(stable.outline))
    start = np.array(first.path.origin)
    end = start + np.multiply(first.path.direction, first.path.length)
    line = shapely.LineString([start, end])
    hits = outline.intersection(line)
    assert not hits.is_empty
    points = np.array([g.coords[0] for g in getattr(hits, "geoms", [hits])])
    point = points[np.argmin(np.linalg.norm(points - start, axis=1))]
    contact = Contact(tuple(point), _normal_at(outline, point))
    after = session.observe(Observation(first.path, contact))
    assert after.localization.classes == 1
    assert after.localization.bound.translation < where.bound.translation / 2
    assert not after.localization.missing


def _normal_at(ring, point):
    """The outward normal of the ring's face nearest `point` (counter-clockwise ring)."""
    coords = np.array(ring.coords)
    a, b = coords[:-1], coords[1:]
    t = np.clip(np.einsum("ij,ij->i", point - a, b - a) / np.einsum("ij,ij->i", b - a, b - a), 0, 1)
    k = int(np.argmin(np.linalg.norm(a + t[:, None] * (b - a) - point, axis=1)))
    d = (b[k] - a[k]) / np.linalg.norm(b[k] - a[k])
    n = np.array([d[1], -d[0]])
    return tuple(n if ring.is_ccw else -n)


def _stadium_sliding() -> Session:
    """A world of the shared curved set (the stadium, 1 mm / 0.05 rad, trial 32 of
    a simulated run) touched three times: one class that can still slide 89 mm,
    whose fitted pose lies 3-7 mm off its contacts."""
    from planner.types import Workspace
    from tests.conftest import object_set

    models = [m for m in object_set("curved") if len(m.stable_poses[0].outline) <= 500]
    session = Session(models, SensorBounds(1.0, 0.05), Workspace((0, 0), 200))
    for origin, direction, point, normal in [
        ((200.0, 0.0), (-1.0, 0.0), (15.743227, 0.712612), (0.877868, -0.478903)),
        (
            (-141.421356, 141.421356), (0.722197, -0.691688),
            (-24.847825, 29.478869), (-0.885085, 0.465429),
        ),
        (
            (-193.196571, 51.721223), (0.861967, -0.506965),
            (-59.369312, -27.824592), (-0.923441, 0.383741),
        ),
    ]:  # fmt: skip
        path = SensingPath(origin, direction, 400.0)
        session = session.observe(Observation(path, Contact(point, normal)))
    return session


def test_a_class_whose_fit_contradicts_its_contacts_is_refined_where_it_may_lie():
    """The scene above: the plan works on the class' pose nearest the middle of
    those its contacts allow (:mod:`planner.planning.pose_spread`), so the contacts
    the recognition predicts there agree with the ones made, and it ranks the
    refining paths on them."""
    from planner.planning.plan import plan_session

    session = _stadium_sliding()
    where = session.localization
    assert where.classes == 1 and where.missing == ("accuracy",)
    found = plan_session(session, (200.0, 0.0), StrategyConfig(budget_ms=None), 0)
    assert found.paths and found.paths[0].family == REFINING
    assert "refining the pose on the recognition's predictions" in (found.note or "")


def test_a_class_whose_predicted_contacts_contradict_its_contacts_still_gets_a_path(monkeypatch):
    """The scene above with the plan on the fitted pose itself: every contact the
    recognition would predict there contradicts the contacts made. The plan
    offers the paths whose contact would pin the pose most instead of none (the
    robot had stopped)."""
    from planner.planning import pose_spread
    from planner.planning.plan import plan_session

    monkeypatch.setattr(pose_spread, "SPREAD_FROM", math.inf)
    session = _stadium_sliding()
    found = plan_session(session, (200.0, 0.0), StrategyConfig(budget_ms=None), 0)
    assert found.paths and found.paths[0].family == REFINING
    assert "pin the pose most" in (found.note or "")


def test_a_budget_that_ends_the_judging_is_not_taken_for_no_path(monkeypatch):
    """The scene above with no refining path from the outcome model, the budget
    spent once the first shortlisted path is judged, and that path predicted to
    change nothing: the plan does not say no path shrinks the bound (it judged
    one of them); it offers the others, best pinning first, and says the budget
    cut the judging (it said no path shrinks the bound, and the robot stopped)."""
    from planner.planning import forecast
    from planner.planning import refining_paths as refining_module
    from planner.planning.budget import Budget
    from planner.planning.plan import plan_session

    monkeypatch.setattr(refining_module, "refining_paths", lambda *a: ([], None))
    session = _stadium_touched_twice()
    judged = []
    monkeypatch.setattr(forecast, "observed", lambda s, *a: judged.append(a) or s)
    monkeypatch.setattr(Budget, "exhausted", lambda self: bool(judged))
    found = plan_session(session, (200.0, 0.0), StrategyConfig(budget_ms=None), 0)
    assert len(judged) == 1
    assert found.paths and all(p.family == REFINING for p in found.paths)
    assert "the budget judged 1 of the" in (found.note or "")
    assert judged[0][0] not in {p.path for p in found.paths}  # the judged path is not offered
