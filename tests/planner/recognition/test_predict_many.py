"""Predictions observed together (one evaluation) are those observed alone."""

from __future__ import annotations

import math

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from hardware_sim.world import random_world
from planner.recognition.config import RecognitionConfig
from planner.recognition.session import Session
from planner.types import Contact, Observation, SensingPath, SensorBounds
from tests.conftest import SET_NAMES, WORKSPACE, object_set, touched_session


def _state(session: Session | None):
    """Everything a prediction answers, to the bit, and the rows of its tree
    (those it kept and those the next observation extends)."""
    if session is None:
        return None
    derived = session._derived
    return repr(
        [
            (h.object, h.stable_pose, h.assignment, h.pose, h.error_bound, h.probability,
             h.equivalence_class, h.interpretation)
            for h in session.hypotheses
        ]
        + [r.tolist() for r in (*derived.level.rows, *derived.ahead.rows)]
    )  # fmt: skip


@settings(max_examples=30, deadline=None)
@given(
    name=st.sampled_from(SET_NAMES),
    seed=st.integers(0, 10_000),
    touches=st.integers(1, 3),
    bounds=st.sampled_from([SensorBounds(1.0, math.radians(3)), SensorBounds(0.5, 0.05)]),
    outliers=st.integers(0, 1),
)
def test_predictions_observed_together_are_those_observed_alone(
    name, seed, touches, bounds, outliers
):
    """A plan's predictions of one session, observed in one evaluation
    (`predict_many`): contacts on the true part and on parts elsewhere, a miss and
    an observation that is not a valid one, with and without a spurious contact
    allowed; each gives the tree, hypotheses, bounds, probabilities and classes
    that predicting it alone gives, bit for bit."""
    rng = np.random.default_rng(seed)
    world = random_world(object_set(name), WORKSPACE, rng)
    config = RecognitionConfig(max_outliers=outliers)
    session = Session(object_set(name), bounds, WORKSPACE, config)
    for _ in range(touches):
        session = session.observe(world.execute(world.hitting_path(rng), bounds, rng)[0])
    other = random_world(object_set(name), WORKSPACE, rng)
    observations = [w.execute(w.hitting_path(rng), bounds, rng)[0] for w in (world, other) * 3]
    observations.append(Observation(SensingPath((0.0, 250.0), (0.0, 1.0), 50.0), None))
    behind = Observation(SensingPath((0.0, -200.0), (0.0, 1.0), 400.0), Contact((0, -250), (0, -1)))
    observations.insert(2, behind)
    together = session.predict_many(observations)
    assert together[2] is None
    for observation, predicted in zip(observations, together, strict=True):
        if predicted is None:
            continue
        assert _state(predicted) == _state(session.predict(observation))


@settings(max_examples=40, deadline=None)
@given(
    name=st.sampled_from(SET_NAMES),
    seed=st.integers(0, 10_000),
    touches=st.integers(1, 3),
)
def test_the_class_count_is_the_number_of_classes(name, seed, touches):
    """`class_count` (no two hypotheses can share a class when their outlines'
    support values lie apart: counted without the classes) is the number of
    classes the hypotheses carry, for sessions and their predictions alike."""
    bounds = SensorBounds(1.0, math.radians(3))
    world, session, rng = touched_session(name, bounds, seed, touches)
    other = random_world(object_set(name), WORKSPACE, rng)
    observations = [w.execute(w.hitting_path(rng), bounds, rng)[0] for w in (world, other) * 2]
    for s in [session, *session.predict_many(observations)]:
        counted = s.class_count  # before the classes are found
        assert counted == len({h.equivalence_class for h in s.hypotheses})


def test_predictions_after_misses_alone_are_those_observed_alone():
    """A session that has only missed (no contact yet to share) predicts its first
    contacts together as it would one by one."""
    bounds = SensorBounds(1.0, math.radians(3))
    rng = np.random.default_rng(5)
    world = random_world(object_set("thesis_like"), WORKSPACE, rng)
    session = Session(object_set("thesis_like"), bounds, WORKSPACE)
    session = session.observe(Observation(SensingPath((0.0, 250.0), (0.0, 1.0), 50.0), None))
    observations = [world.execute(world.hitting_path(rng), bounds, rng)[0] for _ in range(3)]
    together = session.predict_many(observations)
    assert all(s is not None and s.hypotheses for s in together)
    for observation, predicted in zip(observations, together, strict=True):
        assert _state(predicted) == _state(session.predict(observation))
