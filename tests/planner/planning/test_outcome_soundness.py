"""The outcome model against the recognition it predicts: whatever the recognition
keeps after a contact, the model called confusable on that path (DESIGN §4.11)."""

from __future__ import annotations

import math

import numpy as np

from planner.planning.confusability import confusability
from planner.planning.outcomes import predict_outcomes
from planner.planning.posed_set import pose_hypotheses
from planner.recognition.session import Session
from planner.types import Contact, Observation, SensingPath, SensorBounds, Workspace
from tests.conftest import object_set

#: A simulated trial at the 5 degree sensor (the offset block, `random` strategy,
#: seed 0, trial 68): the sixth path enters the bump of the plain block's posed
#: outline 7 mm before the true contact, on the bump's side, while the contact lies
#: on the top face just past the concave corner, within the disk. Checked against
#: the whole outline's error disk both classes survived it (and the model then
#: called the path sure); checked against how far that face itself may have
#: moved (less than the outline's far corners), the plain block does not.
TRIAL = [
    ((122.04463, -158.44592), (-0.61022, 0.79223), 400.0,
     ((54.38423, -70.57992), (-0.01623, -0.99987))),
    ((-123.88341, -157.01242), (0.8319, 0.55492), 380.377,
     ((6.07443, -70.32431), (0.00064, -1.0))),
    ((-152.41718, -129.49519), (0.86791, 0.49673), 393.2152,
     ((-24.40239, -56.2479), (-0.99994, 0.01139))),
    ((-148.42113, 134.05658), (0.73764, -0.6752), 399.9912,
     ((-12.42048, 9.53802), (0.02375, 0.99972))),
    ((6.4722, -199.89525), (0.11406, 0.99347), 395.7052,
     ((21.26313, -70.30613), (0.02486, -0.99969))),
    ((-2.75041, 199.98109), (0.12527, -0.99212), 397.5006,
     ((21.38016, 9.23232), (0.00101, 1.0))),
]  # fmt: skip


def test_classes_the_recognition_keeps_after_a_contact_were_confusable_on_its_path():
    sensor = SensorBounds(1.0, math.radians(5))
    session = Session(object_set("thesis_like"), sensor, Workspace((0.0, 0.0), 200.0))
    for origin, direction, length, (point, normal) in TRIAL:
        path = SensingPath(origin, direction, length)
        before = list(session.hypotheses)
        session = session.observe(Observation(path, Contact(point, normal)))
        kept = {(h.object, h.stable_pose, h.assignment[:-1]) for h in session.hypotheses}
        rows = [i for i, h in enumerate(before) if (h.object, h.stable_pose, h.assignment) in kept]
        if len({before[i].equivalence_class for i in rows}) < 2:
            continue
        posed = pose_hypotheses(before, session.models_by_name)
        out = predict_outcomes(
            posed, np.array([origin]), np.array([direction]), np.array([length]),
            session.working_sensor,
        )  # fmt: skip
        confusable = confusability(posed, out, session.working_sensor)[0]
        assert any(
            confusable[i, j]
            for i in rows
            for j in rows
            if before[i].equivalence_class != before[j].equivalence_class
        ), f"classes kept after the contact at {point} were called distinguishable"
    assert {h.object for h in session.hypotheses} == {"bump_block_offset"}  # the truth


def test_a_path_slipping_through_a_thin_part_may_meet_a_face_it_passes_near():
    """A table_poses world (the L prism, 1 mm / 3 degrees, two touches): the path
    cuts the other stable pose's outline shallowly at 43 mm, passes on within its
    vertex zone of a face at 120 mm, where the true contact lies; both classes
    survive, so the model must not call the path sure."""
    from tests.conftest import touched_session

    bounds = SensorBounds(1.0, math.radians(3))
    _, session, _ = touched_session("table_poses", bounds, 1908895, 2)
    path = SensingPath((141.39343, 141.44928), (-0.5, -0.8660254), 386.39076)
    contact = Contact((81.89839, 37.21647), (0.90372765, 0.42810785))
    after = session.observe(Observation(path, contact))
    assert len({h.equivalence_class for h in after.hypotheses}) == 2
    before = list(session.hypotheses)
    posed = pose_hypotheses(before, session.models_by_name)
    out = predict_outcomes(
        posed, np.array([path.origin]), np.array([path.direction]), np.array([path.length]),
        session.working_sensor,
    )  # fmt: skip
    classes = posed.cls
    confusable = confusability(posed, out, session.working_sensor)[0]
    assert confusable[np.ix_(classes == 0, classes == 1)].any()
