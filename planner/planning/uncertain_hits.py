"""Where a cast outcome is uncertain: what else a hit or a miss may turn out to be (DESIGN §4.11).

Each function takes the posed faces (:class:`~planner.planning.cast_faces.CastFaces`)
and arrays over c paths and H hypotheses from :mod:`planner.planning.casting`:
a shallow hit (the path cuts the outline no deeper than the tolerance), a thin
stretch past the hit, a slip past the contact to a later hit, a near miss, and a
close pass by a vertex before the contact. World frame, lengths in the object
files' unit, angles in radians.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numba
import numpy as np

from planner.compiled import c_array, outward, segment_gap
from planner.planning.cast_faces import CastFaces, angle_cone, segment_distance

__all__ = [
    "NearContact",
    "close_passes",
    "near_misses",
    "shallow_hits",
    "slip_past",
    "thin_stretch",
]


@dataclass(frozen=True, eq=False)
class NearContact:
    """Where the true outline may be met instead of the nominal outcome, each
    (c, H): `flag`, and, meaningful where it is set, the point (`x`, `y`) and
    the centre and half-width (radians) of the normals there."""

    flag: np.ndarray
    x: np.ndarray
    y: np.ndarray
    centre: np.ndarray
    spread: np.ndarray


def shallow_hits(
    fc: CastFaces,
    t: np.ndarray,
    dist: np.ndarray,
    hit: np.ndarray,
    f: np.ndarray,
    rows: np.ndarray,
    dx: np.ndarray,
    dy: np.ndarray,
    sin_in: np.ndarray,
    length: np.ndarray,
) -> np.ndarray:
    """(c, H) bool: hits whose path cuts the outline no deeper than `geometric`.

    The chord from the entry (`dist`) to the next crossing, of length L, meets
    the entry face at sin(a) = `sin_in` and the exit face at sin(b). A point s
    along it lies ``s sin(a)`` from the entry face's line and ``(L - s) sin(b)``
    from the exit face's, so no point of the chord is deeper than
    ``L sin(a) sin(b) / (sin(a) + sin(b))`` (other faces only make it shallower),
    nor than L / 2. The recognition keeps a hypothesis after a miss unless the
    path enters its outline shrunk by that tolerance, so a shallow hit may well be
    a miss (or meet what lies beyond).
    """
    later = np.where(t > (dist + fc.margin)[..., None], t, np.inf)
    exit_face = np.argmin(later, axis=-1)
    t_exit = np.take_along_axis(later, exit_face[..., None], axis=-1)[..., 0]
    chord = np.where(np.isfinite(t_exit), t_exit, length) - np.where(hit, dist, 0.0)
    sin_out = np.abs(dx * fc.nx[rows, exit_face] + dy * fc.ny[rows, exit_face])
    corner = chord * sin_in * sin_out / np.maximum(sin_in + sin_out, 1e-12)
    depth = np.minimum(np.where(np.isfinite(t_exit), corner, chord), chord / 2)
    return hit & (depth < fc.geometric)


#: Samples along the path past a hit, half a vertex zone apart, looking for depth.
_STRETCH_SAMPLES = 8


def thin_stretch(
    fc: CastFaces,
    origins: np.ndarray,
    t: np.ndarray,
    dist: np.ndarray,
    hit: np.ndarray,
    vertex: np.ndarray,
    face_len: np.ndarray,
    f: np.ndarray,
    dx: np.ndarray,
    dy: np.ndarray,
) -> np.ndarray:
    """(c, H): how far past the hit (on face `f`) the path stays within `geometric` of the
    outline, for hits on short faces (under four vertex zones) or near a vertex,
    where thin features live; 0 elsewhere.

    The recognition explains a contact anywhere the path has not yet entered the
    outline shrunk by `geometric` (plus the position error): through a feature
    thinner than twice that, the contact may come well past the nominal hit, on
    another face. Points half a vertex zone apart are tested (inside the outline:
    before the next crossing) until one lies deeper than `geometric`; the stretch
    ends there, at most `_STRETCH_SAMPLES` steps on.
    """
    out = np.zeros(hit.shape)
    c, h = np.nonzero(hit & (vertex | (face_len < 4 * fc.vertex_tol[None, :])))
    if not len(c):
        return out
    step = fc.vertex_tol[h] / 2
    later = np.where(t[c, h] > (dist[c, h] + fc.margin)[:, None], t[c, h], np.inf)
    t_exit = later.min(axis=-1)
    k = np.arange(1, _STRETCH_SAMPLES + 1)
    s = dist[c, h, None] + k * step[:, None]  # (n, M)
    qx = origins[c, 0, None] + s * dx[c, 0, None]
    qy = origins[c, 1, None] + s * dy[c, 0, None]
    first = np.empty(len(c), dtype=np.int64)
    points = (c_array(qx, float), c_array(qy, float), c_array(s, float), c_array(t_exit, float))
    rows = (c_array(h, np.int64), c_array(f[c, h], np.int64))
    faces = [c_array(a, float) for a in (fc.sx, fc.sy, fc.ex, fc.ey)]
    tolerance = c_array(fc.geometric, float)
    _first_deep(*points, *rows, *faces, c_array(fc.valid, bool), tolerance, first)
    out[c, h] = np.minimum(first * step, t_exit - dist[c, h])
    return out


@numba.njit(cache=True, nogil=True)
def _first_deep(qx, qy, s, t_exit, h, hint, sx, sy, ex, ey, valid, geometric, first):  # type: ignore[no-untyped-def]
    """first[i] = 1 + the first sample k of hit i (points qx, qy (n, M) at `s` along
    the path, on hypothesis h[i]) past the exit or farther than geometric[h[i]] from
    every valid face; M when none is. A sample is shallow as soon as one face lies
    within `geometric`, so its scan starts at the face the last one stopped at
    (first the face hit, `hint`) and goes outward both ways: about one face per
    shallow sample, all of them for the deep one that ends the stretch."""
    n, m = qx.shape
    n_faces = sx.shape[1]
    for i in range(n):
        row, near = h[i], hint[i]
        first[i] = m
        for k in range(m):
            if s[i, k] >= t_exit[i]:
                first[i] = k + 1
                break
            shallow = False
            for j in range(n_faces):
                f = outward(near, j, n_faces)
                if not valid[row, f]:
                    continue
                gap = segment_gap(
                    qx[i, k], qy[i, k], sx[row, f], sy[row, f], ex[row, f], ey[row, f]
                )
                d = math.hypot(*gap)
                if d < geometric[row]:
                    shallow, near = True, f
                    break
            if not shallow:
                first[i] = k + 1
                break


def close_passes(
    fc: CastFaces,
    origins: np.ndarray,
    hit: np.ndarray,
    rows: np.ndarray,
    px: np.ndarray,
    py: np.ndarray,
) -> NearContact:
    """Hits whose path passes within the vertex zone (`geometric` plus the
    position error: what the recognition allows a contact) of a vertex before
    reaching the contact (any vertex outside the contact's own vertex zone, the
    hit face's ends included): the true outline may be met there first, at the
    vertex, with the normal of either face meeting there."""
    ox, oy = origins[:, 0, None, None], origins[:, 1, None, None]
    gap = segment_distance(fc.sx, fc.sy, ox, oy, px[..., None], py[..., None])  # (c, H, F)
    # the face hit's own ends count too: a path that runs past one of them at a
    # shallow angle may meet the adjacent face there first
    near_contact = np.hypot(fc.sx - px[..., None], fc.sy - py[..., None]) <= fc.vertex_tol[:, None]
    gap = np.where(fc.valid & ~near_contact & hit[..., None], gap, np.inf)
    k = np.argmin(gap, axis=-1)
    flag = np.take_along_axis(gap, k[..., None], axis=-1)[..., 0] <= fc.vertex_tol
    vx, vy = fc.sx[rows, k], fc.sy[rows, k]
    before = fc.prev[rows, k]
    centre, spread = np.zeros(hit.shape), np.zeros(hit.shape)
    at = np.nonzero(flag)
    centre[at], spread[at] = angle_cone(
        fc.nx[rows, before][at], fc.ny[rows, before][at], fc.nx[rows, k][at], fc.ny[rows, k][at]
    )
    nan = np.full(hit.shape, np.nan)
    return NearContact(flag, np.where(flag, vx, nan), np.where(flag, vy, nan), centre, spread)


def slip_past(
    fc: CastFaces,
    t: np.ndarray,
    slip: np.ndarray,
    end_of_path: np.ndarray,
    px: np.ndarray,
    py: np.ndarray,
    dx: np.ndarray,
    dy: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Where the path may slip past the contact (`slip`, (c, H)): does it hit again
    further on, how far along the path, and the normal angle there."""
    c, h = np.nonzero(slip)
    # past the contact the path is outside the object: only faces turned toward it
    # count, and none within the vertex zone of the contact
    near_contact = (
        segment_distance(px[c, h, None], py[c, h, None], fc.sx[h], fc.sy[h], fc.ex[h], fc.ey[h])
        <= fc.vertex_tol[h, None]
    )
    facing = dx[c, 0, None] * fc.nx[h] + dy[c, 0, None] * fc.ny[h] < 0
    t_slip = np.where(near_contact | ~facing, np.inf, t[c, h])
    slip_face = np.argmin(t_slip, axis=-1)
    dist = np.full(slip.shape, np.inf)
    dist[c, h] = np.take_along_axis(t_slip, slip_face[:, None], axis=-1)[:, 0]
    angle = np.zeros(slip.shape)
    angle[c, h] = np.arctan2(fc.ny[h, slip_face], fc.nx[h, slip_face])
    slip_hit = slip & np.isfinite(dist) & ~end_of_path
    return slip_hit, np.where(slip_hit, dist, 0.0), angle


def near_misses(
    fc: CastFaces, origins: np.ndarray, directions: np.ndarray, lengths: np.ndarray, hit: np.ndarray
) -> NearContact:
    """Misses passing within `geometric` of an outline, at the closest outline
    point, with the normals there."""
    ex_r = origins[:, 0] + directions[:, 0] * lengths
    ey_r = origins[:, 1] + directions[:, 1] * lengths
    ox, oy = origins[:, 0, None], origins[:, 1, None]
    # a miss can only pass near the outline if it passes near its bounding circle
    to_centre = segment_distance(fc.centre_x, fc.centre_y, ox, oy, ex_r[:, None], ey_r[:, None])
    c, h = np.nonzero(~hit & (to_centre - fc.radius <= fc.geometric + fc.margin))
    ox, oy, rx, ry = ox[c], oy[c], ex_r[c, None], ey_r[c, None]
    sx, sy, ex, ey = fc.sx[h], fc.sy[h], fc.ex[h], fc.ey[h]
    # the closest approach of two segments involves an endpoint of one of them
    d_start = segment_distance(sx, sy, ox, oy, rx, ry)
    d_end = segment_distance(ex, ey, ox, oy, rx, ry)
    d_ray = segment_distance(rx, ry, sx, sy, ex, ey)
    gap = np.where(fc.valid[h], np.minimum(np.minimum(d_start, d_end), d_ray), np.inf)
    near_face = np.argmin(gap, axis=-1)[:, None]
    pick = lambda a: np.take_along_axis(a, near_face, axis=-1)[:, 0]  # noqa: E731
    close = pick(gap) <= fc.geometric[h]
    which = np.argmin(np.stack([pick(d_start), pick(d_end), pick(d_ray)]), axis=0)
    nf = near_face[:, 0]
    x0, y0, x1, y1 = fc.sx[h, nf], fc.sy[h, nf], fc.ex[h, nf], fc.ey[h, nf]
    ux, uy = x1 - x0, y1 - y0
    proj = np.clip(
        ((rx[:, 0] - x0) * ux + (ry[:, 0] - y0) * uy) / np.maximum(ux * ux + uy * uy, 1e-300),
        0.0,
        1.0,
    )
    # at a vertex of the face the normal may be either face's; on the face, its own
    px = np.where(which == 0, x0, np.where(which == 1, x1, x0 + proj * ux))
    py = np.where(which == 0, y0, np.where(which == 1, y1, y0 + proj * uy))
    other = np.where(which == 0, fc.prev[h, nf], fc.next[h, nf])
    other = np.where(which == 2, nf, other)
    centre, spread = angle_cone(fc.nx[h, nf], fc.ny[h, nf], fc.nx[h, other], fc.ny[h, other])
    out = [np.zeros(hit.shape, dtype=bool), *(np.full(hit.shape, np.nan) for _ in range(4))]
    for target, value in zip(out, (close, px, py, centre, spread), strict=True):
        target[c, h] = value
    return NearContact(*out)
