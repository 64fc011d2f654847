"""The SQLAlchemy engine of a store: a connection pool per backend, and for SQLite the
pragmas (WAL, synchronous, busy timeout, foreign keys) on every connection and
transactions begun by hand (``BEGIN IMMEDIATE`` for writes, so a writer takes the
file's lock up front instead of failing to upgrade a read lock later)."""

from __future__ import annotations

import sqlite3
import time
from typing import Any

from sqlalchemy import URL, Connection, Engine, create_engine, event

__all__ = ["WRITE_OPTION", "make_engine"]

#: The execution option a store sets on a connection whose transaction will write.
WRITE_OPTION = "tactile_write"


def make_engine(url: URL, busy_timeout_ms: int, synchronous: str, pool_size: int) -> Engine:
    """A pooled engine (at most `pool_size` connections) for `url`."""
    timeout_s = max(busy_timeout_ms / 1000, 1.0)
    if url.get_backend_name() == "postgresql":
        return create_engine(
            url,
            pool_size=pool_size,
            max_overflow=0,
            pool_timeout=timeout_s,
            pool_pre_ping=True,
            connect_args={"connect_timeout": max(int(timeout_s), 1)},
        )
    engine = create_engine(
        url,
        pool_size=pool_size,
        max_overflow=0,
        pool_timeout=timeout_s,
        connect_args={"timeout": busy_timeout_ms / 1000, "check_same_thread": False},
    )

    @event.listens_for(engine, "connect")
    def _on_connect(dbapi_connection: Any, _record: Any) -> None:
        dbapi_connection.isolation_level = None  # transactions are begun below
        cursor = dbapi_connection.cursor()
        cursor.execute(f"PRAGMA busy_timeout = {int(busy_timeout_ms)}")
        cursor.execute(f"PRAGMA synchronous = {synchronous}")
        cursor.execute("PRAGMA foreign_keys = ON")
        mode = cursor.execute("PRAGMA journal_mode").fetchone()[0]
        if str(mode).lower() != "wal":
            mode = _to_wal(cursor, busy_timeout_ms)
        cursor.close()
        if str(mode).lower() != "wal":
            raise RuntimeError(f"SQLite refused WAL mode (got {mode!r})")

    @event.listens_for(engine, "begin")
    def _on_begin(conn: Connection) -> None:
        write = conn.get_execution_options().get(WRITE_OPTION, False)
        conn.exec_driver_sql("BEGIN IMMEDIATE" if write else "BEGIN")

    return engine


def _to_wal(cursor: Any, busy_timeout_ms: int) -> str:
    """Switch a database file to WAL mode; returns the mode it is in. The switch
    needs the file to itself, and SQLite answers "database is locked" at once
    (without waiting the busy timeout) while another connection holds it, as a
    second worker of a new service does while the first creates the schema:
    retried for the busy timeout (at least a second)."""
    deadline = time.monotonic() + max(busy_timeout_ms / 1000, 1.0)
    while True:
        try:
            return str(cursor.execute("PRAGMA journal_mode = WAL").fetchone()[0])
        except sqlite3.OperationalError as exc:
            if "locked" not in str(exc) or time.monotonic() > deadline:
                raise
            time.sleep(0.02)
