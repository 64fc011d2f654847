"""Load test: a real ``tactile serve`` and a headless locust fleet of simulated robots.

``python -m tactile.loadtest --workers 2 --users 8 --seconds 30`` starts the
service on a free loopback port with a fresh database, runs locust headless for a
bounded time, prints requests/s and p50/p95/p99 per endpoint, and exits non-zero on
any failed request. Traffic goes to 127.0.0.1 only.

``--mode recognize`` (default): robots plan, touch and observe (the closed loop);
``--mode observe``: robots post observations only, no plan (what the observation
endpoint sustains by itself). ``--hypotheses N`` asks for at most N hypotheses
in each observation's answer (default: all, the API's default).
"""

from __future__ import annotations

import argparse
import csv
import json
import os
import socket
import subprocess
import sys
import tempfile
import time
import urllib.request
from pathlib import Path

__all__ = ["main"]


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def _wait_ready(url: str, timeout: float = 60.0) -> None:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        try:
            with urllib.request.urlopen(f"{url}/readyz", timeout=2) as r:
                if r.status == 200:
                    return
        except OSError:
            time.sleep(0.2)
    raise RuntimeError(f"the service at {url} did not become ready")


MODES = {"recognize": "Robot", "observe": "Prober"}


def run(
    workers: int,
    users: int,
    seconds: int,
    out: Path,
    mode: str = "recognize",
    hypotheses: int | None = None,
    keepalive: bool = True,
) -> dict:
    """One load run; returns per-endpoint statistics and the failure count."""
    bin_dir = Path(sys.executable).parent
    port = _free_port()
    url = f"http://127.0.0.1:{port}"
    with tempfile.TemporaryDirectory() as tmp:
        server = subprocess.Popen(
            [
                str(bin_dir / "tactile"),
                "serve",
                "--host",
                "127.0.0.1",
                "--port",
                str(port),
                "--workers",
                str(workers),
                "--db",
                str(Path(tmp) / "load.db"),
            ],
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
            env={**os.environ, "TACTILE_LOG_LEVEL": "warning"},
        )
        try:
            _wait_ready(url)
            prefix = out / f"{mode}-workers{workers}"
            env = {
                **os.environ,
                "LOADTEST_HYPOTHESES": "" if hypotheses is None else str(hypotheses),
            }
            subprocess.run(
                [
                    str(bin_dir / "locust"),
                    "-f",
                    str(Path(__file__).with_name("locustfile.py")),
                    MODES[mode],
                    "--headless",
                    "--users",
                    str(users),
                    "--spawn-rate",
                    str(users),
                    "--run-time",
                    f"{seconds}s",
                    "--host",
                    url,
                    "--csv",
                    str(prefix),
                    "--only-summary",
                    "--loglevel",
                    "WARNING",
                    "--stop-timeout",
                    "10",
                ],
                check=False,
                stdout=subprocess.DEVNULL,
                stderr=subprocess.DEVNULL,
                env=env,
            )
        finally:
            server.terminate()
            server.wait(timeout=30)
    with open(f"{prefix}_stats.csv", encoding="utf-8") as f:
        rows = list(csv.DictReader(f))
    endpoints = {
        r["Name"]: {
            "requests": int(r["Request Count"]),
            "failures": int(r["Failure Count"]),
            "rps": float(r["Requests/s"]),
            "p50_ms": float(r["50%"]),
            "p95_ms": float(r["95%"]),
            "p99_ms": float(r["99%"]),
        }
        for r in rows
    }
    failures = sum(e["failures"] for e in endpoints.values())
    return {
        "mode": mode,
        "keepalive": keepalive,
        "workers": workers,
        "users": users,
        "seconds": seconds,
        "endpoints": endpoints,
        "failures": failures,
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--workers", type=int, nargs="+", default=[1, 2])
    parser.add_argument("--users", type=int, default=8)
    parser.add_argument("--seconds", type=int, default=30)
    parser.add_argument("--out", default="out/loadtest")
    parser.add_argument("--mode", choices=sorted(MODES), default="recognize")
    parser.add_argument("--hypotheses", type=int, default=None, help="?limit= on observations")
    parser.add_argument(
        "--no-keepalive",
        action="store_true",
        help="a new connection per request (requests of a session spread over the workers)",
    )
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    results = [
        run(w, args.users, args.seconds, out, args.mode, args.hypotheses, not args.no_keepalive)
        for w in args.workers
    ]
    if args.json:
        print(json.dumps(results, indent=1))
    for res in results:
        print(
            f"\n{res['workers']} worker(s), {res['users']} robots ({res['mode']}"
            f"{'' if res['keepalive'] else ', no keep-alive'}), {res['seconds']} s:"
        )
        print(
            f"  {'endpoint':40s} {'requests':>8s} {'req/s':>7s} {'p50':>6s} {'p95':>6s} {'p99':>6s}"
        )
        for name, e in res["endpoints"].items():
            print(
                f"  {name:40s} {e['requests']:8d} {e['rps']:7.1f} {e['p50_ms']:6.0f} "
                f"{e['p95_ms']:6.0f} {e['p99_ms']:6.0f}"
            )
        print(f"  failed requests: {res['failures']}")
    return 1 if any(r["failures"] for r in results) else 0


if __name__ == "__main__":
    sys.exit(main())
