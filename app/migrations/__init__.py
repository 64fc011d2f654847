"""The store's schema migrations (alembic), applied at start-up by :func:`upgrade`.

Revisions live in ``versions/``; each creates or changes tables with explicit
columns (never from the current table definitions, which move on). A database
that an older release of the service created without migrations (its tables but
no ``alembic_version``) is stamped at the first revision, then upgraded.
"""

from __future__ import annotations

from pathlib import Path

from alembic import command
from alembic.config import Config
from alembic.runtime.migration import MigrationContext
from alembic.script import ScriptDirectory
from sqlalchemy import Connection, inspect

__all__ = ["SchemaTooNewError", "head", "upgrade"]

HERE = Path(__file__).resolve().parent
FIRST = "0001"


class SchemaTooNewError(RuntimeError):
    """The database was migrated by newer code than this one."""


def _config(connection: Connection | None = None) -> Config:
    config = Config()
    config.set_main_option("script_location", str(HERE))
    config.attributes["connection"] = connection
    return config


def head() -> str:
    """The newest revision this code knows."""
    heads = ScriptDirectory.from_config(_config()).get_heads()
    assert len(heads) == 1, heads
    return heads[0]


def upgrade(connection: Connection) -> str:
    """Bring the schema to :func:`head` inside the caller's transaction; returns the
    revision it was at before (None-like ``"empty"`` for a new database).

    Raises :class:`SchemaTooNewError` when the database is at a revision this code
    does not know (a newer release migrated it)."""
    script = ScriptDirectory.from_config(_config())
    current = MigrationContext.configure(connection).get_current_revision()
    if current is not None:
        try:
            script.get_revision(current)
        except Exception as exc:  # alembic raises its own lookup errors here
            raise SchemaTooNewError(
                f"the database's schema is at revision {current!r}, which this release does"
                f" not know (its newest is {head()!r}): it was migrated by a newer release;"
                " run that release, or restore a backup"
            ) from exc
    elif "sessions" in inspect(connection).get_table_names():
        command.stamp(_config(connection), FIRST)  # made before migrations existed
        current = FIRST
    command.upgrade(_config(connection), "head")
    return current or "empty"
