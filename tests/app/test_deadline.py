"""A CPU job past its deadline is stopped in its thread and answered 503 naming the
setting; a job within it is untouched, and the worker goes on serving."""

from __future__ import annotations

import threading
import time

import pytest

from app.deadline import JobStoppedError, with_deadline
from app.settings import Settings
from tests.app.api_support import api, create_session, is_problem

#: How long the runaway work below runs when nothing stops it.
RUNAWAY = 20.0


def _spin(stop: threading.Event, reached: list[str]) -> str:
    """Pure Python work that ends only when told (or after RUNAWAY s)."""
    give_up = time.monotonic() + RUNAWAY
    try:
        while not stop.is_set() and time.monotonic() < give_up:
            sum(range(1000))
    finally:
        reached.append("finally")  # the job unwinds: its cleanup runs
    return "done"


def test_a_job_past_its_deadline_is_stopped_and_unwinds():
    stop, reached = threading.Event(), []
    start = time.monotonic()
    with pytest.raises(JobStoppedError, match=r"0\.2 s"):
        with_deadline(_spin, 0.2)(stop, reached)
    stop.set()
    assert reached == ["finally"]
    assert time.monotonic() - start < RUNAWAY


def test_a_job_within_its_deadline_returns_and_nothing_is_raised_later():
    job = with_deadline(lambda x: x * 2, 0.2)
    assert [job(i) for i in range(50)] == [2 * i for i in range(50)]
    end = time.monotonic() + 0.6
    while time.monotonic() < end:  # past every timer: no stray exception lands here
        sum(range(1000))


def test_a_short_deadline_set_after_a_long_one_still_fires_first():
    # one watchdog serves every job: the later, shorter deadline must wake it
    long_stop, long_reached, outcome = threading.Event(), [], []

    def long_job():
        try:
            outcome.append(with_deadline(_spin, RUNAWAY * 2)(long_stop, long_reached))
        except JobStoppedError:
            outcome.append("stopped")

    other = threading.Thread(target=long_job)
    other.start()
    try:
        start = time.monotonic()
        with pytest.raises(JobStoppedError):
            with_deadline(_spin, 0.2)(threading.Event(), [])
        assert time.monotonic() - start < RUNAWAY / 2
    finally:
        long_stop.set()
        other.join()
    assert outcome == ["done"]  # the long job ran to its end, untouched


def test_jobs_share_one_watchdog_thread():
    job = with_deadline(lambda x: x + 1, 5.0)
    before = threading.active_count()
    assert [job(i) for i in range(100)] == list(range(1, 101))
    assert threading.active_count() <= max(before, 1) + 1
    assert sum(t.name == "deadline" for t in threading.enumerate()) == 1


def test_without_a_deadline_the_job_is_itself():
    def f():
        return 1

    assert with_deadline(f, None) is f


def test_the_deadline_must_leave_room_for_the_longest_plan():
    with pytest.raises(ValueError, match="cpu_job_deadline_s"):
        Settings(cpu_job_deadline_s=5, max_plan_budget_ms=10_000)
    assert Settings(cpu_job_deadline_s=None).cpu_job_deadline_s is None


def test_a_request_whose_work_overruns_is_503_and_the_worker_goes_on(tmp_path, monkeypatch):
    import app.service

    real, calls = app.service.plan_session, []

    def slow_once(*args, **kwargs):
        calls.append(1)
        if len(calls) == 1:  # a plan that would run on
            _spin(threading.Event(), [])
        return real(*args, **kwargs)

    monkeypatch.setattr(app.service, "plan_session", slow_once)
    with api(
        tmp_path,
        cpu_workers=1,
        cpu_job_deadline_s=0.5,
        max_plan_budget_ms=400,
        default_budget_ms=300,
    ) as client:
        sid = create_session(client)["id"]
        stopped = client.get(f"/v1/sessions/{sid}/plan")
        assert is_problem(stopped, 503) and stopped.headers["retry-after"]
        assert "cpu_job_deadline_s" in stopped.json()["detail"]
        # the one worker thread is free again: the retry is planned
        assert client.get(f"/v1/sessions/{sid}/plan").status_code == 200
