"""Folding a contact of a finely drawn curve (DESIGN §4.3, :func:`fold_runs`).

A contact near the end of a chord fits two chords, and every such contact doubled
the rows of a curved part: an ellipse touched 37 times held 19,068. Rows alike but
for the neighbouring face of one contact become one row that leaves the contact
unassigned: a row with fewer constraints admits every pose the rows it stands for
admit, so the truth survives it.
"""

from __future__ import annotations

import math

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from hardware_sim.world import random_world
from planner.geometry import wrap_angle
from planner.models.library import load_objects
from planner.recognition.session import Session
from planner.recognition.tree import FOLD_PINNED, FOLD_ROWS, FOLD_SPAN, face_of, fold_runs
from planner.types import SensorBounds
from tests.conftest import WORKSPACE

RING = np.repeat([0, 1], [40, 10])  # faces 0-39 on the outline, 40-49 on a hole


def _covers(out: np.ndarray, row: np.ndarray) -> bool:
    """Some row of `out` admits every pose `row` admits: equal, or folded where the
    row names a face of the folded run (or a fold starting no later, in the run)."""
    for o in out:
        ok = True
        for a, b in zip(o.tolist(), row.tolist(), strict=True):
            if a == b:
                continue
            if a > -2 or b == -1:
                ok = False
                break
            f, g = face_of(a), face_of(b)
            if not (f <= g < f + FOLD_SPAN and RING[f] == RING[g]):
                ok = False
                break
        if ok:
            return True
    return False


rows_strategy = st.lists(
    st.lists(st.integers(-1, len(RING) - 1), min_size=FOLD_PINNED + 2, max_size=FOLD_PINNED + 2),
    min_size=1,
    max_size=40,
)


@settings(max_examples=150, derandomize=True, deadline=None)
@given(
    rows=rows_strategy,
    base=st.lists(
        st.integers(0, len(RING) - 2), min_size=FOLD_PINNED + 2, max_size=FOLD_PINNED + 2
    ),
    limit=st.integers(0, 8),
)
def test_every_row_is_admitted_by_a_fold(rows, base, limit) -> None:
    # rows near one base row (each contact on its face or the next), plus random ones
    rng = np.random.default_rng(len(rows))
    near = np.array(base) + rng.integers(0, 2, (len(rows), len(base)))
    given_rows = np.unique(np.vstack([np.array(rows), near]), axis=0)
    out = fold_runs(given_rows, RING, limit)
    assert len(out) <= len(given_rows)
    if len(given_rows) <= limit:
        assert np.array_equal(out, given_rows)
    for row in given_rows:
        assert _covers(out, row)
    # a fold keeps the contacts that pin its pose assigned
    folded = (out <= -2).any(axis=1)
    assert ((out[folded] >= 0).sum(axis=1) >= FOLD_PINNED).all()


def test_rows_alike_but_for_a_neighbouring_face_fold() -> None:
    pin = [3 * i for i in range(FOLD_PINNED)]
    rows = np.array([[*pin, 44], [*pin, 45], [*pin, 46], [*pin, 42]])
    out = fold_runs(rows, RING, limit=1)
    assert sorted(out.tolist()) == sorted([[*pin, 42], [*pin, -2 - 44]])
    # faces of different rings never fold, nor rows too few to pin a pose
    assert len(fold_runs(np.array([[*pin, 39], [*pin, 40]]), RING, 1)) == 2
    short = np.array([[*pin[:-1], 44], [*pin[:-1], 45]])
    assert np.array_equal(fold_runs(short, RING, 1), short)


ELLIPSE = [m for m in load_objects("curved") if m.name == "ellipse_60x35"]
BOUNDS = SensorBounds(1.0, math.radians(3.0))


@settings(
    max_examples=6, derandomize=True, deadline=None, suppress_health_check=[HealthCheck.too_slow]
)
@given(seed=st.integers(0, 2**32 - 1))
def test_a_long_session_on_a_drawn_curve_stays_sound_and_bounded(seed: int) -> None:
    """An ellipse of 72 vertices touched 24 times anywhere within the bounds: the
    true object and pose stay inside some hypothesis' bound after every touch, and
    no group holds more rows than folding allows (without it, thousands)."""
    rng = np.random.default_rng(seed)
    world = random_world(ELLIPSE, WORKSPACE, rng)
    session = Session(ELLIPSE, BOUNDS, WORKSPACE)
    most = 0
    for n in range(24):
        obs, face = world.execute(world.hitting_path(rng), BOUNDS, rng, edge_share=0.5)
        assert face is not None
        session = session.observe(obs)
        assert any(
            math.hypot(h.pose.x - world.pose.x, h.pose.y - world.pose.y)
            <= h.error_bound.translation + 1e-9
            and abs(float(wrap_angle(h.pose.theta - world.pose.theta)))
            <= h.error_bound.rotation + 1e-12
            for h in session.hypotheses
        ), f"lost the truth after {n + 1} touches"
        most = max(most, max(len(r) for r in session._derived.level.rows))
    # the checked rows of a level come from at most FOLD_ROWS folded rows, each
    # extended by the few chords one contact fits
    assert most <= 8 * FOLD_ROWS


def test_a_restored_snapshot_continues_as_the_session_and_holds_no_tables() -> None:
    """A snapshot leaves out the constraint tables its groups derive from their
    stable poses (nine tenths of a curved part's snapshot): the restored session
    finds them again and its next update is the original's to the last digit."""
    from planner.recognition.snapshot import restore, snapshot

    models = load_objects("curved")
    rng = np.random.default_rng(3)
    world = random_world(models, WORKSPACE, rng)
    session = Session(models, BOUNDS, WORKSPACE)
    for _ in range(2):
        session = session.observe(world.execute(world.hitting_path(rng), BOUNDS, rng)[0])
    session.hypotheses  # noqa: B018 - derived, so the groups hold their tables
    assert all("tables" in g.__dict__ for g in session._groups)
    again = restore(snapshot(session))
    assert again is not None
    assert not any("tables" in g.__dict__ for g in again._groups)
    obs = world.execute(world.hitting_path(rng), BOUNDS, rng)[0]

    def answer(s: Session) -> list:
        return [
            (h.object, h.assignment, h.pose, h.error_bound, h.probability) for h in s.hypotheses
        ]

    assert answer(again.observe(obs)) == answer(session.observe(obs))
