"""Drawing on one matplotlib ``Axes``: the MII (vector or grid view) and its
overlays (contacts, balls, grown outlines, the safe circle, the sensor, ranked
paths). :mod:`planner.render` composes these into figures and bytes; the
element ids (``gid``) it documents are set here.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np
import shapely

from planner.image.grid import GridMII
from planner.image.vector import VectorMII
from planner.image.windows import ThesisPath
from planner.types import Contact, Observation, SensingPath, Workspace

if TYPE_CHECKING:
    from matplotlib.axes import Axes

__all__ = [
    "GROWN_DRAWN",
    "STRENGTH_CMAP",
    "draw_grid",
    "draw_mii",
    "draw_overlays",
    "outline_alpha",
]

_IA_COLOUR = "#7fc97f"
#: Most hypotheses whose grown outline (ball tip) a session picture draws.
GROWN_DRAWN = 12
STRENGTH_CMAP = "Reds"


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
    return colormaps[STRENGTH_CMAP](0.35 + 0.65 * float(np.clip(strength, 0.0, 1.0)))


def outline_alpha(weight: float, most: float) -> float:
    """Opacity of a hypothesis' outline: ``0.2 + 0.8 w(h) / max_g w(g)``, the ratio
    taken first and held to [0, 1] (0.2 + (0.8 w) / w rounds past 1 for some w,
    which matplotlib refuses).

    >>> outline_alpha(0.6369616873214543, 0.6369616873214543)
    1.0
    """
    share = weight / most if most > 0 else 1.0
    return 0.2 + 0.8 * min(max(share, 0.0), 1.0)


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
        alpha = outline_alpha(float(mii.weights[i]), w_max)
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
    rgba[blocking] = colormaps[STRENGTH_CMAP](shade[blocking])
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
    (rank 1 first) labelled with their P(DM) when given and their probing height
    when they have one. World frame. With a ball tip (`tip_radius`), each contact
    (the ball's centre) gets its ball, and the `grown` rings (outlines grown by the
    radius, where the centre stops) are drawn dashed."""
    from matplotlib.patches import Circle

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
    _draw_contacts(ax, _contact_list(contacts), arrow_length, prefix, tip_radius)
    _draw_paths(ax, paths, p_distinguishing, arrow_length, prefix)


def _draw_contacts(
    ax: Axes, contacts: Sequence[Contact], arrow_length: float, prefix: str, tip_radius: float
) -> None:
    """Each contact as a dot with its normal arrow, and its ball with a ball tip."""
    from matplotlib.patches import Circle, FancyArrow

    for j, c in enumerate(contacts):
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


def _draw_paths(
    ax: Axes,
    paths: Sequence[SensingPath | ThesisPath],
    p_distinguishing: Sequence[float | None] | None,
    arrow_length: float,
    prefix: str,
) -> None:
    """Ranked paths (rank 1 first and thicker), each with its arrow and label."""
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
        height = getattr(path, "height", None)
        if height is not None:  # a path at a probing height other than the default
            label += f"  z={height:g}"
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
