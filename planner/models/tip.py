"""The ball tip (DESIGN §4.14): a probe whose ball of radius r reports its centre.

A ball touching a face has its centre on the face's line moved out by r along the
face's outward normal; touching a vertex, on a circle of radius r around it. The
centres a ball can reach form the outline grown by r (faces offset, vertices
become arcs). Two views of the same touch follow, and the planner uses both:

- the recognition works on the object's own outline, with the contact moved back
  to the surface, ``p = c - r u`` (c the reported centre, u the measured unit
  normal). The true surface point is ``c* - r n``, so ``|p - (c* - r n)| <=
  |c - c*| + r |u - n| <= eps_d + 2 r sin(phi / 2)``: the contact carries the
  sensor's normal bound and a position bound widened by that chord
  (:func:`surface_bounds`, :func:`surface_contact`);
- the planner predicts where the centre stops, so it casts its paths against the
  grown outline (:func:`grown_model`): each face moved out by r, the corners
  where neighbouring faces' offset lines meet (mitred: exact on every face,
  beyond the ball's arc by at most ``r (1 / sin(a / 2) - 1)`` at a corner of
  interior angle a), at most ``6 r`` from the vertex (a spike sharper than 19
  degrees is cut short there, its faces tilted), each grown face keeping its own
  face's normal and index;
- the simulated hardware casts the exact grown outline, offset faces and vertex
  circles (:func:`cast_ball`).

A ball resting on a vertex presses along a normal anywhere between its two faces'.
The recognition's contacts lie on faces (DESIGN §5: a compliant arm slides off a
vertex onto a face); a rest on a vertex is a spurious contact for it
(``max_outliers``). Lengths in the object files' unit, angles in radians.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence

import numpy as np

from planner import geometry
from planner.types import Contact, Faces, ObjectModel, SensorBounds, StablePose

__all__ = [
    "MITRE_LIMIT",
    "cast_ball",
    "grown_model",
    "grown_models",
    "grown_pose",
    "surface_bounds",
    "surface_contact",
]

#: The farthest a grown corner lies from its vertex, in tip radii.
MITRE_LIMIT = 6.0


def surface_bounds(sensor: SensorBounds) -> SensorBounds:
    """The bounds of contacts moved back to the surface: the position bound
    widened by the chord ``2 r sin(phi / 2)`` the normal error swings the ball's
    radius through, the same normal bound, no tip.

    >>> b = surface_bounds(SensorBounds(1.0, 0.05, tip_radius=3.0))
    >>> round(b.position_error, 4), b.normal_error, b.tip_radius
    (1.15, 0.05, 0.0)
    """
    r = sensor.tip_radius
    if r == 0:
        return sensor
    chord = 2.0 * r * math.sin(sensor.normal_error / 2.0)
    return SensorBounds(sensor.position_error + chord, sensor.normal_error)


def surface_contact(contact: Contact, radius: float) -> Contact:
    """The contact moved from the ball's centre back to the surface, ``c - r u``.

    >>> surface_contact(Contact((0.0, 5.0), (0.0, 1.0)), 3.0).point
    (0.0, 2.0)
    """
    if radius == 0:
        return contact
    c, u = contact.point, contact.normal
    return Contact((c[0] - radius * u[0], c[1] - radius * u[1]), u, contact.normal_z)


def _grown_ring(ring: np.ndarray, radius: float) -> np.ndarray:
    """Vertices of one oriented ring grown by `radius` (mitred, capped)."""
    normal_out = geometry.ring_faces([ring])["normal"]  # face i runs from vertex i to i + 1
    n_in, n_out = np.roll(normal_out, 1, axis=0), normal_out  # the faces meeting at vertex i
    # the offset lines n_in.x = d_in + r and n_out.x = d_out + r meet at v + r m with
    # m = (n_in + n_out) / (1 + n_in.n_out): n_in.m = n_out.m = 1
    cos_turn = np.einsum("ij,ij->i", n_in, n_out)
    mitre = (n_in + n_out) / np.maximum(1.0 + cos_turn, 1e-12)[:, None]
    reach = np.hypot(mitre[:, 0], mitre[:, 1])
    mitre *= (np.minimum(reach, MITRE_LIMIT) / np.maximum(reach, 1e-12))[:, None]
    return ring + radius * mitre


def grown_pose(stable: StablePose, radius: float) -> StablePose:
    """The stable pose's outline and holes grown by `radius`, each face keeping its
    index and its own outward normal (a face that the mitres of a concave corner
    shorten past zero keeps its normal; it lies inside the grown outline).

    >>> square = StablePose(np.array([[0.0, 0.0], [2.0, 0.0], [2.0, 2.0], [0.0, 2.0]]))
    >>> grown_pose(square, 1.0).outline.tolist()
    [[-1.0, -1.0], [3.0, -1.0], [3.0, 3.0], [-1.0, 3.0]]
    """
    if radius == 0:
        return stable
    if stable.slices:  # every probing height's outline grown alike
        first, *rest = (grown_pose(p, radius) for p in stable.layers)
        layered = StablePose(
            first.outline, first.holes, stable.probability, stable.normal_z, stable.height,
            tuple(rest),
        )  # fmt: skip
        layered.__dict__["faces"] = first.faces  # with the bare normals, as below
        return layered
    rings = [_grown_ring(r, radius) for r in (stable.outline, *stable.holes)]
    grown = StablePose(
        rings[0], tuple(rings[1:]), stable.probability, stable.normal_z, stable.height
    )
    bare = stable.faces
    edges = geometry.ring_faces(rings)
    # the grown faces keep the bare normals (a mitre cut short tilts its edge a little)
    faces = Faces(
        start=edges["start"],
        end=edges["end"],
        normal=bare.normal,
        offset=np.einsum("ij,ij->i", bare.normal, edges["start"]),
        length=edges["length"],
        angle=bare.angle,
        ring=bare.ring,
    )
    grown.__dict__["faces"] = faces  # StablePose.faces is a cached property
    return grown


def grown_model(model: ObjectModel, radius: float) -> ObjectModel:
    """The object with every stable pose grown by `radius` (memoized per object)."""
    if radius == 0:
        return model
    memo = model.__dict__.setdefault("_grown", {})
    if radius not in memo:
        memo[radius] = ObjectModel(
            model.name, tuple(grown_pose(s, radius) for s in model.stable_poses), model.prior
        )
    return memo[radius]


def grown_models(
    models: Mapping[str, ObjectModel] | Sequence[ObjectModel], radius: float
) -> Mapping[str, ObjectModel] | Sequence[ObjectModel]:
    """:func:`grown_model` over a mapping or a sequence of objects, same shape."""
    if radius == 0:
        return models
    if isinstance(models, Mapping):
        return {name: grown_model(m, radius) for name, m in models.items()}
    return [grown_model(m, radius) for m in models]


def cast_ball(
    origin: np.ndarray,
    direction: np.ndarray,
    length: float,
    start: np.ndarray,
    end: np.ndarray,
    normal: np.ndarray,
    radius: float,
) -> tuple[float, int, int] | None:
    """Where a ball of `radius` whose centre runs along a path first touches an
    outline (world faces `start`, `end`, outward unit `normal`, (F, 2) each).

    The centres at most r from the outline are bounded by the faces moved out by r
    and the circles of radius r around the vertices, and all of them lie within
    r of it: the first of them the centre meets is where the ball stops. Returns
    (distance along the path, face, vertex) with `vertex` -1 on a face, else the
    index of the face starting at the vertex touched (`face` is then the face
    ending there); None on a miss.
    """
    o, d = np.asarray(origin, float), np.asarray(direction, float)
    dist, face = geometry.cast_rays(
        o[None], d[None], np.array([length]), (start + radius * normal)[None],
        (end + radius * normal)[None],
    )  # fmt: skip
    best_t, best_face, best_vertex = float(dist[0]), int(face[0]), -1
    # |o + t d - v| = r: t = b - sqrt(b^2 - c), b = d.(v - o), c = |v - o|^2 - r^2
    w = start - o
    b = w @ d
    disc = b * b - (np.einsum("ij,ij->i", w, w) - radius * radius)
    with np.errstate(invalid="ignore"):
        t = b - np.sqrt(disc)
    t = np.where((disc >= 0) & (t >= 0) & (t <= length), t, np.inf)
    k = int(np.argmin(t))
    if t[k] < best_t:
        # the face ending at vertex k: the one whose end is start[k]
        ending = np.flatnonzero(np.hypot(*(end - start[k]).T) <= 1e-9 * max(1.0, radius))
        best_t, best_face, best_vertex = float(t[k]), int(ending[0]) if len(ending) else k, k
    if not math.isfinite(best_t):
        return None
    return best_t, best_face, best_vertex
