"""The schema-driven API tester run as an outside user runs it: its command line
against a real `tactile serve` with a client key, every phase (examples, coverage,
fuzzing, stateful) and every check, with few examples so that it stays a test.

It must find no failure (no 5xx, no schema-valid request refused outside the
documented answers of schemathesis.toml, no answer unlike its schema), and it must
reach every operation with a 2xx at least once: the examples in the schema and
the links from what is created to the operations on it are what lead it there.
"""

from __future__ import annotations

import json
import re
import subprocess
import sys
from collections import defaultdict
from pathlib import Path

import httpx
import pytest

from tactile.server import ROOT, Server

KEY = "schema-run-key-0123456789abcdef01234567"
#: Wall-clock bound on the whole run: past it the run hangs.
HANG = 300


def _operations(schema: dict) -> dict[tuple[str, str], re.Pattern[str]]:
    """(method, path template) -> a pattern matching the template's request paths."""
    out = {}
    for template, item in schema["paths"].items():
        pattern = re.compile("^" + re.sub(r"\\\{[^}]+\\\}", "[^/]+", re.escape(template)) + "$")
        for method, operation in item.items():
            if isinstance(operation, dict) and "responses" in operation:
                out[(method.upper(), template)] = pattern
    return out


def _statuses(har: dict, operations) -> dict[tuple[str, str], set[int]]:
    seen: dict[tuple[str, str], set[int]] = defaultdict(set)
    for entry in har["log"]["entries"]:
        method = entry["request"]["method"]
        path = httpx.URL(entry["request"]["url"]).path
        for (op_method, template), pattern in operations.items():
            if op_method == method and pattern.match(path):
                seen[(method, template)].add(entry["response"]["status"])
    return seen


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("schema-run")
    env = {"TACTILE_API_KEYS": json.dumps({"tester": KEY})}
    with Server(tmp / "run.db", env=env) as server:
        schema = httpx.get(
            server.url + "/openapi.json", headers={"Authorization": f"Bearer {KEY}"}
        ).json()
        har = tmp / "run.har"
        cli = Path(sys.executable).with_name("schemathesis")
        done = subprocess.run(
            [
                str(cli), "run", server.url + "/openapi.json",
                "--checks", "all", "--max-examples", "8", "--workers", "1", "--seed", "1",
                "--header", f"Authorization: Bearer {KEY}",
                "--report", "har", "--report-har-path", str(har),
            ],
            cwd=ROOT, capture_output=True, text=True, timeout=HANG,
        )  # fmt: skip
        yield done, schema, json.loads(har.read_text()), server.lines


def test_the_api_tester_finds_no_failure_in_any_phase(run):
    done, _, _, lines = run
    assert done.returncode == 0, done.stdout[-6000:]
    for phase in ("Examples", "Coverage", "Fuzzing", "Stateful"):
        assert re.search(rf"✅ {phase}\b", done.stdout), done.stdout[-3000:]
    assert not [line for line in lines if '"status": 5' in line]


def test_the_api_tester_reaches_every_operation_with_a_2xx(run):
    _, schema, har, _ = run
    operations = _operations(schema)
    seen = _statuses(har, operations)
    unreached = {
        f"{method} {template}": sorted(seen.get((method, template), ()))
        for method, template in operations
        if not any(200 <= s < 300 for s in seen.get((method, template), ()))
    }
    assert not unreached, unreached
    assert not [s for statuses in seen.values() for s in statuses if s >= 500]
