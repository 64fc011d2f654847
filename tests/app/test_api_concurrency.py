"""Concurrent writers on one session: optimistic concurrency, per-session serialization,
and idempotent retries (the store itself: test_store.py)."""

from __future__ import annotations

import threading
from concurrent.futures import ThreadPoolExecutor

import pytest

from tests.app.api_support import api, create_session, miss

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
