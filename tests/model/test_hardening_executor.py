"""Hardening of the executor: pool workers die with a killed parent; a listener that is no
Dask scheduler is refused quickly."""

from __future__ import annotations

import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="checks /proc")
def test_pool_workers_die_with_a_killed_parent(tmp_path):
    code = (
        "import multiprocessing, sys, threading, time\n"
        "from sigmapi.executor import run_jobs\n"
        "jobs = [(str(i), 120) for i in range(2)]\n"
        "threading.Thread(target=lambda: list(run_jobs(time.sleep, jobs, workers=2)),"
        " daemon=True).start()\n"
        "while len(multiprocessing.active_children()) < 2: time.sleep(0.05)\n"
        "time.sleep(0.5)\n"
        "print(' '.join(str(p.pid) for p in multiprocessing.active_children()), flush=True)\n"
        "time.sleep(120)\n"
    )
    proc = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, text=True)
    pids = [int(p) for p in proc.stdout.readline().split()]
    proc.stdout.close()
    assert pids, "no workers started"
    proc.kill()
    proc.wait()

    def alive(pid):
        try:
            state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
        except (FileNotFoundError, ProcessLookupError):
            return False
        return state not in ("Z", "X")

    deadline = time.monotonic() + 10
    while any(alive(p) for p in pids) and time.monotonic() < deadline:
        time.sleep(0.05)
    assert not any(alive(p) for p in pids), "a worker outlived its parent"


@pytest.mark.parametrize("greeting", [b"HTTP/1.1 400 Bad Request\r\n\r\n" * 4, None])
def test_a_listener_that_is_no_dask_scheduler_is_refused(tmp_path, capsys, greeting):
    import socket

    from sigmapi.errors import ConfigError
    from sigmapi.executor import probe_scheduler

    server = socket.create_server(("127.0.0.1", 0))
    port = server.getsockname()[1]

    def serve():
        conn, _ = server.accept()
        if greeting:
            conn.sendall(greeting)
        time.sleep(2)
        conn.close()

    threading.Thread(target=serve, daemon=True).start()
    try:
        t0 = time.perf_counter()
        with pytest.raises(ConfigError, match="Dask scheduler"):
            probe_scheduler(f"tcp://127.0.0.1:{port}", timeout=0.5)
        assert time.perf_counter() - t0 < 1.5
    finally:
        server.close()
