"""What a browser is told about the service's answers, and which Host names it answers.

- Every answer says ``X-Content-Type-Options: nosniff`` (a JSON or text answer is
  never run as script or style) and ``Referrer-Policy: no-referrer``.
- Every answer that does not set its own ``Content-Security-Policy`` gets one
  that lets nothing load or run and no page frame it: a JSON, SVG or PNG
  answer opened in a browser stays inert. The viewer page sets its own
  (:data:`app.viewer.VIEW_CSP`: its inline script and style by hash, fetches
  to its own origin). The interactive documentation pages, which load their
  scripts from elsewhere, keep the browser's default.
- With API keys, the schema, the documentation pages and the metrics need one
  of them too (``public_docs`` opens them): they tell a stranger every operation and how
  busy the service is.
- With ``allowed_hosts`` set, a request whose ``Host`` is not in it is refused
  with 400 problem+json naming the setting. A page on another site that makes
  the browser resolve its own name to the service's loopback address (DNS
  rebinding) then reaches nothing; ``tactile serve`` sets the loopback names
  when it binds to a loopback address and the setting is unset.
"""

from __future__ import annotations

import ipaddress
from collections.abc import Iterable

from starlette.requests import Request
from starlette.responses import JSONResponse
from starlette.types import ASGIApp, Message, Receive, Scope, Send

from app.access import Clients
from app.errors import problem_response

__all__ = [
    "LOOPBACK_NAMES",
    "STRICT_CSP",
    "DocumentsKeyMiddleware",
    "HostAllowListMiddleware",
    "SecurityHeadersMiddleware",
    "host_name",
    "is_loopback",
]

#: The policy of every answer that sets none: nothing loads, nothing runs, no framing.
STRICT_CSP = "default-src 'none'; frame-ancestors 'none'; base-uri 'none'; form-action 'none'"
#: Paths whose pages load their scripts from elsewhere (Swagger UI, ReDoc).
_DOCUMENTATION = ("/docs", "/redoc")
#: The Host names a loopback bind answers.
LOOPBACK_NAMES = ("localhost", "127.0.0.1", "::1")


class SecurityHeadersMiddleware:
    """Add nosniff, no-referrer and (unless the answer has one) the strict policy."""

    def __init__(self, app: ASGIApp) -> None:
        self.app = app

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        documentation = scope["path"].startswith(_DOCUMENTATION)

        async def send_with_headers(message: Message) -> None:
            if message["type"] == "http.response.start":
                headers = list(message.get("headers", []))
                names = {name.lower() for name, _ in headers}
                extra = [
                    (b"x-content-type-options", b"nosniff"),
                    (b"referrer-policy", b"no-referrer"),
                ]
                if not documentation:
                    extra.append((b"content-security-policy", STRICT_CSP.encode()))
                headers += [(k, v) for k, v in extra if k not in names]
                message = {**message, "headers": headers}
            await send(message)

        await self.app(scope, receive, send_with_headers)


def host_name(header: str) -> str:
    """The name in a Host header, lower case, without port or IPv6 brackets.

    >>> host_name("LocalHost:8000"), host_name("[::1]:8000"), host_name("127.0.0.1")
    ('localhost', '::1', '127.0.0.1')
    """
    header = header.strip().lower()
    if header.startswith("["):
        return header[1 : header.find("]")] if "]" in header else header
    return header.rsplit(":", 1)[0] if header.count(":") == 1 else header


def is_loopback(host: str) -> bool:
    """Whether a bind address is a loopback one (``localhost`` counts).

    >>> is_loopback("127.0.0.1"), is_loopback("::1"), is_loopback("0.0.0.0")
    (True, True, False)
    """
    if host_name(host) == "localhost":
        return True
    try:
        return ipaddress.ip_address(host_name(host)).is_loopback
    except ValueError:
        return False


def _header(scope: Scope, name: bytes) -> bytes:
    return dict(scope.get("headers") or []).get(name, b"")


class _Gate:
    """An ASGI middleware answering the HTTP requests it does not admit with a problem."""

    def __init__(self, app: ASGIApp) -> None:
        self.app = app

    def admits(self, scope: Scope) -> bool:
        raise NotImplementedError

    def refusal(self, scope: Scope) -> JSONResponse:
        raise NotImplementedError

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http" or self.admits(scope):
            await self.app(scope, receive, send)
        else:
            await self.refusal(scope)(scope, receive, send)


class HostAllowListMiddleware(_Gate):
    """Refuse requests whose Host header names none of `allowed` (``"*"``: any)."""

    def __init__(self, app: ASGIApp, allowed: Iterable[str]) -> None:
        super().__init__(app)
        self.allowed = frozenset(host_name(h) for h in allowed)

    def admits(self, scope: Scope) -> bool:
        given = _header(scope, b"host").decode("latin-1")
        return "*" in self.allowed or host_name(given) in self.allowed

    def refusal(self, scope: Scope) -> JSONResponse:
        given = _header(scope, b"host").decode("latin-1")
        return problem_response(
            Request(scope),
            400,
            title="Host not allowed",
            slug="host-not-allowed",
            detail=f"Host {given[:100]!r} is not in the allowed_hosts setting "
            f"({', '.join(sorted(self.allowed))})",
        )


#: Paths outside /v1 that answer only with the API key (when the service has one).
KEYED_PATHS = ("/docs", "/redoc", "/openapi.json", "/metrics")


class DocumentsKeyMiddleware(_Gate):
    """401 problem for the schema, documentation and metrics without the API key."""

    def __init__(self, app: ASGIApp, clients: Clients) -> None:
        super().__init__(app)
        self.clients = clients

    def admits(self, scope: Scope) -> bool:
        if not scope["path"].startswith(KEYED_PATHS):
            return True
        scheme, _, given = _header(scope, b"authorization").decode("latin-1").partition(" ")
        return scheme.lower() == "bearer" and self.clients.client_of(given.strip()) is not None

    def refusal(self, scope: Scope) -> JSONResponse:
        return problem_response(
            Request(scope),
            401,
            title="Unauthorized",
            slug="unauthorized",
            detail="the schema, documentation and metrics need the API key "
            "(Authorization: Bearer <key>), unless public_docs is set",
            headers={"WWW-Authenticate": 'Bearer realm="tactile"'},
        )
