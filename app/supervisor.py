"""Several workers, each on a listening socket of its own.

uvicorn's supervisor hands one listening socket to every worker, and the kernel
gives a new connection to whichever worker wakes first: under a burst of
connects one worker takes them all, and a client that keeps its connection alive
(a robot's controller does) stays on that worker for good. Measured with the
load test (8 robots on keep-alive connections, 2 workers): 24.3 CPU seconds on
one worker, 0.4 on the other, and no more throughput than one worker.

Here every worker listens on a socket of its own, all bound to the same address
with ``SO_REUSEPORT``: the kernel spreads connections over them by their
addresses. A worker that dies is replaced on its own socket (a socket left
without a worker would hold its share of connections unanswered). A worker that
fails to start stops the service, as uvicorn's supervisor does (a broken app
fails every start), unless other workers serve: then it is started again, up to
`START_RETRIES` times within `START_WINDOW_S`.

:func:`per_worker_supervisor` returns such a supervisor where the installed
uvicorn's supervisor has the shape it builds on (``Multiprocess(config,
sockets)`` and ``Process(config, sockets)``), else None; the caller then falls
back to one shared socket.
"""

from __future__ import annotations

import inspect
import socket
import time
from typing import Any

__all__ = ["START_RETRIES", "START_WINDOW_S", "per_worker_supervisor", "reuse_port_supported"]

#: Failed starts of one worker within `START_WINDOW_S`, while others serve, that the
#: service outlives (one more stops it).
START_RETRIES = 3
START_WINDOW_S = 300.0


def reuse_port_supported() -> bool:
    """Whether this system spreads connections over sockets sharing a port."""
    return hasattr(socket, "SO_REUSEPORT")


def per_worker_supervisor(config: Any, sockets: list[socket.socket]) -> Any | None:
    """A uvicorn supervisor running worker i on ``sockets[i]`` (one socket per
    worker, ``config.workers`` of them), or None where uvicorn's supervisor is not
    the one this builds on."""
    try:
        from uvicorn.config import STARTUP_FAILURE
        from uvicorn.supervisors import multiprocess
    except ImportError:
        return None
    base, process = multiprocess.Multiprocess, getattr(multiprocess, "Process", None)
    if process is None or list(inspect.signature(process).parameters) != ["config", "sockets"]:
        return None
    if list(inspect.signature(base).parameters) != ["config", "sockets"]:
        return None
    needed = hasattr(process, "wait_until_ready") and hasattr(config, "timeout_worker_healthcheck")
    if not needed:
        return None
    if len(sockets) != config.workers:
        raise ValueError("one socket per worker")
    log = multiprocess.logger

    class PerWorker(base):  # type: ignore[misc, valid-type]
        """uvicorn's supervisor with worker i on socket i, replaced on it."""

        def _spawn(self, idx: int) -> Any:
            worker = process(self.config, [sockets[idx]])
            worker.start()
            return worker

        def __init__(self, *args: Any) -> None:
            super().__init__(*args)
            #: per worker, when its recent starts failed
            self.failed_starts: list[list[float]] = [[] for _ in range(config.workers)]

        def init_processes(self) -> None:
            self.processes = [self._spawn(idx) for idx in range(self.processes_num)]

        def restart_all(self) -> None:
            # each replacement in service before its old worker retires (as uvicorn)
            for idx, old in enumerate(self.processes):
                if self.should_exit.is_set():
                    return
                new = self._spawn(idx)
                timeout = self.config.timeout_worker_healthcheck
                if not new.wait_until_ready(timeout, self.should_exit):
                    new.kill()
                    new.join()
                    log.error("a new worker was not ready in time; the restart stops")
                    return
                old.terminate()
                old.join()
                self.processes[idx] = new

        def keep_subprocess_alive(self) -> None:
            if self.should_exit.is_set():
                return
            failed = self.failed_starts
            for idx, worker in enumerate(self.processes):
                if worker.is_alive(timeout=self.config.timeout_worker_healthcheck):
                    continue
                worker.kill()  # hung or gone
                worker.join()
                if worker.exitcode == STARTUP_FAILURE:
                    # a broken app fails every start: stop, unless other workers
                    # serve (a start met a passing fault: the database briefly
                    # away), and then after a few failures within a while
                    now = time.monotonic()
                    failed[idx] = [t for t in failed[idx] if now - t < START_WINDOW_S] + [now]
                    serving = any(
                        w.is_alive(timeout=self.config.timeout_worker_healthcheck)
                        for j, w in enumerate(self.processes)
                        if j != idx
                    )
                    if not serving or len(failed[idx]) > START_RETRIES:
                        log.error("a worker failed to start; stopping")
                        self.should_exit.set()
                        return
                    log.warning("a worker failed to start; started again (others serve)")
                if self.should_exit.is_set():
                    return
                log.info("worker %s died; replaced on its socket", worker.pid)
                self.processes[idx] = self._spawn(idx)

    return PerWorker(config, sockets[:1])
