"""Sensing paths cast against every posed hypothesis in one numpy pass (DESIGN §4.11).

The first hit (point, face normal) or a miss of each path on each hypothesis of a
:class:`~planner.planning.posed_set.PosedSet`, and what else the outcome may turn
out to be: a hit near a vertex, a grazing hit, a near miss, a shallow hit, a
close pass, a thin stretch. World frame, lengths in the object files' unit.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from planner.geometry import LENGTH_SLACK, wrap_angle
from planner.planning.posed_set import PosedSet

__all__ = ["cast_paths", "segment_distance"]


def segment_distance(
    px: np.ndarray, py: np.ndarray, ax: np.ndarray, ay: np.ndarray, bx: np.ndarray, by: np.ndarray
) -> np.ndarray:
    """Distance from points p to segments [a, b], x and y given apart (broadcast);
    the same arithmetic as :func:`planner.geometry.point_segment_distance`."""
    ex, ey = bx - ax, by - ay
    sq = np.maximum(ex * ex + ey * ey, 1e-300)
    # closest point a + u (b - a), u = clip((p - a).(b - a) / |b - a|^2, 0, 1)
    u = np.clip(((px - ax) * ex + (py - ay) * ey) / sq, 0.0, 1.0)
    return np.hypot(px - (ax + u * ex), py - (ay + u * ey))


def cast_paths(
    posed: PosedSet,
    origins: np.ndarray,
    directions: np.ndarray,
    lengths: np.ndarray,
    tolerances: tuple[np.ndarray, np.ndarray, np.ndarray],
    chunk_elements: int = 1_000_000,
) -> dict[str, np.ndarray]:
    """Cast C paths (world frame: origins (C, 2), unit directions (C, 2), lengths
    (C,)) against every posed hypothesis, chunked over the paths: the fields of
    :class:`planner.planning.outcomes.Outcomes`. `tolerances` (each (H,)) are how far the
    true outline may lie from the posed one, the vertex zone, and the sine of the
    grazing angle."""
    n_paths, (n_hyp, n_faces) = len(origins), posed.valid.shape
    faces = _Faces.of(posed, tolerances)
    chunk = max(1, chunk_elements // max(1, n_hyp * n_faces))
    bounds = [(i, i + chunk) for i in range(0, n_paths, chunk)] or [(0, 0)]
    parts = [_outcome_chunk(faces, origins[a:b], directions[a:b], lengths[a:b]) for a, b in bounds]
    return {k: np.concatenate([part[k] for part in parts]) for k in parts[0]}


@dataclass(frozen=True, eq=False)
class _Faces:
    """Posed faces as separate x and y arrays (H, F), the tolerances (H,) and each
    outline's bounding circle (`centre_x`, `centre_y`, `radius`, (H,))."""

    sx: np.ndarray
    sy: np.ndarray
    ex: np.ndarray
    ey: np.ndarray
    nx: np.ndarray
    ny: np.ndarray
    length: np.ndarray
    prev: np.ndarray
    next: np.ndarray
    valid: np.ndarray
    geometric: np.ndarray
    vertex_tol: np.ndarray
    graze_sin: np.ndarray
    centre_x: np.ndarray
    centre_y: np.ndarray
    radius: np.ndarray
    margin: float

    @classmethod
    def of(cls, posed: PosedSet, tol: tuple[np.ndarray, np.ndarray, np.ndarray]) -> _Faces:
        count = np.maximum(posed.valid.sum(axis=1), 1)
        centre = np.where(posed.valid[..., None], posed.start, 0.0).sum(axis=1) / count[:, None]
        # every point of a face lies within the largest vertex distance of the centre
        reach = np.hypot(*np.moveaxis(posed.start - centre[:, None, :], -1, 0))
        radius = np.where(posed.valid, reach, 0.0).max(axis=1)
        return cls(
            sx=np.ascontiguousarray(posed.start[..., 0]),
            sy=np.ascontiguousarray(posed.start[..., 1]),
            ex=np.ascontiguousarray(posed.end[..., 0]),
            ey=np.ascontiguousarray(posed.end[..., 1]),
            nx=np.ascontiguousarray(posed.normal[..., 0]),
            ny=np.ascontiguousarray(posed.normal[..., 1]),
            length=posed.length,
            prev=posed.prev,
            next=posed.next,
            valid=posed.valid,
            geometric=tol[0],
            vertex_tol=tol[1],
            graze_sin=tol[2],
            centre_x=centre[:, 0],
            centre_y=centre[:, 1],
            radius=radius,
            margin=LENGTH_SLACK * posed.scale,
        )


def _angle_cone(
    ax: np.ndarray, ay: np.ndarray, bx: np.ndarray, by: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Centre angle and half-width (radians) of the shorter arc between unit normals a, b."""
    ang_a = np.arctan2(ay, ax)
    diff = wrap_angle(np.arctan2(by, bx) - ang_a)
    return wrap_angle(ang_a + diff / 2), np.abs(diff) / 2


def _outcome_chunk(
    fc: _Faces, origins: np.ndarray, directions: np.ndarray, lengths: np.ndarray
) -> dict[str, np.ndarray]:
    n_hyp = len(fc.valid)
    ox, oy = origins[:, 0, None, None], origins[:, 1, None, None]
    dx, dy = directions[:, 0, None, None], directions[:, 1, None, None]
    length = lengths[:, None]
    edge_x, edge_y = fc.ex - fc.sx, fc.ey - fc.sy
    # o + t d meets s + u (e - s) at t = (w x e)/(d x e), u = (w x d)/(d x e), with w = s - o
    denom = dx * edge_y - dy * edge_x
    wx, wy = fc.sx - ox, fc.sy - oy
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        t = (wx * edge_y - wy * edge_x) / denom
        u = (wx * dy - wy * dx) / denom
    meets = fc.valid & (np.abs(denom) > 1e-12 * fc.length)
    meets &= (t >= 0) & (t <= length[..., None]) & (u >= 0) & (u <= 1)
    t = np.where(meets, t, np.inf)
    face = np.argmin(t, axis=-1)
    dist = np.take_along_axis(t, face[..., None], axis=-1)[..., 0]
    hit = np.isfinite(dist)
    face = np.where(hit, face, -1)
    f = np.maximum(face, 0)
    rows = np.broadcast_to(np.arange(n_hyp), f.shape)
    dx, dy = dx[..., 0], dy[..., 0]
    reached = np.where(hit, dist, 0.0)
    px, py = origins[:, 0, None] + reached * dx, origins[:, 1, None] + reached * dy
    nx, ny = fc.nx[rows, f], fc.ny[rows, f]
    cos_in = np.abs(dx * nx + dy * ny)
    geometric, vertex_tol, graze_sin = fc.geometric, fc.vertex_tol, fc.graze_sin

    # vertex: the contact lies within the vertex zone of one end of the face hit
    u_hit = np.clip(np.take_along_axis(u, f[..., None], axis=-1)[..., 0], 0.0, 1.0)
    face_len = fc.length[rows, f]
    to_start, to_end = u_hit * face_len, (1 - u_hit) * face_len
    vertex = hit & (np.minimum(to_start, to_end) <= vertex_tol)
    adjacent = np.where(to_start <= to_end, fc.prev[rows, f], fc.next[rows, f])
    adj_x, adj_y = fc.nx[rows, adjacent], fc.ny[rows, adjacent]
    grazing = hit & (cos_in < graze_sin)
    # a face displaced by delta moves the contact along the path by delta / |cos|
    along = geometric / np.maximum(cos_in, graze_sin)
    end_of_path = hit & (dist > length - along)
    facing_away = dx * adj_x + dy * adj_y > -graze_sin
    shallow = _shallow(fc, t, dist, hit, f, rows, dx, dy, cos_in, length)
    stretch = _stretch(fc, origins, t, dist, hit, vertex, face_len, rows, dx, dy)
    # a contact may come anywhere along a long shallow stretch, on any face near it
    long_stretch = stretch > 2 * along
    slip = (vertex & facing_away) | grazing | end_of_path | shallow
    slip_hit, slip_dist, slip_angle = _slip(fc, t, slip, end_of_path, px, py, dx, dy)
    near_miss, near_x, near_y, m_centre, m_spread = _near_miss(
        fc, origins, directions, lengths, hit
    )

    close_pass, pass_x, pass_y, p_centre, p_spread = _close_pass(fc, origins, hit, rows, px, py)
    # a vertex hit keeps slot 1 for its own vertex: its close pass goes to a free slot 2
    in_slot1 = close_pass & ~vertex
    in_slot2 = close_pass & vertex & ~slip
    near_miss_or_pass = near_miss | in_slot1
    near_x, near_y = np.where(in_slot1, pass_x, near_x), np.where(in_slot1, pass_y, near_y)
    m_centre = np.where(in_slot1, p_centre, m_centre)
    m_spread = np.where(in_slot1, p_spread, m_spread)

    # a near miss's (or close pass's) closest approach: how far along the path, how far off
    rel_x, rel_y = near_x - origins[:, 0, None], near_y - origins[:, 1, None]
    along_near, off_near = rel_x * dx + rel_y * dy, dx * rel_y - dy * rel_x
    pass_rx, pass_ry = pass_x - origins[:, 0, None], pass_y - origins[:, 1, None]
    along_pass, off_pass = pass_rx * dx + pass_ry * dy, dx * pass_ry - dy * pass_rx

    # outcome slots
    nan = np.full(hit.shape, np.nan)
    angle0 = np.arctan2(ny, nx)
    # the cone between the faces meeting at the vertex, for vertex hits only
    v_centre, v_spread = np.zeros(hit.shape), np.zeros(hit.shape)
    at = np.nonzero(vertex)
    v_centre[at], v_spread[at] = _angle_cone(nx[at], ny[at], adj_x[at], adj_y[at])
    zero = np.zeros_like(angle0)
    slack = np.where(hit, along - geometric, 0.0)
    hit_x, hit_y = np.where(hit, px, nan), np.where(hit, py, nan)
    # slot 0 spans the stretch past the hit; a close pass with no slot left to hold
    # it (a vertex hit that may slip) stretches slot 0 back to the pass instead
    crowded = close_pass & vertex & slip
    lo = np.where(crowded, np.minimum(np.nan_to_num(along_pass), reached), reached)
    hi = reached + np.where(long_stretch, stretch, 0.0)
    mid, half = (lo + hi) / 2 - reached, (hi - lo) / 2
    nominal_x, nominal_y = hit_x + mid * dx, hit_y + mid * dy
    nominal_slack = slack + half
    nominal_spread = np.where(long_stretch | crowded, math.pi, 0.0)
    slip_x = np.where(slip_hit, origins[:, 0, None] + slip_dist * dx, nan)
    slip_y = np.where(slip_hit, origins[:, 1, None] + slip_dist * dy, nan)
    slip_x, slip_y = np.where(in_slot2, pass_x, slip_x), np.where(in_slot2, pass_y, slip_y)
    slot_x = np.stack([nominal_x, np.where(vertex, px, near_x), slip_x], axis=-1)
    slot_y = np.stack([nominal_y, np.where(vertex, py, near_y), slip_y], axis=-1)
    slot2 = slip | in_slot2
    return {
        "hit": hit,
        "distance": dist,
        "point": np.stack([hit_x, hit_y], axis=-1),
        "normal": np.stack([np.where(hit, nx, nan), np.where(hit, ny, nan)], axis=-1),
        "face": face,
        "travel": np.where(hit, dist, length),
        "vertex": vertex,
        "grazing": grazing,
        "near_miss": near_miss,
        "end_of_path": end_of_path,
        "shallow": shallow,
        "close_pass": close_pass,
        "stretch": long_stretch,
        "slot_valid": np.stack([np.ones_like(hit), vertex | near_miss_or_pass, slot2], axis=-1),
        "slot_hit": np.stack([hit, vertex | near_miss_or_pass, slip_hit | in_slot2], axis=-1),
        "slot_point": np.stack([slot_x, slot_y], axis=-1),
        "slot_angle": np.stack(
            [
                angle0,
                np.where(vertex, v_centre, m_centre),
                np.where(in_slot2, p_centre, np.where(slip, slip_angle, 0.0)),
            ],
            axis=-1,
        ),
        "slot_spread": np.stack(
            [
                nominal_spread,
                np.where(vertex, v_spread, m_spread),
                np.where(in_slot2, p_spread, zero),
            ],
            axis=-1,
        ),
        "slot_slack": np.stack([nominal_slack, np.where(vertex, slack, 0.0), zero], axis=-1),
        "slot_distance": np.stack(
            [
                np.where(hit, dist + mid, nan),
                np.where(vertex, dist, along_near),
                np.where(in_slot2, along_pass, np.where(slip_hit, slip_dist, nan)),
            ],
            axis=-1,
        ),
        "slot_offset": np.stack(
            [zero, np.where(vertex, 0.0, off_near), np.where(in_slot2, off_pass, zero)],
            axis=-1,
        ),
        "heading": np.arctan2(directions[:, 1], directions[:, 0]),
    }


def _shallow(
    fc: _Faces,
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


def _stretch(
    fc: _Faces,
    origins: np.ndarray,
    t: np.ndarray,
    dist: np.ndarray,
    hit: np.ndarray,
    vertex: np.ndarray,
    face_len: np.ndarray,
    rows: np.ndarray,
    dx: np.ndarray,
    dy: np.ndarray,
) -> np.ndarray:
    """(c, H): how far past the hit the path stays within `geometric` of the
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
    c, h = np.nonzero(hit & (vertex | (face_len < 4 * fc.vertex_tol[rows])))
    if not len(c):
        return out
    step = fc.vertex_tol[h] / 2
    later = np.where(t[c, h] > (dist[c, h] + fc.margin)[:, None], t[c, h], np.inf)
    t_exit = later.min(axis=-1)
    k = np.arange(1, _STRETCH_SAMPLES + 1)
    s = dist[c, h, None] + k * step[:, None]  # (n, M)
    qx = origins[c, 0, None] + s * dx[c, 0, None]
    qy = origins[c, 1, None] + s * dy[c, 0, None]
    depth = segment_distance(
        qx[..., None], qy[..., None], fc.sx[h, None], fc.sy[h, None], fc.ex[h, None], fc.ey[h, None]
    )
    depth = np.where(fc.valid[h, None], depth, np.inf).min(axis=-1)  # (n, M)
    deep = (depth >= fc.geometric[h, None]) | (s >= t_exit[:, None])
    first = np.where(deep.any(axis=1), np.argmax(deep, axis=1) + 1, _STRETCH_SAMPLES)
    out[c, h] = np.minimum(first * step, t_exit - dist[c, h])
    return out


def _close_pass(
    fc: _Faces,
    origins: np.ndarray,
    hit: np.ndarray,
    rows: np.ndarray,
    px: np.ndarray,
    py: np.ndarray,
) -> tuple[np.ndarray, ...]:
    """Hits whose path passes within the vertex zone (`geometric` plus the
    position error: what the recognition allows a contact) of a vertex before
    reaching the contact (any vertex outside the contact's own vertex zone, the
    hit face's ends included): the true outline may be met there first. Returns
    (flag, the vertex's x and y, centre and half-width of the normals there), each
    (c, H)."""
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
    centre[at], spread[at] = _angle_cone(
        fc.nx[rows, before][at], fc.ny[rows, before][at], fc.nx[rows, k][at], fc.ny[rows, k][at]
    )
    nan = np.full(hit.shape, np.nan)
    return flag, np.where(flag, vx, nan), np.where(flag, vy, nan), centre, spread


def _slip(
    fc: _Faces,
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


def _near_miss(
    fc: _Faces, origins: np.ndarray, directions: np.ndarray, lengths: np.ndarray, hit: np.ndarray
) -> tuple[np.ndarray, ...]:
    """Misses passing within `geometric` of an outline: (flag, closest outline point x
    and y, centre and half-width of the normals there), each (c, H)."""
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
    centre, spread = _angle_cone(fc.nx[h, nf], fc.ny[h, nf], fc.nx[h, other], fc.ny[h, other])
    out = [np.zeros(hit.shape, dtype=bool), *(np.full(hit.shape, np.nan) for _ in range(4))]
    for target, value in zip(out, (close, px, py, centre, spread), strict=True):
        target[c, h] = value
    return tuple(out)
