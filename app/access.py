"""Who is asking: the service's API keys and the client each one names.

A service may hold several keys, one per client (a robot cell, a test rig, an
operator's laptop): ``api_keys`` maps client names to keys (environment
``TACTILE_API_KEYS`` as a JSON object), and ``api_keys_file`` names a JSON file of
the same form, so that keys need not sit in the environment. The single
``api_key`` of earlier releases is the client ``''``, which also owns everything
stored before sessions and objects had owners.

Each session and each object belongs to the client whose key created it; another
client's key finds neither (404, as for an id that does not exist) and may
register an object of the same name. With no key at all the service is open and
every request is the anonymous client ``''``.

>>> c = Clients({"cell-1": "k1", "rig": "k2"})
>>> c.client_of("k2"), c.client_of("nope"), c.key_of("cell-1"), c.keyed
('rig', None, 'k1', True)
"""

from __future__ import annotations

import hashlib
import json
import re
from collections.abc import Mapping
from pathlib import Path

from app.settings import Settings

__all__ = ["ANONYMOUS", "CLIENT_PATTERN", "Clients", "load_clients"]

#: The client of an open service, and of the single ``api_key``.
ANONYMOUS = ""
#: What a client may be called (it is stored with what it owns and logged).
CLIENT_PATTERN = re.compile(r"^[A-Za-z0-9][A-Za-z0-9_.@-]{0,63}$")


def _digest(key: str) -> bytes:
    return hashlib.sha256(key.encode()).digest()


class Clients:
    """The keys a service accepts, each naming its client."""

    def __init__(self, keys: Mapping[str, str]) -> None:
        by_digest: dict[bytes, str] = {}
        for client, key in keys.items():
            if client != ANONYMOUS and not CLIENT_PATTERN.match(client):
                raise ValueError(
                    f"client name {client[:80]!r}: letters, digits and _.@- (at most 64)"
                )
            if not key or key != key.strip() or any(ch.isspace() for ch in key):
                raise ValueError(f"the key of client {client!r} is empty or holds white space")
            if by_digest.setdefault(_digest(key), client) != client:
                raise ValueError(f"clients {by_digest[_digest(key)]!r} and {client!r} share a key")
        self._by_digest = by_digest
        self._keys = dict(keys)

    @property
    def keyed(self) -> bool:
        """Whether the service needs a key at all."""
        return bool(self._keys)

    def client_of(self, given: str) -> str | None:
        """The client whose key `given` is; None for no key of this service.

        The given key is compared by its SHA-256 digest: the lookup's time says
        nothing about how much of a key a guess got right."""
        return self._by_digest.get(_digest(given)) if given else None

    def key_of(self, client: str) -> str | None:
        """The key of `client` (viewer links are signed with it)."""
        return self._keys.get(client)


def _keys_file(path: Path) -> dict[str, str]:
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise ValueError(f"api_keys_file {str(path)!r}: {exc}") from exc
    if not isinstance(data, dict) or not all(
        isinstance(k, str) and isinstance(v, str) for k, v in data.items()
    ):
        raise ValueError(f"api_keys_file {str(path)!r}: give a JSON object {{client: key}}")
    return data


def load_clients(settings: Settings) -> Clients:
    """Every key of `settings`: ``api_key`` (the client ``''``), ``api_keys`` and the
    file ``api_keys_file``. A client named twice, or a key given to two clients, is
    a configuration error (ValueError), found at start-up."""
    keys: dict[str, str] = {}
    if settings.api_key is not None:
        keys[ANONYMOUS] = settings.api_key.get_secret_value()
    given = {c: k.get_secret_value() for c, k in (settings.api_keys or {}).items()}
    if settings.api_keys_file is not None:
        from_file = _keys_file(settings.api_keys_file)
        if twice := sorted(set(from_file) & set(given)):
            raise ValueError(f"client {twice[0]!r} is in both api_keys and api_keys_file")
        given |= from_file
    if ANONYMOUS in given:
        raise ValueError("a client needs a name (the single api_key is the unnamed one)")
    return Clients(keys | given)
