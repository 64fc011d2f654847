"""Classes found without measuring, when no two hypotheses can share one."""

from __future__ import annotations

import math

from hypothesis import given, settings
from hypothesis import strategies as st

import planner.recognition.session as session_module
from planner.types import SensorBounds
from tests.conftest import SET_NAMES, touched_session


def _answer(session):
    return repr(
        [(h.object, h.stable_pose, h.pose, h.probability, h.equivalence_class)
         for h in session.hypotheses]
        + [sorted(session.joined_classes)]
    )  # fmt: skip


@settings(max_examples=40, deadline=None)
@given(name=st.sampled_from(SET_NAMES), seed=st.integers(0, 10_000), touches=st.integers(1, 4))
def test_classes_found_without_measuring_are_those_measured(name, seed, touches):
    """Where the support values say no two hypotheses can share a class, the
    session numbers each as its own class without measuring outlines; the
    hypotheses, their classes (numbers included) and the joined classes are those
    the measured classes give."""
    bounds = SensorBounds(1.0, math.radians(3))
    _, session, _ = touched_session(name, bounds, seed, touches)
    again = session.undo().observe(session.observations[-1])
    shortcut = _answer(session)
    original = session_module.none_can_share
    try:
        session_module.none_can_share = lambda *args: False  # always measure
        measured = _answer(again)
    finally:
        session_module.none_can_share = original
    assert shortcut == measured
