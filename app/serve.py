"""``tactile serve [--host --port --workers --db]``: run the HTTP service with uvicorn.

The listening socket is bound here, with ``TCP_NODELAY`` set on it (accepted
connections inherit it on Linux), and handed to uvicorn: with several workers
uvicorn passes its socket to the worker processes, which then lose
TCP_NODELAY and add about 40 ms to each small response (uvicorn issue #3149).
With several workers each gets a socket of its own on the same port
(SO_REUSEPORT, :mod:`app.supervisor`), so that the kernel spreads connections
over the workers instead of handing a burst of them to one.
With several workers the settings reach the workers through the environment
(``TACTILE_*``) and the metrics of all workers are aggregated through
``PROMETHEUS_MULTIPROC_DIR`` (a temporary folder unless one is given).
"""

from __future__ import annotations

import argparse
import atexit
import inspect
import json
import os
import shutil
import socket
import tempfile
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import TYPE_CHECKING, Any

from app.supervisor import reuse_port_supported

if TYPE_CHECKING:
    from app.settings import Settings

__all__ = ["add_serve_command", "bind_socket", "bind_sockets", "cmd_serve", "serve_in_thread"]

#: uvicorn options shared by ``tactile serve`` and :func:`serve_in_thread`.
UVICORN_OPTIONS: dict[str, Any] = {
    "log_config": None,  # our structlog setup renders uvicorn's lines too
    "access_log": False,  # one access line per request comes from our middleware
    "lifespan": "on",
    "timeout_graceful_shutdown": 10,
    "proxy_headers": False,
}


def bind_socket(
    host: str, port: int, backlog: int = 2048, *, reuse_port: bool = False
) -> socket.socket:
    """A listening TCP socket with SO_REUSEADDR and TCP_NODELAY (port 0: any free port);
    with `reuse_port`, SO_REUSEPORT too (sockets sharing the port share its connections)."""
    family = socket.AF_INET6 if ":" in host else socket.AF_INET
    sock = socket.socket(family, socket.SOCK_STREAM, socket.IPPROTO_TCP)
    try:
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        if reuse_port:
            sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEPORT, 1)
        sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        sock.bind((host, port))
        sock.listen(backlog)
    except OSError:
        sock.close()
        raise
    sock.set_inheritable(True)
    return sock


def bind_sockets(host: str, port: int, count: int) -> list[socket.socket]:
    """`count` listening sockets on one address, one per worker
    (:mod:`app.supervisor`): SO_REUSEPORT sockets, after a plain bind has found the
    port free, so that a second service started on a taken port fails as it would
    with one socket instead of silently sharing the first one's connections. One
    plain socket when `count` is 1 or the system cannot share a port."""
    if count <= 1 or not reuse_port_supported():
        return [bind_socket(host, port)]
    probe = bind_socket(host, port)  # OSError when the port is taken
    port = int(probe.getsockname()[1])
    probe.close()
    return [bind_socket(host, port, reuse_port=True) for _ in range(count)]


def _positive(text: str) -> int:
    value = int(text)
    if value < 1:
        raise argparse.ArgumentTypeError("must be >= 1")
    return value


def _metrics_dir(workers: int) -> None:
    if workers <= 1 or os.environ.get("PROMETHEUS_MULTIPROC_DIR"):
        return
    folder = tempfile.mkdtemp(prefix="tactile-metrics-")
    os.environ["PROMETHEUS_MULTIPROC_DIR"] = folder
    atexit.register(shutil.rmtree, folder, ignore_errors=True)


def _memory_cap(limit: int | None) -> None:
    """Cap this process's heap and anonymous memory (RLIMIT_DATA; worker processes
    inherit it): an allocation past it raises MemoryError in the request that made
    it, which is answered 503, instead of the kernel killing the server."""
    if limit is None:
        return
    import resource

    _, hard = resource.getrlimit(resource.RLIMIT_DATA)
    if hard != resource.RLIM_INFINITY:
        limit = min(limit, hard)
    resource.setrlimit(resource.RLIMIT_DATA, (limit, hard))


def _prepare_database(settings: Any) -> None:
    """Create or migrate the database once, before several workers start: each
    opens it at startup, and two creating a new SQLite file at once had the
    second find it locked, fail to start, and the supervisor stop the service."""
    from app.migrations import SchemaTooNewError
    from app.store import Store
    from app.store_types import StoreUnavailableError

    store = Store(
        settings.database,
        busy_timeout_ms=settings.busy_timeout_ms,
        synchronous=settings.sqlite_synchronous,
        pool_size=1,
    )
    try:
        store.open()
    except (StoreUnavailableError, SchemaTooNewError) as exc:
        raise SystemExit(f"tactile serve: {exc}") from exc
    finally:
        store.close()


def cmd_serve(args: argparse.Namespace) -> int:
    import structlog
    import uvicorn
    from uvicorn.supervisors import Multiprocess

    from app.access import load_clients
    from app.observability import configure_logging
    from app.security import LOOPBACK_NAMES, is_loopback
    from app.settings import Settings
    from app.store_types import database_label, database_url, is_url
    from app.supervisor import per_worker_supervisor

    if args.db is not None:
        database_url(args.db)  # refuse what no backend takes before anything starts
        db = args.db if is_url(args.db) else str(Path(args.db).expanduser().resolve())
        os.environ["TACTILE_DB"] = db
    settings = Settings()
    try:
        keyed = load_clients(settings).keyed  # a broken keys file stops the start
    except ValueError as exc:
        raise SystemExit(f"tactile serve: {exc}") from exc
    if not is_loopback(args.host) and not keyed and not settings.open_access:
        raise SystemExit(
            f"tactile serve: binding {args.host} (reachable from other hosts) needs an API "
            "key: set TACTILE_API_KEYS (per client), TACTILE_API_KEYS_FILE or TACTILE_API_KEY, "
            "or TACTILE_OPEN_ACCESS=true to serve without one"
        )
    if settings.allowed_hosts is None and is_loopback(args.host):
        # a loopback service answers loopback names only: no page elsewhere reaches it
        # by resolving its own name to this address; the workers read the environment
        os.environ["TACTILE_ALLOWED_HOSTS"] = json.dumps(list(LOOPBACK_NAMES))
        settings = Settings()
    configure_logging(settings.log_level, settings.log_json)
    if args.workers > 1:
        _prepare_database(settings)
    _memory_cap(settings.max_memory_bytes)
    _metrics_dir(args.workers)
    sockets = bind_sockets(args.host, args.port, args.workers)
    sock = sockets[0]
    host, port = sock.getsockname()[:2]
    common = dict(UVICORN_OPTIONS, limit_concurrency=settings.limit_concurrency)
    structlog.get_logger("app.serve").info(
        "listening",
        host=host,
        port=port,
        workers=args.workers,
        db=database_label(settings.database),
        url=f"http://{host}:{port}",
        allowed_hosts=settings.allowed_hosts,
        max_memory_bytes=settings.max_memory_bytes,
    )
    if args.workers > 1:
        config = uvicorn.Config("app.main:create_app", factory=True, workers=args.workers, **common)
        own = per_worker_supervisor(config, sockets) if len(sockets) == args.workers else None
        if own is not None:  # each worker on its own socket: connections spread over them
            own.run()
            return 0
        for extra in sockets[1:]:
            extra.close()
        if "target" in inspect.signature(Multiprocess).parameters:  # older uvicorn
            server = uvicorn.Server(config)
            Multiprocess(config, target=server.run, sockets=[sock]).run()  # type: ignore[call-arg]
        else:
            Multiprocess(config, sockets=[sock]).run()
    else:
        from app.main import create_app

        config = uvicorn.Config(create_app(settings), **common)
        uvicorn.Server(config).run(sockets=[sock])
    return 0


@contextmanager
def serve_in_thread(
    settings: Settings, host: str = "127.0.0.1", port: int = 0, timeout: float = 30.0
) -> Iterator[str]:
    """A one-worker ``tactile serve`` (same socket, same uvicorn options) in a thread of
    this process; yields its base URL once it accepts requests, and shuts it down
    (lifespan end, database closed) when the block ends.

    >>> from app.settings import Settings
    >>> with serve_in_thread(Settings(db_path="/tmp/doc.db")) as url:  # doctest: +SKIP
    ...     print(url)
    http://127.0.0.1:40123
    """
    import uvicorn

    from app.main import create_app

    sock = bind_socket(host, port)
    bound_host, bound_port = sock.getsockname()[:2]
    server = uvicorn.Server(uvicorn.Config(create_app(settings), **UVICORN_OPTIONS))
    failed: list[BaseException] = []

    def run() -> None:
        try:
            server.run(sockets=[sock])
        except BaseException as exc:  # reported to the caller below
            failed.append(exc)

    thread = threading.Thread(target=run, name="tactile-serve", daemon=True)
    thread.start()
    try:
        deadline = time.monotonic() + timeout
        while not server.started:
            if not thread.is_alive() or time.monotonic() > deadline:
                reason = f": {failed[0]!r}" if failed else ""
                raise RuntimeError(f"the service did not start{reason}")
            time.sleep(0.01)
        url_host = f"[{bound_host}]" if ":" in bound_host else bound_host
        yield f"http://{url_host}:{bound_port}"
    finally:
        server.should_exit = True
        thread.join(timeout)
        sock.close()


def add_serve_command(subparsers: Any) -> None:
    """Add ``serve`` to the ``tactile`` command's subparsers."""
    serve = subparsers.add_parser("serve", help="run the HTTP service (DESIGN §6)")
    serve.add_argument("--host", default="127.0.0.1", help="address to listen on")
    serve.add_argument("--port", type=int, default=8000, help="0: any free port (logged)")
    serve.add_argument("--workers", type=_positive, default=1, help="worker processes")
    serve.add_argument(
        "--db",
        default=None,
        help="a SQLite file or a postgresql://user:pass@host:port/db URL"
        " (default: TACTILE_DB, else TACTILE_DB_PATH, else ./tactile.db)",
    )
    serve.set_defaults(func=cmd_serve)
