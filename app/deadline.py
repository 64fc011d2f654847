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
import threading
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


def with_deadline(fn: Callable[..., _T], seconds: float | None) -> Callable[..., _T]:
    """`fn` run in the calling thread, stopped with :class:`JobStoppedError` after
    `seconds` (None: never)."""
    if seconds is None:
        return fn

    def run(*args: Any) -> _T:
        job = _Job(threading.get_ident())
        timer = threading.Timer(seconds, job.fire)
        timer.daemon = True
        try:
            timer.start()
            try:
                result = fn(*args)
            finally:
                timer.cancel()
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
