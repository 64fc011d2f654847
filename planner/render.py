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
import shapely

from planner.geometry import LENGTH_SLACK
from planner.image.grid import GridMII, build_grid
from planner.image.vector import VectorMII, build_mii
from planner.image.windows import ThesisPath
from planner.models.tip import grown_pose
from planner.types import Contact, Observation, SensingPath, Workspace

if TYPE_CHECKING:
    from matplotlib.axes import Axes
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

_IA_COLOUR = "#7fc97f"
#: Most hypotheses whose grown outline (ball tip) a session picture draws.
GROWN_DRAWN = 12
_STRENGTH_CMAP = "Reds"


def _object_colours(names: Sequence[str]) -> dict[str, Any]:
    from matplotlib import colormaps

    cmap = colormaps["tab10"]
    return {name: cmap(i % 10) for i, name in enumerate(sorted(set(names)))}


def _polygon_patch(polygon: shapely.Polygon, **kwargs: Any):
    """A PathPatch for a shapely polygon with holes."""
    from matplotlib.patches import PathPatch
    from matplotlib.path import Path

    rings = [np.asarray(polygon.exterior.coords)] + [
        np.asarray(r.coords) for r in polygon.interiors
    ]
    vertices = np.concatenate(rings)
    codes = np.concatenate(
        [[Path.MOVETO] + [Path.LINETO] * (len(r) - 2) + [Path.CLOSEPOLY] for r in rings]
    )
    return PathPatch(Path(vertices, codes), **kwargs)


def _strength_colour(strength: float):
    from matplotlib import colormaps

    # shade 0.35 .. 1.0 of the colormap so that weak boundaries stay visible
    return colormaps[_STRENGTH_CMAP](0.35 + 0.65 * float(np.clip(strength, 0.0, 1.0)))


def draw_mii(ax: Axes, mii: VectorMII, *, prefix: str = "") -> None:
    """Draw the vector MII on `ax` (world frame): outlines coloured per object and
    faded by probability, the IA filled, blocking boundaries shaded by strength."""
    colours = _object_colours([h.object for h in mii.hypotheses])
    w_max = float(mii.weights.max())
    for k, part in enumerate(shapely.get_parts(mii.certain_intersection)):
        if part.area > 0:
            ax.add_patch(
                _polygon_patch(
                    part,
                    facecolor=_IA_COLOUR,
                    edgecolor="none",
                    alpha=0.5,
                    gid=f"{prefix}ia-{k}",
                    zorder=1,
                )
            )
    for i, (h, outline) in enumerate(zip(mii.hypotheses, mii.outlines, strict=True)):
        # alpha = 0.2 + 0.8 w(h) / max_g w(g)
        alpha = 0.2 + 0.8 * float(mii.weights[i]) / w_max
        ax.add_patch(
            _polygon_patch(
                outline,
                facecolor="none",
                edgecolor=colours[h.object],
                alpha=alpha,
                linewidth=1.0,
                gid=f"{prefix}outline-{i}",
                zorder=2,
            )
        )
    if colours:
        from matplotlib.lines import Line2D

        handles = [Line2D([], [], color=c, label=name) for name, c in colours.items()]
        ax.legend(handles=handles, fontsize=7, loc="upper left").set_gid(f"{prefix}legend")
    for k, b in enumerate(mii.blocking):
        colour = _strength_colour(b.strength)
        if b.is_region:
            for part in shapely.get_parts(b.geometry):
                ax.add_patch(
                    _polygon_patch(
                        part,
                        facecolor=colour,
                        edgecolor="none",
                        alpha=0.75,
                        gid=f"{prefix}blocking-{k}",
                        zorder=3,
                    )
                )
        else:
            xy = np.asarray(b.geometry.coords)
            ax.plot(
                xy[:, 0],
                xy[:, 1],
                color=colour,
                linewidth=1.5 + 3.0 * b.strength,
                solid_capstyle="butt",
                gid=f"{prefix}blocking-{k}",
                zorder=3,
            )


def draw_grid(ax: Axes, grid: GridMII, *, prefix: str = "") -> None:
    """Draw the grid MII on `ax` in world coordinates: faces grey, IA green,
    blocking cells shaded by weighted strength, targets marked."""
    from matplotlib import colormaps

    size = grid.mapping.size
    rgba = np.ones((size, size, 4))
    rgba[grid.faces] = (0.75, 0.75, 0.75, 1.0)
    rgba[grid.ia] = (0.5, 0.79, 0.5, 1.0)
    blocking = grid.strength > 0
    shade = 0.35 + 0.65 * np.clip(grid.strength, 0.0, 1.0)
    rgba[blocking] = colormaps[_STRENGTH_CMAP](shade[blocking])
    # cell i spans grid coordinates [i + 0.5, i + 1.5): its world extent by eq. A5
    (x0, y0), (x1, y1) = grid.mapping.inverse([[0.5, 0.5], [size + 0.5, size + 0.5]])
    ax.imshow(
        np.transpose(rgba, (1, 0, 2)),
        origin="lower",
        extent=(x0, x1, y0, y1),
        interpolation="nearest",
        gid="grid-image",
        zorder=0,
    )
    for k, (x, y) in enumerate(grid.world_targets()):
        ax.plot([x], [y], marker="+", color="black", markersize=9, gid=f"{prefix}target-{k}")


def _contact_list(contacts: Sequence[Contact | Observation]) -> list[Contact]:
    out = []
    for c in contacts:
        contact = c.contact if isinstance(c, Observation) else c
        if contact is not None:
            out.append(contact)
    return out


def draw_overlays(
    ax: Axes,
    *,
    contacts: Sequence[Contact | Observation] = (),
    workspace: Workspace | None = None,
    sensor_position: Sequence[float] | None = None,
    paths: Sequence[SensingPath | ThesisPath] = (),
    p_distinguishing: Sequence[float | None] | None = None,
    arrow_length: float = 10.0,
    prefix: str = "",
    tip_radius: float = 0.0,
    grown: Sequence[np.ndarray] = (),
) -> None:
    """Contacts with normal arrows, the safe circle, the sensor, and ranked paths
    (rank 1 first) labelled with their P(DM) when given. World frame. With a ball
    tip (`tip_radius`), each contact (the ball's centre) gets its ball, and the
    `grown` rings (outlines grown by the radius, where the centre stops) are
    drawn dashed."""
    from matplotlib.patches import Circle, FancyArrow

    for k, ring in enumerate(grown):
        xy = np.vstack([ring, ring[:1]])
        ax.plot(
            xy[:, 0], xy[:, 1], color="0.35", linestyle=":", linewidth=0.8,
            gid=f"{prefix}grown-{k}", zorder=2,
        )  # fmt: skip

    if workspace is not None:
        ax.add_patch(
            Circle(
                workspace.center,
                workspace.radius,
                facecolor="none",
                edgecolor="0.4",
                linestyle="--",
                linewidth=1.0,
                gid=f"{prefix}safe-circle",
                zorder=1,
            )
        )
    if sensor_position is not None:
        ax.plot(
            [sensor_position[0]],
            [sensor_position[1]],
            marker="s",
            color="black",
            markersize=6,
            gid=f"{prefix}sensor",
            zorder=6,
        )
    for j, c in enumerate(_contact_list(contacts)):
        (x, y), (nx, ny) = c.point, c.normal
        ax.plot([x], [y], marker="o", color="black", markersize=4, zorder=6)
        if tip_radius > 0:
            ax.add_patch(
                Circle(
                    (x, y), tip_radius, facecolor="none", edgecolor="black",
                    linewidth=0.8, gid=f"{prefix}ball-{j}", zorder=6,
                )
            )  # fmt: skip
        ax.add_patch(
            FancyArrow(
                x,
                y,
                nx * arrow_length,
                ny * arrow_length,
                width=arrow_length * 0.04,
                head_width=arrow_length * 0.25,
                length_includes_head=True,
                color="black",
                gid=f"{prefix}contact-{j}",
                zorder=6,
            )
        )
    for rank, p in enumerate(paths, start=1):
        path = p.path if isinstance(p, ThesisPath) else p
        origin, end = np.asarray(path.origin), path.end
        direction = np.asarray(path.direction)
        colour = "tab:blue" if rank == 1 else "tab:cyan"
        ax.plot(
            [origin[0], end[0]],
            [origin[1], end[1]],
            color=colour,
            linewidth=2.0 if rank == 1 else 1.0,
            gid=f"{prefix}path-{rank}",
            zorder=5,
        )
        ax.annotate(
            "",
            xy=(end[0], end[1]),
            xytext=tuple(end - arrow_length * direction),
            arrowprops={"arrowstyle": "-|>", "color": colour, "lw": 1.0},
            gid=f"{prefix}path-{rank}-arrow",
            zorder=5,
        )
        label = str(rank)
        pdm = None if p_distinguishing is None else p_distinguishing[rank - 1]
        if pdm is not None:
            label += f"  P(DM)={pdm:.2f}"
        # keep the label inside the picture: it extends from the rim toward the centre
        ha = "right" if direction[0] < -0.3 else "left" if direction[0] > 0.3 else "center"
        ax.text(
            origin[0],
            origin[1],
            label,
            fontsize=8,
            color=colour,
            ha=ha,
            va="bottom",
            gid=f"{prefix}path-{rank}-label",
            zorder=7,
        )


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

    if mii is None and grid is None:
        from planner.errors import PlanningNotPossibleError

        raise PlanningNotPossibleError("nothing to draw: give a vector or a grid MII", field="mii")
    views: list[VectorMII | GridMII] = [v for v in (mii, grid) if v is not None]
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
        else:
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
        ax.set_title(f"{kind} MII", fontsize=9)
        ax.tick_params(labelsize=7)
    mappable = ScalarMappable(
        norm=Normalize(0.0, 1.0),
        cmap=colormaps[_STRENGTH_CMAP].resampled(256),
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
    A session without hypotheses has no MII to draw
    (:class:`~planner.errors.PlanningNotPossibleError`).

    >>> from planner.models.library import object_from_dict
    >>> from planner.recognition.session import Session
    >>> sq = object_from_dict({"name": "sq", "outline": [[-1, -1], [1, -1], [1, 1], [-1, 1]]})
    >>> touch = Observation(SensingPath((0, -10), (0, 1), 20), Contact((0, -1), (0, -1)))
    >>> session = Session([sq], workspace=Workspace((0, 0), 10)).observe(touch)
    >>> session_picture(session, (10, 0), fmt="svg")[:5]
    b'<?xml'
    """
    hyps = session.hypotheses
    mii = build_mii(hyps, session.models) if view in ("vector", "both") else None
    grid = build_grid(hyps, session.models, grid_size) if view in ("grid", "both") else None
    ranked = () if plan is None else plan.paths if paths is None else plan.paths[:paths]
    kwargs: dict[str, Any] = {
        "contacts": session.observations,
        "workspace": session.workspace,
        "sensor_position": sensor_position,
        "paths": [p.path for p in ranked],
        "p_distinguishing": [p.p_distinguishing for p in ranked],
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
