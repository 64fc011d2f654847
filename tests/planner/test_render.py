"""Pictures of the MII: SVG and PNG bytes, vector and grid views (planner/render.py)."""

from __future__ import annotations

import struct
import subprocess
import sys
import xml.etree.ElementTree as ET
from concurrent.futures import ThreadPoolExecutor
from functools import cache
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from planner.errors import PlanningNotPossibleError
from planner.image.grid import build_grid
from planner.image.vector import build_mii
from planner.image.windows import thesis_paths
from planner.models.library import object_from_dict
from planner.planning.config import StrategyConfig
from planner.planning.plan import plan_session
from planner.recognition.session import Session
from planner.render import render_png, render_svg, session_picture
from planner.types import Contact, Observation, SensingPath, Workspace
from tests.planner.image.test_vector import BUMP_CONTACTS, bump_block_case

WORKSPACE = Workspace((50.0, 40.0), 150.0)
SENSOR = (200.0, 40.0)
CONTACTS = [Contact(p, n) for p, n in BUMP_CONTACTS]


@cache
def scene(eps_t: float = 0.0):
    models, hs = bump_block_case(eps_t=eps_t, rotation=0.03 if eps_t else 0.0)
    grid = build_grid(hs, models, size=70)
    paths = thesis_paths(hs, models, WORKSPACE, SENSOR, grid=grid)[:3]
    return build_mii(hs, models), grid, paths


def ids(svg: bytes) -> set[str]:
    root = ET.fromstring(svg)
    return {el.get("id") for el in root.iter() if el.get("id")}


def svg_text(svg: bytes) -> str:
    return " ".join(t for t in ET.fromstring(svg).itertext())


@pytest.mark.parametrize("eps_t", [0.0, 8.0])
def test_svg_holds_the_image_with_blocking_and_ranked_paths(eps_t):
    mii, grid, paths = scene(eps_t)
    p_dm = [1.0 - p.strength for p in paths]
    svg = render_svg(
        mii, grid, contacts=CONTACTS, workspace=WORKSPACE, sensor_position=SENSOR,
        paths=paths, p_distinguishing=p_dm, title="bump_block",
    )  # fmt: skip
    found = ids(svg)
    blocking = {i for i in found if i.startswith("blocking-")}
    assert blocking == {f"blocking-{k}" for k in range(len(mii.blocking))}
    for rank in (1, 2, 3):
        assert {f"path-{rank}", f"path-{rank}-label", f"grid-path-{rank}"} <= found
    assert {f"outline-{i}" for i in range(len(mii.hypotheses))} <= found
    assert {"ia-0", "safe-circle", "sensor", "contact-0", "contact-1", "grid-image"} <= found
    assert "grid-target-0" in found
    assert f"P(DM)={p_dm[0]:.2f}" in svg_text(svg)


def test_labels_only_show_p_dm_when_given():
    mii, _, paths = scene()
    text = svg_text(render_svg(mii, paths=paths, workspace=WORKSPACE))
    assert "P(DM)" not in text
    plain = [SensingPath((0.0, 40.0), (1.0, 0.0), 60.0)]
    text = svg_text(render_svg(mii, paths=plain, p_distinguishing=[0.25]))
    assert "P(DM)=0.25" in text


def test_single_views_and_observations_as_contacts():
    mii, grid, paths = scene()
    grid_only = ids(render_svg(grid=grid, paths=paths, workspace=WORKSPACE))
    assert "grid-image" in grid_only and "path-1" in grid_only and "outline-0" not in grid_only
    obs = [Observation(SensingPath((30.0, -100.0), (0.0, 1.0), 150.0), CONTACTS[0])]
    vector_only = ids(render_svg(mii, contacts=obs))
    assert "contact-0" in vector_only and "grid-image" not in vector_only


def test_svg_is_deterministic():
    mii, grid, paths = scene()
    a = render_svg(mii, grid, paths=paths, workspace=WORKSPACE)
    b = render_svg(mii, grid, paths=paths, workspace=WORKSPACE)
    assert a == b


@pytest.mark.parametrize(("views", "dpi"), [(2, 100), (1, 50)])
def test_png_signature_and_size(views, dpi):
    mii, grid, paths = scene()
    png = render_png(
        mii, grid if views == 2 else None, paths=paths, workspace=WORKSPACE, dpi=dpi,
        panel_inches=4.0,
    )  # fmt: skip
    assert png[:8] == b"\x89PNG\r\n\x1a\n" and png[12:16] == b"IHDR"
    width, height = struct.unpack(">II", png[16:24])
    assert (width, height) == (round((4.0 * views + 0.8) * dpi), round(4.0 * dpi))


def test_nothing_to_draw_is_an_error():
    with pytest.raises(PlanningNotPossibleError):
        render_svg()


@pytest.mark.parametrize("touches", [0, 2])
def test_a_session_without_hypotheses_is_drawn_as_its_scene(touches):
    """Before the first contact, or with no hypothesis left (two contacts no
    placement explains), the picture still shows the safe circle, the sensor, the
    contacts and the paths."""
    square = object_from_dict({"name": "sq", "outline": [[-5, -5], [5, -5], [5, 5], [-5, 5]]})
    session = Session([square], workspace=Workspace((0, 0), 50))
    touches_made = [
        Observation(SensingPath((0, -50), (0, 1), 100), Contact((0, -5), (0, -1))),
        Observation(SensingPath((0, 50), (0, -1), 100), Contact((0, 30), (0, 1))),
    ][:touches]
    for touch in touches_made:
        session = session.observe(touch)
    assert not session.hypotheses
    svg = session_picture(session, (50, 0), fmt="svg")
    assert b'id="safe-circle"' in svg and b'id="sensor"' in svg
    assert (b'id="contact-1"' in svg) == (touches == 2) and b"outline-0" not in svg
    assert b"P(DM)" not in svg  # nothing to distinguish yet


def test_matplotlib_is_lazy_and_pyplot_never_loaded():
    code = (
        "import sys, planner.render as r\n"
        "assert 'matplotlib' not in sys.modules\n"
        "from tests.planner.test_render import scene\n"
        "r.render_png(scene()[0])\n"
        "assert 'matplotlib.pyplot' not in sys.modules\n"
    )
    root = Path(__file__).resolve().parents[2]
    subprocess.run([sys.executable, "-c", code], check=True, timeout=120, cwd=root)


@cache
def touched_session():
    square = object_from_dict({"name": "square", "outline": [[-1, -1], [1, -1], [1, 1], [-1, 1]]})
    rect = object_from_dict({"name": "rect", "outline": [[-2, -1], [2, -1], [2, 1], [-2, 1]]})
    workspace = Workspace((0.0, 0.0), 10.0)
    bottom = Contact((0.0, -1.0), (0.0, -1.0))
    touch = Observation(SensingPath((0.0, -10.0), (0.0, 1.0), 20.0), bottom)
    session = Session([square, rect], workspace=workspace).observe(touch)
    plan = plan_session(session, (10.0, 0.0), StrategyConfig(name="pdm", budget_ms=2000), 0)
    return session, plan


def test_session_picture_is_the_session_drawn_with_its_ranked_paths():
    session, plan = touched_session()
    assert len(plan.paths) >= 3
    svg = session_picture(session, (10.0, 0.0), plan, fmt="svg", paths=2, title="touched")
    found = ids(svg)
    assert {"path-1", "path-2", "grid-path-1", "contact-0", "safe-circle", "sensor"} <= found
    assert "path-3" not in found and "grid-image" in found and "outline-0" in found
    ranked = plan.paths[:2]
    assert svg == render_svg(
        build_mii(session.hypotheses, session.models),
        build_grid(session.hypotheses, session.models, 70),
        contacts=session.observations,
        workspace=session.workspace,
        sensor_position=(10.0, 0.0),
        paths=[p.path for p in ranked],
        p_distinguishing=[p.p_distinguishing for p in ranked],
        title="touched",
    )


def test_session_picture_views_formats_and_no_plan():
    session, plan = touched_session()
    vector = ids(session_picture(session, (10.0, 0.0), plan, fmt="svg", view="vector"))
    assert "outline-0" in vector and "grid-image" not in vector
    assert {f"path-{k}" for k in range(1, len(plan.paths) + 1)} <= vector
    grid = ids(session_picture(session, (10.0, 0.0), None, fmt="svg", view="grid", grid_size=30))
    assert "grid-image" in grid and "outline-0" not in grid and "path-1" not in grid
    png = session_picture(session, (10.0, 0.0), plan, view="vector", dpi=50)
    assert png[:8] == b"\x89PNG\r\n\x1a\n"
    assert struct.unpack(">II", png[16:24]) == (round(6.8 * 50), round(6.0 * 50))


def test_pictures_drawn_in_threads_are_the_pictures_drawn_one_by_one():
    mii, grid, paths = scene()
    serial = render_svg(mii, grid, paths=paths, workspace=WORKSPACE)
    with ThreadPoolExecutor(3) as pool:
        drawn = list(
            pool.map(lambda _: render_svg(mii, grid, paths=paths, workspace=WORKSPACE), range(3))
        )
    assert drawn == [serial] * 3


def test_many_faces_draw_the_most_probable_hypotheses_and_say_so():
    """Past DRAWN_FACES posed faces the picture draws the most probable prefix (the
    overlay of the blocking regions grows faster than the faces) and its title says
    how many of how many."""
    import math

    from planner.image.vector import DRAWN_FACES, drawable
    from planner.types import SensorBounds

    ring = [[40 * math.cos(k * math.pi / 60), 40 * math.sin(k * math.pi / 60)] for k in range(120)]
    part = object_from_dict({"name": "round", "outline": ring})
    # a normal bound finer than the ring turns at a vertex: worked as drawn
    session = Session([part], SensorBounds(1.0, 0.02), Workspace((0, 0), 200)).observe(
        Observation(SensingPath((0, -200), (0, 1), 400), Contact((0, -40), (0, -1)))
    )
    faces = len(session.models[0].stable_poses[0].outline)
    hyps = session.hypotheses
    drawn = drawable(hyps, session.models)
    assert faces == 120 and faces * len(hyps) > DRAWN_FACES
    assert len(drawn) == DRAWN_FACES // faces
    assert drawn == tuple(hyps[: len(drawn)])
    svg = session_picture(session, (200, 0), fmt="svg", view="vector")
    assert f"the {len(drawn)} most probable of {len(hyps)} hypotheses".encode() in svg
    assert f'id="outline-{len(drawn) - 1}"'.encode() in svg
    assert f'id="outline-{len(drawn)}"'.encode() not in svg


@settings(max_examples=200, deadline=None, derandomize=True)
@given(st.floats(1e-300, 1.0), st.floats(0.0, 1.0))
def test_an_outline_is_never_more_opaque_than_one(most, share):
    """matplotlib refuses an alpha past 1: 0.2 + (0.8 w) / w rounds to
    1.0000000000000002 for some w (a session picture answered 500 for it)."""
    from planner.drawing import outline_alpha

    assert 0.2 <= outline_alpha(most * share, most) <= 1.0
    assert outline_alpha(0.6369616873214543, 0.6369616873214543) == 1.0
