"""Pictures of the multi-interpretation image: SVG and PNG bytes (DESIGN §6 image.svg/png).

Matplotlib is imported lazily inside the functions and only through
``matplotlib.figure.Figure`` with an Agg canvas (never pyplot, so no global
state and no display). Nothing is written to disk: the functions return bytes
and the caller stores or serves them.

:func:`session_picture` draws a session (its MII, contacts and planned paths)
for the service's ``image.svg``/``image.png`` and for the simulator's pictures.
One figure is drawn at a time (matplotlib's rc parameters are process-global),
so the functions may be called from several threads.

Every artist carries a ``gid`` that becomes an element id in the SVG:
``outline-<i>``, ``ia-<k>``, ``blocking-<k>``, ``contact-<j>``,
``safe-circle``, ``sensor``, ``path-<rank>`` (and ``path-<rank>-label``),
``grid-image``, ``target-<k>``, and with a ball tip ``ball-<j>`` and
``grown-<k>``; a panel's artists are prefixed ``grid-`` in the grid view when
both views are drawn.
"""

from __future__ import annotations

import io
import threading
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any, Literal

import numpy as np

from planner.drawing import GROWN_DRAWN, STRENGTH_CMAP, draw_grid, draw_mii, draw_overlays
from planner.geometry import LENGTH_SLACK
from planner.image.grid import GridMII, build_grid
from planner.image.vector import VectorMII, build_mii, drawable
from planner.image.windows import ThesisPath
from planner.models.tip import grown_pose
from planner.types import Contact, Observation, SensingPath, Workspace

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from planner.planning.result import Plan
    from planner.recognition.session import Session

__all__ = [
    "draw_grid",
    "draw_mii",
    "draw_overlays",
    "render_png",
    "render_svg",
    "session_picture",
]

#: Held while a figure is drawn and saved: rc parameters are global to matplotlib.
_DRAWING = threading.Lock()


def _limits(
    mii: VectorMII | None, grid: GridMII | None, workspace: Workspace | None
) -> tuple[float, float, float, float]:
    if workspace is not None:
        (cx, cy), r = workspace.center, workspace.radius * 1.05
        return cx - r, cx + r, cy - r, cy + r
    if mii is not None:
        x0, y0, x1, y1 = mii.bounds
    elif grid is not None:
        size = grid.mapping.size
        (x0, y0), (x1, y1) = grid.mapping.inverse([[0.5, 0.5], [size + 0.5, size + 0.5]])
    else:
        return -1.0, 1.0, -1.0, 1.0
    pad = 0.1 * max(x1 - x0, y1 - y0, LENGTH_SLACK)
    return x0 - pad, x1 + pad, y0 - pad, y1 + pad


def _figure(
    mii: VectorMII | None,
    grid: GridMII | None,
    *,
    contacts: Sequence[Contact | Observation],
    workspace: Workspace | None,
    sensor_position: Sequence[float] | None,
    paths: Sequence[SensingPath | ThesisPath],
    p_distinguishing: Sequence[float | None] | None,
    title: str | None,
    panel_inches: float,
    tip_radius: float = 0.0,
    grown: Sequence[np.ndarray] = (),
) -> Figure:
    from matplotlib import colormaps
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.cm import ScalarMappable
    from matplotlib.colors import Normalize
    from matplotlib.figure import Figure

    if mii is None and grid is None and workspace is None:
        from planner.errors import PlanningNotPossibleError

        raise PlanningNotPossibleError(
            "nothing to draw: give a vector or a grid MII, or a workspace", field="mii"
        )
    # no MII (no hypothesis yet, or none left): the scene alone, the safe circle,
    # the sensor, the contacts and the planned paths (the opening probe)
    views: list[VectorMII | GridMII | None] = [v for v in (mii, grid) if v is not None] or [None]
    fig = Figure(figsize=(panel_inches * len(views) + 0.8, panel_inches))
    FigureCanvasAgg(fig)
    axes = fig.subplots(1, len(views), squeeze=False)[0]
    x0, x1, y0, y1 = _limits(mii, grid, workspace)
    arrow = 0.06 * max(x1 - x0, y1 - y0)
    for ax, image in zip(axes, views, strict=True):
        kind = "vector" if isinstance(image, VectorMII) else "grid"
        prefix = "grid-" if kind == "grid" and len(views) > 1 else ""
        if isinstance(image, VectorMII):
            draw_mii(ax, image, prefix=prefix)
        elif isinstance(image, GridMII):
            draw_grid(ax, image, prefix=prefix)
        draw_overlays(
            ax,
            contacts=contacts,
            workspace=workspace,
            sensor_position=sensor_position,
            paths=paths,
            p_distinguishing=p_distinguishing,
            arrow_length=arrow,
            prefix=prefix,
            tip_radius=tip_radius,
            grown=grown,
        )
        ax.set_xlim(x0, x1)
        ax.set_ylim(y0, y1)
        ax.set_aspect("equal")
        ax.set_title(f"{kind} MII" if image is not None else "no hypotheses", fontsize=9)
        ax.tick_params(labelsize=7)
    mappable = ScalarMappable(
        norm=Normalize(0.0, 1.0),
        cmap=colormaps[STRENGTH_CMAP].resampled(256),
    )
    bar = fig.colorbar(mappable, ax=list(axes), fraction=0.04, pad=0.02)
    bar.set_label("blocking strength", fontsize=8)
    bar.ax.tick_params(labelsize=7)
    if title:
        fig.suptitle(title, fontsize=10)
    return fig


def render_svg(
    mii: VectorMII | None = None,
    grid: GridMII | None = None,
    *,
    contacts: Sequence[Contact | Observation] = (),
    workspace: Workspace | None = None,
    sensor_position: Sequence[float] | None = None,
    paths: Sequence[SensingPath | ThesisPath] = (),
    p_distinguishing: Sequence[float | None] | None = None,
    title: str | None = None,
    panel_inches: float = 6.0,
    tip_radius: float = 0.0,
    grown: Sequence[np.ndarray] = (),
) -> bytes:
    """SVG of the vector MII, the grid MII, or both side by side (world frame).

    `paths` are ranked (first = rank 1); `p_distinguishing` gives one P(DM) per
    path (or None) for its label; `tip_radius` and `grown` as for
    :func:`draw_overlays`. Text stays text (``svg.fonttype = none``) and
    ids are stable, so the output is deterministic for a given input.

    >>> from planner.models.outlines import make_stable_pose
    >>> from planner.image.vector import build_mii
    >>> from planner.types import ErrorBound, Hypothesis, ObjectModel, Pose
    >>> sq = ObjectModel("sq", (make_stable_pose([[0, 0], [2, 0], [2, 1], [0, 1]]),))
    >>> hs = [Hypothesis("sq", 0, (), Pose(x, 0, 0), ErrorBound(0, 0, 0), 0.5,
    ...                  equivalence_class=i) for i, x in enumerate([0.0, 1.0])]
    >>> render_svg(build_mii(hs, [sq]))[:5]
    b'<?xml'
    """
    return _picture_bytes(
        "svg",
        mii,
        grid,
        contacts=contacts,
        workspace=workspace,
        sensor_position=sensor_position,
        paths=paths,
        p_distinguishing=p_distinguishing,
        title=title,
        panel_inches=panel_inches,
        tip_radius=tip_radius,
        grown=grown,
    )


def render_png(
    mii: VectorMII | None = None,
    grid: GridMII | None = None,
    *,
    contacts: Sequence[Contact | Observation] = (),
    workspace: Workspace | None = None,
    sensor_position: Sequence[float] | None = None,
    paths: Sequence[SensingPath | ThesisPath] = (),
    p_distinguishing: Sequence[float | None] | None = None,
    title: str | None = None,
    panel_inches: float = 6.0,
    dpi: int = 100,
    tip_radius: float = 0.0,
    grown: Sequence[np.ndarray] = (),
) -> bytes:
    """PNG of the same picture as :func:`render_svg`, `dpi` pixels per inch."""
    return _picture_bytes(
        "png",
        mii,
        grid,
        dpi=dpi,
        contacts=contacts,
        workspace=workspace,
        sensor_position=sensor_position,
        paths=paths,
        p_distinguishing=p_distinguishing,
        title=title,
        panel_inches=panel_inches,
        tip_radius=tip_radius,
        grown=grown,
    )


def _picture_bytes(
    fmt: str, mii: VectorMII | None, grid: GridMII | None, dpi: int = 100, **figure: Any
) -> bytes:
    """The figure drawn (one at a time: matplotlib is not thread-safe) and saved as
    `fmt`; SVG with a fixed hash salt and no date, so equal pictures are equal bytes.
    Text is drawn as given (no mathtext): an object named ``$x^2$`` is its name."""
    from matplotlib import rc_context

    buf = io.BytesIO()
    with _DRAWING, rc_context({"text.parse_math": False}):
        fig = _figure(mii, grid, **figure)
        if fmt == "svg":
            with rc_context({"svg.hashsalt": "tactile-planner", "svg.fonttype": "none"}):
                fig.savefig(buf, format="svg", metadata={"Date": None})
        else:
            fig.savefig(buf, format="png", dpi=dpi)
    return buf.getvalue()


def session_picture(
    session: Session,
    sensor_position: Sequence[float],
    plan: Plan | None = None,
    *,
    fmt: Literal["svg", "png"] = "png",
    view: Literal["vector", "grid", "both"] = "both",
    grid_size: int = 70,
    paths: int | None = None,
    title: str | None = None,
    dpi: int = 100,
) -> bytes:
    """SVG or PNG (`fmt`) of a session: its vector MII, grid MII (`grid_size`
    cells a side) or both (`view`), with the contacts and their normals, the safe
    circle, the sensor at `sensor_position` (world frame) and the first `paths`
    ranked paths of `plan` (None: all; no plan: none) labelled with their P(DM).
    Of many hypotheses, the most probable within
    :data:`~planner.image.vector.DRAWN_FACES` posed faces are drawn, and the title
    says how many.
    A session without hypotheses (before its first contact, or with none left)
    is drawn as its scene alone: safe circle, sensor, contacts and paths.

    >>> from planner.models.library import object_from_dict
    >>> from planner.recognition.session import Session
    >>> sq = object_from_dict({"name": "sq", "outline": [[-1, -1], [1, -1], [1, 1], [-1, 1]]})
    >>> touch = Observation(SensingPath((0, -10), (0, 1), 20), Contact((0, -1), (0, -1)))
    >>> session = Session([sq], workspace=Workspace((0, 0), 10)).observe(touch)
    >>> session_picture(session, (10, 0), fmt="svg")[:5]
    b'<?xml'
    """
    hyps = drawable(session.hypotheses, session.models)
    if len(hyps) < len(session.hypotheses):
        shown = f"the {len(hyps)} most probable of {len(session.hypotheses)} hypotheses"
        title = f"{title}: {shown}" if title else shown
    mii = build_mii(hyps, session.models) if hyps and view in ("vector", "both") else None
    grid = (
        build_grid(hyps, session.models, grid_size) if hyps and view in ("grid", "both") else None
    )
    ranked = () if plan is None else plan.paths if paths is None else plan.paths[:paths]
    kwargs: dict[str, Any] = {
        "contacts": session.observations,
        "workspace": session.workspace,
        "sensor_position": sensor_position,
        "paths": [p.path for p in ranked],
        # no hypotheses, no P(DM) to show (the opening probe)
        "p_distinguishing": [p.p_distinguishing if hyps else None for p in ranked],
        "title": title,
    }
    r = session.sensor.tip_radius
    if r > 0:  # the ball at each contact, and where its centre stops
        kwargs["tip_radius"] = r
        kwargs["grown"] = [
            h.pose.apply(
                grown_pose(session.models_by_name[h.object].stable_poses[h.stable_pose], r).outline
            )
            for h in hyps[:GROWN_DRAWN]
        ]
    if fmt == "svg":
        return render_svg(mii, grid, **kwargs)
    return render_png(mii, grid, dpi=dpi, **kwargs)
