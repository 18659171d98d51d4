"""Dask orchestration of a batch: :func:`run_batch`.

Dask (``distributed``) is imported inside :func:`run_batch` only, with an install hint: the
rest of the package never needs it.
"""

from __future__ import annotations

import contextlib
import importlib.util
import inspect
import logging
import os
import re
import sys
import time
import uuid
from dataclasses import dataclass, field
from datetime import datetime, timezone
from pathlib import Path

from ..io import is_complete
from ..version import __version__
from .discover import discover
from .jobs import job_kind
from .summary import (
    FAILED_STATUSES,
    counts,
    remove_stale_temporaries,
    skipped_record,
    write_gallery,
    write_summary,
)
from .worker import process_mesh

__all__ = ["run_batch", "BatchResult", "parse_memory", "INSTALL_HINT"]

log = logging.getLogger(__name__)

INSTALL_HINT = "igl-heatseg batch needs Dask distributed: pip install 'igl_heatseg[batch]'"

#: Seconds between rewrites of the summary while a batch runs.
SUMMARY_EVERY = 5.0

_UNITS = {
    "": 1,
    "b": 1,
    "k": 10**3,
    "kb": 10**3,
    "m": 10**6,
    "mb": 10**6,
    "g": 10**9,
    "gb": 10**9,
    "t": 10**12,
    "tb": 10**12,
    "kib": 2**10,
    "mib": 2**20,
    "gib": 2**30,
    "tib": 2**40,
}


def parse_memory(text) -> int | None:
    """Bytes of ``"4GB"``, ``"512MiB"``, ``"2e9"``, an int; ``None`` for ``none``/``0``.

    Examples
    --------
    >>> parse_memory("4GB"), parse_memory("1.5 GiB"), parse_memory("none")
    (4000000000, 1610612736, None)
    """
    if text is None:
        return None
    if isinstance(text, (int, float)):
        return int(text) or None
    s = str(text).strip().lower()
    if s in ("", "none", "0", "off", "unlimited"):
        return None
    m = re.fullmatch(r"([0-9.]+(?:e[0-9]+)?)\s*([a-z]*)", s)
    if not m or m.group(2) not in _UNITS:
        raise ValueError(f"memory limit {text!r}: expected a size such as 4GB, 512MiB or none")
    return int(float(m.group(1)) * _UNITS[m.group(2)]) or None


@dataclass
class BatchResult:
    """What :func:`run_batch` did.

    Attributes
    ----------
    records : list of dict
        One per mesh (see :data:`igl_heatseg.batch.summary.COLUMNS`), sorted by mesh.
    counts : dict
        ``{status: n, "total": n}``.
    out : Path
    wall_seconds : float
    dashboard : str or None
        The Dask dashboard address, when there was one.
    """

    records: list
    counts: dict
    out: Path
    wall_seconds: float
    dashboard: str | None = None
    files: dict = field(default_factory=dict)

    @property
    def failed(self) -> list:
        """Records of the meshes without an output."""
        return [r for r in self.records if r["status"] in FAILED_STATUSES]


class _Progress:
    """Progress over meshes on stderr: one rewritten line on a terminal, else a line per ~5% and
    one per failure."""

    def __init__(self, total: int, enabled: bool, stream=None) -> None:
        self.total = total
        self.enabled = enabled
        self.stream = stream if stream is not None else sys.stderr
        self.tty = bool(getattr(self.stream, "isatty", lambda: False)())
        self.t0 = time.perf_counter()
        self.n = 0
        self.c: dict[str, int] = {}
        self.step = max(1, total // 20)

    def say(self, text: str) -> None:
        if self.enabled:
            self.stream.write(("\r\033[K" if self.tty else "") + text + "\n")
            self.stream.flush()

    def update(self, rec: dict) -> None:
        self.n += 1
        s = rec["status"]
        self.c[s] = self.c.get(s, 0) + 1
        if not self.enabled:
            return
        if s in FAILED_STATUSES:
            self.say(f"igl-heatseg batch: {rec['mesh']}: {s}: {rec.get('reason', '')}")
        width = 30
        fill = int(width * self.n / max(1, self.total))
        tally = " ".join(f"{k} {v}" for k, v in sorted(self.c.items()))
        line = (
            f"[{'#' * fill}{'-' * (width - fill)}] {self.n}/{self.total} meshes  {tally}  "
            f"{time.perf_counter() - self.t0:.0f} s"
        )
        if self.tty:
            self.stream.write("\r\033[K" + line + ("\n" if self.n == self.total else ""))
            self.stream.flush()
        elif self.n % self.step == 0 or self.n == self.total:
            self.stream.write(line + "\n")
            self.stream.flush()


def _import_distributed():
    try:
        import dask  # noqa: F401
        import distributed
    except ImportError as exc:
        raise ImportError(f"{INSTALL_HINT} ({exc})") from None
    return distributed


def _start_client(distributed, client, scheduler, workers):
    """``(client, cluster, owned)``: the given client, one on ``scheduler``, or a LocalCluster."""
    import dask

    if client is not None:
        return client, None, False
    if scheduler:
        c = distributed.Client(scheduler, timeout="30s")
        c.wait_for_workers(1, timeout=120)
        return c, None, True
    if workers:
        n = int(workers)
    elif hasattr(os, "sched_getaffinity"):
        n = len(os.sched_getaffinity(0))
    else:
        n = os.cpu_count() or 1
    dashboard = ":0" if importlib.util.find_spec("bokeh") else None
    # A worker that dies while running a mesh is replaced by its nanny, and the mesh is
    # retried once on a live worker before it counts as crashed.
    with dask.config.set({"distributed.scheduler.allowed-failures": 1}):
        cluster = distributed.LocalCluster(
            n_workers=n,
            threads_per_worker=1,
            processes=True,
            dashboard_address=dashboard,
            silence_logs=logging.ERROR,
            host="127.0.0.1",
        )
    return distributed.Client(cluster), cluster, True


def _dashboard(client, local: bool) -> str | None:
    """The dashboard address, or ``None`` when the scheduler serves none (a local scheduler
    serves one only with bokeh installed)."""
    if local and importlib.util.find_spec("bokeh") is None:
        return None
    try:
        if "dashboard" in client.scheduler_info().get("services", {}):
            return client.dashboard_link
    except Exception:  # noqa: BLE001 - the address is a convenience
        return None
    return None


def _stop_servers_plugin(distributed):
    """A worker plugin stopping the worker's job servers when the worker closes."""

    class StopJobServers(distributed.WorkerPlugin):
        name = "igl-heatseg-stop-job-servers"

        def teardown(self, worker):
            import sys

            mod = sys.modules.get("igl_heatseg.batch.worker")  # imported iff it ran a mesh
            if mod is not None:
                mod.stop_servers()

    return StopJobServers()


@contextlib.contextmanager
def _quiet(names=("distributed", "bokeh", "tornado")):
    """Dask's own INFO logs off for the length of a batch (warnings and errors stay)."""
    saved = {n: logging.getLogger(n).level for n in names}
    for n in names:
        if logging.getLogger(n).getEffectiveLevel() < logging.WARNING:
            logging.getLogger(n).setLevel(logging.WARNING)
    try:
        yield
    finally:
        for n, level in saved.items():
            logging.getLogger(n).setLevel(level)


def run_batch(
    inputs,
    out: str | os.PathLike,
    command: str = "segment",
    client=None,
    *,
    scheduler: str | None = None,
    workers: int | None = None,
    mode: str | None = None,
    options: dict | None = None,
    memory_limit="4GB",
    timeout: float | None = 600.0,
    force: bool = False,
    pictures: bool = True,
    progress: bool = True,
    stream=None,
) -> BatchResult:
    """Process many meshes on Dask: each mesh's output as the single-mesh command writes it,
    skipped when already complete, and one summary.

    Parameters
    ----------
    inputs : iterable of str or path-like
        Files, folders, glob patterns (:func:`~igl_heatseg.batch.discover.discover`).
    out : path-like
        ``OUT``: ``OUT/<mesh>/`` per mesh, ``OUT/summary.csv``, ``OUT/summary.json``,
        ``OUT/index.html``. On a cluster, inputs and OUT must be on a filesystem every worker
        sees under the same path.
    command : str
        Job kind, a key of :data:`~igl_heatseg.batch.jobs.JOB_KINDS` (``segment``, ``run``,
        ``cad``).
    client : dask.distributed.Client, optional
        Run on this client (left open). Otherwise on ``scheduler``, or on a new LocalCluster of
        ``workers`` single-threaded worker processes (closed at the end).
    scheduler : str, optional
        Scheduler address, ``tcp://host:8786``.
    workers : int, optional
        LocalCluster size (default: the CPUs this process may use).
    mode : {"paper", "robust"}, optional
        Segmentation mode; default: the command's own (``paper`` for ``segment`` and ``run``,
        ``robust`` for ``cad``, as on the command line).
    options : dict, optional
        More options of the job kind (``theta``, ``eps``, ``solver``, ``energy``, ``cut``).
    memory_limit : str or int or None
        Address-space limit of each mesh's process (``"4GB"``; ``None`` for none).
    timeout : float or None
        Seconds a mesh may take before its process is killed (``None``: no limit).
    force : bool
        Redo meshes whose output is complete.
    pictures : bool
        ``run``: render the pictures.
    progress : bool
        Progress over meshes and the dashboard address on ``stream`` (stderr).

    Returns
    -------
    BatchResult

    Notes
    -----
    A LocalCluster starts its workers with ``multiprocessing``'s spawn method, which re-imports
    the calling script: in a script, call this under ``if __name__ == "__main__":`` (notebooks
    and the command line need nothing). On a scheduler of your own, set
    ``distributed.scheduler.allowed-failures`` to 1 there for "a mesh whose worker died is
    retried once" (environment: ``DASK_DISTRIBUTED__SCHEDULER__ALLOWED_FAILURES=1``); Dask's
    default retries it up to 3 times. Each worker thread runs one mesh at a time in a child of
    its job server.

    Raises
    ------
    ImportError
        Dask distributed is not installed (the message says how to install it).
    ValueError
        Unknown command, bad memory limit, an input that does not exist, no mesh found.
    """
    kind = job_kind(command)
    limit = parse_memory(memory_limit)
    out = Path(out).resolve()
    if out.exists() and not out.is_dir():
        raise ValueError(f"{out}: output path is a file, not a folder")
    meshes = discover(inputs, exclude=out)
    if not meshes:
        raise ValueError("no mesh found in the inputs (" + ", ".join(map(str, inputs)) + ")")
    if mode is None:  # the single-mesh command's own default
        param = inspect.signature(kind.run).parameters.get("mode")
        mode = None if param is None or param.default is param.empty else param.default
    opts = {"pictures": pictures} if mode is None else {"mode": mode, "pictures": pictures}
    opts.update(options or {})
    t0 = time.perf_counter()
    started = datetime.now(timezone.utc).isoformat(timespec="seconds")
    records: dict[str, dict] = {}
    todo = []
    for m in meshes:
        output = out / m.key
        if not force and is_complete(output):
            records[m.key] = skipped_record(m.name, str(m.path), str(output), kind.summarize)
        else:
            todo.append(m)
    prog = _Progress(len(meshes), progress, stream)
    for rec in records.values():
        prog.update(rec)
    meta = {
        "igl_heatseg": __version__,
        "command": command,
        "options": opts,
        "memory_limit": memory_limit,
        "timeout": timeout,
        "force": force,
        "inputs": [str(i) for i in inputs],
        "started": started,
    }
    out.mkdir(parents=True, exist_ok=True)
    remove_stale_temporaries(out)  # of a batch killed while writing its summary
    dashboard = None

    def flush(final: bool = False) -> None:
        meta["wall_seconds"] = time.perf_counter() - t0
        meta["finished"] = final
        write_summary(out, list(records.values()), meta)

    if todo:
        prog.say(
            f"igl-heatseg batch: {len(todo)} mesh(es) to process, "
            f"{len(meshes) - len(todo)} already complete"
        )
        distributed = _import_distributed()
        stack = contextlib.ExitStack()
        stack.enter_context(_quiet())
        try:
            client_, cluster, owned = _start_client(distributed, client, scheduler, workers)
        except BaseException:
            stack.close()
            raise
        try:
            dashboard = _dashboard(client_, local=cluster is not None)
            if owned:
                client_.register_plugin(_stop_servers_plugin(distributed))
            nworkers = len(client_.scheduler_info().get("workers", {}))
            meta["workers"] = nworkers
            meta["scheduler"] = client_.scheduler.address
            prog.say(
                f"igl-heatseg batch: {nworkers} worker(s) at {client_.scheduler.address}"
                + (
                    f"; dashboard {dashboard}"
                    if dashboard
                    else "; no dashboard (pip install bokeh for one)"
                    if cluster is not None
                    else ""
                )
            )
            todo.sort(key=lambda m: -m.path.stat().st_size)  # the largest first
            run_id = uuid.uuid4().hex[:8]
            futures = {}
            for i, m in enumerate(todo):
                task = {
                    "mesh": m.name,
                    "input": str(m.path),
                    "output": str(out / m.key),
                    "kind": command,
                    "options": opts,
                    "timeout": timeout,
                    "memory_limit": limit,
                    "memory_limit_text": str(memory_limit) if limit else None,
                }
                f = client_.submit(
                    process_mesh,
                    task,
                    key=f"igl-heatseg-{run_id}-{i}",
                    retries=1,
                    pure=False,
                    priority=len(todo) - i,
                )
                futures[f] = m
            last = time.perf_counter()
            try:
                for f in distributed.as_completed(list(futures)):
                    m = futures[f]
                    try:
                        rec = f.result()
                    except Exception as exc:  # noqa: BLE001 - KilledWorker and the like
                        rec = {
                            "mesh": m.name,
                            "input": str(m.path),
                            "output": str(out / m.key),
                            "status": "crashed",
                            "reason": f"{type(exc).__name__}: {exc}",
                        }
                    if rec["status"] not in ("done",):
                        rec["output"] = rec["output"] if is_complete(rec["output"]) else None
                    records[m.key] = rec
                    prog.update(rec)
                    if time.perf_counter() - last > SUMMARY_EVERY:
                        flush()
                        last = time.perf_counter()
            except BaseException:
                for f, m in futures.items():
                    if m.key not in records:
                        f.cancel()
                        records[m.key] = {
                            "mesh": m.name,
                            "input": str(m.path),
                            "output": None,
                            "status": "pending",
                            "reason": "batch interrupted",
                        }
                flush()
                raise
        finally:
            if owned:
                client_.close()
                if cluster is not None:
                    cluster.close()
            stack.close()
    wall = time.perf_counter() - t0
    flush(final=True)
    recs = sorted(records.values(), key=lambda r: r["mesh"])
    gallery = write_gallery(out, recs, kind.pictures, title=f"igl-heatseg batch {command}: {out}")
    c = counts(recs)
    prog.say(
        "igl-heatseg batch: "
        + ", ".join(f"{k} {v}" for k, v in sorted(c.items()))
        + f" in {wall:.1f} s; wrote {out}/summary.csv, summary.json, index.html"
    )
    return BatchResult(
        records=recs,
        counts=c,
        out=out,
        wall_seconds=wall,
        dashboard=dashboard,
        files={"csv": out / "summary.csv", "json": out / "summary.json", "html": gallery},
    )
