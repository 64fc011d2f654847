"""Where a cast outcome is uncertain: what else a hit or a miss may turn out to be (DESIGN §4.11).

Each function takes the posed faces (:class:`~planner.planning.cast_faces.CastFaces`)
and arrays over c paths and H hypotheses from :mod:`planner.planning.casting`:
a shallow hit (the path cuts the outline no deeper than the vertex zone), the
stretch past a hit where a contact may still come on other faces, a slip past the
contact to a later hit or to a face passed near further on, a miss's near
approaches, and a close pass by a vertex before the contact. World frame, lengths in the object
files' unit, angles in radians.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numba
import numpy as np

from planner.compiled import SQUARE_SCREEN, c_array, segment_gap
from planner.planning.cast_faces import CastFaces, angle_cone, segment_distance
from planner.planning.near_kernel import closest_vertices, near_stretches

__all__ = [
    "NearContact",
    "Stretch",
    "close_passes",
    "exits",
    "near_after_slip",
    "near_misses",
    "shallow_hits",
    "slip_past",
    "stretch_past_hits",
]


@dataclass(frozen=True, eq=False)
class NearContact:
    """Where the true outline may be met instead of the nominal outcome, each
    (c, H): `flag`, and, meaningful where it is set, the point (`x`, `y`), the
    centre and half-width (radians) of the normals there, and the `slack` along
    the path (the point is the middle of a stretch of it that long each way)."""

    flag: np.ndarray
    x: np.ndarray
    y: np.ndarray
    centre: np.ndarray
    spread: np.ndarray
    slack: np.ndarray


def exits(fc: CastFaces, t: np.ndarray, dist: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(c, H) each: how far along the path it next crosses a face past its hit at
    `dist` (inf if it does not, or misses), and that face (0 if none); `t` (c, H, F)
    where the path meets each face."""
    later = np.where(t > (dist + fc.margin)[..., None], t, np.inf)
    exit_face = np.argmin(later, axis=-1)
    return np.take_along_axis(later, exit_face[..., None], axis=-1)[..., 0], exit_face


def shallow_hits(
    fc: CastFaces,
    t_exit: np.ndarray,
    exit_face: np.ndarray,
    dist: np.ndarray,
    hit: np.ndarray,
    rows: np.ndarray,
    dx: np.ndarray,
    dy: np.ndarray,
    sin_in: np.ndarray,
    length: np.ndarray,
) -> np.ndarray:
    """(c, H) bool: hits whose path cuts the outline no deeper than the vertex
    zone (`geometric`, how far the pose may stand off, plus the position error).

    The chord from the entry (`dist`) to the next crossing (`t_exit`, on face
    `exit_face`: :func:`exits`), of length L, meets
    the entry face at sin(a) = `sin_in` and the exit face at sin(b). A point s
    along it lies ``s sin(a)`` from the entry face's line and ``(L - s) sin(b)``
    from the exit face's, so no point of the chord is deeper than
    ``L sin(a) sin(b) / (sin(a) + sin(b))`` (other faces only make it shallower),
    nor than L / 2. The recognition keeps a hypothesis after a miss unless the
    path enters its outline shrunk by half its error disk (at a pose within the
    bound), so a shallow hit may well be a miss (or meet what lies beyond).
    """
    chord = np.where(np.isfinite(t_exit), t_exit, length) - np.where(hit, dist, 0.0)
    sin_out = np.abs(dx * fc.nx[rows, exit_face] + dy * fc.ny[rows, exit_face])
    corner = chord * sin_in * sin_out / np.maximum(sin_in + sin_out, 1e-12)
    depth = np.minimum(np.where(np.isfinite(t_exit), corner, chord), chord / 2)
    return hit & (depth < fc.vertex_tol)


#: Samples along the path past a hit, half a vertex zone apart, looking for depth.
_STRETCH_SAMPLES = 16


@dataclass(frozen=True, eq=False)
class Stretch:
    """Where past its nominal hit a path may still meet the true outline, each
    (c, H): `length` how far past the hit the path stays shallow enough for a
    contact, `lo` and `hi` the range of normal angles (radians, from the hit
    face's) of the other faces a contact there may lie on (both 0 when there is
    none), `open` whether the path was still shallow at the last sample."""

    length: np.ndarray
    lo: np.ndarray
    hi: np.ndarray
    open: np.ndarray

    @property
    def other_faces(self) -> np.ndarray:
        """(c, H): a contact past the hit may lie on another face (or anywhere)."""
        return self.open | (self.lo < 0) | (self.hi > 0)


def stretch_past_hits(
    fc: CastFaces,
    origins: np.ndarray,
    t_exit: np.ndarray,
    dist: np.ndarray,
    hit: np.ndarray,
    f: np.ndarray,
    dx: np.ndarray,
    dy: np.ndarray,
    length: np.ndarray,
) -> Stretch:
    """How far past each hit (on face `f`) a contact may still come, and on which
    other faces.

    The recognition keeps a hypothesis whose path, up to the contact less the
    position error, stays clear of its outline shrunk by half its error disk, at a
    pose within the bound: the path may run into the nominal outline before a
    contact, and the contact may lie on any face within `geometric` plus the
    position error (the vertex zone) of the path there that the path may meet
    from outside (turned toward it within the rotation bound). Points half a
    vertex zone apart are tested from the hit on, up to the exit from the outline,
    the path's end or the first point farther than the vertex zone plus half a
    step from every face (at most `_STRETCH_SAMPLES` steps on); a face counts
    within that distance of a point, so that nothing between two points is
    missed. The pose's shift and the shrink together could let a path run in by
    twice `geometric` plus the position error; stretches to that depth cost
    lookahead a quarter touch at the 5-degree sensor and, like these, left no
    touch called sure with two classes in 250 worlds of that sensor.
    """
    zero = np.zeros(hit.shape)
    out = Stretch(zero, zero.copy(), zero.copy(), np.zeros(hit.shape, dtype=bool))
    c, h = np.nonzero(hit)
    if not len(c):
        return out
    step = fc.vertex_tol[h] / 2
    # the path ends at the exit from the outline (:func:`exits`) or at its own end
    end = np.minimum(t_exit[c, h], length[c, 0])
    # a face counts within the vertex zone plus half a step of a point, and a point
    # farther than that from every face ends the stretch
    reach = fc.vertex_tol + fc.vertex_tol / 4
    first = np.empty(len(c), dtype=np.int64)
    lo, hi = np.zeros(len(c)), np.zeros(len(c))
    path = [c_array(a, float) for a in (origins[c, 0], origins[c, 1], dx[c, 0], dy[c, 0])]
    samples = (c_array(dist[c, h], float), c_array(step, float), c_array(end, float))
    rows = (c_array(h, np.int64), c_array(f[c, h], np.int64))
    faces = [c_array(a, float) for a in (fc.sx, fc.sy, fc.ex, fc.ey, fc.nx, fc.ny)]
    limits = (c_array(reach, float), c_array(fc.turn_sin, float))
    valid = c_array(fc.valid, bool)
    _stretch_kernel(*path, *samples, *rows, *faces, valid, *limits, first, lo, hi)  # type: ignore[call-arg]
    out.length[c, h] = np.minimum(first * step, np.maximum(end - dist[c, h], 0.0))
    out.lo[c, h], out.hi[c, h] = lo, hi
    out.open[c, h] = first > _STRETCH_SAMPLES
    return out


@numba.njit(cache=True, nogil=True)
def _stretch_kernel(  # type: ignore[no-untyped-def]
    ox, oy, dx, dy, dist, step, end, h, hit_face, sx, sy, ex, ey, nx, ny, valid,
    reach, turn_sin, first, lo, hi,
):  # fmt: skip
    """For hit i (path from ox[i], oy[i] along dx[i], dy[i], the hit at dist[i],
    on hypothesis h[i] and face hit_face[i]), points step[i] apart from the hit on,
    M + 1 of them (M = `_STRETCH_SAMPLES`): first[i] = the first point at or past
    end[i] (the exit or the path's end) or farther than reach[h[i]] from every
    valid face (M + 1 when none is); lo[i], hi[i] the range of normal angles, from
    the hit face's, of the faces the path may meet (d . n < turn_sin[h[i]]) within
    reach[h[i]] of a point before that one."""
    m = _STRETCH_SAMPLES + 1
    n, n_faces = len(ox), sx.shape[1]
    near = np.empty(n_faces, dtype=np.int64)
    for i in range(n):
        row, own = h[i], hit_face[i]
        base = math.atan2(ny[row, own], nx[row, own])
        first[i] = m
        lo[i], hi[i] = 0.0, 0.0
        # only faces whose boxes come within `reach` of the points' box can be near
        # any point (the others lie farther than that from them all)
        last = 0
        while last + 1 < m and dist[i] + (last + 1) * step[i] < end[i]:
            last += 1
        pad = reach[row]
        ax, ay = ox[i] + dist[i] * dx[i], oy[i] + dist[i] * dy[i]
        s_last = dist[i] + last * step[i]
        bx, by = ox[i] + s_last * dx[i], oy[i] + s_last * dy[i]
        count = 0
        for j in range(n_faces):
            if valid[row, j] and not (
                max(sx[row, j], ex[row, j]) < min(ax, bx) - pad
                or min(sx[row, j], ex[row, j]) > max(ax, bx) + pad
                or max(sy[row, j], ey[row, j]) < min(ay, by) - pad
                or min(sy[row, j], ey[row, j]) > max(ay, by) + pad
            ):
                near[count] = j
                count += 1
        for k in range(m):
            if k > last:
                first[i] = k
                break
            s_k = dist[i] + k * step[i]
            px, py = ox[i] + s_k * dx[i], oy[i] + s_k * dy[i]
            nearest = np.inf
            for c in range(count):
                j = near[c]
                if (
                    max(sx[row, j], ex[row, j]) < px - pad
                    or min(sx[row, j], ex[row, j]) > px + pad
                    or max(sy[row, j], ey[row, j]) < py - pad
                    or min(sy[row, j], ey[row, j]) > py + pad
                ):
                    continue  # farther than `reach`
                gx, gy = segment_gap(px, py, sx[row, j], sy[row, j], ex[row, j], ey[row, j])
                if gx * gx + gy * gy > pad * pad * (1 + SQUARE_SCREEN):
                    continue  # farther than `reach` (squares decide all but near-ties)
                d = math.hypot(gx, gy)
                nearest = min(nearest, d)
                facing = dx[i] * nx[row, j] + dy[i] * ny[row, j] < turn_sin[row]
                if j == own or d > reach[row] or not facing:
                    continue
                turn = math.atan2(ny[row, j], nx[row, j]) - base
                turn = (turn + math.pi) % (2 * math.pi) - math.pi
                lo[i], hi[i] = min(lo[i], turn), max(hi[i], turn)
            if nearest > pad:
                first[i] = k
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
    # the face hit's own ends count too: a path that runs past one of them at a
    # shallow angle may meet the adjacent face there first
    c, h = np.nonzero(hit)
    nearest, gap = closest_vertices(
        (fc.sx, fc.sy), fc.valid, fc.vertex_tol, origins, (px, py), (c, h)
    )
    k = np.zeros(hit.shape, dtype=np.int64)
    k[c, h] = nearest
    flag = np.zeros(hit.shape, dtype=bool)
    flag[c, h] = gap <= fc.vertex_tol[h]
    vx, vy = fc.sx[rows, k], fc.sy[rows, k]
    before = fc.prev[rows, k]
    centre, spread = np.zeros(hit.shape), np.zeros(hit.shape)
    at = np.nonzero(flag)
    centre[at], spread[at] = angle_cone(
        fc.nx[rows, before][at], fc.ny[rows, before][at], fc.nx[rows, k][at], fc.ny[rows, k][at]
    )
    nan = np.full(hit.shape, np.nan)
    return NearContact(
        flag, np.where(flag, vx, nan), np.where(flag, vy, nan), centre, spread, np.zeros(hit.shape)
    )


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
    """Misses passing within the vertex zone (`geometric` plus the position error)
    of a face they may meet (turned toward the path within the rotation bound): at
    a pose within the bound that face may stand where the path passes. Every
    point of the path so near some such face is covered, as one stretch along it
    from the first to the last, with the range of those faces' normals."""
    ox, oy = origins[:, 0, None], origins[:, 1, None]
    ex_r = ox + directions[:, 0, None] * lengths[:, None]
    ey_r = oy + directions[:, 1, None] * lengths[:, None]
    # a miss can only pass near the outline if it passes near its bounding circle
    to_centre = segment_distance(fc.centre_x, fc.centre_y, ox, oy, ex_r, ey_r)
    c, h = np.nonzero(~hit & (to_centre - fc.radius <= fc.vertex_tol + fc.margin))
    return _near_stretch(fc, origins, directions, c, h, (np.zeros(len(c)), lengths[c]), hit.shape)


def near_after_slip(
    fc: CastFaces,
    origins: np.ndarray,
    directions: np.ndarray,
    lengths: np.ndarray,
    slip: np.ndarray,
    dist: np.ndarray,
    px: np.ndarray,
    py: np.ndarray,
) -> NearContact:
    """Where a path that may slip past its contact (`slip`, at `dist` along it, the
    point `px`, `py`) passes on within the vertex zone of a face it may meet, as in
    :func:`near_misses`, beyond the contact and leaving out the faces within the
    vertex zone of the contact (the nominal and vertex outcomes cover those)."""
    c, h = np.nonzero(slip)
    span = (dist[c, h], lengths[c])
    return _near_stretch(fc, origins, directions, c, h, span, slip.shape, (px[c, h], py[c, h]))


def _near_stretch(
    fc: CastFaces,
    origins: np.ndarray,
    directions: np.ndarray,
    c: np.ndarray,
    h: np.ndarray,
    span: tuple[np.ndarray, np.ndarray],
    shape: tuple[int, ...],
    contact: tuple[np.ndarray, np.ndarray] | None = None,
) -> NearContact:
    """For pairs (path c, hypothesis h), the stretch of each path between distances
    `span` along it within the vertex zone of a face it may meet (none within that
    zone of the `contact` point), as a point mid-way with that slack, and the cone
    of those faces' normals; a NearContact of `shape` (unset elsewhere)."""
    ox, oy, dx, dy = origins[c, 0], origins[c, 1], directions[c, 0], directions[c, 1]
    faces = (fc.sx, fc.sy, fc.ex, fc.ey, fc.nx, fc.ny)
    found = near_stretches(
        faces, fc.valid, fc.vertex_tol, fc.turn_sin, (ox, oy, dx, dy), h, span, contact
    )
    flag = found[:, 0] > 0
    s_lo, s_hi, base, t_lo, t_hi = found[:, 1:].T
    mid = (s_lo + s_hi) / 2
    values = (
        flag,
        ox + mid * dx,
        oy + mid * dy,
        base + (t_lo + t_hi) / 2,
        np.minimum((t_hi - t_lo) / 2, math.pi),
        (s_hi - s_lo) / 2,
    )
    out = [np.zeros(shape, dtype=bool), *(np.full(shape, np.nan) for _ in range(4))]
    out.append(np.zeros(shape))
    for target, value in zip(out, values, strict=True):
        target[c[flag], h[flag]] = value[flag]
    return NearContact(*out)
