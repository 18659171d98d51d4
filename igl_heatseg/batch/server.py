"""The job server: runs each mesh of a batch in a child process with a timeout and a memory limit.

A batch worker (:func:`igl_heatseg.batch.worker.process_mesh`) starts one server per worker
thread (``python -m igl_heatseg.batch``) and sends it one request per mesh, a JSON line
on its stdin; the answer is one JSON line on its stdout. The server has imported the pipeline
once; for every mesh it forks a child (single-threaded parent, so the fork is safe and costs
milliseconds instead of the ~0.8 s a fresh interpreter spends importing numpy, scipy and
libigl). The child:

* limits its address space with ``resource.setrlimit(RLIMIT_AS)`` (``memory_limit`` bytes),
* runs the job kind (:data:`~igl_heatseg.batch.jobs.JOB_KINDS`) on the mesh, which writes the
  output folder atomically,
* sends back a record (status, reason, summary numbers) through a pipe.

A job kind that takes a ``time_limit`` (``cad``: the B-Rep build starts no further rebuild
after it) gets :data:`TIME_LIMIT_SHARE` of the timeout unless the batch gives one, so that a
part whose rebuilds would outlast the timeout still gets a model written.

The server kills a child that outlives ``timeout`` seconds, reads the child's peak resident
memory from ``wait4``, and records deaths by signal. It exits when its stdin closes (the worker
is gone) and kills its child when it is orphaned.

The memory limit bounds the child's whole address space, the server's imports included
(a few hundred MB); memory the server has mapped but not used counts once, so a limit below the
server's own size still lets a small job through.

Test hooks (for tests of timeouts, memory limits and interrupted batches only; read nowhere
else): ``IGL_HEATSEG_BATCH_TEST_SLEEP="GLOB=SECONDS[,GLOB=SECONDS...]"`` makes the child sleep
that long before a mesh whose file name matches ``GLOB`` (the first pattern that matches);
``IGL_HEATSEG_BATCH_TEST_ALLOCATE="GLOB=BYTES"`` makes it allocate that much first.
"""

from __future__ import annotations

import fnmatch
import json
import os
import resource
import select
import signal
import sys
import tempfile
import time
import traceback
from pathlib import Path

__all__ = [
    "run_request",
    "serve",
    "TEST_SLEEP_ENV",
    "TEST_ALLOCATE_ENV",
    "BLAS_ENV",
    "TIME_LIMIT_SHARE",
]

#: Environment variables of the test hooks (see the module docstring).
TEST_SLEEP_ENV = "IGL_HEATSEG_BATCH_TEST_SLEEP"
TEST_ALLOCATE_ENV = "IGL_HEATSEG_BATCH_TEST_ALLOCATE"

#: Thread counts set in the server's environment: one BLAS/OpenMP thread per job.
BLAS_ENV = {
    "OPENBLAS_NUM_THREADS": "1",
    "OMP_NUM_THREADS": "1",
    "MKL_NUM_THREADS": "1",
    "VECLIB_MAXIMUM_FRAMEWORKS": "1",
    "NUMEXPR_NUM_THREADS": "1",
}

#: Share of a job's timeout after which a job kind taking a ``time_limit`` starts no further
#: rebuild (the rest is for the build running then, the fidelity, the STEP file and pictures:
#: on a 40k-triangle housing one sewn build with its checks took about a minute).
TIME_LIMIT_SHARE = 0.5

#: Characters of a reason kept in the summary.
REASON_CHARS = 500


def _test_hook(env: str, mesh: str) -> float:
    spec = os.environ.get(env, "")
    for item in filter(None, spec.split(",")):
        pattern, _, seconds = item.rpartition("=")
        if fnmatch.fnmatch(Path(mesh).name, pattern):
            return float(seconds)
    return 0.0


def _remove_stale_temporaries(out: Path) -> None:
    """Remove ``.NAME.*.tmp`` / ``.NAME.*.old`` siblings an interrupted job left behind."""
    import shutil

    parent = out.parent
    if not parent.is_dir():
        return
    for p in parent.glob(f".{out.name}.*"):
        if p.is_dir() and p.suffix in (".tmp", ".old"):
            shutil.rmtree(p, ignore_errors=True)


def _short(text: str) -> str:
    text = " ".join(str(text).split())
    return text if len(text) <= REASON_CHARS else text[: REASON_CHARS - 3] + "..."


def child_job(req: dict) -> dict:
    """Run one mesh in the current process; never raises. Returns the partial record."""
    from ..errors import MeshError
    from .jobs import job_kind

    t0 = time.perf_counter()
    try:
        kind = job_kind(req["kind"])
        delay = _test_hook(TEST_SLEEP_ENV, req["mesh"])
        if delay:
            time.sleep(delay)
        size = int(_test_hook(TEST_ALLOCATE_ENV, req["mesh"]))
        if size:
            import numpy as np

            np.ones(size // 8)
        out = Path(req["out"])
        _remove_stale_temporaries(out)
        opts = {k: v for k, v in (req.get("options") or {}).items() if k in kind.options}
        if "time_limit" in kind.options and opts.get("time_limit") is None and req.get("timeout"):
            opts["time_limit"] = TIME_LIMIT_SHARE * float(req["timeout"])
        output = kind.run(req["mesh"], out, **opts)
        report = getattr(output, "report", output)
        rec = {"status": "done", "reason": ""}
        rec.update(kind.summarize(report))
        rec["reason"] = _short(rec["reason"])  # (a cad job's is the build's message)
    except MemoryError as exc:
        rec = {
            "status": "memory",
            "reason": _short(
                f"out of memory (limit {req.get('memory_limit_text') or 'none'}): MemoryError {exc}"
            ),
        }
    except (MeshError, ValueError) as exc:
        rec = {"status": "rejected", "reason": _short(exc)}
    except Exception as exc:  # a bug or an unexpected failure: recorded, the batch goes on
        tb = traceback.extract_tb(exc.__traceback__)
        where = f" at {Path(tb[-1].filename).name}:{tb[-1].lineno}" if tb else ""
        rec = {"status": "error", "reason": _short(f"{type(exc).__name__}: {exc}{where}")}
    rec["seconds"] = time.perf_counter() - t0
    return rec


def _die_with_parent() -> None:
    """Linux: SIGKILL this process when the process that forked it dies (no orphaned job)."""
    try:
        import ctypes

        libc = ctypes.CDLL(None, use_errno=True)
        libc.prctl(1, signal.SIGKILL, 0, 0, 0)  # PR_SET_PDEATHSIG
    except (OSError, AttributeError):
        pass


#: pid of the child running now (killed with the server on SIGTERM).
_CHILD: list[int] = []


def _on_sigterm(signum, frame) -> None:
    for pid in _CHILD:
        try:
            os.kill(pid, signal.SIGKILL)
        except OSError:
            pass
    os._exit(128 + signum)


def _tail(fh, n: int = 300) -> str:
    try:
        fh.seek(0, os.SEEK_END)
        size = fh.tell()
        fh.seek(max(0, size - n))
        return fh.read().decode("utf-8", "replace").strip()
    except OSError:
        return ""


def run_request(req: dict) -> dict:
    """Fork a child for one request, enforce its timeout, return its record.

    Parameters
    ----------
    req : dict
        ``kind``, ``mesh`` and ``out`` (absolute paths), ``options``, ``timeout`` (seconds or
        ``None``), ``memory_limit`` (bytes or ``None``), ``memory_limit_text``.

    Returns
    -------
    dict
        ``status`` (done, rejected, error, memory, timeout, crashed), ``reason``, the summary
        numbers of the job kind, ``seconds``, ``peak_memory_mb``.
    """
    timeout = req.get("timeout")
    limit = req.get("memory_limit")
    r, w = os.pipe()
    log = tempfile.TemporaryFile(prefix="igl-heatseg-job-")
    sys.stdout.flush()
    sys.stderr.flush()
    t0 = time.perf_counter()
    pid = os.fork()
    if pid == 0:  # the child
        code = 0
        try:
            os.close(r)
            _die_with_parent()
            os.dup2(log.fileno(), 1)
            os.dup2(log.fileno(), 2)
            signal.signal(signal.SIGINT, signal.SIG_DFL)
            signal.signal(signal.SIGTERM, signal.SIG_DFL)
            if limit:
                resource.setrlimit(resource.RLIMIT_AS, (int(limit), int(limit)))
            rec = child_job(req)
            data = json.dumps(rec, default=float).encode()
            while data:
                n = os.write(w, data)
                data = data[n:]
        except BaseException:
            code = 3
        finally:
            try:
                sys.stdout.flush()
                sys.stderr.flush()
            finally:
                os._exit(code)
    os.close(w)
    _CHILD[:] = [pid]
    ppid = os.getppid()
    chunks: list[bytes] = []
    timed_out = False
    status = None
    rusage = None
    while True:
        ready, _, _ = select.select([r], [], [], 0.02)
        if ready:
            chunk = os.read(r, 65536)
            if chunk:
                chunks.append(chunk)
        wpid, st, ru = os.wait4(pid, os.WNOHANG)
        if wpid:
            status, rusage = st, ru
            break
        if timeout and time.perf_counter() - t0 > timeout:
            os.kill(pid, signal.SIGKILL)
            _, status, rusage = os.wait4(pid, 0)
            timed_out = True
            break
        if os.getppid() != ppid:  # the worker is gone: so is this mesh
            os.kill(pid, signal.SIGKILL)
            os.wait4(pid, 0)
            os._exit(1)
    while True:  # whatever the child wrote before it ended
        chunk = os.read(r, 65536)
        if not chunk:
            break
        chunks.append(chunk)
    os.close(r)
    _CHILD.clear()
    seconds = time.perf_counter() - t0
    peak_mb = rusage.ru_maxrss / 1024.0 if rusage is not None else None
    rec = None
    if chunks and not timed_out:
        try:
            rec = json.loads(b"".join(chunks))
        except ValueError:
            rec = None
    if rec is None:
        tail = _short(_tail(log).splitlines()[-1]) if _tail(log) else ""
        if timed_out:
            rec = {"status": "timeout", "reason": f"exceeded the {timeout:g} s timeout; killed"}
        elif os.WIFSIGNALED(status):
            sig = os.WTERMSIG(status)
            name = signal.Signals(sig).name if sig in signal.Signals._value2member_map_ else sig
            reason = f"killed by {name}"
            if limit:
                reason += f" (memory limit {req.get('memory_limit_text')}; peak {peak_mb:.0f} MB)"
            rec = {"status": "crashed", "reason": reason + (f": {tail}" if tail else "")}
        else:
            code = os.WEXITSTATUS(status)
            rec = {
                "status": "crashed",
                "reason": f"exited with code {code}" + (f": {tail}" if tail else ""),
            }
    log.close()
    rec["seconds"] = seconds
    rec["peak_memory_mb"] = peak_mb
    return rec


_WARM: set[str] = set()


def warm_up(kind_name: str) -> None:
    """Run the job kind's warm-up once in this process (before any fork); failures ignored."""
    if kind_name in _WARM:
        return
    _WARM.add(kind_name)
    from .jobs import JOB_KINDS

    kind = JOB_KINDS.get(kind_name)
    if kind is not None and kind.warm_up is not None:
        try:
            kind.warm_up()
        except Exception:  # noqa: BLE001 - only an optimisation
            pass


def serve(inp=None, out=None) -> int:
    """Answer requests (JSON lines on ``inp``) until ``inp`` closes.

    A request ``{"preload": [module, ...]}`` without ``mesh`` only imports those modules
    (before any fork, so children inherit them) and answers ``{"ok": true}``.
    """
    import importlib

    inp = inp if inp is not None else sys.stdin
    out = out if out is not None else sys.stdout
    for name in ("igl_heatseg.batch.jobs",):
        importlib.import_module(name)
    for line in inp:
        if not line.strip():
            continue
        req = json.loads(line)
        for name in req.get("preload", ()):
            try:
                importlib.import_module(name)
            except ImportError:
                pass
        if "mesh" not in req:
            res = {"ok": True}
        else:
            warm_up(req.get("kind", ""))
            res = run_request(req)
        out.write(json.dumps(res, default=float) + "\n")
        out.flush()
    return 0


def main() -> int:
    """``python -m igl_heatseg.batch``: protocol on the original stdout, whatever a job
    or a library prints goes to stderr."""
    proto = os.fdopen(os.dup(1), "w")
    os.dup2(2, 1)
    sys.stdout = sys.stderr
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # ^C reaches the batch, which stops us
    signal.signal(signal.SIGTERM, _on_sigterm)
    return serve(sys.stdin, proto)
