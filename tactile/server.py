"""``tactile serve`` in a subprocess on 127.0.0.1, for the latency command and the tests."""

from __future__ import annotations

import os
import queue
import re
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

__all__ = ["ROOT", "Server"]

#: The checkout the server runs in.
ROOT = Path(__file__).resolve().parents[1]


class Server:
    """`tactile serve` in a subprocess on 127.0.0.1 and a port it picked itself; `db` is
    a SQLite file or a postgresql:// URL.

    A thread keeps reading the server's log (stderr) so that it never blocks on a
    full pipe; the lines are kept in `lines`."""

    def __init__(self, db: Path | str, *args: str, env: dict[str, str] | None = None) -> None:
        self.db = db
        self.args = args
        self.env = {**os.environ, "TACTILE_LOG_LEVEL": "info", **(env or {})}
        self.proc: subprocess.Popen[bytes] | None = None
        self.port = 0
        self.lines: list[str] = []
        self._queue: queue.Queue[str | None] = queue.Queue()

    def _drain(self) -> None:
        assert self.proc is not None and self.proc.stderr is not None
        for raw in self.proc.stderr:
            line = raw.decode(errors="replace").rstrip()
            self.lines.append(line)
            self._queue.put(line)
        self._queue.put(None)

    def start(self, timeout: float = 30.0) -> Server:
        cmd = [sys.executable, "-m", "tactile.cli", "serve", "--host", "127.0.0.1", "--port", "0"]
        self.proc = subprocess.Popen(
            [*cmd, "--db", str(self.db), *self.args],
            cwd=ROOT,
            env=self.env,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.PIPE,
        )
        threading.Thread(target=self._drain, daemon=True).start()
        deadline = time.monotonic() + timeout
        started = 0
        args = list(self.args)
        workers = int(args[args.index("--workers") + 1]) if "--workers" in args else 1
        while started < workers:
            try:
                line = self._queue.get(timeout=max(deadline - time.monotonic(), 0.01))
            except queue.Empty:
                line = None
            if line is None:
                self.kill()
                raise RuntimeError("server did not start:\n" + "\n".join(self.lines[-20:]))
            if not self.port and (m := re.search(r'"port": (\d+)', line)):
                self.port = int(m.group(1))
            started += "Application startup complete" in line
        return self

    @property
    def url(self) -> str:
        return f"http://127.0.0.1:{self.port}"

    def kill(self, sig: int = signal.SIGKILL) -> None:
        if self.proc is not None and self.proc.poll() is None:
            self.proc.send_signal(sig)
            try:
                self.proc.wait(timeout=30)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait(timeout=30)

    def __enter__(self) -> Server:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.kill(signal.SIGTERM)
