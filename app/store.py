"""SQLite storage of objects and event-sourced sessions (DESIGN §3, §6).

A session is stored as what it is made of: its configuration (object set as
§8 dictionaries, sensor bounds, safe circle, strategy) and its ordered
observations; the hypothesis set is derived by the planner and never stored.
Every write is one ``BEGIN IMMEDIATE`` transaction that compares the session's
`version` before bumping it (compare-and-swap), so several worker processes can
share one file. An idempotency record (key, request fingerprint, first answer)
is written in the same transaction as the change it answers for, so a change
and its replayable answer are durable together. WAL mode with
``synchronous=FULL`` by default: a committed observation survives a killed
process (and a power cut).

The methods are blocking; the service calls them from worker threads. Each
call takes one connection from a small pool (connections are never used by two
threads at once). ``:memory:`` is refused: it would give each connection its
own database.
"""

from __future__ import annotations

import json
import queue
import sqlite3
import threading
import time
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

__all__ = [
    "IdempotentWrite",
    "ObjectConflictError",
    "SessionGoneError",
    "SessionRecord",
    "Store",
    "StoredResponse",
    "VersionConflictError",
]

SCHEMA_VERSION = 1
_SCHEMA = """
CREATE TABLE IF NOT EXISTS objects (
    name TEXT PRIMARY KEY,
    body TEXT NOT NULL,
    created_at REAL NOT NULL
);
CREATE TABLE IF NOT EXISTS sessions (
    id TEXT PRIMARY KEY,
    version INTEGER NOT NULL,
    config TEXT NOT NULL,
    created_at REAL NOT NULL,
    updated_at REAL NOT NULL
);
CREATE TABLE IF NOT EXISTS observations (
    session_id TEXT NOT NULL REFERENCES sessions(id) ON DELETE CASCADE,
    seq INTEGER NOT NULL,
    body TEXT NOT NULL,
    version INTEGER NOT NULL,
    created_at REAL NOT NULL,
    PRIMARY KEY (session_id, seq)
) WITHOUT ROWID;
CREATE TABLE IF NOT EXISTS idempotency (
    scope TEXT NOT NULL,
    key TEXT NOT NULL,
    fingerprint TEXT NOT NULL,
    status INTEGER NOT NULL,
    headers TEXT NOT NULL,
    body BLOB NOT NULL,
    session_id TEXT,
    created_at REAL NOT NULL,
    PRIMARY KEY (scope, key)
) WITHOUT ROWID;
CREATE INDEX IF NOT EXISTS idempotency_session ON idempotency(session_id);
"""


class VersionConflictError(Exception):
    """The session's version is not the one the write was computed for."""

    def __init__(self, current: int) -> None:
        super().__init__(f"session is at version {current}")
        self.current = current


class SessionGoneError(Exception):
    """The session does not exist (never created, or deleted)."""


class ObjectConflictError(Exception):
    """An object of that name with other geometry is already registered."""


@dataclass(frozen=True)
class StoredResponse:
    """The first answer to an idempotent request, replayed on a retry."""

    fingerprint: str
    status: int
    body: bytes
    headers: dict[str, str] = field(default_factory=dict)


@dataclass(frozen=True)
class IdempotentWrite:
    """An answer to store under (`scope`, `key`) together with the change it answers."""

    scope: str
    key: str
    response: StoredResponse


@dataclass(frozen=True)
class SessionRecord:
    """What a session is made of: configuration and ordered observations (JSON dicts)."""

    id: str
    version: int
    config: dict[str, Any]
    observations: tuple[dict[str, Any], ...]
    created_at: float


def _dumps(value: Any) -> str:
    return json.dumps(value, separators=(",", ":"), sort_keys=True, allow_nan=False)


class Store:
    """Objects and sessions in one SQLite file (WAL, busy timeout, CAS on `version`)."""

    def __init__(
        self,
        path: str | Path,
        *,
        busy_timeout_ms: int = 5000,
        synchronous: str = "FULL",
        pool_size: int = 4,
    ) -> None:
        text = str(path)
        if text in ("", ":memory:") or "mode=memory" in text or text.startswith("file::memory:"):
            raise ValueError("an in-memory SQLite database is not shared between threads")
        if synchronous not in ("NORMAL", "FULL", "EXTRA"):
            raise ValueError("synchronous must be NORMAL, FULL or EXTRA")
        self.path = Path(path)
        self.busy_timeout_ms = busy_timeout_ms
        self.synchronous = synchronous
        self.pool_size = pool_size
        self._pool: queue.LifoQueue[sqlite3.Connection] = queue.LifoQueue()
        self._all: list[sqlite3.Connection] = []
        self._lock = threading.Lock()
        self._closed = False

    # -- connections ----------------------------------------------------------------------------
    def _connect(self) -> sqlite3.Connection:
        conn = sqlite3.connect(
            self.path,
            timeout=self.busy_timeout_ms / 1000,
            isolation_level=None,  # explicit BEGIN / COMMIT
            check_same_thread=False,  # the pool hands it to one thread at a time
        )
        conn.execute(f"PRAGMA busy_timeout = {int(self.busy_timeout_ms)}")
        conn.execute(f"PRAGMA synchronous = {self.synchronous}")
        conn.execute("PRAGMA foreign_keys = ON")
        return conn

    @contextmanager
    def _connection(self) -> Iterator[sqlite3.Connection]:
        if self._closed:
            raise RuntimeError("the store is closed")
        try:
            conn = self._pool.get_nowait()
        except queue.Empty:
            with self._lock:
                grow = len(self._all) < self.pool_size
                if grow:
                    conn = self._connect()
                    self._all.append(conn)
            if not grow:
                conn = self._pool.get(timeout=max(self.busy_timeout_ms / 1000, 1.0))
        try:
            yield conn
        finally:
            if conn.in_transaction:  # a failure between BEGIN and COMMIT
                conn.rollback()
            self._pool.put(conn)

    @contextmanager
    def _write(self) -> Iterator[sqlite3.Connection]:
        """One write transaction: BEGIN IMMEDIATE takes the write lock up front."""
        with self._connection() as conn:
            conn.execute("BEGIN IMMEDIATE")
            try:
                yield conn
            except BaseException:
                conn.execute("ROLLBACK")
                raise
            conn.execute("COMMIT")

    @contextmanager
    def _read(self) -> Iterator[sqlite3.Connection]:
        """One read transaction (a consistent snapshot across several SELECTs)."""
        with self._connection() as conn:
            conn.execute("BEGIN")
            try:
                yield conn
            finally:
                conn.execute("COMMIT")

    def open(self, idempotency_ttl_s: float | None = None) -> None:
        """Create the file and schema (safe to run from several processes at once)."""
        self.path.parent.mkdir(parents=True, exist_ok=True)
        with self._connection() as conn:
            mode = conn.execute("PRAGMA journal_mode = WAL").fetchone()[0]
            if str(mode).lower() != "wal":
                raise RuntimeError(f"SQLite refused WAL mode (got {mode!r})")
        with self._write() as conn:
            for statement in filter(str.strip, _SCHEMA.split(";")):
                conn.execute(statement)
            conn.execute(f"PRAGMA user_version = {SCHEMA_VERSION}")
            if idempotency_ttl_s is not None:
                conn.execute(
                    "DELETE FROM idempotency WHERE created_at < ?",
                    (time.time() - idempotency_ttl_s,),
                )

    def close(self) -> None:
        self._closed = True
        with self._lock:
            for conn in self._all:
                conn.close()
            self._all.clear()

    def ping(self) -> bool:
        with self._connection() as conn:
            return conn.execute("SELECT 1").fetchone()[0] == 1

    # -- objects --------------------------------------------------------------------------------
    def put_object(self, name: str, body: dict[str, Any]) -> bool:
        """Register an object; True when new, False when the same object was there.

        Raises :class:`ObjectConflictError` when the name holds another object."""
        text = _dumps(body)
        with self._write() as conn:
            row = conn.execute("SELECT body FROM objects WHERE name = ?", (name,)).fetchone()
            if row is not None:
                if row[0] != text:
                    raise ObjectConflictError(name)
                return False
            conn.execute(
                "INSERT INTO objects (name, body, created_at) VALUES (?, ?, ?)",
                (name, text, time.time()),
            )
            return True

    def get_objects(self, names: Sequence[str]) -> dict[str, dict[str, Any]]:
        """The registered objects among `names` (missing names are left out)."""
        if not names:
            return {}
        marks = ",".join("?" * len(set(names)))
        with self._connection() as conn:
            rows = conn.execute(
                f"SELECT name, body FROM objects WHERE name IN ({marks})", tuple(set(names))
            ).fetchall()
        return {name: json.loads(body) for name, body in rows}

    def list_objects(self, limit: int) -> list[dict[str, Any]]:
        with self._connection() as conn:
            rows = conn.execute(
                "SELECT body FROM objects ORDER BY name LIMIT ?", (limit,)
            ).fetchall()
        return [json.loads(r[0]) for r in rows]

    # -- sessions -------------------------------------------------------------------------------
    def get_session(self, session_id: str) -> SessionRecord | None:
        with self._read() as conn:
            row = conn.execute(
                "SELECT version, config, created_at FROM sessions WHERE id = ?", (session_id,)
            ).fetchone()
            if row is None:
                return None
            obs = conn.execute(
                "SELECT body FROM observations WHERE session_id = ? ORDER BY seq", (session_id,)
            ).fetchall()
        return SessionRecord(
            session_id, row[0], json.loads(row[1]), tuple(json.loads(o[0]) for o in obs), row[2]
        )

    def get_idempotent(self, scope: str, key: str) -> StoredResponse | None:
        with self._connection() as conn:
            return self._stored(conn, scope, key)

    @staticmethod
    def _stored(conn: sqlite3.Connection, scope: str, key: str) -> StoredResponse | None:
        row = conn.execute(
            "SELECT fingerprint, status, headers, body FROM idempotency"
            " WHERE scope = ? AND key = ?",
            (scope, key),
        ).fetchone()
        if row is None:
            return None
        return StoredResponse(row[0], row[1], bytes(row[3]), json.loads(row[2]))

    @staticmethod
    def _remember(
        conn: sqlite3.Connection, idem: IdempotentWrite | None, session_id: str | None
    ) -> None:
        if idem is None:
            return
        r = idem.response
        conn.execute(
            "INSERT INTO idempotency (scope, key, fingerprint, status, headers, body, session_id,"
            " created_at) VALUES (?, ?, ?, ?, ?, ?, ?, ?)",
            (
                idem.scope,
                idem.key,
                r.fingerprint,
                r.status,
                _dumps(r.headers),
                r.body,
                session_id,
                time.time(),
            ),
        )

    @staticmethod
    def _current_version(conn: sqlite3.Connection, session_id: str) -> int:
        row = conn.execute("SELECT version FROM sessions WHERE id = ?", (session_id,)).fetchone()
        if row is None:
            raise SessionGoneError(session_id)
        return int(row[0])

    def create_session(
        self, record: SessionRecord, idem: IdempotentWrite | None = None
    ) -> StoredResponse | None:
        """Insert a new session (version 1, no observation). Returns the stored answer
        instead when `idem`'s key was already used (nothing is written then)."""
        with self._write() as conn:
            if idem is not None and (old := self._stored(conn, idem.scope, idem.key)):
                return old
            now = time.time()
            conn.execute(
                "INSERT INTO sessions (id, version, config, created_at, updated_at)"
                " VALUES (?, ?, ?, ?, ?)",
                (record.id, record.version, _dumps(record.config), now, now),
            )
            self._remember(conn, idem, record.id)
        return None

    def append_observation(
        self,
        session_id: str,
        expected_version: int,
        observation: dict[str, Any],
        idem: IdempotentWrite | None = None,
    ) -> StoredResponse | None:
        """Append one observation if the session is still at `expected_version`.

        Raises :class:`VersionConflictError` or :class:`SessionGoneError`; returns the
        stored answer instead when `idem`'s key was already used."""
        with self._write() as conn:
            if idem is not None and (old := self._stored(conn, idem.scope, idem.key)):
                return old
            current = self._current_version(conn, session_id)
            if current != expected_version:
                raise VersionConflictError(current)
            seq = conn.execute(
                "SELECT COALESCE(MAX(seq) + 1, 0) FROM observations WHERE session_id = ?",
                (session_id,),
            ).fetchone()[0]
            now = time.time()
            conn.execute(
                "INSERT INTO observations (session_id, seq, body, version, created_at)"
                " VALUES (?, ?, ?, ?, ?)",
                (session_id, seq, _dumps(observation), current + 1, now),
            )
            conn.execute(
                "UPDATE sessions SET version = ?, updated_at = ? WHERE id = ?",
                (current + 1, now, session_id),
            )
            self._remember(conn, idem, session_id)
        return None

    def drop_last_observation(
        self, session_id: str, expected_version: int, idem: IdempotentWrite | None = None
    ) -> StoredResponse | None:
        """Undo: remove the last observation if still at `expected_version`."""
        with self._write() as conn:
            if idem is not None and (old := self._stored(conn, idem.scope, idem.key)):
                return old
            current = self._current_version(conn, session_id)
            if current != expected_version:
                raise VersionConflictError(current)
            deleted = conn.execute(
                "DELETE FROM observations WHERE session_id = ? AND seq ="
                " (SELECT MAX(seq) FROM observations WHERE session_id = ?)",
                (session_id, session_id),
            ).rowcount
            if deleted != 1:
                raise LookupError("no observation to undo")
            conn.execute(
                "UPDATE sessions SET version = ?, updated_at = ? WHERE id = ?",
                (current + 1, time.time(), session_id),
            )
            self._remember(conn, idem, session_id)
        return None

    def delete_session(self, session_id: str, expected_version: int | None = None) -> None:
        """Delete a session, its observations and its idempotency records."""
        with self._write() as conn:
            current = self._current_version(conn, session_id)
            if expected_version is not None and current != expected_version:
                raise VersionConflictError(current)
            conn.execute("DELETE FROM observations WHERE session_id = ?", (session_id,))
            conn.execute("DELETE FROM idempotency WHERE session_id = ?", (session_id,))
            conn.execute("DELETE FROM sessions WHERE id = ?", (session_id,))
