"""Concurrent writers on one session: optimistic concurrency, per-session serialization,
and idempotent retries (the store itself: test_store.py)."""

from __future__ import annotations

import importlib
import threading
import time
from concurrent.futures import ThreadPoolExecutor

import pytest

from tests.app.api_support import BOTTOM, api, create_session, is_problem, miss

THREADS = 8
PER_THREAD = 3


@pytest.fixture
def client(tmp_path, db_target):
    with api(tmp_path, cpu_workers=2, db=db_target) as c:
        yield c


def _origins(client, sid):
    state = client.get(f"/v1/sessions/{sid}").json()
    return [round(o["path"]["origin"][1], 4) for o in state["observations"]], state


def test_if_match_writers_with_retry_on_412_all_land_once(client):
    sid = create_session(client)["id"]
    url = f"/v1/sessions/{sid}"
    stale = [0]
    lock = threading.Lock()

    def writer(t: int) -> list[int]:
        versions = []
        for j in range(PER_THREAD):
            k = t * PER_THREAD + j
            while True:
                etag = client.get(url).headers["etag"]
                r = client.post(f"{url}/observations", json=miss(k), headers={"If-Match": etag})
                if r.status_code == 412:
                    with lock:
                        stale[0] += 1
                    continue
                assert r.status_code == 201, r.text
                versions.append(r.json()["version"])
                break
        return versions

    with ThreadPoolExecutor(THREADS) as pool:
        versions = [v for vs in pool.map(writer, range(THREADS)) for v in vs]

    total = THREADS * PER_THREAD
    assert sorted(versions) == list(range(2, total + 2))  # every write got its own version
    origins, state = _origins(client, sid)
    assert state["version"] == total + 1
    expected = sorted(round(-9 + 0.001 * k, 4) for k in range(total))
    assert sorted(origins) == expected  # all landed, none twice


def test_writers_without_if_match_are_serialized_per_session(client):
    sid = create_session(client)["id"]

    def writer(k: int) -> int:
        r = client.post(f"/v1/sessions/{sid}/observations", json=miss(k))
        assert r.status_code == 201, r.text
        assert len(r.json()["observations"]) == r.json()["version"] - 1
        return r.json()["version"]

    with ThreadPoolExecutor(THREADS) as pool:
        versions = list(pool.map(writer, range(2 * THREADS)))
    assert sorted(versions) == list(range(2, 2 * THREADS + 2))
    origins, _ = _origins(client, sid)
    assert sorted(origins) == sorted(round(-9 + 0.001 * k, 4) for k in range(2 * THREADS))


def test_idempotent_retries_store_once(client):
    sid = create_session(client)["id"]
    url = f"/v1/sessions/{sid}/observations"
    barrier = threading.Barrier(THREADS)

    def retry(_: int):
        barrier.wait()
        r = client.post(url, json=miss(5), headers={"Idempotency-Key": "probe-5"})
        return r.status_code, r.headers.get("idempotent-replayed"), r.content

    with ThreadPoolExecutor(THREADS) as pool:
        answers = list(pool.map(retry, range(THREADS)))
    firsts = [a for a in answers if a[0] == 201 and a[1] is None]
    assert len(firsts) == 1
    # the others were either told the first was in flight (409) or got its answer replayed
    for status, replayed, body in answers:
        assert status == 409 or (status == 201 and body == firsts[0][2]), (status, replayed)
    # a later retry replays the first answer; the observation is stored once
    later = client.post(url, json=miss(5), headers={"Idempotency-Key": "probe-5"})
    assert later.status_code == 201 and later.content == firsts[0][2]
    assert later.headers["idempotent-replayed"] == "true"
    origins, _ = _origins(client, sid)
    assert origins == [round(-9 + 0.005, 4)]


def _held(fn, started: threading.Event, release: threading.Event, gave_up: list[bool]):
    """`fn` that, once called, waits until `release` (at most 10 s, then noting in
    `gave_up` that it waited in vain) before working."""

    def held(*args, **kwargs):
        started.set()
        gave_up.append(not release.wait(10))
        return fn(*args, **kwargs)

    return held


@pytest.mark.parametrize(
    ("reader", "target"),
    [
        ("plan", "app.service.plan_session"),
        ("image.png", "app.service.plan_session"),
        ("image.json", "app.viewer.mii_json"),
    ],
)
def test_observations_do_not_wait_for_plans_or_pictures_of_the_same_session(
    tmp_path, monkeypatch, reader, target
):
    # the read's computation is held until the observation has been answered: were the
    # observation waiting for the read (its lock), the read would give up holding
    # after 10 s and the observation would come back only after it
    module, name = target.rsplit(".", 1)
    started, release, gave_up = threading.Event(), threading.Event(), []
    real = getattr(importlib.import_module(module), name)
    monkeypatch.setattr(target, _held(real, started, release, gave_up))
    with api(tmp_path, cpu_workers=2) as client:
        sid = create_session(client)["id"]
        url = f"/v1/sessions/{sid}"
        assert client.post(f"{url}/observations", json=BOTTOM).status_code == 201
        with ThreadPoolExecutor(1) as pool:
            reading = pool.submit(client.get, f"{url}/{reader}")
            assert started.wait(10)
            r = client.post(f"{url}/observations", json=miss(1))
            release.set()
            assert r.status_code == 201 and r.json()["version"] == 3
            assert reading.result().status_code == 200
        assert gave_up == [False]  # the observation came back while the read was held


def test_the_same_plan_asked_twice_at_once_is_computed_once(tmp_path, monkeypatch):
    started, release, gave_up = threading.Event(), threading.Event(), []
    import app.service

    calls = []
    real = app.service.plan_session

    def counted(*args, **kwargs):
        calls.append(1)
        return real(*args, **kwargs)

    monkeypatch.setattr(app.service, "plan_session", _held(counted, started, release, gave_up))
    with api(tmp_path, cpu_workers=2) as client:
        url = f"/v1/sessions/{create_session(client)['id']}/plan"
        with ThreadPoolExecutor(2) as pool:
            first = pool.submit(client.get, url)
            assert started.wait(10)
            second = pool.submit(client.get, url)
            time.sleep(0.2)  # let the second request reach the wait for the first
            release.set()
            assert first.result().json() == second.result().json()
    assert len(calls) == 1 and gave_up == [False]


def test_a_full_cpu_queue_answers_503_with_retry_after_and_recovers(tmp_path, monkeypatch):
    # one CPU worker, no room to wait: while a plan holds the worker, another is refused
    started, release, gave_up = threading.Event(), threading.Event(), []
    import app.service

    monkeypatch.setattr(
        app.service, "plan_session", _held(app.service.plan_session, started, release, gave_up)
    )
    with api(tmp_path, cpu_workers=1, max_cpu_queue=0) as client:
        a = f"/v1/sessions/{create_session(client)['id']}/plan"
        b = f"/v1/sessions/{create_session(client)['id']}/plan"
        with ThreadPoolExecutor(1) as pool:
            first = pool.submit(client.get, a)
            assert started.wait(10)
            busy = client.get(b)
            release.set()
            assert first.result().status_code == 200
        assert is_problem(busy, 503) and busy.headers["retry-after"] == "1"
        assert "max_cpu_queue" in busy.json()["detail"]
        assert client.get(b).status_code == 200  # the retry is served
    assert gave_up and not any(gave_up)
