"""Matching of hit slots pair by pair along each path, compiled (DESIGN §4.11).

:func:`planner.planning.matching.match_rows` finds which hypotheses can give the
same hit on a path. A slot's point lies at its distance `d` along the path, or
off the path by its closest approach (a near miss): either way two points are at
least as far apart as their distances along it. Sorted by `d`, each slot needs
testing only against the slots ahead of it within twice the largest reach on the
path (a window that only moves forward, so its pairs are counted in one pass):
a sweep that tests those pairs with :func:`slots_match`'s
formula and sets both owners' bits. Slots with no distance along the path are
tested against every hit. When the reaches are wide next to the spread of the
hits, the sweep tests nearly every pair; :func:`window_pairs` says how many it
would test, so the caller can take sorted interval ends instead.
"""

from __future__ import annotations

import numba
import numpy as np

from planner.compiled import c_array

__all__ = ["pair_rows", "window_pairs"]


@numba.njit(cache=True, nogil=True)
def _finite_hits(hit, d):  # type: ignore[no-untyped-def]
    """The hit items of one path with a distance along it, sorted by it, and the
    others (no distance along the path)."""
    on = np.empty(hit.shape[0], dtype=np.int64)
    off = np.empty(hit.shape[0], dtype=np.int64)
    n_on = n_off = 0
    for k in range(hit.shape[0]):
        if hit[k]:
            if np.isfinite(d[k]):
                on[n_on] = k
                n_on += 1
            else:
                off[n_off] = k
                n_off += 1
    on = on[:n_on]
    return on[np.argsort(d[on], kind="mergesort")], off[:n_off]


@numba.njit(cache=True, nogil=True)
def _largest(values, at):  # type: ignore[no-untyped-def]
    top = 0.0
    for k in at:
        top = max(top, values[k])
    return top


@numba.njit(cache=True, nogil=True)
def _window_pairs(hit, d, reach, band):  # type: ignore[no-untyped-def]
    total = 0
    for c in range(hit.shape[0]):
        on, off = _finite_hits(hit[c], d[c])
        top = _largest(reach[c], on)
        end = 0
        for a in range(len(on)):
            limit = d[c, on[a]] + 2 * top + band
            end = max(end, a + 1)
            while end < len(on) and d[c, on[end]] <= limit:
                end += 1
            total += end - a - 1
        total += len(off) * (len(on) + len(off))
    return total


def window_pairs(hit: np.ndarray, d: np.ndarray, reach: np.ndarray, band: float) -> int:
    """How many pairs of the hit items (paths, N) :func:`pair_rows` would test, at
    distances `d` along the path (non-finite: off it) and half-widths `reach`.

    >>> hit = np.ones((1, 3), dtype=bool)
    >>> window_pairs(hit, np.array([[0.0, 1.0, 5.0]]), np.full((1, 3), 0.6), 0.0)
    1
    """
    return int(
        _window_pairs(
            c_array(hit, dtype=np.bool_),
            c_array(d, dtype=np.float64),
            c_array(reach, dtype=np.float64),
            float(band),
        )
    )


@numba.njit(cache=True, nogil=True, inline="always")
def _match(f, i, j):  # type: ignore[no-untyped-def]
    """`slots_match` of two hit items, rows i and j of the fields `f` (n, 8): x,
    y, cos, sin, reach, alpha, cos alpha, sin alpha; term for term."""
    dx = f[i, 0] - f[j, 0]
    dy = f[i, 1] - f[j, 1]
    r = f[i, 4] + f[j, 4]
    cos_turn = f[i, 2] * f[j, 2] + f[i, 3] * f[j, 3]
    cos_limit = f[i, 6] * f[j, 6] - f[i, 7] * f[j, 7]
    aligned = (cos_turn >= cos_limit - 1e-12) | (f[i, 5] + f[j, 5] >= np.pi)
    return (dx * dx + dy * dy <= r * r) & aligned


@numba.njit(cache=True, nogil=True, inline="always")
def _set(rows, g, h):  # type: ignore[no-untyped-def]
    rows[g, h // 64] |= np.uint64(1) << np.uint64(h % 64)
    rows[h, g // 64] |= np.uint64(1) << np.uint64(g % 64)


@numba.njit(cache=True, nogil=True)
def _pair_rows(hit, d, x, y, cos, sin, reach, alpha, cos_a, sin_a, owner, band, rows):  # type: ignore[no-untyped-def]
    fields = (x, y, cos, sin, reach, alpha, cos_a, sin_a)
    for c in range(hit.shape[0]):
        on, off = _finite_hits(hit[c], d[c])
        n_on = len(on)
        at = np.concatenate((on, off))
        # the path's hit items, those along it sorted by distance, side by side
        f = np.empty((len(at), 8))
        for q in range(8):
            column = fields[q]
            for k in range(len(at)):
                f[k, q] = column[c, at[k]]
        dist = d[c, on]
        who = owner[at]
        top = _largest(f[:, 4], np.arange(n_on))
        out = rows[c]
        for i in range(n_on):
            _set(out, who[i], who[i])
            limit = dist[i] + 2 * top + band
            for j in range(i + 1, n_on):
                if dist[j] > limit:
                    break
                if _match(f, i, j):
                    _set(out, who[i], who[j])
        for i in range(n_on, len(at)):
            for j in range(len(at)):
                if _match(f, i, j):
                    _set(out, who[i], who[j])


def pair_rows(
    hit: np.ndarray,
    d: np.ndarray,
    fields: tuple[np.ndarray, ...],
    owner: np.ndarray,
    band: float,
    rows: np.ndarray,
) -> None:
    """Set in `rows` (paths, H, W) both ways the owners (N,) of every pair of hit
    items (paths, N) whose slots match; `fields` the slots' x, y, cos, sin, reach,
    alpha, cos alpha, sin alpha (paths, N), `band` the rounding allowed between a
    point's distance along the path and its distance `d`."""
    _pair_rows(
        c_array(hit, dtype=np.bool_),
        c_array(d, dtype=np.float64),
        *(c_array(f, dtype=np.float64) for f in fields),
        c_array(owner, dtype=np.int64),
        float(band),
        rows,
    )
