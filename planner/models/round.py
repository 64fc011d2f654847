"""Outlines with a continuous rotational symmetry: a disc, a ring (DESIGN §2).

A disc turned about its centre by any angle coincides with itself, so its
rotation can never be measured and need not be: every rotation is one
equivalence class, and a session reports the rotation of such a part as free
instead of naming one with a bound it cannot have.

A stable pose is round within `tolerance` when every ring of every layer
(outline and holes) lies in an annulus about one common centre (the outline's
area centroid, in the model frame) no wider than `tolerance`: with each ring
within ``tolerance / 2`` of a circle about that centre (its points at radii
within the annulus, the circle's points within as much of the ring along each
ray from the centre), any rotation moves every ring by at most `tolerance`
(Hausdorff distance between the boundaries). The annulus is measured exactly:
vertices give the largest radius, each face's nearest point to the centre the
smallest.

>>> import numpy as np
>>> from planner.models.outlines import make_stable_pose
>>> t = np.linspace(0, 2 * np.pi, 400, endpoint=False)
>>> disc = make_stable_pose(np.column_stack([30 * np.cos(t), 30 * np.sin(t)]))
>>> round_within(disc, 0.1), round_within(make_stable_pose(disc.outline * [1, 0.9]), 0.1)
(True, False)
"""

from __future__ import annotations

import numpy as np

from planner.geometry import point_segment_distance
from planner.types import StablePose

__all__ = ["annulus_width", "round_within"]


def annulus_width(stable: StablePose) -> float:
    """The widest annulus (length) about the outline's centroid that one ring of
    any layer needs: 0 for a circle, and what any rotation about the centroid can
    move the boundary by, at most."""
    centre = np.asarray(stable.centroid, dtype=float)
    widest = 0.0
    for layer in stable.layers:
        for ring in (layer.outline, *layer.holes):
            ring = np.asarray(ring, dtype=float)
            outer = float(np.hypot(*(ring - centre).T).max())
            inner = float(point_segment_distance(centre, ring, np.roll(ring, -1, axis=0)).min())
            widest = max(widest, outer - inner)
    return widest


def round_within(stable: StablePose, tolerance: float) -> bool:
    """Whether every rotation of `stable` about its centroid coincides with it
    within `tolerance` (length): see the module's note."""
    return annulus_width(stable) <= tolerance
