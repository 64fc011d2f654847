"""Sensing paths cast against every posed hypothesis in one numpy pass (DESIGN §4.11).

The first hit (point, face normal) or a miss of each path on each hypothesis of a
:class:`~planner.planning.posed_set.PosedSet`, and what else the outcome may turn
out to be: a hit near a vertex, a grazing hit, a near miss, a shallow hit, a
close pass, a thin stretch (those found by :mod:`planner.planning.uncertain_hits`).
Each path's outcome on each hypothesis fills three slots: the nominal hit or
miss, the vertex or near contact, and the hit after a slip. World frame,
lengths in the object files' unit, angles in radians.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from planner.planning.cast_faces import CastFaces, angle_cone
from planner.planning.near_kernel import crossings
from planner.planning.posed_set import PosedSet
from planner.planning.uncertain_hits import (
    NearContact,
    Stretch,
    close_passes,
    exits,
    near_after_slip,
    near_misses,
    shallow_hits,
    slip_past,
    stretch_past_hits,
)

__all__ = ["cast_paths"]


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
    faces = CastFaces.of(posed, tolerances)
    chunk = max(1, chunk_elements // max(1, n_hyp * n_faces))
    bounds = [(i, i + chunk) for i in range(0, n_paths, chunk)] or [(0, 0)]
    parts = [_outcome_chunk(faces, origins[a:b], directions[a:b], lengths[a:b]) for a, b in bounds]
    return {k: np.concatenate([part[k] for part in parts]) for k in parts[0]}


@dataclass(frozen=True, eq=False)
class _Hits:
    """The first hit of each of c paths on each of H hypotheses.

    `t`, `u` (c, H, F): where the path line meets each face line, as a distance
    along the path (inf where the path misses the face) and a fraction of the
    face; `length` (c, 1) the paths' lengths; `dist` (c, H) the distance to the
    first hit (inf for a miss), `hit` its flag, `face` the face hit (-1 for a
    miss) and `f` that face clipped to 0; `rows` (c, H) the hypothesis index of
    each entry; `dx`, `dy` (c, 1) the unit directions; `reached` (c, H) how far
    each path got (0 for a miss) and `px`, `py` the point there; `hit_x`, `hit_y`
    the contact (NaN for a miss); `nx`, `ny` the outward normal of face `f`;
    `cos_in` |cos| of the angle between the path and that normal.
    """

    t: np.ndarray
    u: np.ndarray
    length: np.ndarray
    dist: np.ndarray
    hit: np.ndarray
    face: np.ndarray
    f: np.ndarray
    rows: np.ndarray
    dx: np.ndarray
    dy: np.ndarray
    reached: np.ndarray
    px: np.ndarray
    py: np.ndarray
    hit_x: np.ndarray
    hit_y: np.ndarray
    nx: np.ndarray
    ny: np.ndarray
    cos_in: np.ndarray


@dataclass(frozen=True, eq=False)
class _Doubts:
    """What may make the outcome other than the nominal first hit, each (c, H).

    `vertex`: the contact lies in a vertex zone, `adj_x`, `adj_y` the normal of
    the face adjacent at the nearer end; `grazing`, `end_of_path` (the hit may
    lie past the path's end), `shallow` (the path cuts the outline no deeper than
    `geometric`); `stretch` how far past the hit a contact may still come and on
    which other faces (:class:`~planner.planning.uncertain_hits.Stretch`);
    `slack` how far along the path a face displaced by `geometric` moves the
    contact, beyond `geometric` itself; `slip` whether the path may slip past
    the contact, and if it hits again further on (`slip_hit`) how far along
    (`slip_dist`) at what normal angle (`slip_angle`); `near_miss` and
    `close_pass` where a miss passes near an outline and a hit passes near a
    vertex before its contact; `after_slip` where a path that slips past its
    contact passes near a face further on.
    """

    vertex: np.ndarray
    adj_x: np.ndarray
    adj_y: np.ndarray
    grazing: np.ndarray
    end_of_path: np.ndarray
    shallow: np.ndarray
    stretch: Stretch
    slack: np.ndarray
    slip: np.ndarray
    slip_hit: np.ndarray
    slip_dist: np.ndarray
    slip_angle: np.ndarray
    near_miss: NearContact
    close_pass: NearContact
    after_slip: NearContact


@dataclass(frozen=True, eq=False)
class _Slot:
    """One outcome slot (c, H): whether it is `valid`, whether it is a `hit`, the
    contact point (`x`, `y`), the normal's `angle` and `spread` (radians), the
    `slack` along the path, the `distance` along the path and the signed
    `offset` from it (positive to its left)."""

    valid: np.ndarray
    hit: np.ndarray
    x: np.ndarray
    y: np.ndarray
    angle: np.ndarray
    spread: np.ndarray
    slack: np.ndarray
    distance: np.ndarray
    offset: np.ndarray


def _outcome_chunk(
    fc: CastFaces, origins: np.ndarray, directions: np.ndarray, lengths: np.ndarray
) -> dict[str, np.ndarray]:
    """The outcomes of c paths (world frame: origins (c, 2), unit directions
    (c, 2), lengths (c,)) on every hypothesis: the fields of
    :class:`planner.planning.outcomes.Outcomes`. Slot 0 is the nominal hit (or
    the miss), slot 1 the vertex a vertex hit may have touched or where a near
    miss or close pass may meet the outline, slot 2 where a slipping path hits
    next, or a close pass that found slot 1 taken, slot 3 where a slipping path
    passes near a face further on."""
    hits = _first_hits(fc, origins, directions, lengths)
    doubt = _doubts(fc, origins, directions, lengths, hits)
    close = doubt.close_pass
    # a vertex hit keeps slot 1 for its own vertex: its close pass goes to a free slot 2
    in_slot1 = close.flag & ~doubt.vertex
    in_slot2 = close.flag & doubt.vertex & ~doubt.slip
    near = NearContact(
        doubt.near_miss.flag | in_slot1,
        np.where(in_slot1, close.x, doubt.near_miss.x),
        np.where(in_slot1, close.y, doubt.near_miss.y),
        np.where(in_slot1, close.centre, doubt.near_miss.centre),
        np.where(in_slot1, close.spread, doubt.near_miss.spread),
        np.where(in_slot1, close.slack, doubt.near_miss.slack),
    )
    along_pass, off_pass = _along_and_off(origins, hits, close.x, close.y)
    slots = (
        _nominal_slot(hits, doubt, along_pass),
        _vertex_or_near_slot(origins, hits, doubt, near),
        _slip_or_pass_slot(origins, hits, doubt, in_slot2, along_pass, off_pass),
        _after_slip_slot(origins, hits, doubt.after_slip),
    )
    hit, nan = hits.hit, np.full(hits.hit.shape, np.nan)
    return {
        "hit": hit,
        "distance": hits.dist,
        "point": np.stack([hits.hit_x, hits.hit_y], axis=-1),
        "normal": np.stack([np.where(hit, hits.nx, nan), np.where(hit, hits.ny, nan)], axis=-1),
        "face": hits.face,
        "travel": np.where(hit, hits.dist, hits.length),
        "vertex": doubt.vertex,
        "grazing": doubt.grazing,
        "near_miss": doubt.near_miss.flag,
        "end_of_path": doubt.end_of_path,
        "shallow": doubt.shallow,
        "close_pass": close.flag,
        "stretch": doubt.stretch.other_faces,
        "open_stretch": doubt.stretch.open,
        **_stacked(slots),
        "heading": np.arctan2(directions[:, 1], directions[:, 0]),
    }


def _first_hits(
    fc: CastFaces, origins: np.ndarray, directions: np.ndarray, lengths: np.ndarray
) -> _Hits:
    """The first face each path (c) meets on each hypothesis, if any."""
    n_hyp = len(fc.valid)
    length = lengths[:, None]
    # o + t d meets s + u (e - s) at t = (w x e)/(d x e), u = (w x d)/(d x e), with w = s - o
    faces = (fc.sx, fc.sy, fc.ex, fc.ey)
    t, u = crossings(origins, directions, lengths, faces, fc.length, fc.valid)
    face = np.argmin(t, axis=-1)
    dist = np.take_along_axis(t, face[..., None], axis=-1)[..., 0]
    hit = np.isfinite(dist)
    face = np.where(hit, face, -1)
    f = np.maximum(face, 0)
    rows = np.broadcast_to(np.arange(n_hyp), f.shape)
    dx, dy = directions[:, 0, None], directions[:, 1, None]
    reached = np.where(hit, dist, 0.0)
    px, py = origins[:, 0, None] + reached * dx, origins[:, 1, None] + reached * dy
    nx, ny = fc.nx[rows, f], fc.ny[rows, f]
    nan = np.full(hit.shape, np.nan)
    return _Hits(
        t=t,
        u=u,
        length=length,
        dist=dist,
        hit=hit,
        face=face,
        f=f,
        rows=rows,
        dx=dx,
        dy=dy,
        reached=reached,
        px=px,
        py=py,
        hit_x=np.where(hit, px, nan),
        hit_y=np.where(hit, py, nan),
        nx=nx,
        ny=ny,
        cos_in=np.abs(dx * nx + dy * ny),
    )


def _doubts(
    fc: CastFaces, origins: np.ndarray, directions: np.ndarray, lengths: np.ndarray, hits: _Hits
) -> _Doubts:
    """What else each first hit (or miss) may turn out to be."""
    t, dist, hit, f, rows = hits.t, hits.dist, hits.hit, hits.f, hits.rows
    dx, dy, cos_in, length = hits.dx, hits.dy, hits.cos_in, hits.length
    geometric, vertex_tol, graze_sin = fc.geometric, fc.vertex_tol, fc.graze_sin
    # vertex: the contact lies within the vertex zone of one end of the face hit
    u_hit = np.clip(np.take_along_axis(hits.u, f[..., None], axis=-1)[..., 0], 0.0, 1.0)
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
    t_exit, exit_face = exits(fc, t, dist)
    shallow = shallow_hits(fc, t_exit, exit_face, dist, hit, rows, dx, dy, cos_in, length)
    stretch = stretch_past_hits(fc, origins, t_exit, dist, hit, f, dx, dy, length)
    slip = (vertex & facing_away) | grazing | end_of_path | shallow
    slip_hit, slip_dist, slip_angle = slip_past(fc, t, slip, end_of_path, hits.px, hits.py, dx, dy)
    return _Doubts(
        vertex=vertex,
        adj_x=adj_x,
        adj_y=adj_y,
        grazing=grazing,
        end_of_path=end_of_path,
        shallow=shallow,
        stretch=stretch,
        slack=np.where(hit, along - geometric, 0.0),
        slip=slip,
        slip_hit=slip_hit,
        slip_dist=slip_dist,
        slip_angle=slip_angle,
        near_miss=near_misses(fc, origins, directions, lengths, hit),
        close_pass=close_passes(fc, origins, hit, rows, hits.px, hits.py),
        after_slip=near_after_slip(fc, origins, directions, lengths, slip, dist, hits.px, hits.py),
    )


def _along_and_off(
    origins: np.ndarray, hits: _Hits, x: np.ndarray, y: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """How far along each path the points (x, y) (c, H) lie, and how far to its left."""
    rel_x, rel_y = x - origins[:, 0, None], y - origins[:, 1, None]
    return rel_x * hits.dx + rel_y * hits.dy, hits.dx * rel_y - hits.dy * rel_x


def _nominal_slot(hits: _Hits, doubt: _Doubts, along_pass: np.ndarray) -> _Slot:
    """Slot 0: the first hit (or the miss), spread over what it may turn out to be."""
    hit, reached = hits.hit, hits.reached
    nan = np.full(hit.shape, np.nan)
    stretch = doubt.stretch
    # past the hit a contact may still come on other faces near the path: slot 0
    # spans that stretch and every normal there; a stretch still open at its last
    # point may meet anything
    other = stretch.other_faces
    angle0 = np.arctan2(hits.ny, hits.nx) + np.where(other, (stretch.lo + stretch.hi) / 2, 0.0)
    # a close pass with no slot left to hold it (a vertex hit that may slip)
    # stretches slot 0 back to the pass instead
    crowded = doubt.close_pass.flag & doubt.vertex & doubt.slip
    lo = np.where(crowded, np.minimum(np.nan_to_num(along_pass), reached), reached)
    hi = reached + np.where(other, stretch.length, 0.0)
    mid, half = (lo + hi) / 2 - reached, (hi - lo) / 2
    spread = np.where(other, np.minimum((stretch.hi - stretch.lo) / 2, math.pi), 0.0)
    return _Slot(
        valid=np.ones_like(hit),
        hit=hit,
        x=hits.hit_x + mid * hits.dx,
        y=hits.hit_y + mid * hits.dy,
        angle=angle0,
        spread=np.where(stretch.open | crowded, math.pi, spread),
        slack=doubt.slack + half,
        distance=np.where(hit, hits.dist + mid, nan),
        offset=np.zeros_like(angle0),
    )


def _vertex_or_near_slot(
    origins: np.ndarray, hits: _Hits, doubt: _Doubts, near: NearContact
) -> _Slot:
    """Slot 1: the vertex a vertex hit lies at, else where a near miss (or a
    close pass) may meet the outline."""
    vertex, nx, ny = doubt.vertex, hits.nx, hits.ny
    # the cone between the faces meeting at the vertex, for vertex hits only
    v_centre, v_spread = np.zeros(hits.hit.shape), np.zeros(hits.hit.shape)
    at = np.nonzero(vertex)
    v_centre[at], v_spread[at] = angle_cone(nx[at], ny[at], doubt.adj_x[at], doubt.adj_y[at])
    # a near miss's (or close pass's) closest approach: how far along the path, how far off
    along_near, off_near = _along_and_off(origins, hits, near.x, near.y)
    return _Slot(
        valid=vertex | near.flag,
        hit=vertex | near.flag,
        x=np.where(vertex, hits.px, near.x),
        y=np.where(vertex, hits.py, near.y),
        angle=np.where(vertex, v_centre, near.centre),
        spread=np.where(vertex, v_spread, near.spread),
        slack=np.where(vertex, doubt.slack, near.slack),
        distance=np.where(vertex, hits.dist, along_near),
        offset=np.where(vertex, 0.0, off_near),
    )


def _slip_or_pass_slot(
    origins: np.ndarray,
    hits: _Hits,
    doubt: _Doubts,
    in_slot2: np.ndarray,
    along_pass: np.ndarray,
    off_pass: np.ndarray,
) -> _Slot:
    """Slot 2: where a path that may slip past its contact hits next, or the close
    pass of a vertex hit that cannot slip (`in_slot2`)."""
    close, slip_hit, slip_dist = doubt.close_pass, doubt.slip_hit, doubt.slip_dist
    nan = np.full(hits.hit.shape, np.nan)
    zero = np.zeros(hits.hit.shape)
    slip_x = np.where(slip_hit, origins[:, 0, None] + slip_dist * hits.dx, nan)
    slip_y = np.where(slip_hit, origins[:, 1, None] + slip_dist * hits.dy, nan)
    return _Slot(
        valid=doubt.slip | in_slot2,
        hit=slip_hit | in_slot2,
        x=np.where(in_slot2, close.x, slip_x),
        y=np.where(in_slot2, close.y, slip_y),
        angle=np.where(in_slot2, close.centre, np.where(doubt.slip, doubt.slip_angle, 0.0)),
        spread=np.where(in_slot2, close.spread, zero),
        slack=zero,
        distance=np.where(in_slot2, along_pass, np.where(slip_hit, slip_dist, nan)),
        offset=np.where(in_slot2, off_pass, zero),
    )


def _after_slip_slot(origins: np.ndarray, hits: _Hits, near: NearContact) -> _Slot:
    """Slot 3: where a path that may slip past its contact passes near a face
    further on (a stretch of the path, with the cone of those faces' normals)."""
    along, off = _along_and_off(origins, hits, near.x, near.y)
    return _Slot(
        valid=near.flag,
        hit=near.flag,
        x=near.x,
        y=near.y,
        angle=np.where(near.flag, near.centre, 0.0),
        spread=np.where(near.flag, near.spread, 0.0),
        slack=near.slack,
        distance=np.where(near.flag, along, np.nan),
        offset=np.where(near.flag, off, 0.0),
    )


def _stacked(slots: tuple[_Slot, ...]) -> dict[str, np.ndarray]:
    """The slots side by side: each field (c, H, slots), `slot_point` (c, H, slots, 2)."""

    def stack(name: str) -> np.ndarray:
        return np.stack([getattr(slot, name) for slot in slots], axis=-1)

    return {
        "slot_valid": stack("valid"),
        "slot_hit": stack("hit"),
        "slot_point": np.stack([stack("x"), stack("y")], axis=-1),
        "slot_angle": stack("angle"),
        "slot_spread": stack("spread"),
        "slot_slack": stack("slack"),
        "slot_distance": stack("distance"),
        "slot_offset": stack("offset"),
    }
