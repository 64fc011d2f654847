"""Short-lived links to one session's viewer when the service has an API key.

A browser cannot send the key in a header when it opens a page, and a key in a
URL would open every session to whoever sees the link. So a client holding the
key asks for a link (POST .../view-link): its token names one session and an
expiry, signed with HMAC-SHA256 under the key. The token opens that session's
page and the reads the page makes (the session, its image geometry, its plan),
until it expires, and nothing else: no write, no other session.
"""

from __future__ import annotations

import base64
import hashlib
import hmac

__all__ = ["VIEWER_READS", "check_token", "make_token"]

#: The operations a viewer token opens (GET only, on the token's session).
VIEWER_READS = frozenset({"get_view", "get_session", "get_image_json", "get_plan"})


def _signature(key: str, session_id: str, expires: int) -> str:
    mac = hmac.new(key.encode(), f"view:{session_id}:{expires}".encode(), hashlib.sha256)
    return base64.urlsafe_b64encode(mac.digest()).decode().rstrip("=")


def make_token(key: str, session_id: str, expires: int) -> str:
    """``<expires>.<signature>``: opens `session_id`'s viewer until `expires` (Unix s).

    >>> t = make_token("k", "s1", 2_000_000_000)
    >>> check_token("k", t, "s1", now=1_900_000_000), check_token("k", t, "s2", now=0)
    (True, False)
    """
    return f"{int(expires)}.{_signature(key, session_id, int(expires))}"


def check_token(key: str, token: str, session_id: str, now: float) -> bool:
    """Whether `token` was made under `key` for `session_id` and has not expired."""
    expires, _, signature = token.partition(".")
    if not expires.isdigit() or len(expires) > 12 or int(expires) < now:
        return False
    return hmac.compare_digest(signature, _signature(key, session_id, int(expires)))
