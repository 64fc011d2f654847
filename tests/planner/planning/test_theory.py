"""Theory = outcome model: what the planner calls certain happens (DESIGN §4.11-4.12)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from planner.types import SensingPath, SensorBounds
from tests.conftest import SET_NAMES, analysed, touched_session

BOUNDS = [SensorBounds(0.0, 0.0), SensorBounds(1.0, math.radians(3))]


@pytest.mark.parametrize("name", SET_NAMES)
@pytest.mark.parametrize("bounds", BOUNDS, ids=["exact", "1mm-3deg"])
@settings(max_examples=12, derandomize=True, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), touches=st.integers(2, 3))
def test_a_path_sure_to_distinguish_leaves_one_class(name, bounds, seed, touches):
    # any error within the bounds, on the true object: the session is then localized
    world, session, rng = touched_session(name, bounds, seed, touches)
    if session.status != "ambiguous":
        return
    found = analysed(session)
    c = found.candidates
    for i in np.flatnonzero(found.info.p_distinguishing >= 1 - 1e-9)[:4]:
        path = SensingPath(tuple(c.origins[i]), tuple(c.directions[i]), float(c.lengths[i]))
        observation, _ = world.execute(path, bounds, rng, edge_share=0.5)
        assert session.observe(observation).status == "localized"
