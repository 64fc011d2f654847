"""Storage of objects and event-sourced sessions (DESIGN §3, §6) on SQLite or PostgreSQL.

A session is stored as what it is made of: its configuration (object set as §8
dictionaries, sensor bounds, safe circle, strategy) and its ordered observations.
Beside that event log the store keeps snapshots of the derived state (opaque
bytes, tagged with the code version that wrote them) so that a host that never
saw a session serves it without replaying every observation; the log stays the
source of truth.

Written on SQLAlchemy Core; the backend is chosen by :func:`database_url`:

- a file path: SQLite, embedded. WAL mode, ``synchronous=FULL`` by default (a
  committed observation survives a killed process and a power cut); a write
  transaction begins ``IMMEDIATE`` and so takes the file's write lock up front.
- a ``postgresql://`` URL: PostgreSQL through psycopg 3, at its default
  isolation (read committed), so several hosts share one database.

Every change is one transaction, and a compare-and-swap on the session's
`version`: ``UPDATE ... WHERE id = :id AND version = :expected`` and a row-count
check. The update takes the session row's lock before anything else is
written, so two writers of one session, on any host, are serialized by the
database and the loser sees the winner's version. An idempotency record (key,
request fingerprint, first answer) is written in the same transaction as the
change it answers for (``INSERT ... ON CONFLICT DO NOTHING``; a record another
host wrote first is answered instead).

The schema is migrated with alembic at :meth:`Store.open` (:mod:`app.migrations`).
The methods are blocking; the service calls them from worker threads.

Sessions and objects carry their owner, the client whose key created them
(``''``: anonymous); objects are named per owner.
"""

from __future__ import annotations

import json
import time
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from sqlalchemy import Connection, Engine, delete, func, select, text, update
from sqlalchemy import exc as sa_exc
from sqlalchemy.dialects import postgresql, sqlite

from app import migrations
from app.store_engine import WRITE_OPTION, make_engine
from app.store_schema import idempotency, objects, observations, sessions, snapshots
from app.store_types import (
    IdempotentWrite,
    ObjectConflictError,
    SessionGoneError,
    SessionRecord,
    Snapshot,
    StoredResponse,
    StoreUnavailableError,
    VersionConflictError,
    database_url,
)

__all__ = ["Store"]

#: Snapshots kept per session: the newest and the one before it (an undo's target).
SNAPSHOTS_KEPT = 2
#: The key of PostgreSQL advisory locks the store takes (migrations, retention).
_LOCK_MIGRATE, _LOCK_RETENTION = 0x7AC7_0001, 0x7AC7_0002


class _IdempotencyRaceError(Exception):
    """Another transaction stored an answer under the same key first."""


def _dumps(value: Any) -> str:
    return json.dumps(value, separators=(",", ":"), sort_keys=True, allow_nan=False)


class Store:
    """Objects and sessions in SQLite or PostgreSQL (CAS on `version`, one transaction
    per write, snapshots beside the log)."""

    def __init__(
        self,
        target: str | Path,
        *,
        busy_timeout_ms: int = 5000,
        synchronous: str = "FULL",
        pool_size: int = 4,
    ) -> None:
        if synchronous not in ("NORMAL", "FULL", "EXTRA"):
            raise ValueError("synchronous must be NORMAL, FULL or EXTRA")
        self.url = database_url(target)
        self.busy_timeout_ms = busy_timeout_ms
        self.synchronous = synchronous
        self.pool_size = pool_size
        self._engine: Engine | None = None
        self._closed = False

    @property
    def backend(self) -> str:
        """``sqlite`` or ``postgresql``."""
        return self.url.get_backend_name()

    @property
    def path(self) -> Path | None:
        """The SQLite file (None on PostgreSQL)."""
        return Path(self.url.database) if self.backend == "sqlite" and self.url.database else None

    def describe(self) -> str:
        """Where the data lives, without a password (for logs)."""
        return self.url.render_as_string(hide_password=True)

    # -- connections ----------------------------------------------------------------------------
    def _make_engine(self) -> Engine:
        return make_engine(self.url, self.busy_timeout_ms, self.synchronous, self.pool_size)

    @property
    def engine(self) -> Engine:
        if self._closed:
            raise RuntimeError("the store is closed")
        if self._engine is None:
            self._engine = self._make_engine()
        return self._engine

    @contextmanager
    def _transaction(self, write: bool) -> Iterator[Connection]:
        try:
            with self.engine.connect() as conn:
                if write:
                    conn = conn.execution_options(**{WRITE_OPTION: True})
                with conn.begin():
                    yield conn
        except (sa_exc.OperationalError, sa_exc.InterfaceError, sa_exc.TimeoutError) as exc:
            detail = getattr(exc, "orig", None) or exc
            raise StoreUnavailableError(f"the database is unavailable: {detail}") from exc

    def _write(self) -> Any:
        """One write transaction (SQLite: BEGIN IMMEDIATE takes the write lock up front)."""
        return self._transaction(write=True)

    def _read(self) -> Any:
        """One read transaction (a consistent view across several SELECTs)."""
        return self._transaction(write=False)

    def _insert(self, table: Any) -> Any:
        dialect = postgresql if self.backend == "postgresql" else sqlite
        return dialect.insert(table)

    def _advisory_lock(self, conn: Connection, key: int, wait: bool) -> bool:
        """PostgreSQL: a transaction-scoped advisory lock (SQLite's write lock is enough)."""
        if self.backend != "postgresql":
            return True
        if wait:
            conn.execute(text("SELECT pg_advisory_xact_lock(:k)"), {"k": key})
            return True
        return bool(conn.execute(text("SELECT pg_try_advisory_xact_lock(:k)"), {"k": key}).scalar())

    def open(self) -> str:
        """Create the database's schema or migrate it to this code's (safe to run from
        several processes and hosts at once); returns the revision it was at before.

        Raises :class:`app.migrations.SchemaTooNewError` for a database that a newer
        release migrated."""
        if self.path is not None:
            self.path.parent.mkdir(parents=True, exist_ok=True)
        with self._write() as conn:
            self._advisory_lock(conn, _LOCK_MIGRATE, wait=True)
            return migrations.upgrade(conn)

    def close(self) -> None:
        self._closed = True
        if self._engine is not None:
            self._engine.dispose()
            self._engine = None

    def ping(self) -> bool:
        with self._read() as conn:
            return conn.execute(select(1)).scalar() == 1

    # -- retention ------------------------------------------------------------------------------
    def purge(self, idempotency_ttl_s: float, session_ttl_s: float | None) -> dict[str, int] | None:
        """Delete idempotency records older than their TTL and sessions idle for longer
        than theirs. One host at a time: returns None when another is purging."""
        now = time.time()
        with self._write() as conn:
            if not self._advisory_lock(conn, _LOCK_RETENTION, wait=False):
                return None
            old = idempotency.c.created_at < now - idempotency_ttl_s
            removed = {"idempotency": conn.execute(delete(idempotency).where(old)).rowcount}
            idle = 0
            if session_ttl_s is not None:
                stale = select(sessions.c.id).where(sessions.c.updated_at < now - session_ttl_s)
                ids = list(conn.execute(stale).scalars())
                for chunk in range(0, len(ids), 500):
                    part = ids[chunk : chunk + 500]
                    conn.execute(delete(idempotency).where(idempotency.c.session_id.in_(part)))
                    conn.execute(delete(snapshots).where(snapshots.c.session_id.in_(part)))
                    conn.execute(delete(observations).where(observations.c.session_id.in_(part)))
                    idle += conn.execute(delete(sessions).where(sessions.c.id.in_(part))).rowcount
            removed["sessions"] = idle
        return removed

    # -- objects --------------------------------------------------------------------------------
    def put_object(self, name: str, body: dict[str, Any], owner: str = "") -> bool:
        """Register an object of `owner`; True when new, False when the same object was there.

        Raises :class:`ObjectConflictError` when the name holds another object."""
        body_text = _dumps(body)
        mine = (objects.c.owner == owner) & (objects.c.name == name)
        with self._write() as conn:
            added = conn.execute(
                self._insert(objects)
                .values(owner=owner, name=name, body=body_text, created_at=time.time())
                .on_conflict_do_nothing(index_elements=["owner", "name"])
                .returning(objects.c.name)  # a row back when inserted (rowcount is not kept)
            ).first()
            if added is not None:
                return True
            there = conn.execute(select(objects.c.body).where(mine)).scalar()
        if there != body_text:
            raise ObjectConflictError(name)
        return False

    def delete_object(self, name: str, owner: str = "") -> bool:
        """Unregister an object of `owner`; False when it has none of that name."""
        with self._write() as conn:
            mine = (objects.c.owner == owner) & (objects.c.name == name)
            return conn.execute(delete(objects).where(mine)).rowcount == 1

    def get_objects(self, names: Sequence[str], owner: str = "") -> dict[str, dict[str, Any]]:
        """`owner`'s registered objects among `names` (missing names are left out)."""
        if not names:
            return {}
        with self._read() as conn:
            rows = conn.execute(
                select(objects.c.name, objects.c.body).where(
                    objects.c.owner == owner, objects.c.name.in_(set(names))
                )
            ).all()
        return {name: json.loads(body) for name, body in rows}

    def list_objects(self, limit: int, owner: str = "") -> list[dict[str, Any]]:
        """`owner`'s registered objects by name, at most `limit`."""
        with self._read() as conn:
            rows = conn.execute(
                select(objects.c.body)
                .where(objects.c.owner == owner)
                .order_by(objects.c.name)
                .limit(limit)
            ).scalars()
            return [json.loads(r) for r in rows]

    # -- sessions -------------------------------------------------------------------------------
    def get_session(self, session_id: str) -> SessionRecord | None:
        with self._read() as conn:
            row = conn.execute(
                select(
                    sessions.c.version, sessions.c.config, sessions.c.created_at, sessions.c.owner
                ).where(sessions.c.id == session_id)
            ).first()
            if row is None:
                return None
            obs = conn.execute(
                select(observations.c.body)
                .where(observations.c.session_id == session_id)
                .order_by(observations.c.seq)
            ).scalars()
            stored = tuple(json.loads(o) for o in obs)
        return SessionRecord(session_id, row[0], json.loads(row[1]), stored, row[2], row[3])

    def session_owner(self, session_id: str) -> str | None:
        """Who owns the session (``''``: anonymous); None when there is no such session."""
        with self._read() as conn:
            return conn.execute(
                select(sessions.c.owner).where(sessions.c.id == session_id)
            ).scalar()

    def get_snapshot(
        self, session_id: str, code_version: str, at_most: int
    ) -> tuple[int, bytes] | None:
        """The newest snapshot of `code_version` after at most `at_most` observations."""
        with self._read() as conn:
            row = conn.execute(
                select(snapshots.c.n, snapshots.c.body)
                .where(
                    snapshots.c.session_id == session_id,
                    snapshots.c.code_version == code_version,
                    snapshots.c.n <= at_most,
                )
                .order_by(snapshots.c.n.desc())
                .limit(1)
            ).first()
        return None if row is None else (int(row[0]), bytes(row[1]))

    def get_idempotent(self, scope: str, key: str) -> StoredResponse | None:
        with self._read() as conn:
            return self._stored(conn, scope, key)

    @staticmethod
    def _stored(conn: Connection, scope: str, key: str) -> StoredResponse | None:
        row = conn.execute(
            select(
                idempotency.c.fingerprint,
                idempotency.c.status,
                idempotency.c.headers,
                idempotency.c.body,
            ).where(idempotency.c.scope == scope, idempotency.c.key == key)
        ).first()
        if row is None:
            return None
        return StoredResponse(row[0], row[1], bytes(row[3]), json.loads(row[2]))

    def _remember(
        self, conn: Connection, idem: IdempotentWrite | None, session_id: str | None
    ) -> None:
        """Store the answer under its key; :class:`_IdempotencyRaceError` (the transaction is
        then rolled back) when another transaction stored one under it first."""
        if idem is None:
            return
        r = idem.response
        added = conn.execute(
            self._insert(idempotency)
            .values(
                scope=idem.scope,
                key=idem.key,
                fingerprint=r.fingerprint,
                status=r.status,
                headers=_dumps(r.headers),
                body=r.body,
                session_id=session_id,
                created_at=time.time(),
            )
            .on_conflict_do_nothing(index_elements=["scope", "key"])
            .returning(idempotency.c.key)  # a row back when inserted (rowcount is not kept)
        ).first()
        if added is None:
            raise _IdempotencyRaceError

    def _change(
        self,
        idem: IdempotentWrite | None,
        session_id: str,
        work: Callable[[Connection], None],
    ) -> StoredResponse | None:
        """One write transaction: `work`, then the answer stored under `idem`'s key.

        Returns the stored answer instead (nothing written) when the key was already
        used, also when another host stored it while this transaction ran (rolled back)."""
        try:
            with self._write() as conn:
                if idem is not None and (old := self._stored(conn, idem.scope, idem.key)):
                    return old
                work(conn)
                self._remember(conn, idem, session_id)
        except _IdempotencyRaceError:
            assert idem is not None
            old = self.get_idempotent(idem.scope, idem.key)
            if old is None:  # pragma: no cover - the winner's record is committed
                raise
            return old
        return None

    def _swap_version(
        self, conn: Connection, session_id: str, expected: int, idem: IdempotentWrite | None
    ) -> int:
        """The compare-and-swap: version `expected` -> `expected + 1`, or the reason not."""
        bumped = conn.execute(
            update(sessions)
            .where(sessions.c.id == session_id, sessions.c.version == expected)
            .values(version=expected + 1, updated_at=time.time())
        ).rowcount
        if bumped == 1:
            return expected + 1
        current = conn.execute(
            select(sessions.c.version).where(sessions.c.id == session_id)
        ).scalar()
        if current is None:
            raise SessionGoneError(session_id)
        if idem is not None and self._stored(conn, idem.scope, idem.key) is not None:
            raise _IdempotencyRaceError  # the same request landed on another host first
        raise VersionConflictError(int(current))

    def create_session(
        self, record: SessionRecord, idem: IdempotentWrite | None = None
    ) -> StoredResponse | None:
        """Insert a new session (version 1, no observation). Returns the stored answer
        instead when `idem`'s key was already used (nothing is written then)."""

        def work(conn: Connection) -> None:
            now = time.time()
            conn.execute(
                sessions.insert().values(
                    id=record.id,
                    version=record.version,
                    config=_dumps(record.config),
                    owner=record.owner,
                    created_at=now,
                    updated_at=now,
                )
            )

        return self._change(idem, record.id, work)

    def append_observation(
        self,
        session_id: str,
        expected_version: int,
        observation: dict[str, Any],
        idem: IdempotentWrite | None = None,
        snapshot: Snapshot | None = None,
    ) -> StoredResponse | None:
        """Append one observation if the session is still at `expected_version`, with
        the snapshot of the state it leads to.

        Raises :class:`VersionConflictError` or :class:`SessionGoneError`; returns the
        stored answer instead when `idem`'s key was already used."""

        def work(conn: Connection) -> None:
            version = self._swap_version(conn, session_id, expected_version, idem)
            seq = conn.execute(
                select(func.coalesce(func.max(observations.c.seq) + 1, 0)).where(
                    observations.c.session_id == session_id
                )
            ).scalar()
            now = time.time()
            conn.execute(
                observations.insert().values(
                    session_id=session_id,
                    seq=seq,
                    body=_dumps(observation),
                    version=version,
                    created_at=now,
                )
            )
            if snapshot is not None:
                self._put_snapshot(conn, session_id, int(seq) + 1, snapshot, now)

        return self._change(idem, session_id, work)

    def _put_snapshot(
        self, conn: Connection, session_id: str, n: int, snap: Snapshot, now: float
    ) -> None:
        values = {"code_version": snap.code_version, "body": snap.body, "created_at": now}
        conn.execute(
            self._insert(snapshots)
            .values(session_id=session_id, n=n, **values)
            .on_conflict_do_update(index_elements=["session_id", "n"], set_=values)
        )
        conn.execute(
            delete(snapshots).where(
                snapshots.c.session_id == session_id, snapshots.c.n <= n - SNAPSHOTS_KEPT
            )
        )

    def drop_last_observation(
        self, session_id: str, expected_version: int, idem: IdempotentWrite | None = None
    ) -> StoredResponse | None:
        """Undo: remove the last observation (and the snapshots after the ones left) if
        still at `expected_version`."""

        def work(conn: Connection) -> None:
            self._swap_version(conn, session_id, expected_version, idem)
            last = conn.execute(
                select(func.max(observations.c.seq)).where(observations.c.session_id == session_id)
            ).scalar()
            if last is None:
                raise LookupError("no observation to undo")
            conn.execute(
                delete(observations).where(
                    observations.c.session_id == session_id, observations.c.seq == last
                )
            )
            conn.execute(
                delete(snapshots).where(
                    snapshots.c.session_id == session_id, snapshots.c.n > int(last)
                )
            )

        return self._change(idem, session_id, work)

    def delete_session(self, session_id: str, expected_version: int | None = None) -> None:
        """Delete a session, its observations, snapshots and idempotency records."""
        with self._write() as conn:
            if expected_version is not None:
                self._swap_version(conn, session_id, expected_version, None)
            elif (
                conn.execute(
                    select(sessions.c.version).where(sessions.c.id == session_id).with_for_update()
                ).first()
                is None
            ):
                raise SessionGoneError(session_id)
            for table in (observations, snapshots):
                conn.execute(delete(table).where(table.c.session_id == session_id))
            conn.execute(delete(idempotency).where(idempotency.c.session_id == session_id))
            conn.execute(delete(sessions).where(sessions.c.id == session_id))
