"""The store's contract on both backends (SQLite file, PostgreSQL database): sessions,
compare-and-swap across stores (hosts), idempotency races, snapshots, retention and
schema migrations."""

from __future__ import annotations

import sqlite3
import threading
import time
from concurrent.futures import ThreadPoolExecutor

import pytest
from alembic.autogenerate import compare_metadata
from alembic.migration import MigrationContext
from sqlalchemy import text

from app import migrations
from app.store import Store
from app.store_schema import metadata
from app.store_types import (
    IdempotentWrite,
    ObjectConflictError,
    SessionGoneError,
    SessionRecord,
    Snapshot,
    StoredResponse,
    VersionConflictError,
    database_url,
)

THREADS = 8
PER_THREAD = 4


@pytest.fixture
def stores(db_target):
    """Two stores on one database: two hosts (or worker processes) sharing it."""
    a, b = Store(db_target), Store(db_target)
    a.open()
    b.open()
    yield a, b
    a.close()
    b.close()


def _idem(key: str, body: bytes = b"{}") -> IdempotentWrite:
    return IdempotentWrite("scope", key, StoredResponse("fp", 201, body, {"ETag": '"2"'}))


def test_sessions_and_observations_round_trip(stores):
    a, b = stores
    config = {"objects": ["square"], "nested": {"x": 1.5}}
    assert a.create_session(SessionRecord("s", 1, config, (), 0.0)) is None
    a.append_observation("s", 1, {"n": 1})
    a.append_observation("s", 2, {"n": 2})
    record = b.get_session("s")
    assert record.version == 3 and record.config == config
    assert [o["n"] for o in record.observations] == [1, 2]
    b.drop_last_observation("s", 3)
    assert [o["n"] for o in a.get_session("s").observations] == [1]
    assert a.get_session("s").version == 4
    with pytest.raises(VersionConflictError):
        a.delete_session("s", 3)
    a.delete_session("s", 4)
    assert b.get_session("s") is None
    with pytest.raises(SessionGoneError):
        b.append_observation("s", 4, {"n": 3})
    with pytest.raises(SessionGoneError):
        b.delete_session("s")


def test_a_write_computed_on_a_stale_version_loses(stores):
    a, b = stores
    a.create_session(SessionRecord("s", 1, {"k": 1}, (), 0.0))
    a.append_observation("s", 1, {"n": 1})
    with pytest.raises(VersionConflictError) as lost:
        b.append_observation("s", 1, {"n": 2})
    assert lost.value.current == 2
    with pytest.raises(VersionConflictError):
        b.drop_last_observation("s", 1)
    b.append_observation("s", 2, {"n": 2})
    assert [o["n"] for o in a.get_session("s").observations] == [1, 2]


def test_concurrent_writers_on_two_stores_each_land_once(stores):
    """8 writers over two stores, each retrying on a conflict: every observation lands
    once, every write gets its own version, the log has no gap."""
    a, b = stores
    a.create_session(SessionRecord("s", 1, {}, (), 0.0))
    conflicts = [0]
    lock = threading.Lock()

    def writer(t: int) -> list[int]:
        store = (a, b)[t % 2]
        versions = []
        for j in range(PER_THREAD):
            while True:
                current = store.get_session("s").version
                try:
                    store.append_observation("s", current, {"k": t * PER_THREAD + j})
                except VersionConflictError:
                    with lock:
                        conflicts[0] += 1
                    continue
                versions.append(current + 1)
                break
        return versions

    with ThreadPoolExecutor(THREADS) as pool:
        versions = [v for vs in pool.map(writer, range(THREADS)) for v in vs]
    total = THREADS * PER_THREAD
    assert sorted(versions) == list(range(2, total + 2))
    record = b.get_session("s")
    assert record.version == total + 1
    assert sorted(o["k"] for o in record.observations) == list(range(total))


def test_idempotency_records_replay_and_survive_a_race(stores):
    a, b = stores
    a.create_session(SessionRecord("s", 1, {}, (), 0.0))
    assert a.append_observation("s", 1, {"n": 1}, _idem("k1", b"first")) is None
    replay = b.append_observation("s", 2, {"n": 99}, _idem("k1", b"second"))
    assert replay is not None and replay.body == b"first" and replay.headers == {"ETag": '"2"'}
    assert len(a.get_session("s").observations) == 1  # the retry wrote nothing

    # the same request on both hosts at once: one lands, the other gets its answer
    barrier = threading.Barrier(2)

    def post(store: Store, body: bytes):
        barrier.wait()
        try:
            return store.append_observation("s", 2, {"n": 2}, _idem("k2", body))
        except VersionConflictError as exc:
            return exc

    with ThreadPoolExecutor(2) as pool:
        answers = list(pool.map(post, (a, b), (b"from-a", b"from-b")))
    landed = [r for r in answers if r is None]
    assert len(landed) == 1
    other = next(r for r in answers if r is not None)
    assert isinstance(other, StoredResponse), other  # never a conflict: the key is known
    assert other.body in (b"from-a", b"from-b")
    assert [o["n"] for o in a.get_session("s").observations] == [1, 2]

    # the same key on two new sessions at once: one session is created
    def create(store: Store, sid: str):
        barrier.wait()
        return store.create_session(SessionRecord(sid, 1, {}, (), 0.0), _idem("new", sid.encode()))

    with ThreadPoolExecutor(2) as pool:
        made = list(pool.map(create, (a, b), ("x", "y")))
    assert sum(m is None for m in made) == 1
    winner = next(m for m in made if m is not None).body.decode()
    assert a.get_session(winner) is not None
    assert a.get_session({"x": "y", "y": "x"}[winner]) is None


def test_objects_register_once(stores):
    a, b = stores
    assert a.put_object("sq", {"name": "sq", "outline": [[0, 0], [1, 0], [0, 1]]})
    assert not b.put_object("sq", {"name": "sq", "outline": [[0, 0], [1, 0], [0, 1]]})
    with pytest.raises(ObjectConflictError):
        b.put_object("sq", {"name": "sq", "outline": [[0, 0], [2, 0], [0, 2]]})
    assert b.get_objects(["sq", "nope"]).keys() == {"sq"}
    assert [o["name"] for o in a.list_objects(10)] == ["sq"]
    assert b.delete_object("sq") and not a.delete_object("sq")
    assert a.get_objects(["sq"]) == {}


def test_snapshots_keep_the_newest_two_and_follow_undo(stores):
    a, b = stores
    a.create_session(SessionRecord("s", 1, {}, (), 0.0))
    for n in range(1, 5):
        a.append_observation("s", n, {"n": n}, snapshot=Snapshot("v1", f"state{n}".encode()))
    assert b.get_snapshot("s", "v1", 4) == (4, b"state4")
    assert b.get_snapshot("s", "v1", 3) == (3, b"state3")
    assert b.get_snapshot("s", "v1", 2) is None  # older ones are dropped
    assert b.get_snapshot("s", "v2", 4) is None  # another code version's are not used
    b.drop_last_observation("s", 5)
    assert a.get_snapshot("s", "v1", 10) == (3, b"state3")  # the undone state's is gone
    a.append_observation("s", 6, {"n": 40}, snapshot=Snapshot("v1", b"state4-new"))
    assert b.get_snapshot("s", "v1", 10) == (4, b"state4-new")
    a.delete_session("s")
    assert a.get_snapshot("s", "v1", 10) is None


def test_retention_purges_expired_records_and_idle_sessions(stores):
    a, b = stores
    a.create_session(SessionRecord("old", 1, {}, (), 0.0), _idem("k-old"))
    a.append_observation("old", 1, {"n": 1}, snapshot=Snapshot("v", b"x"))
    time.sleep(0.05)
    a.create_session(SessionRecord("new", 1, {}, (), 0.0), _idem("k-new"))
    removed = b.purge(idempotency_ttl_s=0.03, session_ttl_s=0.03)
    assert removed == {"idempotency": 1, "sessions": 1}
    assert a.get_session("old") is None and a.get_session("new") is not None
    assert a.get_idempotent("scope", "k-old") is None
    assert a.get_idempotent("scope", "k-new") is not None
    assert b.purge(idempotency_ttl_s=3600, session_ttl_s=None) == {
        "idempotency": 0,
        "sessions": 0,
    }


def test_retention_runs_on_one_host_at_a_time(postgres_url):
    a, b = Store(postgres_url), Store(postgres_url)
    a.open()
    try:
        with a._write() as conn:  # host A is purging: it holds the retention lock
            conn.execute(text("SELECT pg_advisory_xact_lock(:k)"), {"k": 0x7AC7_0002})
            assert b.purge(3600, None) is None  # host B skips this round
        assert b.purge(3600, None) == {"idempotency": 0, "sessions": 0}
    finally:
        a.close()
        b.close()


def test_a_new_database_is_migrated_to_the_tables_the_code_uses(db_target):
    store = Store(db_target)
    try:
        assert store.open() == "empty"
        assert store.open() == migrations.head()  # a second start has nothing to do
        with store.engine.connect() as conn:
            context = MigrationContext.configure(conn)
            assert context.get_current_revision() == migrations.head()
            assert compare_metadata(context, metadata) == []
    finally:
        store.close()


def test_a_database_migrated_by_newer_code_refuses_to_start(db_target):
    store = Store(db_target)
    store.open()
    with store._write() as conn:
        conn.execute(text("UPDATE alembic_version SET version_num = '9999'"))
    store.close()
    again = Store(db_target)
    try:
        with pytest.raises(migrations.SchemaTooNewError, match="newer release"):
            again.open()
    finally:
        again.close()


def test_a_file_of_the_release_before_migrations_is_upgraded_in_place(tmp_path):
    """The first release wrote its schema by hand (``user_version`` 1): its data stays."""
    path = tmp_path / "old.db"
    with sqlite3.connect(path) as conn:
        conn.executescript(
            """
            CREATE TABLE objects (name TEXT PRIMARY KEY, body TEXT NOT NULL,
                created_at REAL NOT NULL);
            CREATE TABLE sessions (id TEXT PRIMARY KEY, version INTEGER NOT NULL,
                config TEXT NOT NULL, created_at REAL NOT NULL, updated_at REAL NOT NULL);
            CREATE TABLE observations (session_id TEXT NOT NULL REFERENCES sessions(id)
                ON DELETE CASCADE, seq INTEGER NOT NULL, body TEXT NOT NULL,
                version INTEGER NOT NULL, created_at REAL NOT NULL,
                PRIMARY KEY (session_id, seq)) WITHOUT ROWID;
            CREATE TABLE idempotency (scope TEXT NOT NULL, key TEXT NOT NULL,
                fingerprint TEXT NOT NULL, status INTEGER NOT NULL, headers TEXT NOT NULL,
                body BLOB NOT NULL, session_id TEXT, created_at REAL NOT NULL,
                PRIMARY KEY (scope, key)) WITHOUT ROWID;
            CREATE INDEX idempotency_session ON idempotency(session_id);
            INSERT INTO sessions VALUES ('s', 2, '{}', 0, 0);
            INSERT INTO observations VALUES ('s', 0, '{"n":1}', 2, 0);
            PRAGMA user_version = 1;
            """
        )
    store = Store(path)
    try:
        assert store.open() == "0001"
        assert [o["n"] for o in store.get_session("s").observations] == [1]
        store.append_observation("s", 2, {"n": 2}, snapshot=Snapshot("v", b"x"))
        assert store.get_snapshot("s", "v", 2) == (2, b"x")
    finally:
        store.close()


def test_sqlite_uses_wal_full_sync_and_the_busy_timeout(tmp_path):
    store = Store(tmp_path / "wal.db", busy_timeout_ms=1234)
    store.open()
    try:
        with store.engine.connect() as conn:
            raw = conn.connection.dbapi_connection
            assert raw.execute("PRAGMA journal_mode").fetchone()[0] == "wal"
            assert raw.execute("PRAGMA busy_timeout").fetchone()[0] == 1234
            assert raw.execute("PRAGMA synchronous").fetchone()[0] == 2  # FULL
    finally:
        store.close()


@pytest.mark.parametrize(
    ("target", "backend"),
    [
        ("postgresql://u:p@db.example:5432/tactile", "postgresql"),
        ("postgres://u@db/tactile", "postgresql"),
        ("postgresql+psycopg://u@db/tactile", "postgresql"),
        ("sqlite:///var/lib/tactile.db", "sqlite"),
        ("relative/dir/t.db", "sqlite"),
        ("/abs/t.db", "sqlite"),
        ("odd name:with colon.db", "sqlite"),
    ],
)
def test_a_url_is_never_taken_for_a_file(target, backend):
    url = database_url(target)
    assert url.get_backend_name() == backend
    if backend == "sqlite" and "://" not in target:
        assert url.database == target


@pytest.mark.parametrize("target", [":memory:", "", "sqlite://", "mysql://u@h/db", "file::memory:"])
def test_unsupported_databases_are_refused(target):
    with pytest.raises(ValueError):
        database_url(target)


def test_a_connection_waits_to_switch_a_busy_new_file_to_wal(tmp_path):
    """A second worker of a new service connects while the first writes to the file,
    still in SQLite's first (rollback) mode: the switch to WAL is answered "database
    is locked" at once, and is retried until the writer is done."""
    from sqlalchemy import URL

    from app.store_engine import make_engine

    path = tmp_path / "fresh.db"
    holder = sqlite3.connect(path, isolation_level=None, check_same_thread=False)
    holder.execute("CREATE TABLE t (x)")
    holder.execute("BEGIN IMMEDIATE")
    holder.execute("INSERT INTO t VALUES (1)")
    release = threading.Timer(0.3, holder.execute, ("COMMIT",))
    release.start()
    engine = make_engine(URL.create("sqlite", database=str(path)), 5000, "FULL", 1)
    try:
        with engine.connect() as conn:
            assert conn.exec_driver_sql("PRAGMA journal_mode").scalar() == "wal"
    finally:
        release.join()
        engine.dispose()
        holder.close()
