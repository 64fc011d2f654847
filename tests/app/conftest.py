"""The store's backends for tests: a SQLite file, or a fresh database on a PostgreSQL
server (``TACTILE_TEST_POSTGRES``, an admin URL whose role may create databases;
`.ci/postgres` starts the machine's server and prints one).

Where no server answers, PostgreSQL cases skip with the reason, unless
``TACTILE_REQUIRE_POSTGRES=1`` (CI), where they fail instead.
"""

from __future__ import annotations

import os
import uuid
from collections.abc import Iterator
from pathlib import Path

import pytest
from sqlalchemy import create_engine, text

from app.store_types import database_url

DEFAULT_ADMIN = "postgresql://tactile:tactile@127.0.0.1:5432/postgres"
BACKENDS = ["sqlite", "postgresql"]


@pytest.fixture(scope="session")
def postgres_admin() -> str:
    """The admin URL of a running PostgreSQL server (or a skip / failure saying why)."""
    url = os.environ.get("TACTILE_TEST_POSTGRES", DEFAULT_ADMIN).strip()
    if not url.startswith(("postgresql://", "postgresql+psycopg://")):
        # a path would open a SQLite file and the cases would test nothing they claim
        pytest.fail(f"TACTILE_TEST_POSTGRES is not a PostgreSQL URL: {url!r}")
    try:
        engine = create_engine(database_url(url), connect_args={"connect_timeout": 3})
        with engine.connect() as conn:
            conn.execute(text("SELECT 1"))
        engine.dispose()
    except Exception as exc:
        reason = f"no PostgreSQL at {database_url(url).render_as_string()}: {exc}"
        if os.environ.get("TACTILE_REQUIRE_POSTGRES") == "1":
            pytest.fail(reason)
        pytest.skip(reason + " (run .ci/postgres and set TACTILE_TEST_POSTGRES)")
    return url


@pytest.fixture
def postgres_url(postgres_admin: str) -> Iterator[str]:
    """A new, empty database on the server, dropped after the test."""
    name = f"tactile_test_{uuid.uuid4().hex[:12]}"
    admin = create_engine(database_url(postgres_admin), isolation_level="AUTOCOMMIT")
    with admin.connect() as conn:
        conn.execute(text(f'CREATE DATABASE "{name}"'))
    url = database_url(postgres_admin).set(database=name)
    try:
        yield url.render_as_string(hide_password=False)
    finally:
        with admin.connect() as conn:
            conn.execute(text(f'DROP DATABASE IF EXISTS "{name}" WITH (FORCE)'))
        admin.dispose()


@pytest.fixture(params=BACKENDS)
def db_target(request: pytest.FixtureRequest, tmp_path: Path) -> str:
    """The ``--db`` value of a new store on each backend."""
    if request.param == "sqlite":
        return str(tmp_path / "store.db")
    return request.getfixturevalue("postgres_url")
