"""A deadline that stops a CPU job running in a worker thread.

The planner's plans stop themselves (their work budget and wall-clock cap), and
every input is bounded before work starts; this is the net under both: a job
still running at its deadline gets :class:`JobStoppedError` raised inside its thread
(``PyThreadState_SetAsyncExc``), so the thread unwinds, its ``finally`` blocks
and ``with`` blocks run, and the worker is free again. Python raises it at the
job's next bytecode, so a single numpy call in progress finishes first (each one
is bounded by the input limits).

A job stopped is answered 503 with Retry-After naming ``cpu_job_deadline_s``: a
slow job is most often one that shared the machine with others.
"""

from __future__ import annotations

import ctypes
import heapq
import itertools
import threading
import time
from collections.abc import Callable
from typing import Any, TypeVar

import anyio
import anyio.to_thread

from app.errors import UnavailableError

__all__ = ["JobStoppedError", "run_stopped_at", "with_deadline"]

_T = TypeVar("_T")
_set_async_exc = ctypes.pythonapi.PyThreadState_SetAsyncExc
_set_async_exc.argtypes = (ctypes.c_ulong, ctypes.py_object)


class JobStoppedError(Exception):
    """Raised in a worker thread whose job passed its deadline."""


class _Job:
    """One run of a job: whether it has ended, whether the deadline fired."""

    def __init__(self, thread_id: int) -> None:
        self.thread_id = thread_id
        self.lock = threading.Lock()
        self.done = False
        self.fired = False

    def fire(self) -> None:
        with self.lock:
            if not self.done:
                self.fired = True
                _set_async_exc(self.thread_id, ctypes.py_object(JobStoppedError))

    def end(self) -> None:
        with self.lock:
            self.done = True
            if self.fired:  # raised already or still pending: clear what is pending
                _set_async_exc(self.thread_id, ctypes.py_object())


class _Watchdog:
    """One thread per process firing the jobs whose deadline passed (a timer thread
    per job cost a thread start on every request). Jobs wait in a heap by
    deadline; one that ended is dropped when its deadline comes."""

    def __init__(self) -> None:
        self._due: list[tuple[float, int, _Job]] = []
        self._wake = threading.Condition()
        self._count = itertools.count()
        self._thread: threading.Thread | None = None

    def watch(self, job: _Job, seconds: float) -> None:
        entry = (time.monotonic() + seconds, next(self._count), job)
        with self._wake:
            if self._thread is None:
                self._thread = threading.Thread(target=self._run, name="deadline", daemon=True)
                self._thread.start()
            heapq.heappush(self._due, entry)
            if self._due[0] is entry:  # the earliest now: the thread waits for it
                self._wake.notify()

    def _run(self) -> None:
        with self._wake:
            while True:
                if not self._due:
                    self._wake.wait()
                    continue
                wait = self._due[0][0] - time.monotonic()
                if wait > 0:
                    self._wake.wait(wait)
                    continue
                heapq.heappop(self._due)[2].fire()


_watchdog = _Watchdog()


def with_deadline(fn: Callable[..., _T], seconds: float | None) -> Callable[..., _T]:
    """`fn` run in the calling thread, stopped with :class:`JobStoppedError` after
    `seconds` (None: never)."""
    if seconds is None:
        return fn

    def run(*args: Any) -> _T:
        job = _Job(threading.get_ident())
        try:
            _watchdog.watch(job, seconds)
            try:
                result = fn(*args)
            finally:
                job.end()
        except JobStoppedError:
            raise JobStoppedError(f"stopped after {seconds:g} s") from None
        if job.fired:  # fired as `fn` returned; its answer came too late all the same
            raise JobStoppedError(f"stopped after {seconds:g} s")
        return result

    return run


async def run_stopped_at(
    seconds: float | None, fn: Callable[..., _T], *args: Any, limiter: anyio.CapacityLimiter
) -> _T:
    """`fn(*args)` in a worker thread behind `limiter`, stopped after `seconds`
    (``cpu_job_deadline_s``) and then answered 503 with Retry-After."""
    try:
        return await anyio.to_thread.run_sync(with_deadline(fn, seconds), *args, limiter=limiter)
    except JobStoppedError as exc:
        raise UnavailableError(
            f"the work of this request was {exc} (cpu_job_deadline_s {seconds:g}); "
            "retry later, or with fewer objects, poses or observations",
            headers={"Retry-After": "5"},
        ) from None
