"""Tells a robot where to touch an unseen object to recognize and localize it.

The planner's whole surface is "take an observation" and "plan the next path":

>>> import math
>>> from planner import Observation, SensingPath, SensorBounds, Session, Workspace
>>> from planner import load_objects, plan_session
>>> session = Session(load_objects("thesis_like"), SensorBounds(1.0, math.radians(3)),
...                   Workspace((0, 0), 200))
>>> plan = plan_session(session, sensor_position=(200, 0))
>>> plan.status, len(plan.paths)
('awaiting_contact', 1)
>>> session = session.observe(Observation(plan.paths[0].path, None))  # it touched nothing
>>> session.status
'awaiting_contact'

The stages, from the ground up: :mod:`planner.models` (object models, object
files, meshes, the prior), :mod:`planner.recognition` (constraint tables, the
interpretation tree, pose fit and bounds, the session), :mod:`planner.image`
(the multi-interpretation image, vector and grid), :mod:`planner.planning`
(candidate paths, their outcomes, scores, strategies, the plan) and
:mod:`planner.render` (pictures).
"""

from planner.errors import (
    InvalidModelError,
    InvalidObservationError,
    ModelFileError,
    PlannerError,
    PlanningNotPossibleError,
)
from planner.models.library import dump_objects, load_objects, parse_objects
from planner.models.outlines import make_stable_pose
from planner.planning.config import StrategyConfig
from planner.planning.plan import plan, plan_session
from planner.planning.result import Plan, PlannedPath
from planner.recognition.config import RecognitionConfig
from planner.recognition.session import Session
from planner.types import (
    Contact,
    ErrorBound,
    Hypothesis,
    InterpretationId,
    ObjectModel,
    Observation,
    Pose,
    SensingPath,
    SensorBounds,
    StablePose,
    Workspace,
)

__all__ = [
    "Contact",
    "ErrorBound",
    "Hypothesis",
    "InterpretationId",
    "InvalidModelError",
    "InvalidObservationError",
    "ModelFileError",
    "ObjectModel",
    "Observation",
    "Plan",
    "PlannedPath",
    "PlannerError",
    "PlanningNotPossibleError",
    "Pose",
    "RecognitionConfig",
    "SensingPath",
    "SensorBounds",
    "Session",
    "StablePose",
    "StrategyConfig",
    "Workspace",
    "dump_objects",
    "load_objects",
    "make_stable_pose",
    "parse_objects",
    "plan",
    "plan_session",
]
