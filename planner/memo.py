"""A lock-free cached property, and values kept for the process.

``functools.cached_property`` on Python 3.11 holds one lock per property shared
by every instance, so threads computing the property on different objects (two
sessions served at once) wait for each other. This descriptor stores the value
in the instance like the 3.12 version does: two threads racing on one object may
both compute it, which is harmless for the pure computations it caches.

:class:`SharedCache` keeps what sessions on the same parts would each compute
again (a robot cell works on one library): keyed by the parts' numbers, the least
recently used dropped past a bound on the values' total size. :class:`ScopedMemo`
keeps what one plan would compute twice, for the length of that plan only.

>>> cache = SharedCache(limit=5, size=len)
>>> cache.get("ab", lambda: "xy"), cache.get("ab", lambda: "other")
('xy', 'xy')
>>> cache.get("cd", lambda: "uvw"), cache.get("ab", lambda: "again")  # 2 + 3 <= 5
('uvw', 'xy')
>>> cache.get("ef", lambda: "z"), cache.get("cd", lambda: "new")  # "cd" was the oldest
('z', 'new')
"""

from __future__ import annotations

import hashlib
import threading
from collections import OrderedDict
from collections.abc import Callable, Hashable, Iterable, Iterator
from contextlib import contextmanager
from contextvars import ContextVar
from typing import Any, Generic, TypeVar, overload

import numpy as np

__all__ = ["ScopedMemo", "SharedCache", "array_key", "cached_property"]

T = TypeVar("T")


class cached_property(Generic[T]):  # noqa: N801 - named after the functools original
    def __init__(self, func: Callable[[Any], T]) -> None:
        self.func = func
        self.attrname: str | None = None
        self.__doc__ = func.__doc__

    def __set_name__(self, owner: type, name: str) -> None:
        self.attrname = name

    @overload
    def __get__(self, instance: None, owner: type | None = None) -> cached_property[T]: ...
    @overload
    def __get__(self, instance: object, owner: type | None = None) -> T: ...
    def __get__(self, instance: object | None, owner: type | None = None) -> Any:
        if instance is None:
            return self
        value = self.func(instance)
        instance.__dict__[self.attrname] = value  # type: ignore[index]
        return value


class ScopedMemo:
    """A dict that exists within :meth:`scope` (one plan, in its own thread or
    task) and is None outside it, so that nothing it holds outlives the plan.

    >>> memo = ScopedMemo("example")
    >>> memo.get() is None
    True
    >>> with memo.scope():
    ...     memo.get()["a"] = 1
    ...     memo.get()
    {'a': 1}
    >>> memo.get() is None
    True
    """

    def __init__(self, name: str) -> None:
        self._var: ContextVar[dict | None] = ContextVar(name, default=None)

    def get(self) -> dict | None:
        return self._var.get()

    @contextmanager
    def scope(self) -> Iterator[None]:
        token = self._var.set({})
        try:
            yield
        finally:
            self._var.reset(token)


class SharedCache(Generic[T]):
    """Values kept for the process, least recently used dropped once their total
    `size` passes `limit` (the newest is kept whatever its size). Thread-safe; a
    value two threads make at once is made twice and either is kept, harmless for
    the pure computations it holds."""

    def __init__(self, limit: int, size: Callable[[T], int]) -> None:
        self.limit = limit
        self._size = size
        self._values: OrderedDict[Hashable, tuple[T, int]] = OrderedDict()
        self._total = 0
        self._lock = threading.Lock()

    def get(self, key: Hashable, make: Callable[[], T]) -> T:
        """The value kept for `key`, made by `make` (outside the lock) if none is."""
        with self._lock:
            found = self._values.get(key)
            if found is not None:
                self._values.move_to_end(key)
                return found[0]
        value = make()
        units = self._size(value)
        with self._lock:
            old = self._values.pop(key, None)
            self._total += units - (old[1] if old is not None else 0)
            self._values[key] = (value, units)
            while self._total > self.limit and len(self._values) > 1:
                _, (_, dropped) = self._values.popitem(last=False)
                self._total -= dropped
        return value

    def __len__(self) -> int:
        return len(self._values)


def array_key(arrays: Iterable[np.ndarray]) -> bytes:
    """A key for a :class:`SharedCache` naming `arrays` by their numbers (as floats,
    in order; each array's end marked, so splitting one array in two makes
    another key).

    >>> a = np.array([[0.0, 1.0], [2.0, 3.0]])
    >>> array_key([a]) == array_key([a.copy()]), array_key([a]) == array_key([a[:1], a[1:]])
    (True, False)
    """
    digest = hashlib.blake2b(digest_size=16)
    for a in arrays:
        digest.update(np.ascontiguousarray(a, dtype=float).tobytes() + b"|")
    return digest.digest()
