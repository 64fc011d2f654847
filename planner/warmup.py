"""Load the compiled kernels before the first real request needs them.

The recognition and the planner keep their innermost loops compiled (cached on
disk after the first build); a process still loads each one at its first call,
a tenth to a few tenths of a second each, and builds them when the cache is
missing. :func:`warm_up` runs one touch of a small part and one plan, so that
the first recognition a user asks for pays none of it.

>>> warm_up() >= 0.0
True
"""

from __future__ import annotations

import time

import numpy as np

from planner.models.library import object_from_dict
from planner.planning.bitsets import sorted_count
from planner.planning.config import StrategyConfig
from planner.planning.plan import plan
from planner.recognition.session import Session
from planner.types import Contact, Observation, SensingPath, SensorBounds, Workspace

__all__ = ["warm_up"]

#: An L-shaped plate and a square: two touches leave several classes, and the
#: square's rotations are one class (its members' outlines are measured).
_PARTS = (
    {"name": "warm-l", "outline": [[0, 0], [40, 0], [40, 12], [22, 12], [22, 30], [0, 30]]},
    {"name": "warm-square", "outline": [[0, 0], [30, 0], [30, 30], [0, 30]]},
)


def warm_up() -> float:
    """Run one small recognition and plan; returns the seconds it took."""
    start = time.perf_counter()
    models = [object_from_dict(part) for part in _PARTS]
    session = Session(models, SensorBounds(1.0, 0.05), Workspace((0.0, 0.0), 100.0))
    up, right = (
        SensingPath((0.0, -100.0), (0.0, 1.0), 200.0),
        SensingPath((-100.0, 0.0), (1.0, 0.0), 200.0),
    )
    touches = [
        Observation(up, Contact((0.0, -15.0), (0.0, -1.0))),
        Observation(right, Contact((-20.0, 0.0), (-1.0, 0.0))),
    ]
    for touch in touches:
        session = session.observe(touch)
        plan(
            session.hypotheses,
            session.models,
            session.bounds,
            session.workspace,
            (100.0, 0.0),
            StrategyConfig(name="lookahead", budget_work=50_000),
            0,
            observations=session.observations,
            session=session,
        )
    # the search after a miss, before any contact
    miss = SensingPath((0.0, 100.0), (0.0, -1.0), 200.0)
    plan(
        [],
        models,
        session.bounds,
        session.workspace,
        (0.0, 100.0),
        observations=[Observation(miss)],
    )
    # kernels of paths so small a session does not take (many hits on one path)
    sorted_count(np.zeros((1, 1)), np.zeros(1, dtype=np.int64), np.zeros(1), "right")
    return time.perf_counter() - start
