"""Shared test catalogue: the object sets, the standard safe circle, seeded worlds."""

from __future__ import annotations

from pathlib import Path

import pytest

from planner.library import load_objects
from planner.types import ObjectModel, Workspace

DATA = Path(__file__).resolve().parents[1] / "planner" / "data"
SET_NAMES = ["thesis_like", "workshop", "symmetric", "mcube_prisms", "table_poses"]
WORKSPACE = Workspace((0.0, 0.0), 200.0)


def object_set(name: str) -> list[ObjectModel]:
    return load_objects(DATA / f"{name}.json")


@pytest.fixture(params=SET_NAMES)
def set_name(request: pytest.FixtureRequest) -> str:
    return request.param
