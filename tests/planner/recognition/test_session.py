"""Session behaviour: equivalence classes, misses, undo, status, priors, normal_z."""

from __future__ import annotations

import math

import numpy as np
import pytest
import shapely

from planner.errors import InvalidObservationError
from planner.models.library import object_from_dict
from planner.recognition.config import RecognitionConfig
from planner.recognition.session import Session
from planner.types import Contact, Observation, SensingPath, SensorBounds, Workspace
from tests.conftest import WORKSPACE, object_set


def _obs(origin, direction, point=None, normal=None, length=400.0):
    contact = None if point is None else Contact(point, normal)
    return Observation(SensingPath(origin, direction, length), contact)


def _by_name(name, set_name="symmetric"):
    return [m for m in object_set(set_name) if m.name == name]


def test_square_ends_as_one_class_of_four_rotations():
    session = Session(_by_name("square"), SensorBounds(0.5, math.radians(2)), WORKSPACE)
    session = session.observe(_obs((0, -200), (0, 1), (5, -40), (0, -1)))
    assert session.status == "ambiguous"
    session = session.observe(_obs((200, 10), (-1, 0), (40, 10), (1, 0)))
    assert session.status == "localized"
    hyps = session.hypotheses
    assert len(hyps) == 4 and {h.equivalence_class for h in hyps} == {0}
    thetas = sorted(round(math.degrees(h.pose.theta) % 360) % 360 for h in hyps)
    assert thetas == [0, 90, 180, 270]
    assert all(abs(h.pose.x) < 1.5 and abs(h.pose.y) < 1.5 for h in hyps)
    assert math.isclose(sum(h.probability for h in hyps), 1.0)


def test_a_miss_prunes_exactly_the_hypotheses_whose_shrunk_outline_it_crosses():
    models = _by_name("plate")
    session = Session(models, SensorBounds(), WORKSPACE)
    session = session.observe(_obs((0, -200), (0, 1), (0, -30), (0, -1)))
    before = session.hypotheses
    miss = _obs((50, -200), (0, 1), length=400.0)
    line = shapely.LineString([(50, -200), (50, 200)])
    expected = set()
    for h in before:
        shrunk = shapely.Polygon(session.posed_outline(h)).buffer(-h.error_bound.eps_t / 2)
        if not line.intersects(shrunk):
            expected.add(
                (h.assignment, round(h.pose.x, 6), round(h.pose.y, 6), round(h.pose.theta, 6))
            )
    after = session.observe(miss).hypotheses
    got = {
        (h.assignment, round(h.pose.x, 6), round(h.pose.y, 6), round(h.pose.theta, 6))
        for h in after
    }
    assert 0 < len(got) < len(before)
    assert got == expected


def test_undo_restores_the_previous_state():
    models = object_set("thesis_like")
    s0 = Session(models, SensorBounds(1, 0.05), WORKSPACE)
    s1 = s0.observe(_obs((0, -200), (0, 1), (0, -30), (0, -1)))
    s2 = s1.observe(_obs((200, 0), (-1, 0), (45, -5), (1, 0)))
    assert s2.undo() is s1
    rebuilt = Session(models, s0.sensor, WORKSPACE, observations=s2.observations).undo()
    assert [h.pose for h in rebuilt.hypotheses] == [h.pose for h in s1.hypotheses]
    with pytest.raises(InvalidObservationError, match="no observation"):
        s0.undo()


def test_impossible_touches_are_inconsistent_and_undo_recovers():
    models = _by_name("square")
    s = Session(models, SensorBounds(), WORKSPACE)
    s = s.observe(_obs((0, -200), (0, 1), (0, -40), (0, -1)))
    bad = s.observe(_obs((0, 200), (0, -1), (0, 150), (0, 1)))  # 190 apart: no square fits
    assert bad.status == "inconsistent" and bad.hypotheses == []
    assert bad.undo().status == "ambiguous"


def test_a_spurious_contact_is_tolerated_with_max_outliers():
    models = _by_name("square")
    touches = [
        _obs((0, -200), (0, 1), (0, -40), (0, -1)),
        _obs((0, 200), (0, -1), (0, 150), (0, 1)),  # impossible for any square face
        _obs((200, 0), (-1, 0), (40, 0), (1, 0)),
    ]
    strict = Session(models, SensorBounds(), WORKSPACE, observations=touches)
    assert strict.status == "inconsistent"
    lenient = Session(models, SensorBounds(), WORKSPACE, RecognitionConfig(max_outliers=1), touches)
    assert lenient.status == "localized"
    assert all(h.assignment[1] is None for h in lenient.hypotheses)


def test_no_contact_yet_is_awaiting_contact():
    s = Session(object_set("workshop"), SensorBounds(), WORKSPACE)
    assert s.status == "awaiting_contact"
    s = s.observe(_obs((0, -200), (1, 0), length=10.0))
    assert s.status == "awaiting_contact" and s.hypotheses == []


def test_probabilities_follow_the_stable_pose_priors():
    # box poses 0 (60 x 100) and 1 (40 x 100): one touch on a 100-long face is equally
    # explained by both, so their posteriors stand in the ratio of their priors
    box = [m for m in object_set("table_poses") if m.name == "box_40x60x100"]
    s = Session(box, SensorBounds(0.5, math.radians(2)), Workspace((0, 0), 300))
    s = s.observe(_obs((0, -300), (0, 1), (0, -30), (0, -1), length=600))
    mass = {0: 0.0, 1: 0.0}
    for h in s.hypotheses:
        face = h.assignment[0]
        stable = box[0].stable_poses[h.stable_pose]
        if h.stable_pose in mass and math.isclose(stable.faces.length[face], 100.0):
            mass[h.stable_pose] += h.probability
    priors = [p.probability for p in box[0].stable_poses]
    assert mass[0] / mass[1] == pytest.approx(priors[0] / priors[1], rel=1e-6)


def test_normal_z_prunes_faces_that_contradict_it():
    wedge = object_from_dict(
        {
            "name": "ramp",
            "outline": [[0, 0], [60, 0], [60, 30], [0, 30]],
            "normal_z": [0.0, 0.0, 0.6, 0.0],  # face 2 (top) is sloped
        }
    )
    s = Session([wedge], SensorBounds(0.5, 0.05), WORKSPACE)
    flat = Observation(
        SensingPath((30, -200), (0, 1), 400), Contact((30, 0), (0, -1), normal_z=0.0)
    )
    sloped = Observation(
        SensingPath((30, -200), (0, 1), 400), Contact((30, 0), (0, -1), normal_z=0.6)
    )
    faces_flat = {h.assignment[0] for h in s.observe(flat).hypotheses}
    faces_sloped = {h.assignment[0] for h in s.observe(sloped).hypotheses}
    assert 2 not in faces_flat and faces_flat
    assert faces_sloped == {2}


def test_probabilities_sum_to_one_and_sort_descending():
    s = Session(object_set("workshop"), SensorBounds(1, 0.05), WORKSPACE)
    s = s.observe(_obs((0, -200), (0, 1), (0, -30), (0, -1)))
    p = np.array([h.probability for h in s.hypotheses])
    assert p.sum() == pytest.approx(1.0) and np.all(np.diff(p) <= 1e-15)


@pytest.mark.parametrize("outliers", [0, 1])
def test_the_hypothesis_count_known_before_the_classes_is_their_number(outliers):
    s = Session(
        object_set("workshop"), SensorBounds(1, 0.05), WORKSPACE, RecognitionConfig(outliers)
    )
    assert s.hypothesis_count == 0
    for touch in [
        _obs((0, -200), (0, 1), (0, -30), (0, -1)),
        _obs((200, 0), (-1, 0), (35, 0), (1, 0)),
    ]:
        s = s.observe(touch)
        count = s.hypothesis_count
        assert "hypotheses" not in s.__dict__  # nothing of the classes computed yet
        assert count == len(s.hypotheses) > 0


@pytest.mark.parametrize("outliers", [0, 1])
def test_the_interpretation_work_is_known_before_any_interpretation_is_checked(outliers):
    config = RecognitionConfig(outliers)
    s = Session(object_set("workshop"), SensorBounds(1, 0.05), WORKSPACE, config)
    assert s.interpretation_work == 0
    touches = [
        _obs((0, -200), (0, 1), (0, -30), (0, -1)),
        _obs((0, 200), (0, -1)),  # a miss: the tree does not grow
        _obs((200, 0), (-1, 0), (35, 0), (1, 0)),
    ]
    for contacts, touch in zip([1, 1, 2], touches, strict=True):
        s = s.observe(touch)
        work = s.interpretation_work
        assert "_derived" not in s.__dict__  # nothing checked yet
        rows = sum(len(r) for r in s._extended.rows)
        assert work == rows * (contacts + config.max_family_samples) > 0
        s.hypotheses  # noqa: B018 - the check
        # the checks only remove interpretations; a checked session counts what they left
        left = sum(len(r) for r in s._derived.level.rows)
        assert s.interpretation_work == left * (contacts + config.max_family_samples) <= work
        assert "_extended" not in s.__getstate__()


def test_a_prediction_keeps_what_the_update_keeps_weighed_without_the_residual_fitness():
    """A predicted observation prunes as the update does (the residual fitness only
    weighs): the same interpretations with the same poses and bounds survive; the
    weights differ where the fitness is below one."""
    from hardware_sim.world import random_world

    models, bounds = object_set("workshop"), SensorBounds(1.0, math.radians(3.0))
    rng = np.random.default_rng(5)
    reweighed = 0
    for _ in range(4):
        world = random_world(models, WORKSPACE, rng)
        session = Session(models, bounds, WORKSPACE)
        for _ in range(3):
            obs, _ = world.execute(world.hitting_path(rng), bounds, rng)
            observed, predicted = session.observe(obs), session.predict(obs)
            assert predicted.config.residual_fitness is False
            kept = {(h.interpretation, h.pose, h.error_bound): h for h in observed.hypotheses}
            guess = {(h.interpretation, h.pose, h.error_bound): h for h in predicted.hypotheses}
            assert kept.keys() == guess.keys() and kept
            reweighed += any(
                not math.isclose(kept[k].probability, guess[k].probability) for k in kept
            )
            session = observed
    assert reweighed  # the fitness was left out somewhere it mattered


def test_a_contact_measured_behind_an_origin_at_the_part_is_kept_within_the_error():
    """A path may start within the position error of the part (one lying at the
    edge of the workspace): its measured contact may then lie behind the origin.
    Up to the error it is a measurement like any other, and the truth survives;
    farther back it is refused."""
    session = Session(_by_name("square"), SensorBounds(1.0, math.radians(3)), WORKSPACE)
    near = _obs((0, -40.3), (0, 1), (0.2, -40.8), (0, -1))
    assert near.behind_origin() == pytest.approx(0.5)
    session = session.observe(near).observe(_obs((200, 10), (-1, 0), (40.4, 10), (1, 0)))
    assert session.status == "localized"
    best = session.hypotheses[0]
    assert math.hypot(best.pose.x, best.pose.y) <= best.error_bound.eps_t / 2 + 1e-9
    far = _obs((0, -40.3), (0, 1), (0.2, -42.5), (0, -1))
    with pytest.raises(InvalidObservationError) as refused:
        session.observe(far)
    assert refused.value.field == "contact.point"
    # a session built from a log checks every observation, the last included
    square = _by_name("square")
    with pytest.raises(InvalidObservationError):
        Session(square, SensorBounds(1.0, math.radians(3)), WORKSPACE, observations=[near, far])
    assert len(Session(square, SensorBounds(1.0, 0.05), WORKSPACE, observations=[near]).hypotheses)
