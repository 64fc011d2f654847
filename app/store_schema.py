"""The store's tables (SQLAlchemy Core), as the newest migration leaves them.

The migrations in :mod:`app.migrations` create and change the schema; these
definitions are what the queries of :mod:`app.store` are written against, and a
test checks that the two agree on both backends.
"""

from __future__ import annotations

from sqlalchemy import (
    Column,
    Float,
    ForeignKey,
    Index,
    Integer,
    LargeBinary,
    MetaData,
    PrimaryKeyConstraint,
    String,
    Table,
    Text,
)

__all__ = ["idempotency", "metadata", "objects", "observations", "sessions", "snapshots"]

metadata = MetaData()

#: Objects are named per owner (the client whose key registered them; ``''``: anonymous).
objects = Table(
    "objects",
    metadata,
    Column("owner", Text, nullable=False, server_default=""),
    Column("name", Text, nullable=False),
    Column("body", Text, nullable=False),
    Column("created_at", Float, nullable=False),
    PrimaryKeyConstraint("owner", "name", name="objects_owner_name_pkey"),
)

sessions = Table(
    "sessions",
    metadata,
    Column("id", Text, primary_key=True),
    Column("version", Integer, nullable=False),
    Column("config", Text, nullable=False),
    Column("created_at", Float, nullable=False),
    Column("updated_at", Float, nullable=False),
    Column("owner", Text, nullable=False, server_default=""),
    Index("sessions_updated_at", "updated_at"),
)

observations = Table(
    "observations",
    metadata,
    Column("session_id", Text, ForeignKey("sessions.id", ondelete="CASCADE"), primary_key=True),
    Column("seq", Integer, primary_key=True, autoincrement=False),
    Column("body", Text, nullable=False),
    Column("version", Integer, nullable=False),
    Column("created_at", Float, nullable=False),
    sqlite_with_rowid=False,
)

idempotency = Table(
    "idempotency",
    metadata,
    Column("scope", Text, primary_key=True),
    Column("key", Text, primary_key=True),
    Column("fingerprint", Text, nullable=False),
    Column("status", Integer, nullable=False),
    Column("headers", Text, nullable=False),
    Column("body", LargeBinary, nullable=False),
    Column("session_id", Text),
    Column("created_at", Float, nullable=False),
    Index("idempotency_session", "session_id"),
    Index("idempotency_created_at", "created_at"),
    sqlite_with_rowid=False,
)

#: The derived state of a session after its first `n` observations (see
#: :mod:`planner.recognition.snapshot`), tagged with the code version that wrote it.
snapshots = Table(
    "snapshots",
    metadata,
    Column("session_id", Text, ForeignKey("sessions.id", ondelete="CASCADE"), primary_key=True),
    Column("n", Integer, primary_key=True, autoincrement=False),
    Column("code_version", String(64), nullable=False),
    Column("body", LargeBinary, nullable=False),
    Column("created_at", Float, nullable=False),
    sqlite_with_rowid=False,
)
