"""Pairwise constraint tables and their checks (DESIGN §4.2, thesis §2.3.2, App. 1).

For contacts j, k (points p, measured unit normals u, ``r = p_k - p_j``) assigned
to faces a, b of one stable pose, with position bound ``eps_d`` and normal bound
``phi``:

- distance:  ``Dmin(a,b) - 2 eps_d <= |r| <= Dmax(a,b) + 2 eps_d``
- angle:     ``|wrap(angle(u_j -> u_k) - angle(n_a -> n_b))| <= 2 phi`` (signed: 2-D has
  no mirror images)
- direction: ``u_j·r`` within ``phi |r| + 2 eps_d`` of ``[Cmin(a,b), Cmax(a,b)]``, the range
  of ``n_a·(y - x)`` over x on face a, y on face b; and the same from k to j.

Tables are built once per stable pose; checks are table lookups vectorized over
all face pairs. Pruning is sound: with errors inside the bounds the true
assignment always passes (a tiny numeric slack guards the bounds' edges).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numba
import numpy as np

from planner.compiled import c_array
from planner.geometry import ANGLE_SLACK, LENGTH_SLACK, segment_segment_distance, wrap_angle
from planner.memo import SharedCache, array_key
from planner.types import Contact, Faces, StablePose

__all__ = [
    "ConstraintTables",
    "build_tables",
    "extend_feasibility",
    "pair_columns",
    "pair_feasibility",
    "shared_tables",
    "unary_feasibility",
]

#: Relative slack (of the object size) added to every length bound, and absolute
#: slack (radians) added to every angle bound, so the bounds' edges pass.


@dataclass(frozen=True, eq=False)
class ConstraintTables:
    """F x F tables of one stable pose, indexed [face a, face b]."""

    d_min: np.ndarray
    d_max: np.ndarray
    angle: np.ndarray  # signed angle from n_a to n_b
    c_min: np.ndarray  # min over x on a, y on b of n_a·(y - x)
    c_max: np.ndarray
    scale: float  # object size, for the numeric slack


def build_tables(faces: Faces) -> ConstraintTables:
    """Distance, angle and direction tables of a stable pose's faces.

    Dmax is reached at endpoints; Dmin is the segment-segment distance; since
    ``n_a·x = d_a`` on face a, ``n_a·(y - x)`` ranges over ``n_a·y - d_a`` at b's endpoints.
    """
    a0, a1 = faces.start[:, None, :], faces.end[:, None, :]
    b0, b1 = faces.start[None, :, :], faces.end[None, :, :]
    ends_a = np.stack(np.broadcast_arrays(a0, a1), axis=0)  # (2, F, 1, 2)
    ends_b = np.stack(np.broadcast_arrays(b0, b1), axis=0)  # (2, 1, F, 2)
    gaps = ends_a[:, None] - ends_b[None, :]  # (2, 2, F, F, 2)
    d_max = np.hypot(gaps[..., 0], gaps[..., 1]).max(axis=(0, 1))
    d_min = segment_segment_distance(a0, a1, b0, b1)
    angle = wrap_angle(faces.angle[None, :] - faces.angle[:, None])
    # n_a·(y - x) = n_a·y - d_a for y at either end of face b
    proj = np.einsum("ak,ebk->eab", faces.normal, np.stack([faces.start, faces.end]))
    proj = proj - faces.offset[None, :, None]
    scale = float(max(np.ptp(faces.start, axis=0).max(), faces.length.max()))
    return ConstraintTables(
        d_min=d_min,
        d_max=d_max,
        angle=angle,
        c_min=proj.min(axis=0),
        c_max=proj.max(axis=0),
        scale=scale,
    )


#: Table cells (faces squared, summed over the stable poses) the process keeps.
SHARED_CELLS = 500_000
_shared: SharedCache[ConstraintTables] = SharedCache(SHARED_CELLS, lambda t: t.d_min.size)


def shared_tables(faces: Faces) -> ConstraintTables:
    """:func:`build_tables` of `faces`, kept for the process: sessions on the same
    parts (a robot cell's library) build each stable pose's tables once, not at
    every session's second touch. Keyed by the faces' numbers, least recently used
    dropped past :data:`SHARED_CELLS`; the arrays are read-only."""
    key = array_key(getattr(faces, name) for name in ("start", "end", "normal", "offset"))
    return _shared.get(key, lambda: _read_only(build_tables(faces)))


def _read_only(tables: ConstraintTables) -> ConstraintTables:
    for array in (tables.d_min, tables.d_max, tables.angle, tables.c_min, tables.c_max):
        array.setflags(write=False)
    return tables


@dataclass(frozen=True)
class _Pair:
    """What the checks of two contacts read besides the tables: the distance
    ``|r|``, the measured turn from the first normal to the second, the
    projections ``u·r`` and ``v·(-r)``, and the direction checks' widening."""

    dist: float
    measured: float
    forward: float
    backward: float
    widen: float


def _pair(first: Contact, second: Contact, eps_d: float, phi: float, slack: float) -> _Pair:
    p, q = np.asarray(first.point), np.asarray(second.point)
    u, v = np.asarray(first.normal), np.asarray(second.normal)
    r = q - p
    dist = float(np.hypot(*r))
    measured = float(np.arctan2(v[1], v[0]) - np.arctan2(u[1], u[0]))
    widen = phi * dist + 2 * eps_d + slack
    return _Pair(dist, measured, float(u @ r), float(v @ -r), widen)


def pair_feasibility(
    tables: ConstraintTables, first: Contact, second: Contact, eps_d: float, phi: float
) -> np.ndarray:
    """Boolean F x F matrix: may `first` lie on face a and `second` on face b?

    >>> from planner.models.outlines import make_stable_pose
    >>> square = make_stable_pose([[0, 0], [2, 0], [2, 2], [0, 2]])
    >>> t = build_tables(square.faces)
    >>> ok = pair_feasibility(t, Contact((1, 0), (0, -1)), Contact((2, 1), (1, 0)), 0.0, 0.0)
    >>> np.argwhere(ok).tolist()  # bottom face then right face, and its rotations
    [[0, 1], [1, 2], [2, 3], [3, 0]]
    """
    slack = LENGTH_SLACK * tables.scale
    pair = _pair(first, second, eps_d, phi, slack)
    dist, widen = pair.dist, pair.widen
    # distance: Dmin - 2 eps_d <= |r| <= Dmax + 2 eps_d
    ok = (tables.d_min - 2 * eps_d - slack <= dist) & (dist <= tables.d_max + 2 * eps_d + slack)
    # angle: |wrap(angle(u -> v) - angle(n_a -> n_b))| <= 2 phi
    ok &= np.abs(wrap_angle(pair.measured - tables.angle)) <= 2 * phi + ANGLE_SLACK
    # direction j -> k: u·r within phi |r| + 2 eps_d of [Cmin(a,b), Cmax(a,b)]
    ok &= (tables.c_min - widen <= pair.forward) & (pair.forward <= tables.c_max + widen)
    # direction k -> j: v·(-r) against the tables read from b to a
    ok &= (tables.c_min.T - widen <= pair.backward) & (pair.backward <= tables.c_max.T + widen)
    return ok


def extend_feasibility(
    tables: ConstraintTables,
    rows: np.ndarray,
    contacts: list[Contact],
    unary: np.ndarray,
    eps_d: float,
    phi: float,
    columns: np.ndarray | None = None,
) -> np.ndarray:
    """(K, F) may the newest of `contacts` lie on face b, given each row's faces
    (`rows` (K, k), -1: spurious) for the k contacts before it? `unary` (F,) and
    every pair check of :func:`pair_feasibility` between each earlier contact on
    its row's face and the newest on b: the same arithmetic, in one compiled pass
    that reads only the table cells the rows name (a table per earlier contact
    was F x F numbers, most of them never read). `columns`: the contacts'
    :func:`pair_columns`, when known."""
    slack = LENGTH_SLACK * tables.scale
    dist, measured, forward, backward = pair_columns(contacts) if columns is None else columns
    widen = phi * dist + 2 * eps_d + slack
    out = np.empty((len(rows), len(unary)), dtype=bool)
    # the tables are always read-only (shared between sessions): one compiled version
    _extend(
        c_array(rows, dtype=np.int64), c_array(unary, dtype=bool),
        tables.d_min, tables.d_max, tables.angle, tables.c_min, tables.c_max,
        dist, measured, forward, backward, widen, 2 * eps_d, slack, 2 * phi + ANGLE_SLACK, out,
    )  # fmt: skip
    return out


def pair_columns(contacts: list[Contact]) -> np.ndarray:
    """(4, k) what the pair checks read of each of the k contacts before the newest
    of `contacts` and the newest (:class:`_Pair`, the same arithmetic): the
    distance, the measured turn and the two projections. The same for every
    stable pose: :func:`extend_feasibility` of each takes them."""
    *before, new = contacts
    pairs = [_pair(c, new, 0.0, 0.0, 0.0) for c in before]
    return np.array(
        [[getattr(x, f) for x in pairs] for f in ("dist", "measured", "forward", "backward")],
        dtype=float,
    ).reshape(4, len(before))


@numba.njit(cache=True, nogil=True)
def _extend(
    rows,
    unary,
    d_min,
    d_max,
    angle,
    c_min,
    c_max,
    dist,
    measured,
    forward,
    backward,
    widen,
    two_eps,
    slack,
    turn,
    out,
):  # type: ignore[no-untyped-def]
    """:func:`extend_feasibility` into `out`: each check written as the array
    expressions of :func:`pair_feasibility` evaluate it, cell by cell."""
    two_pi = 2 * math.pi
    for r in range(rows.shape[0]):
        for b in range(unary.shape[0]):
            ok = unary[b]
            j = 0
            while ok and j < rows.shape[1]:
                a = rows[r, j]
                if a >= 0:
                    d, w = dist[j], widen[j]
                    ok = d_min[a, b] - two_eps - slack <= d and d <= d_max[a, b] + two_eps + slack
                    turned = (measured[j] - angle[a, b] + math.pi) % two_pi - math.pi
                    ok = ok and abs(turned) <= turn
                    ok = ok and c_min[a, b] - w <= forward[j] and forward[j] <= c_max[a, b] + w
                    ok = ok and c_min[b, a] - w <= backward[j] and backward[j] <= c_max[b, a] + w
                j += 1
            out[r, b] = ok


def unary_feasibility(
    pose: StablePose, contact: Contact, normal_z_error: float, height: float | None = None
) -> np.ndarray:
    """Boolean (F,) mask over `pose.all_faces`: faces a single contact made at
    probing `height` may lie on by itself.

    Only the faces of the layer at that height (DESIGN §4.13), and the optional
    out-of-plane normal (thesis §6.3): a measured `normal_z` must lie within
    `normal_z_error` of the face's.
    """
    mask = pose.face_layer == pose.layer_index(height)
    normal_z = pose.all_normal_z
    if contact.normal_z is not None and normal_z is not None:
        mask &= np.abs(normal_z - contact.normal_z) <= normal_z_error + ANGLE_SLACK
    return mask
