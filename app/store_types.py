"""What the store takes and gives: records, errors, and the database a ``--db`` value names."""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from sqlalchemy import URL, make_url

__all__ = [
    "IdempotentWrite",
    "ObjectConflictError",
    "SessionGoneError",
    "SessionRecord",
    "Snapshot",
    "StoreUnavailableError",
    "StoredResponse",
    "VersionConflictError",
    "database_label",
    "database_url",
    "is_url",
]

_URL_SCHEME = re.compile(r"^[A-Za-z][A-Za-z0-9+.\-]*://")


class VersionConflictError(Exception):
    """The session's version is not the one the write was computed for."""

    def __init__(self, current: int) -> None:
        super().__init__(f"session is at version {current}")
        self.current = current


class SessionGoneError(Exception):
    """The session does not exist (never created, or deleted)."""


class ObjectConflictError(Exception):
    """An object of that name with other geometry is already registered."""


class StoreUnavailableError(Exception):
    """The database cannot take the request now (locked, busy, down): retry later."""


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
class Snapshot:
    """Derived state after a session's first `n` observations, as opaque bytes."""

    code_version: str
    body: bytes


@dataclass(frozen=True)
class SessionRecord:
    """What a session is made of: configuration and ordered observations (JSON dicts),
    and the client whose key created it (``''``: anonymous)."""

    id: str
    version: int
    config: dict[str, Any]
    observations: tuple[dict[str, Any], ...]
    created_at: float
    owner: str = ""


def is_url(value: str | Path) -> bool:
    """True when `value` is written as a URL (``scheme://...``), never a file name."""
    return bool(_URL_SCHEME.match(str(value).strip()))


def database_label(target: str | Path) -> str:
    """The database of a ``--db`` value for a log line: a URL without its password
    (what :meth:`app.store.Store.describe` says of an open store).

    >>> database_label("postgresql://u:secret@db/tactile")
    'postgresql+psycopg://u:***@db/tactile'
    """
    return database_url(target).render_as_string(hide_password=True)


def database_url(target: str | Path) -> URL:
    """The SQLAlchemy URL of a ``--db`` value: a URL is taken as one (PostgreSQL, or
    ``sqlite:///file``), never as a file name; anything else is a SQLite file path.

    >>> database_url("postgresql://u:p@db:5432/tactile").drivername
    'postgresql+psycopg'
    >>> database_url("data/tactile.db").database
    'data/tactile.db'
    >>> database_url("mysql://u@h/db")
    Traceback (most recent call last):
    ...
    ValueError: unsupported database URL scheme 'mysql': give a postgresql:// URL or a file path
    """
    value = str(target).strip()
    if is_url(value):
        url = make_url(value)
        backend = url.get_backend_name()
        if backend in ("postgresql", "postgres"):
            return url.set(drivername="postgresql+psycopg")
        if backend == "sqlite" and url.database and ":memory:" not in url.database:
            return url.set(drivername="sqlite")
        raise ValueError(
            f"unsupported database URL scheme {url.drivername!r}:"
            " give a postgresql:// URL or a file path"
        )
    if value in ("", ":memory:") or "mode=memory" in value or value.startswith("file:"):
        raise ValueError("an in-memory SQLite database is not shared between threads")
    return URL.create("sqlite", database=value)
