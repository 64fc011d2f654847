"""Finely drawn outlines worked with as fewer faces, soundly (DESIGN §4.1).

A CAD export or a mesh slice draws a curve as hundreds to thousands of short
faces. The recognition and the planner work per face, so such an outline costs
in proportion to how finely it is drawn, and a contact on it fits many adjacent
faces at once. Here each ring is replaced by a subset of its own vertices: a
run of faces becomes one chord when every face's direction lies within `normal`
(radians) of the chord's and every vertex of the run within `position` (length)
of it.

Why this stays sound against the TRUE outline. With every face of a run turned
less than 90 degrees from its chord, the run is the graph of a function over the
chord: the foot of each true boundary point on the chord lies on the chord, at
most `position` away, and each point of the chord has a point of the run at most
`position` away. A contact on a true face, measured within eps_d and phi of it,
therefore lies within ``eps_d + position`` of the chord and its normal within
``phi + normal`` of the chord's, and the true outline lies within `position` of
the worked one everywhere (free space included). A session that works with the
simplified outlines widens its sensor bounds by the largest deviation actually
met (:class:`Deviation`), never by more than it asked for, and by nothing when
no face was merged.

Runs never join faces of different out-of-plane normal (``normal_z``, from a
mesh), and a simplified pose that is no longer valid (a ring crossing itself or
a hole) is kept as given.

>>> import numpy as np
>>> t = np.linspace(0, 2 * np.pi, 2000, endpoint=False)
>>> disc = make_stable_pose(np.column_stack([30 * np.cos(t), 30 * np.sin(t)]))
>>> pose, dev = simplify_pose(disc, position=0.25, normal=0.026)
>>> len(pose.outline) < 200, dev.normal <= 0.026, dev.position <= 0.25
(True, True, True)
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from planner.errors import InvalidModelError
from planner.geometry import vertex_turns
from planner.models.outlines import make_stable_pose, with_slices
from planner.types import ObjectModel, SensorBounds, StablePose

__all__ = [
    "NORMAL_SHARE",
    "POSITION_SHARE",
    "Deviation",
    "given_faces",
    "simplify_models",
    "simplify_pose",
    "simplify_ring",
    "widened",
]

#: Share of the sensor's position bound a chord may stray from the faces it stands for.
POSITION_SHARE = 0.25
#: Share of the sensor's normal bound a chord may turn from the faces it stands for: a
#: contact on a curve then fits about three faces (four at half the bound), which keeps
#: the interpretations of a finely drawn curve from multiplying touch after touch.
NORMAL_SHARE = 1.0
#: Below pi/4, the bound of any sensor's normal error, widened or not.
MAX_NORMAL = 0.99 * math.pi / 4
#: Out-of-plane normals this close are one (faces of one mesh facet).
NORMAL_Z_TOLERANCE = 1e-9


@dataclass(frozen=True)
class Deviation:
    """How far worked outlines stray from the true ones: every true boundary point
    within `position` (length) of the worked boundary and back, every true face's
    direction within `normal` (radians) of the chord that stands for it; `faces`
    given and `kept` after simplification."""

    position: float = 0.0
    normal: float = 0.0
    faces: int = 0
    kept: int = 0

    def __or__(self, other: Deviation) -> Deviation:
        return Deviation(
            max(self.position, other.position),
            max(self.normal, other.normal),
            self.faces + other.faces,
            self.kept + other.kept,
        )


def _wrapped(angle: np.ndarray) -> np.ndarray:
    return (angle + math.pi) % (2 * math.pi) - math.pi


def _run_deviation(
    ring: np.ndarray, phi: np.ndarray, nz: np.ndarray | None, i: int, j: int
) -> tuple[float, float] | None:
    """(position, normal) deviation of the faces i..j-1 (indices mod n) from the
    chord from vertex i to vertex j, or None when they may not merge."""
    n = len(ring)
    idx = np.arange(i, j) % n
    if nz is not None and np.ptp(nz[idx]) > NORMAL_Z_TOLERANCE:
        return None
    a, b = ring[i % n], ring[j % n]
    chord = b - a
    length = math.hypot(*chord)
    if length == 0.0:
        return None
    turn = float(np.max(np.abs(_wrapped(phi[idx] - math.atan2(chord[1], chord[0])))))
    inner = ring[idx[1:]] - a
    # perpendicular distance of the run's inner vertices from the chord's line
    off = np.abs(inner[:, 0] * chord[1] - inner[:, 1] * chord[0]) / length
    return (float(off.max()) if len(off) else 0.0), turn


def _fits(dev: tuple[float, float] | None, position: float, normal: float) -> bool:
    return dev is not None and dev[0] <= position and dev[1] <= normal


def simplify_ring(
    ring: np.ndarray, position: float, normal: float, normal_z: np.ndarray | None = None
) -> tuple[np.ndarray, float, float]:
    """Indices of the vertices of `ring` ((n, 2), closed implicitly; face k runs
    from vertex k to k + 1) kept as chords, and the largest (position, normal)
    deviation of a merged run. Each chord reaches as far as doubling then halving
    the run finds it fits; the ring starts at its sharpest corner, which is kept.
    `normal` must stay below pi/2."""
    n = len(ring)
    edge = np.roll(ring, -1, axis=0) - ring
    phi = np.arctan2(edge[:, 1], edge[:, 0])
    start = int(np.argmax(vertex_turns(ring)))
    order = (np.arange(n) + start) % n
    ring, phi = ring[order], phi[order]
    nz = None if normal_z is None else np.asarray(normal_z)[order]
    kept = [0]
    worst = (0.0, 0.0)
    i = 0
    while i < n:
        step, best = 1, (0.0, 0.0)
        # double while the run fits, then halve between the last fit and the first miss
        while i + 2 * step <= n and _fits(
            d := _run_deviation(ring, phi, nz, i, i + 2 * step), position, normal
        ):
            step, best = 2 * step, d
        lo, hi = step, min(2 * step, n - i + 1)
        while hi - lo > 1:
            mid = (lo + hi) // 2
            d = _run_deviation(ring, phi, nz, i, i + mid)
            if _fits(d, position, normal):
                lo, best = mid, d
            else:
                hi = mid
        worst = (max(worst[0], best[0]), max(worst[1], best[1]))
        i += lo
        if i < n:
            kept.append(i)
    return np.sort(order[kept]), worst[0], worst[1]


def _simplify_layer(
    pose: StablePose, position: float, normal: float
) -> tuple[StablePose, Deviation]:
    rings = [pose.outline, *pose.holes]
    given = sum(len(r) for r in rings)
    starts = np.cumsum([0] + [len(r) for r in rings])
    kept_rings, kept_nz = [], []
    dev_p = dev_n = 0.0
    for r, s in zip(rings, starts, strict=False):
        nz = None if pose.normal_z is None else pose.normal_z[s : s + len(r)]
        keep, p, a = simplify_ring(r, position, normal, nz)
        kept_rings.append(r[keep])
        kept_nz.append(None if nz is None else nz[keep])
        dev_p, dev_n = max(dev_p, p), max(dev_n, a)
    kept = sum(len(r) for r in kept_rings)
    if kept == given:
        return pose, Deviation(0.0, 0.0, given, given)
    normal_z = None if pose.normal_z is None else np.concatenate(kept_nz)
    try:
        new = make_stable_pose(kept_rings[0], kept_rings[1:], pose.probability, normal_z)
    except InvalidModelError:  # a ring now crosses itself or a hole: keep it as given
        return pose, Deviation(0.0, 0.0, given, given)
    return (
        StablePose(new.outline, new.holes, pose.probability, new.normal_z, pose.height),
        Deviation(dev_p, dev_n, given, kept),
    )


def simplify_pose(pose: StablePose, position: float, normal: float) -> tuple[StablePose, Deviation]:
    """A stable pose with every layer's rings simplified (:func:`simplify_ring`)
    within `position` (length) and `normal` (radians), and the deviation met."""
    if not (0 <= normal < math.pi / 2) or not (position >= 0):
        raise ValueError("position must be >= 0 and normal in [0, pi/2)")
    layers = [_simplify_layer(p, position, normal) for p in pose.layers]
    dev = Deviation()
    for _, d in layers:
        dev = dev | d
    if dev.kept == dev.faces:
        return pose, dev
    if not pose.slices:
        return layers[0][0], dev
    slices = with_slices([(float(p.height), p) for p, _ in layers])  # type: ignore[arg-type]
    return slices, dev


def simplify_models(
    models: Sequence[ObjectModel], sensor: SensorBounds
) -> tuple[tuple[ObjectModel, ...], Deviation]:
    """The objects as a session with `sensor` works with them: every stable pose
    simplified within `POSITION_SHARE` of the position bound and `NORMAL_SHARE`
    of the normal bound, and the largest deviation met over all of them (the
    models themselves where nothing merged)."""
    position = POSITION_SHARE * sensor.position_error
    # the widened normal bound must stay below pi/4, as every sensor's does
    normal = min(NORMAL_SHARE * sensor.normal_error, max(0.0, MAX_NORMAL - sensor.normal_error))
    out, dev = [], Deviation()
    for m in models:
        poses = []
        for p in m.stable_poses:
            q, d = simplify_pose(p, position, normal)
            poses.append(q)
            dev = dev | d
        same = all(q is p for q, p in zip(poses, m.stable_poses, strict=True))
        out.append(m if same else ObjectModel(m.name, tuple(poses), m.prior))
    return tuple(out), dev


def given_faces(given: StablePose, worked: StablePose) -> np.ndarray:
    """(F_given,) the face of `worked` (:func:`simplify_pose` of `given`, one
    layer) that stands for each face of `given`, rings in the same order.

    >>> square = make_stable_pose([[0, 0], [1, 0], [2, 0], [2, 2], [0, 2]])
    >>> worked, _ = simplify_pose(square, 0.0, 0.0)
    >>> given_faces(square, worked).tolist()
    [0, 0, 1, 2, 3]
    """
    out, first = [], 0
    for r, w in zip([given.outline, *given.holes], [worked.outline, *worked.holes], strict=True):
        where = {tuple(v): i for i, v in enumerate(r.tolist())}
        kept = np.array([where[tuple(v)] for v in w.tolist()])
        # face k of the given ring lies on the chord that starts at the last kept vertex <= k
        chord = np.searchsorted(kept, np.arange(len(r)), side="right") - 1
        out.append(first + np.where(chord < 0, len(w) - 1, chord))
        first += len(w)
    return np.concatenate(out)


def widened(sensor: SensorBounds, dev: Deviation) -> SensorBounds:
    """The sensor bounds as seen against simplified outlines: position and normal
    bounds widened by the deviation (the same bounds when nothing merged)."""
    if dev.position == 0.0 and dev.normal == 0.0:
        return sensor
    return SensorBounds(
        sensor.position_error + dev.position,
        sensor.normal_error + dev.normal,
        sensor.tip_radius,
    )
