"""What the routes call: stored sessions -> planner sessions -> answers.

The planner does the work (:class:`planner.recognition.session.Session` derives the
hypotheses, :func:`planner.planning.strategies.plan` ranks paths, :mod:`planner.render`
draws); this module only moves data between the store, the planner and JSON,
and decides where work runs:

- CPU work (fits, plans, pictures) runs in worker threads behind one
  :class:`anyio.CapacityLimiter` (``cpu_workers``); encoding an answer behind a
  second one of the same size, so that a read does not wait behind plans; SQLite
  calls run in threads behind a third (``db_pool_size``); the event loop never
  blocks. A request makes as few trips to the CPU workers as it can (under load
  each trip waits for a free worker).
- A CPU job still running after ``cpu_job_deadline_s`` is stopped: 503 (:mod:`app.deadline`).
- One lock per session id: two requests on one session never compute on stale
  state; across worker processes the store's version compare-and-swap does the
  same (a lost race is recomputed, or answered 412 when the client sent If-Match).
- Derived sessions and plans are cached per (id, version) in small LRUs.
"""

from __future__ import annotations

import json
import uuid
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Any, TypeVar

import anyio
import anyio.to_thread

from app.cache import LRU, KeyedLocks
from app.convert import (
    build_session,
    derive,
    draw,
    etag,
    extends,
    idempotent_write,
    if_match_ok,
    next_state,
    observed,
    plan_json,
    plan_rng,
    resume,
    session_json,
    strategy_config,
    to_json,
)
from app.deadline import run_stopped_at
from app.errors import (
    ConflictError,
    IdempotencyInFlightError,
    IdempotencyMismatchError,
    LimitExceededError,
    NotFoundError,
    PreconditionFailedError,
    UnavailableError,
)
from app.mesh_upload import mesh_object
from app.schemas import InputModels
from app.session_config import resolve_models, session_config
from app.settings import Settings
from app.store import Store
from app.store_types import (
    IdempotentWrite,
    SessionGoneError,
    SessionRecord,
    Snapshot,
    StoredResponse,
    VersionConflictError,
)
from planner.codec import observation_from_dict, observation_to_dict
from planner.errors import PlannerError
from planner.models.library import object_from_dict, object_to_dict
from planner.planning.plan import plan_session
from planner.planning.result import Plan
from planner.recognition.session import Session
from planner.recognition.snapshot import code_version

__all__ = ["Answer", "SessionService"]

_T = TypeVar("_T")
#: Retries of a write that lost the version race to another process (no If-Match).
_CAS_ATTEMPTS = 8


@dataclass(frozen=True)
class Answer:
    """A finished response: status, JSON body bytes and headers (ETag, Location, ...)."""

    status: int
    body: bytes
    headers: dict[str, str]
    replayed: bool = False


class SessionService:
    """Sessions over a :class:`Store`, with the planner doing the work in threads."""

    def __init__(self, settings: Settings, store: Store, inputs: InputModels) -> None:
        self.settings = settings
        self.store = store
        self.inputs = inputs
        self.cpu = anyio.CapacityLimiter(settings.cpu_workers)
        self.db = anyio.CapacityLimiter(settings.db_pool_size)
        self.light = anyio.CapacityLimiter(settings.cpu_workers)
        self.locks = KeyedLocks()
        self.sessions: LRU[tuple[str, int], Session] = LRU(settings.session_cache_size)
        self.plans: LRU[tuple[Any, ...], Plan] = LRU(settings.plan_cache_size)
        # plans being computed, by cache key: a second request for the same plan waits
        # for the first instead of computing it again
        self._planning: dict[tuple[Any, ...], anyio.Event] = {}
        self.pictures: LRU[tuple[Any, ...], bytes] = LRU(16)
        # who owns each session: never changes, so kept without expiry (bounded)
        self.owners: LRU[str, str] = LRU(max(1024, settings.session_cache_size))
        self._in_flight: set[tuple[str, str]] = set()

    # -- running work off the event loop ----------------------------------------------------
    async def run_cpu(self, fn: Callable[..., _T], *args: Any) -> _T:
        """Run `fn` on a CPU worker; when `max_cpu_queue` jobs already wait for one,
        answer 503 with Retry-After instead of queueing without end."""
        waiting = self.cpu.statistics().tasks_waiting
        if self.cpu.available_tokens == 0 and waiting >= self.settings.max_cpu_queue:
            raise UnavailableError(
                f"busy: {waiting} fits and plans wait for a CPU worker "
                f"(max_cpu_queue {self.settings.max_cpu_queue}); retry shortly",
                headers={"Retry-After": "1"},
            )
        return await run_stopped_at(self.settings.cpu_job_deadline_s, fn, *args, limiter=self.cpu)

    async def run_light(self, fn: Callable[..., _T], *args: Any) -> _T:
        """Short CPU work (encoding an answer) that should not queue behind plans."""
        return await anyio.to_thread.run_sync(fn, *args, limiter=self.light)

    async def run_db(self, fn: Callable[..., _T], *args: Any) -> _T:
        return await anyio.to_thread.run_sync(fn, *args, limiter=self.db)

    @contextmanager
    def _claim(self, scope: str, key: str | None) -> Iterator[None]:
        """Mark an idempotency key as in flight (a second request with it gets 409)."""
        if key is None:
            yield
            return
        if (scope, key) in self._in_flight:
            raise IdempotencyInFlightError(
                "a request with this Idempotency-Key is still being processed; retry later",
                field="Idempotency-Key",
                headers={"Retry-After": "1"},
            )
        self._in_flight.add((scope, key))
        try:
            yield
        finally:
            self._in_flight.discard((scope, key))

    @staticmethod
    def _replay(stored: StoredResponse, fp: str) -> Answer:
        if stored.fingerprint != fp:
            raise IdempotencyMismatchError(
                "this Idempotency-Key was used with another request body",
                field="Idempotency-Key",
            )
        return Answer(stored.status, stored.body, dict(stored.headers), replayed=True)

    async def record(self, session_id: str) -> SessionRecord:
        """The stored session (one read, nothing derived); 404 when there is none."""
        record = await self.run_db(self.store.get_session, session_id)
        if record is None:
            raise NotFoundError(f"no session {session_id}", field="id")
        return record

    async def owner_of(self, session_id: str) -> str | None:
        """The client owning the session; None when there is no such session."""
        owner = self.owners.get(session_id)
        if owner is None:
            owner = await self.run_db(self.store.session_owner, session_id)
            if owner is not None:
                self.owners.put(session_id, owner)
        return owner

    async def _session(self, record: SessionRecord) -> Session:
        """The derived session of a record (cached per version; caller holds the lock).

        On a miss (another worker process or host wrote the newer versions, or this
        one restarted) the newest of the cached versions and the stored snapshots
        whose observations begin the record's is extended by the missing ones,
        instead of re-deriving the whole tree from the first observation."""
        key = (record.id, record.version)
        session = self.sessions.get(key)
        if session is None:
            base = self._newest_prefix(record)
            n = len(record.observations)
            stored = None
            if base is None or len(base.observations) < n:  # another host may have it
                found = await self.run_db(self.store.get_snapshot, record.id, code_version(), n)
                if found is not None and (base is None or found[0] > len(base.observations)):
                    stored = found[1]
            session = await self.run_cpu(resume, base, stored, record)
            self.sessions.put(key, session)
        return session

    def _newest_prefix(self, record: SessionRecord) -> Session | None:
        mine = [s for (sid, _), s in self.sessions.items() if sid == record.id]
        usable = [s for s in mine if extends(s, record)]
        return max(usable, key=lambda s: len(s.observations), default=None)

    def _forget(self, session_id: str) -> None:
        self.sessions.drop(lambda k: k[0] == session_id)
        self.plans.drop(lambda k: k[0] == session_id)
        self.pictures.drop(lambda k: k[0] == session_id)

    # -- objects ----------------------------------------------------------------------------
    async def register_object(self, data: dict[str, Any], owner: str) -> tuple[bool, str]:
        try:
            model = await self.run_cpu(object_from_dict, data)
        except PlannerError as exc:  # name fields from the body's root, like validation does
            field = (exc.field or "").removeprefix("object").removeprefix(".") or None
            raise type(exc)(exc.message, field=field) from exc
        created = await self.run_db(self.store.put_object, model.name, object_to_dict(model), owner)
        return created, model.name

    async def import_mesh(
        self,
        data: bytes,
        file_type: str,
        heights: tuple,
        name: str,
        max_poses: int | None,
        owner: str,
    ) -> tuple[bool, str]:
        """Register the object model of an uploaded triangle mesh (:func:`mesh_object`)."""
        stored = await self.run_cpu(
            mesh_object, data, file_type, heights, name, max_poses, self.settings, self.inputs
        )
        created = await self.run_db(self.store.put_object, stored["name"], stored, owner)
        return created, stored["name"]

    # -- sessions ---------------------------------------------------------------------------
    async def _stored_objects(
        self, refs: Sequence[str | dict[str, Any]], owner: str
    ) -> dict[str, Any]:
        names = [r for r in refs if isinstance(r, str)]
        return await self.run_db(self.store.get_objects, names, owner) if names else {}

    async def create_session(
        self, body: dict[str, Any], idem_key: str | None, fp: str, limit: int | None, owner: str
    ) -> Answer:
        # a key another client used replays nothing of theirs
        scope = f"sessions:{owner}" if owner else "sessions"
        with self._claim(scope, idem_key):
            if idem_key and (old := await self.run_db(self.store.get_idempotent, scope, idem_key)):
                return self._replay(old, fp)
            stored = await self._stored_objects(body["objects"], owner)

            def prepare() -> tuple[SessionRecord, Session, bytes]:
                # one trip to the CPU workers: under load each trip waits behind plans
                worked = self.settings.max_worked_vertices
                cfg = session_config(body, resolve_models(body["objects"], stored), worked)
                record = SessionRecord(str(uuid.uuid4()), 1, cfg, (), 0.0, owner)
                session = derive(build_session(record))
                return record, session, session_json(record.id, 1, cfg, session, limit)

            record, session, answer_body = await self.run_cpu(prepare)
            headers = {"ETag": etag(1), "Location": f"/v1/sessions/{record.id}"}
            answer = Answer(201, answer_body, headers)
            idem = idempotent_write(scope, idem_key, fp, answer)
            if (old := await self.run_db(self.store.create_session, record, idem)) is not None:
                return self._replay(old, fp)
            self.sessions.put((record.id, 1), session)
            self.owners.put(record.id, owner)
            return answer

    async def get_session(self, session_id: str, limit: int | None) -> Answer:
        async with self.locks.hold(session_id):
            record = await self.record(session_id)
            session = await self._session(record)
        body = await self.run_light(
            session_json, session_id, record.version, record.config, session, limit
        )
        return Answer(200, body, {"ETag": etag(record.version)})

    async def _mutate(
        self,
        session_id: str,
        scope: str,
        idem_key: str | None,
        fp: str,
        if_match: str | None,
        step: Callable[[SessionRecord, Session], Session],
        write: Callable[
            [SessionRecord, IdempotentWrite | None, Snapshot | None], StoredResponse | None
        ],
        status: int,
        limit: int | None,
        keep: bool = True,
    ) -> Answer:
        """Compute the next state from the current one and store it (CAS on version)."""
        with self._claim(scope, idem_key):
            async with self.locks.hold(session_id):
                old = idem_key and await self.run_db(self.store.get_idempotent, scope, idem_key)
                if old:
                    return self._replay(old, fp)
                for _ in range(_CAS_ATTEMPTS):
                    record = await self.record(session_id)
                    if not if_match_ok(if_match, record.version):
                        raise PreconditionFailedError(
                            f"session is at version {record.version} ({etag(record.version)})",
                            field="If-Match",
                            headers={"ETag": etag(record.version)},
                        )
                    current = await self._session(record)
                    version = record.version + 1
                    new, body, snap = await self.run_cpu(
                        next_state, record, current, step, limit, keep
                    )
                    answer = Answer(status, body, {"ETag": etag(version)})
                    idem = idempotent_write(scope, idem_key, fp, answer)
                    try:
                        old = await self.run_db(write, record, idem, snap)
                    except VersionConflictError as exc:
                        if if_match is not None:
                            raise PreconditionFailedError(
                                f"session is at version {exc.current}",
                                field="If-Match",
                                headers={"ETag": etag(exc.current)},
                            ) from exc
                        continue  # another process wrote first: recompute on its state
                    except SessionGoneError as exc:
                        self._forget(session_id)
                        raise NotFoundError(f"no session {session_id}", field="id") from exc
                    if old is not None:
                        return self._replay(old, fp)
                    self.sessions.put((session_id, version), new)
                    return answer
                raise ConflictError("the session kept changing; retry", field="id")

    async def add_observation(
        self,
        session_id: str,
        body: dict[str, Any],
        idem_key: str | None,
        fp: str,
        if_match: str | None,
        limit: int | None,
    ) -> Answer:
        observation = observation_from_dict(body)  # planner checks: zero vectors, behind origin
        stored = observation_to_dict(observation)
        cap = self.settings.max_observations_per_session
        most, work = self.settings.max_hypotheses, self.settings.max_interpretation_work

        def step(record: SessionRecord, session: Session) -> Session:
            if len(record.observations) >= cap:
                raise LimitExceededError(
                    f"a session holds at most {cap} observations", field="observations"
                )
            return observed(session, observation, most, work)

        def write(
            record: SessionRecord, idem: IdempotentWrite | None, snap: Snapshot | None
        ) -> StoredResponse | None:
            return self.store.append_observation(session_id, record.version, stored, idem, snap)

        return await self._mutate(
            session_id, f"sessions/{session_id}/observations", idem_key, fp, if_match, step,
            write, 201, limit,
        )  # fmt: skip

    async def undo(
        self,
        session_id: str,
        idem_key: str | None,
        fp: str,
        if_match: str | None,
        limit: int | None,
    ) -> Answer:
        def step(record: SessionRecord, session: Session) -> Session:
            if not record.observations:
                raise ConflictError("the session has no observation to undo", field="observations")
            return session.undo()

        def write(
            record: SessionRecord, idem: IdempotentWrite | None, _snap: Snapshot | None
        ) -> StoredResponse | None:
            return self.store.drop_last_observation(session_id, record.version, idem)

        # the state undone to is the snapshot before the last one, already stored
        return await self._mutate(
            session_id, f"sessions/{session_id}/undo", idem_key, fp, if_match, step, write,
            200, limit, keep=False,
        )  # fmt: skip

    async def delete_session(self, session_id: str, if_match: str | None) -> None:
        async with self.locks.hold(session_id):
            record = await self.record(session_id)
            if not if_match_ok(if_match, record.version):
                raise PreconditionFailedError(
                    f"session is at version {record.version}",
                    field="If-Match",
                    headers={"ETag": etag(record.version)},
                )
            expected = None if if_match is None else record.version
            try:
                await self.run_db(self.store.delete_session, session_id, expected)
            except VersionConflictError as exc:
                raise PreconditionFailedError(
                    f"session is at version {exc.current}", field="If-Match"
                ) from exc
            except SessionGoneError as exc:
                raise NotFoundError(f"no session {session_id}", field="id") from exc
            finally:
                self._forget(session_id)

    # -- plans and pictures -----------------------------------------------------------------
    async def _plan(
        self,
        record: SessionRecord,
        session: Session,
        position: tuple[float, float] | None = None,
    ) -> Plan:
        """The plan for the record's version from `position` (None: the session's
        sensor_position), cached per (id, version, position) and computed once at a
        time per key. Runs without the session's lock: a plan is a function of one
        version, and observations must not wait for it."""
        key = (record.id, record.version, position)
        while (cached := self.plans.get(key)) is None and key in self._planning:
            await self._planning[key].wait()
        if cached is not None:
            return cached
        done = self._planning[key] = anyio.Event()
        try:
            cfg = record.config
            rng = plan_rng(record.id, record.version, cfg["strategy"].get("seed"))
            sensor_position = cfg["sensor_position"] if position is None else list(position)
            result = await self.run_cpu(
                lambda: plan_session(session, sensor_position, strategy_config(cfg), rng)
            )
            self.plans.put(key, result)
            return result
        finally:
            del self._planning[key]
            done.set()

    async def get_plan(self, session_id: str, limit: int, position: tuple | None = None) -> Answer:
        """The plan from `position` (None, or a None coordinate: the session's)."""
        async with self.locks.hold(session_id):  # the state only; the plan is computed after
            record = await self.record(session_id)
            session = await self._session(record)
        if position is not None:
            home = record.config["sensor_position"]
            position = tuple(home[i] if v is None else v for i, v in enumerate(position))
        result = await self._plan(record, session, position)
        body = plan_json(result, record.version, limit)
        return Answer(200, body, {"ETag": etag(record.version)})

    async def picture(self, session_id: str, kind: str, view: str, dpi: int) -> Answer:
        async with self.locks.hold(session_id):  # the state only: observations go on
            record = await self.record(session_id)
            key = (session_id, record.version, kind, view, dpi)
            image = self.pictures.get(key)
            if image is None:
                session = await self._session(record)
        if image is None:
            result = await self._plan(record, session)
            image = await self.run_cpu(draw, session, result, record, kind, view, dpi)
            self.pictures.put(key, image)
        media = "image/svg+xml" if kind == "svg" else "image/png"
        return Answer(200, image, {"ETag": etag(record.version), "Content-Type": media})

    async def report(self, session_id: str, kind: str) -> Answer:
        """The session's report (:mod:`planner.report`) as JSON or CSV."""
        from planner.report import report_csv, session_report

        async with self.locks.hold(session_id):
            record = await self.record(session_id)
            session = await self._session(record)
        data = await self.run_light(session_report, session)
        headers = {"ETag": etag(record.version)}
        if kind == "csv":
            headers["Content-Type"] = "text/csv; charset=utf-8"
            return Answer(200, report_csv(data).encode(), headers)
        body = to_json({"id": session_id, "version": record.version, **data})
        return Answer(200, body, headers)

    async def image_json(self, session_id: str) -> Answer:
        """The MII's world geometry as JSON (cached per version), for the live viewer."""
        from app.viewer import mii_json

        async with self.locks.hold(session_id):  # the state only: observations go on
            record = await self.record(session_id)
            key = (session_id, record.version, "json")
            body = self.pictures.get(key)
            if body is None:
                session = await self._session(record)
        if body is None:
            data = await self.run_cpu(mii_json, session, record.config["sensor_position"])
            body = json.dumps(data).encode()
            self.pictures.put(key, body)
        return Answer(200, body, {"ETag": etag(record.version)})
