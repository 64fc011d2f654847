"""A :class:`~hardware_sim.client.RecognitionService` over HTTP, on the generated client.

:class:`HttpService` holds one session of a running ``tactile serve`` and talks
to it only through :mod:`hardware_sim.api_client` (generated from the service's
OpenAPI schema):

- :meth:`HttpService.create`: ``POST /v1/sessions`` (objects by registered name
  or inline §8 dictionaries, sensor bounds, safe circle, sensor position, strategy);
- :meth:`~HttpService.advise`: ``GET .../plan?limit=1`` from the sensor's current place;
- :meth:`~HttpService.observe`: ``POST .../observations`` with ``If-Match`` (the
  version this client holds) and a fresh ``Idempotency-Key`` per observation, so
  a retry after a lost answer never records the touch twice;
- :meth:`~HttpService.estimates`: ``GET /v1/sessions/{id}`` hypotheses.

Problem details (RFC 9457) become a :class:`ServiceError` subclass naming the
operation, the status and the offending field. World frame, angles in radians,
lengths in the object files' unit.

In tests the service runs in process: hand the generated client an httpx
transport to the app (``Client(base_url=...).set_httpx_client(TestClient(app))``).

>>> from hardware_sim.api_client import Client
>>> client = Client(base_url="http://127.0.0.1:8000")  # doctest: +SKIP
>>> service = HttpService.create(client, ["plate"], SensorBounds(1.0, 0.05),
...                              Workspace((0, 0), 200))  # doctest: +SKIP
>>> run_recognition(service, arm, max_touches=12)  # doctest: +SKIP
"""

from __future__ import annotations

import time
import uuid
from collections.abc import Callable, Mapping, Sequence
from typing import Any, TypeVar

import attrs
import httpx

from hardware_sim.api_client import Client
from hardware_sim.api_client.api.observations import add_observation
from hardware_sim.api_client.api.pictures import (
    get_image_png,
    get_image_svg,
    get_report_csv,
    get_report_json,
)
from hardware_sim.api_client.api.plan import get_plan
from hardware_sim.api_client.api.sessions import create_session, delete_session, get_session
from hardware_sim.api_client.models import (
    GetImagePngView,
    GetImageSvgView,
    ObservationIn,
    PlanOut,
    Problem,
    SessionCreate,
    SessionOut,
    StrategyIn,
)
from hardware_sim.api_client.types import UNSET, Response, Unset
from hardware_sim.client import Advice, Estimate, Update
from planner.codec import observation_to_dict, sensor_to_dict, workspace_to_dict
from planner.models.library import object_to_dict
from planner.types import ObjectModel, Observation, Pose, SensingPath, SensorBounds, Workspace

__all__ = [
    "ConflictError",
    "HttpService",
    "InvalidRequestError",
    "NotFoundError",
    "ServiceError",
    "ServiceUnavailableError",
    "StaleVersionError",
]

_T = TypeVar("_T")
#: Statuses worth retrying with the same request (and the same Idempotency-Key).
_TRANSIENT = (502, 503, 504)


class ServiceError(Exception):
    """The service did not give the expected answer.

    `operation` (e.g. ``POST /v1/sessions/{id}/observations``), HTTP `status` (0:
    no answer at all), `title` and `detail` of the problem, `field` (the offending
    input as the service names it, e.g. ``path.direction`` or ``If-Match``; None
    when not about one input), `problem` (the parsed problem details, if any)."""

    def __init__(
        self,
        operation: str,
        status: int,
        title: str,
        detail: str | None = None,
        field: str | None = None,
        problem: Problem | None = None,
    ) -> None:
        self.operation = operation
        self.status = status
        self.title = title
        self.detail = detail
        self.field = field
        self.problem = problem
        text = f"{operation}: {status} {title}" if status else f"{operation}: {title}"
        if detail:
            text += f": {detail}"
        if field:
            text += f" (field {field})"
        super().__init__(text)


class InvalidRequestError(ServiceError):
    """400 or 422: the request was malformed or a value out of bounds."""


class NotFoundError(ServiceError):
    """404: no such session (never created, or deleted)."""


class ConflictError(ServiceError):
    """409: conflicts with the session's state (a limit, nothing to undo, ...)."""


class StaleVersionError(ServiceError):
    """412: the session changed since this client last saw it (another writer)."""


class ServiceUnavailableError(ServiceError):
    """No usable answer after the retries: the connection failed, or 5xx."""


_BY_STATUS: dict[int, type[ServiceError]] = {
    400: InvalidRequestError,
    404: NotFoundError,
    409: ConflictError,
    412: StaleVersionError,
    422: InvalidRequestError,
}


def _problem_error(operation: str, response: Response[Any]) -> ServiceError:
    status = int(response.status_code)
    cls = _BY_STATUS.get(status, ServiceUnavailableError if status >= 500 else ServiceError)
    problem = response.parsed if isinstance(response.parsed, Problem) else None
    if problem is None:
        text = response.content.decode(errors="replace").strip()[:500]
        return cls(operation, status, response.status_code.phrase, text or None)
    errors = problem.errors if not isinstance(problem.errors, Unset) else []
    detail = problem.detail if isinstance(problem.detail, str) else None
    if detail is None and errors:
        detail = "; ".join(f"{e.field}: {e.message}" for e in errors)
    field = errors[0].field if errors else None
    return cls(operation, status, problem.title, detail, field, problem)


def _opt(value: Any) -> Any:
    return None if isinstance(value, Unset) else value


def _strategy(strategy: Mapping[str, Any] | None) -> dict[str, Any]:
    """The ``strategy`` member of a new session; unknown keys are refused here
    (the generated model would silently drop them)."""
    data = dict(strategy or {})
    known = {f.name for f in attrs.fields(StrategyIn)}
    unknown = sorted(set(data) - known)
    if unknown:
        raise ValueError(f"strategy.{unknown[0]}: unknown setting; one of {sorted(known)}")
    return data


class HttpService:
    """One session of a running service, as a :class:`RecognitionService`.

    `client`: the generated client (its base URL, timeouts and transport);
    `session`: the session as created (or fetched). `retries`: how often a request
    that got no answer (connection error, timeout) or a 502/503/504 is sent again,
    `backoff_s` the first pause (doubling). The version this client holds is the
    one of the last answer it got; an observation is sent with ``If-Match`` on it.
    """

    def __init__(
        self,
        client: Client,
        session: SessionOut,
        *,
        retries: int = 2,
        backoff_s: float = 0.2,
    ) -> None:
        if retries < 0:
            raise ValueError("retries must be >= 0")
        self.client = client
        self.session_id = uuid.UUID(session.id)
        self.version = session.version
        self.status = session.status.value
        self.retries = retries
        self.backoff_s = backoff_s

    # -- construction ----------------------------------------------------------------------
    @classmethod
    def create(
        cls,
        client: Client,
        objects: Sequence[str | Mapping[str, Any] | ObjectModel],
        bounds: SensorBounds,
        workspace: Workspace,
        *,
        sensor_position: Sequence[float] | None = None,
        strategy: Mapping[str, Any] | None = None,
        max_outliers: int = 0,
        retries: int = 2,
        backoff_s: float = 0.2,
    ) -> HttpService:
        """Start a session: `objects` by registered name, as §8 dictionaries or as
        planner models (sent inline); `strategy` as the service takes it, e.g.
        ``{"name": "pdm", "budget_ms": 1000, "seed": 7}``; `sensor_position` on the
        safe circle (default: its +x point)."""
        refs = [
            o if isinstance(o, str) else object_to_dict(o) if isinstance(o, ObjectModel) else o
            for o in objects
        ]
        body: dict[str, Any] = {
            "objects": refs,
            "sensor": sensor_to_dict(bounds),
            "workspace": workspace_to_dict(workspace),
            "strategy": _strategy(strategy),
            "max_outliers": max_outliers,
        }
        if sensor_position is not None:
            body["sensor_position"] = [float(v) for v in sensor_position]
        key = str(uuid.uuid4())
        operation = "POST /v1/sessions"
        session = cls._call(
            operation,
            lambda: create_session.sync_detailed(
                client=client, body=SessionCreate.from_dict(body), limit=0, idempotency_key=key
            ),
            201,
            retries,
            backoff_s,
        )
        return cls(client, session, retries=retries, backoff_s=backoff_s)

    @classmethod
    def attach(cls, client: Client, session_id: str | uuid.UUID, **kw: Any) -> HttpService:
        """An existing session (its current version becomes the one this client holds)."""
        sid = uuid.UUID(str(session_id))
        session = cls._call(
            "GET /v1/sessions/{id}",
            lambda: get_session.sync_detailed(sid, client=client, limit=0),
            200,
            kw.get("retries", 2),
            kw.get("backoff_s", 0.2),
        )
        return cls(client, session, **kw)

    # -- plumbing ----------------------------------------------------------------------------
    @staticmethod
    def _call(
        operation: str,
        send: Callable[[], Response[Any]],
        expected: int,
        retries: int,
        backoff_s: float,
    ) -> Any:
        """Send (again after a lost answer, a 5xx gateway error or a 409 "key in
        flight"), and answer the parsed body of the expected status or raise."""
        pause = backoff_s
        for attempt in range(retries + 1):
            last = attempt == retries
            try:
                response = send()
            except httpx.TransportError as exc:
                if last:
                    raise ServiceUnavailableError(operation, 0, f"no answer ({exc!r})") from exc
                time.sleep(pause)
                pause *= 2
                continue
            status = int(response.status_code)
            if status == expected and not isinstance(response.parsed, Problem):
                return response.parsed
            in_flight = status == 409 and _problem_slug(response) == "idempotency-key-in-flight"
            if not last and (status in _TRANSIENT or in_flight):
                time.sleep(_retry_after(response, pause))
                pause *= 2
                continue
            raise _problem_error(operation, response)
        raise AssertionError("unreachable")  # pragma: no cover

    def _send(self, operation: str, send: Callable[[], Response[Any]], expected: int) -> Any:
        return self._call(operation, send, expected, self.retries, self.backoff_s)

    # -- the RecognitionService protocol --------------------------------------------------
    def advise(self, sensor_position: Sequence[float]) -> Advice:
        """``GET .../plan?limit=1`` planned from `sensor_position`."""
        x, y = (float(v) for v in sensor_position)
        plan: PlanOut = self._send(
            "GET /v1/sessions/{id}/plan",
            lambda: get_plan.sync_detailed(
                self.session_id, client=self.client, limit=1, sensor_x=x, sensor_y=y
            ),
            200,
        )
        status = plan.status.value
        best = plan.paths[0] if plan.paths else None
        path = None if best is None else SensingPath(
            best.origin, best.direction, best.length, _height(best.height)
        )  # fmt: skip
        opening = best is None or status == "awaiting_contact"
        return Advice(
            status=status,
            path=path,
            p_distinguishing=None if opening else best.p_distinguishing,
            plan_ms=plan.elapsed_ms,
            truncated=plan.truncated,
            note=_opt(plan.note),
            expected_remaining=None if best is None else best.expected_remaining,
            p_forecast=None if opening else _opt(best.p_forecast),
            stopped_by=_opt(plan.stopped_by),
        )

    def observe(self, observation: Observation) -> Update:
        """``POST .../observations`` (``If-Match`` the held version, a new
        ``Idempotency-Key``); answers once the observation is stored durably."""
        body = observation_to_dict(observation)
        key = str(uuid.uuid4())
        held = f'"{self.version}"'
        state: SessionOut = self._send(
            "POST /v1/sessions/{id}/observations",
            lambda: add_observation.sync_detailed(
                self.session_id,
                client=self.client,
                body=ObservationIn.from_dict(body),
                limit=0,
                if_match=held,
                idempotency_key=key,
            ),
            201,
        )
        self.version = state.version
        self.status = state.status.value
        return Update(self.status, state.hypothesis_count, state.class_count)

    def answer_bound(self) -> float | None:
        """``GET /v1/sessions/{id}``: the bound of its ``localization``."""
        return self.answer(limit=1)[1]

    def estimates(self, limit: int | None = None) -> list[Estimate]:
        """``GET /v1/sessions/{id}``: the hypotheses, most probable first."""
        return self.answer(limit)[0]

    def answer(self, limit: int | None = None) -> tuple[list[Estimate], float | None]:
        """``GET /v1/sessions/{id}``, once: the hypotheses (most probable first) and
        the bound of its ``localization``."""
        state: SessionOut = self._send(
            "GET /v1/sessions/{id}",
            lambda: get_session.sync_detailed(
                self.session_id, client=self.client, limit=UNSET if limit is None else limit
            ),
            200,
        )
        bound = state.localization.bound
        estimates = [
            Estimate(
                h.object_,
                h.stable_pose,
                Pose(h.pose.x, h.pose.y, h.pose.theta),
                h.error_bound.eps_t,
                h.probability,
                h.equivalence_class,
                h.error_bound.translation,
            )
            for h in state.hypotheses
        ]
        return estimates, None if bound is None else float(bound.eps_t)

    # -- beyond the protocol -----------------------------------------------------------------
    def picture(self, fmt: str = "png", view: str = "vector") -> bytes:
        """The session's multi-interpretation image (``image.png`` or ``image.svg``;
        `view`: vector, grid or both)."""
        if fmt not in ("png", "svg"):
            raise ValueError("fmt must be 'png' or 'svg'")
        operation = f"GET /v1/sessions/{{id}}/image.{fmt}"
        if fmt == "png":
            kind = GetImagePngView(view)

            def send() -> Response[Any]:
                return get_image_png.sync_detailed(self.session_id, client=self.client, view=kind)
        else:
            kind_svg = GetImageSvgView(view)

            def send() -> Response[Any]:
                return get_image_svg.sync_detailed(
                    self.session_id, client=self.client, view=kind_svg
                )

        return self._content(operation, send)

    def report(self, fmt: str = "json") -> bytes:
        """The session's report (``report.json`` or ``report.csv``): each touch with its
        residuals, the answer with its bound, probability and status."""
        if fmt not in ("json", "csv"):
            raise ValueError("fmt must be 'json' or 'csv'")
        call = get_report_json if fmt == "json" else get_report_csv
        return self._content(
            f"GET /v1/sessions/{{id}}/report.{fmt}",
            lambda: call.sync_detailed(self.session_id, client=self.client),
        )

    def _content(self, operation: str, send: Callable[[], Response[Any]]) -> bytes:
        """The body of a 200 answer to `send`, retrying transport failures."""
        pause = self.backoff_s
        for attempt in range(self.retries + 1):
            try:
                response = send()
            except httpx.TransportError as exc:
                if attempt == self.retries:
                    raise ServiceUnavailableError(operation, 0, f"no answer ({exc!r})") from exc
                time.sleep(pause)
                pause *= 2
                continue
            if int(response.status_code) == 200:
                return response.content
            raise _problem_error(operation, response)
        raise AssertionError("unreachable")  # pragma: no cover

    def view_path(self) -> str:
        """The live viewer's path below the service's base URL."""
        return f"/v1/sessions/{self.session_id}/view"

    def delete(self) -> None:
        """``DELETE /v1/sessions/{id}`` (``If-Match`` the version this client holds)."""
        held = f'"{self.version}"'
        self._send(
            "DELETE /v1/sessions/{id}",
            lambda: delete_session.sync_detailed(
                self.session_id, client=self.client, if_match=held
            ),
            204,
        )


def _problem_slug(response: Response[Any]) -> str | None:
    problem = response.parsed
    if isinstance(problem, Problem) and isinstance(problem.type_, str):
        return problem.type_.rsplit(":", 1)[-1]
    return None


def _retry_after(response: Response[Any], default: float) -> float:
    try:
        return min(float(response.headers.get("retry-after", default)), 30.0)
    except ValueError:
        return default


def _height(value: object) -> float | None:
    """The plan's probing height (absent or null: the default height)."""
    return float(value) if isinstance(value, int | float) else None
