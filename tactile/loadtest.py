"""Load test: a real ``tactile serve`` and a headless locust fleet of simulated robots.

``python -m tactile.loadtest --workers 2 --users 8 --seconds 30`` starts the
service on a free loopback port with a fresh database (``--db URL``: a
PostgreSQL database instead of a temporary SQLite file; ``--hosts N``: N
services on N ports sharing that database, every robot's requests spread over
all of them at random, results per host), runs locust headless for a
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


_TICK = os.sysconf("SC_CLK_TCK") if hasattr(os, "sysconf") else 100


def process_cpu(pid: int) -> dict[int, float]:
    """CPU time (user + system, s) of process `pid` and of each of its living children,
    by process id (Linux /proc; empty elsewhere): a server's workers are its children."""
    out = {}
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue
        this, parent = int(stat.parent.name), int(fields[1])
        if pid in (this, parent):
            out[this] = (int(fields[11]) + int(fields[12])) / _TICK
    return out


def worker_cpu(before: dict[int, float], after: dict[int, float], server: int) -> list[float]:
    """CPU seconds each worker of `server` spent between two :func:`process_cpu`
    readings, most first: how evenly the workers shared the load (keep-alive
    connections stay on the worker that accepted them)."""
    spent = [t - before.get(p, 0.0) for p, t in after.items() if p != server]
    return sorted((round(s, 1) for s in spent), reverse=True)


def _serve(port: int, workers: int, db: str) -> subprocess.Popen[bytes]:
    return subprocess.Popen(
        [
            str(Path(sys.executable).parent / "tactile"),
            "serve",
            "--host",
            "127.0.0.1",
            "--port",
            str(port),
            "--workers",
            str(workers),
            "--db",
            db,
        ],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
        env={**os.environ, "TACTILE_LOG_LEVEL": "warning"},
    )


def _endpoints(prefix: Path) -> dict[str, dict]:
    """Per-endpoint statistics from locust's CSV (the aggregate row left out)."""
    with open(f"{prefix}_stats.csv", encoding="utf-8") as f:
        rows = list(csv.DictReader(f))
    return {
        r["Name"]: {
            "requests": int(r["Request Count"]),
            "failures": int(r["Failure Count"]),
            "rps": float(r["Requests/s"]),
            "p50_ms": float(r["50%"]),
            "p95_ms": float(r["95%"]),
            "p99_ms": float(r["99%"]),
        }
        for r in rows
        if r["Name"] != "Aggregated"
    }


def _per_host(endpoints: dict[str, dict], hosts: int) -> dict[str, dict]:
    """Requests, requests/s and failures per host (endpoints named ``... @h<i>``
    when there are several)."""
    out = {}
    for h in range(hosts):
        mine = [e for name, e in endpoints.items() if hosts == 1 or name.endswith(f"@h{h}")]
        out[f"h{h}"] = {
            "requests": sum(e["requests"] for e in mine),
            "rps": round(sum(e["rps"] for e in mine), 2),
            "failures": sum(e["failures"] for e in mine),
        }
    return out


def run(
    workers: int,
    users: int,
    seconds: int,
    out: Path,
    mode: str = "recognize",
    hypotheses: int | None = None,
    keepalive: bool = True,
    hosts: int = 1,
    db: str | None = None,
) -> dict:
    """One load run; returns per-endpoint statistics and the failure count."""
    bin_dir = Path(sys.executable).parent
    urls = []
    with tempfile.TemporaryDirectory() as tmp:
        target = db or str(Path(tmp) / "load.db")
        servers = []
        try:
            for _ in range(hosts):
                port = _free_port()
                servers.append(_serve(port, workers, target))
                urls.append(f"http://127.0.0.1:{port}")
                _wait_ready(urls[-1])  # one at a time: the first one migrates the schema
            prefix = out / f"{mode}-hosts{hosts}-workers{workers}"
            env = {
                **os.environ,
                "LOADTEST_HYPOTHESES": "" if hypotheses is None else str(hypotheses),
                "LOADTEST_KEEPALIVE": "1" if keepalive else "0",
                "LOADTEST_HOSTS": ",".join(urls) if hosts > 1 else "",
            }
            cpu_before = [process_cpu(s.pid) for s in servers]
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
                    urls[0],
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
            cpu_after = [process_cpu(s.pid) for s in servers]
            cpu = [
                sum(a.values()) - sum(b.values())
                for a, b in zip(cpu_after, cpu_before, strict=True)
            ]
            workers_cpu = [
                worker_cpu(b, a, s.pid)
                for s, b, a in zip(servers, cpu_before, cpu_after, strict=True)
            ]
        finally:
            for server in servers:
                server.terminate()
            for server in servers:
                server.wait(timeout=30)
    endpoints = _endpoints(prefix)
    failures = sum(e["failures"] for e in endpoints.values())
    per_host = _per_host(endpoints, hosts)
    plans = sum(e["requests"] for name, e in endpoints.items() if "/plan" in name)
    touches = sum(e["requests"] for name, e in endpoints.items() if "/observations" in name)
    return {
        "mode": mode,
        "hosts": hosts,
        "server_cpu_s": round(sum(cpu), 2),
        # per host, the CPU seconds of each process the server started (its workers;
        # empty when the server is its only worker)
        "worker_cpu_s": workers_cpu,
        # the servers' CPU per touch the robots made (each planned, then observed)
        "cpu_ms_per_touch": round(1e3 * sum(cpu) / max(touches, 1), 1),
        "plans": plans,
        "database": "postgresql" if db and db.startswith("postgres") else "sqlite",
        "per_host": per_host,
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
    parser.add_argument("--hosts", type=int, default=1, help="services sharing one database")
    parser.add_argument(
        "--db", default=None, help="a postgresql:// URL (default: a temporary SQLite file)"
    )
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    results = [
        run(
            w,
            args.users,
            args.seconds,
            out,
            args.mode,
            args.hypotheses,
            not args.no_keepalive,
            args.hosts,
            args.db,
        )
        for w in args.workers
    ]
    if args.json:
        print(json.dumps(results, indent=1))
    for res in results:
        print(
            f"\n{res['hosts']} host(s) x {res['workers']} worker(s) on {res['database']},"
            f" {res['users']} robots ({res['mode']}"
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
        for host, total in res["per_host"].items():
            print(
                f"  host {host}: {total['requests']} requests, {total['rps']:.1f} req/s,"
                f" {total['failures']} failed"
            )
        print(
            f"  server CPU: {res['server_cpu_s']:.1f} s, {res['cpu_ms_per_touch']:.1f} ms"
            f" per touch ({'planned and ' if res['plans'] else ''}observed)"
        )
        for h, spent in enumerate(res["worker_cpu_s"]):
            if len(spent) > 1:  # several workers: how evenly they shared the robots
                print(f"  host h{h} CPU per worker process: {' / '.join(map(str, spent))} s")
        print(f"  failed requests: {res['failures']}")
    return 1 if any(r["failures"] for r in results) else 0


if __name__ == "__main__":
    sys.exit(main())
