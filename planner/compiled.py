"""What the compiled kernels share (numba, ``cache=True``).

A kernel is built once per installation and argument types, then loaded from its
disk cache. The array types include the layout and whether the array may be
written: a read-only view (a broadcast, a slice of a frozen input) would build
and cache a second version of the kernel, and on a fresh installation that
build (a second or two) would fall inside whichever plan first met it. Every
array a kernel gets therefore goes through :func:`c_array`: C order, writable,
aligned, of the kernel's dtype (copied only when it is not so already).

>>> c_array(np.broadcast_to(np.arange(3.0), (2, 3))).flags.writeable
True
>>> a = np.zeros((2, 3))
>>> c_array(a) is a, c_array(a, float) is a, c_array(a[:, ::2]).flags.c_contiguous
(True, True, True)
>>> c_array(np.arange(3), dtype=float).dtype, c_array(a, dtype=np.float32).dtype
(dtype('float64'), dtype('float32'))
>>> segment_gap(1.0, 1.0, 0.0, 0.0, 2.0, 0.0)
(0.0, 1.0)
"""

from __future__ import annotations

import numba
import numpy as np
from numpy.typing import DTypeLike

__all__ = ["SQUARE_SCREEN", "c_array", "outward", "segment_gap"]


#: Relative margin within which a squared length does not decide a comparison that
#: the rounded length (hypot) decides: kernels compare squares first and take hypot
#: only for the near-ties, with the same answers as hypot alone.
SQUARE_SCREEN = 1e-9


def c_array(a: np.ndarray | float, dtype: DTypeLike = None) -> np.ndarray:
    """`a` as a C-ordered, writable, aligned array of `dtype` (default: its own).
    An array that is so already comes back as it is, without `np.require`'s
    checks (a kernel call passes a dozen arrays, most of them so)."""
    if type(a) is np.ndarray and (dtype is None or a.dtype == dtype):
        flags = a.flags
        if flags.c_contiguous and flags.writeable and flags.aligned:
            return a
    return np.require(a, dtype=dtype, requirements=("C", "W", "A"))


@numba.njit(cache=True, nogil=True)
def segment_gap(px, py, ax, ay, bx, by):  # type: ignore[no-untyped-def]
    """The vector from the point of segment a -> b nearest (px, py) to that point:
    the closest point is ``a + u (b - a)``, ``u = clip((p - a).(b - a) / |b - a|^2, 0,
    1)``, the arithmetic of :func:`planner.planning.cast_faces.segment_distance`."""
    ex, ey = bx - ax, by - ay
    sq = max(ex * ex + ey * ey, 1e-300)
    u = ((px - ax) * ex + (py - ay) * ey) / sq
    u = min(max(u, 0.0), 1.0)
    return px - (ax + u * ex), py - (ay + u * ey)


@numba.njit(cache=True, nogil=True)
def outward(start, k, n):  # type: ignore[no-untyped-def]
    """The k-th of n indices taken outward from `start` both ways round: start,
    start + 1, start - 1, start + 2, ... (mod n); k = 0 .. n - 1 gives each once.
    Scans that start at the face where the last point stopped find a near face
    first."""
    step = (k + 1) // 2
    return (start + (step if k % 2 == 1 else -step) + n) % n
