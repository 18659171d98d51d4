"""The task a Dask worker runs for one mesh: hand it to this thread's job server, return a record.

:func:`process_mesh` needs no Dask: it is a plain function of a plain dict, so it can be called
in a loop too. Each worker thread keeps one job server (:mod:`igl_heatseg.batch.server`, a
``python -m igl_heatseg.batch`` subprocess) alive across meshes; the mesh itself runs in
a child of that server, killed at its timeout, under its memory limit.
"""

from __future__ import annotations

import atexit
import json
import os
import select
import socket
import subprocess
import sys
import threading
import time

from .server import BLAS_ENV

__all__ = ["process_mesh", "JobServer", "stop_servers", "TEST_KILL_ENV"]

#: Test hook: ``IGL_HEATSEG_BATCH_TEST_KILL_WORKER="GLOB=FOLDER"`` kills the worker process
#: (SIGKILL) the first time it is given a mesh whose file name matches GLOB (a marker file in
#: FOLDER remembers it), to test that a dead worker's mesh is retried. For tests only.
TEST_KILL_ENV = "IGL_HEATSEG_BATCH_TEST_KILL_WORKER"

#: Seconds a job server may take to start (import numpy, scipy, libigl) and to answer beyond
#: the job's own timeout, before it is taken for dead and restarted.
SERVER_GRACE = 120.0

_local = threading.local()
_servers: list[JobServer] = []
_servers_lock = threading.Lock()


class JobServer:
    """A ``python -m igl_heatseg.batch`` subprocess and its request/answer pipes."""

    def __init__(self, preload=()) -> None:
        env = dict(os.environ)
        env.update(BLAS_ENV)
        self.proc = subprocess.Popen(
            [sys.executable, "-m", "igl_heatseg.batch"],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            env=env,
            text=True,
            bufsize=1,
        )
        self.preloaded: set[str] = set()
        self.preload(preload)

    def alive(self) -> bool:
        return self.proc.poll() is None

    def request(self, req: dict, wait: float | None) -> dict | None:
        """Send one request; the answer, or ``None`` when the server died or hung."""
        try:
            self.proc.stdin.write(json.dumps(req) + "\n")
            self.proc.stdin.flush()
        except (BrokenPipeError, OSError):
            return None
        deadline = None if wait is None else time.monotonic() + wait
        out = self.proc.stdout
        while True:
            left = None if deadline is None else max(0.0, deadline - time.monotonic())
            ready, _, _ = select.select([out], [], [], left)
            if not ready:
                return None
            line = out.readline()
            if not line:
                return None
            try:
                return json.loads(line)
            except ValueError:
                continue

    def preload(self, modules) -> None:
        todo = [m for m in modules if m not in self.preloaded]
        if todo:
            self.request({"preload": todo}, SERVER_GRACE)
            self.preloaded.update(todo)

    def stop(self, wait: float = 0.5) -> None:
        """Close its stdin (it exits at the end of a request); terminate it after ``wait`` s."""
        if self.proc.poll() is not None:
            return
        try:
            self.proc.stdin.close()
        except OSError:
            pass
        try:
            self.proc.wait(wait)
        except subprocess.TimeoutExpired:
            self.proc.terminate()  # its child dies with it (it watches its parent)
            try:
                self.proc.wait(2)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()


def stop_servers() -> None:
    """Stop every job server this process started (at most ~0.5 s when they are idle)."""
    with _servers_lock:
        servers = list(_servers)
        _servers.clear()
    for s in servers:
        try:
            s.proc.stdin.close()
        except OSError:
            pass
    for s in servers:
        s.stop()


atexit.register(stop_servers)


def _server(preload=()) -> JobServer:
    s = getattr(_local, "server", None)
    if s is None or not s.alive():
        s = JobServer(preload)
        _local.server = s
        with _servers_lock:
            _servers.append(s)
    else:
        s.preload(preload)
    return s


def _drop_server() -> None:
    s = getattr(_local, "server", None)
    if s is not None:
        _local.server = None
        with _servers_lock:
            if s in _servers:
                _servers.remove(s)
        s.proc.kill()
        s.proc.wait()


def _test_kill(mesh: str) -> None:
    import fnmatch
    import signal
    from pathlib import Path

    spec = os.environ.get(TEST_KILL_ENV, "")
    pattern, _, folder = spec.partition("=")
    if spec and fnmatch.fnmatch(Path(mesh).name, pattern):
        marker = Path(folder) / f"killed-{Path(mesh).name}"
        if not marker.exists():
            marker.write_text(str(os.getpid()))
            os.kill(os.getpid(), signal.SIGKILL)


def process_mesh(task: dict) -> dict:
    """Process one mesh; never raises for a bad mesh, a timeout or a crash of the job.

    Parameters
    ----------
    task : dict
        ``mesh`` (the input's relative name), ``input`` and ``output`` (absolute paths),
        ``kind``, ``options``, ``timeout`` (seconds or ``None``), ``memory_limit`` (bytes or
        ``None``), ``memory_limit_text``, ``preload`` (modules the server imports once).

    Returns
    -------
    dict
        The summary record: ``mesh``, ``status``, ``reason``, the job kind's numbers,
        ``seconds``, ``peak_memory_mb``, ``worker``.
    """
    req = {
        "kind": task["kind"],
        "mesh": task["input"],
        "out": task["output"],
        "options": task.get("options") or {},
        "timeout": task.get("timeout"),
        "memory_limit": task.get("memory_limit"),
        "memory_limit_text": task.get("memory_limit_text"),
    }
    _test_kill(task["input"])
    t0 = time.perf_counter()
    timeout = task.get("timeout")
    wait = None if not timeout else float(timeout) + SERVER_GRACE
    server = _server(task.get("preload") or ())
    res = server.request(req, wait)
    if res is None:
        _drop_server()
        res = {
            "status": "crashed",
            "reason": "the job server died or stopped answering",
            "seconds": time.perf_counter() - t0,
        }
    rec = {"mesh": task["mesh"], "input": task["input"], "output": task["output"]}
    rec.update(res)
    rec["worker"] = f"{socket.gethostname()}:{os.getpid()}"
    return rec
