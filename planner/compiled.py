"""How the compiled kernels are called (numba, ``cache=True``).

A kernel is built once per installation and argument types, then loaded from its
disk cache. The array types include the layout and whether the array may be
written: a read-only view (a broadcast, a slice of a frozen input) would build
and cache a second version of the kernel, and on a fresh installation that
build (a second or two) would fall inside whichever plan first met it. Every
array a kernel gets therefore goes through :func:`c_array`: C order, writable,
aligned, of the kernel's dtype (copied only when it is not so already).

>>> c_array(np.broadcast_to(np.arange(3.0), (2, 3))).flags.writeable
True
"""

from __future__ import annotations

import numpy as np
from numpy.typing import DTypeLike

__all__ = ["c_array"]


def c_array(a: np.ndarray | float, dtype: DTypeLike = None) -> np.ndarray:
    """`a` as a C-ordered, writable, aligned array of `dtype` (default: its own)."""
    return np.require(a, dtype=dtype, requirements=("C", "W", "A"))
