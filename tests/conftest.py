"""Shared test catalogue: the object sets, the standard safe circle, seeded worlds."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from hypothesis import settings

from hardware_sim.experiments import ExperimentSpec, run_experiment
from hardware_sim.world import random_world
from planner.models.library import load_objects, object_from_dict
from planner.recognition.session import Session
from planner.types import ObjectModel, SensorBounds, Workspace

# seeded: every run draws the same examples (no example database carried between runs)
settings.register_profile("seeded", derandomize=True, database=None)
settings.load_profile("seeded")

DATA = Path(__file__).resolve().parents[1] / "planner" / "data"
SET_NAMES = ["thesis_like", "workshop", "symmetric", "mcube_prisms", "table_poses"]
WORKSPACE = Workspace((0.0, 0.0), 200.0)


def object_set(name: str) -> list[ObjectModel]:
    return load_objects(DATA / f"{name}.json")


@pytest.fixture(params=SET_NAMES)
def set_name(request: pytest.FixtureRequest) -> str:
    return request.param


def touched_session(name: str, bounds: SensorBounds, seed: int, touches: int):
    """A world of set `name` drawn from the prior and a session after `touches`
    paths that hit it, errors within `bounds`; returns (world, session, rng)."""
    rng = np.random.default_rng(seed)
    models = object_set(name)
    world = random_world(models, WORKSPACE, rng)
    session = Session(models, bounds, WORKSPACE)
    for _ in range(touches):
        session = session.observe(world.execute(world.hitting_path(rng), bounds, rng)[0])
    return world, session, rng


def analysed(session: Session):
    """The planner's analysis of a session's state (default strategy, no budget),
    planned from (R, 0) on the safe circle."""
    from planner.planning.analysis import analyse
    from planner.planning.config import StrategyConfig

    return analyse(
        session.hypotheses,
        session.models,
        session.sensor,
        session.workspace,
        (WORKSPACE.radius, 0.0),
        StrategyConfig(budget_ms=None, budget_work=None),
        0,
        observations=session.observations,
    )


# -- a small experiment: two shapes in a small safe circle, a few seeded trials --------
ELL = object_from_dict(
    {"name": "ell", "outline": [[0, 0], [40, 0], [40, 15], [15, 15], [15, 30], [0, 30]]}
)
WEDGE = object_from_dict({"name": "wedge", "outline": [[0, 0], [40, 0], [10, 25]]})
SQUARE = object_from_dict({"name": "sq", "outline": [[-10, -10], [10, -10], [10, 10], [-10, 10]]})
SMALL_WS = Workspace((0.0, 0.0), 80.0)


def small_spec(**kw) -> ExperimentSpec:
    base = {
        "models": (ELL, WEDGE),
        "strategies": ("pdm", "random"),
        "trials": 3,
        "seed": 3,
        "workspace": SMALL_WS,
        "max_touches": 6,
        # no budget at all: the plans are the same however it is counted
        "strategy": {"budget_ms": None, "budget_work": None},
    }
    return ExperimentSpec(**{**base, **kw})


@pytest.fixture(scope="module")
def sequential_results():
    """The small experiment run in this process."""
    return run_experiment(small_spec(), workers=1)


def pytest_terminal_summary(terminalreporter) -> None:
    """Say how many tests ran on PostgreSQL (CI must show them run, not skipped)."""
    stats = terminalreporter.stats
    ran = [r for r in stats.get("passed", []) + stats.get("failed", []) if "postgres" in r.nodeid]
    skipped = [r for r in stats.get("skipped", []) if "postgres" in getattr(r, "nodeid", "")]
    if ran or skipped:
        terminalreporter.write_line(
            f"PostgreSQL: {len(ran)} tests ran on a live server, {len(skipped)} skipped"
        )
