"""Probing heights of a set of objects (DESIGN §4.13).

A stable pose cut at several heights carries one outline per height; a pose with
a single outline and no height is a prism, the same at every height. A session
can probe at the heights every sliced pose has, and at the default height (None),
where each pose's first slice was cut.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence

from planner.errors import InvalidObservationError
from planner.types import HEIGHT_TOLERANCE, ObjectModel, StablePose

__all__ = ["canonical_height", "check_height", "models_at", "probing_heights"]


def _same(a: float, b: float) -> bool:
    return abs(a - b) <= HEIGHT_TOLERANCE * max(1.0, abs(a), abs(b))


def probing_heights(models: Iterable[ObjectModel]) -> tuple[float | None, ...]:
    """The heights a path may take: None (the default) first, then the heights
    every sliced stable pose has a slice at, ascending, less one that is every
    sliced pose's default (it is None again).

    >>> from planner.models.outlines import make_stable_pose, with_slices
    >>> sq = make_stable_pose([[0, 0], [2, 0], [2, 2], [0, 2]])
    >>> tall = ObjectModel("t", (with_slices([(5.0, sq), (20.0, sq)]),))
    >>> probing_heights([tall, ObjectModel("flat", (sq,))])
    (None, 20.0)
    """
    sliced = [p for m in models for p in m.stable_poses if p.heights is not None]
    if not sliced:
        return (None,)
    common = [float(z) for z in sliced[0].heights or ()]
    for pose in sliced[1:]:
        common = [z for z in common if any(_same(z, h) for h in pose.heights or ())]
    defaults = {float(p.height) for p in sliced}  # type: ignore[arg-type]
    if len(defaults) == 1:
        common = [z for z in common if not _same(z, next(iter(defaults)))]
    return (None, *sorted(common))


def canonical_height(models: Iterable[ObjectModel], height: float | None) -> float | None:
    """`height` as :func:`probing_heights` names it: None when it is every sliced
    stable pose's default height (or no pose is sliced)."""
    if height is None:
        return None
    sliced = [p for m in models for p in m.stable_poses if p.heights is not None]
    if all(_same(height, float(p.height)) for p in sliced):  # type: ignore[arg-type]
        return None
    return height


def check_height(models: Sequence[ObjectModel], height: float | None) -> None:
    """Refuse a path height some sliced stable pose has no slice at."""
    if height is None:
        return
    heights = [z for z in probing_heights(models) if z is not None]
    sliced = [p for m in models for p in m.stable_poses if p.heights is not None]
    if all(any(_same(height, h) for h in p.heights or ()) for p in sliced):
        return
    said = ", ".join(f"{z:g}" for z in heights) or "only the default (no height)"
    raise InvalidObservationError(
        f"no slice of every object at height {height:g}; this set's heights: {said}",
        field="path.height",
    )


def models_at(models: Iterable[ObjectModel], height: float | None) -> list[ObjectModel]:
    """The objects as a path at `height` meets them: each stable pose replaced by
    its layer at that height (with the pose's probability)."""
    return [
        ObjectModel(m.name, tuple(_at(p, height) for p in m.stable_poses), m.prior) for m in models
    ]


def _at(pose: StablePose, height: float | None) -> StablePose:
    layer = pose.layer(height)
    if layer is pose and not pose.slices:
        return pose
    return StablePose(layer.outline, layer.holes, pose.probability, layer.normal_z, layer.height)
