"""Benchmark ``igl-heatseg batch`` against a plain sequential loop over ``igl-heatseg segment``.

The set: 200 meshes of mixed sizes, made in WORKDIR/meshes: the repo's data/ and the shared
mechanical and scan meshes (copied until they make 60 files), and 140 generated shapes
(ellipsoids, boxes, cylinders; 200 to 20k faces, seeded).

Measured, each end to end as a user runs it (wall time of the command):

1. the loop: ``igl-heatseg segment MESH -o OUT/<mesh>`` in a subprocess per mesh, one after
   the other;
2. ``igl-heatseg batch MESHES -o OUT --workers 1``;
3. ``igl-heatseg batch MESHES -o OUT --workers 2``;
4. resumption: the 2-worker batch killed (SIGKILL to its process group) once a third of the
   meshes are complete, then run again: what it skipped, what it redid, its wall time.

Then: the labels of every mesh agree between the loop and the batches, peak memory per worker
(the largest peak RSS of a job on that worker, from summary.json), and the results as markdown
(``--write benchmarks/batch_results.md``).

Usage::

    python benchmarks/bench_batch.py [--workdir /tmp/bench_batch] \\
        [--write benchmarks/batch_results.md]
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import resource
import shutil
import signal
import subprocess
import sys
import time
from datetime import datetime, timezone
from pathlib import Path

import igl
import numpy as np

ROOT = Path(__file__).resolve().parents[1]
SHARED = ROOT.parent / "shared" / "data"
if not SHARED.is_dir():
    SHARED = Path("/work/shared/data")
N_MESHES = 200
N_REAL = 60


def _ellipsoid(level, axes):
    V, F = igl.icosahedron()
    V, F = igl.loop(V, F, level)
    return V / np.linalg.norm(V, axis=1, keepdims=True) * axes, F


def _box(level, size):
    V = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], float)
    F = np.array([[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1],
                  [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]])  # fmt: skip
    V, F = igl.upsample(V, F, level)
    return V * size, F


def _cylinder(n, rings, r, h):
    t = 2 * np.pi * np.arange(n) / n
    V = [[r * np.cos(a), r * np.sin(a), z] for z in np.linspace(0, h, rings + 1) for a in t]
    F = []
    for i in range(rings):
        for j in range(n):
            a, b = i * n + j, i * n + (j + 1) % n
            F += [[a, b, b + n], [a, b + n, a + n]]
    bottom, top = len(V), len(V) + 1
    V += [[0, 0, 0], [0, 0, h]]
    for j in range(n):
        F.append([bottom, (j + 1) % n, j])
        F.append([top, rings * n + j, rings * n + (j + 1) % n])
    return np.array(V, float), np.array(F)


def make_set(folder: Path) -> list[Path]:
    """The 200 meshes (made once; reused when the folder is complete)."""
    real = sorted(p for p in (ROOT / "data").iterdir() if p.suffix in (".ply", ".off", ".obj"))
    for sub in ("mechanical", "scan"):
        real += sorted(
            p
            for p in (SHARED / sub).glob("*")
            if p.suffix.lower() in (".ply", ".off", ".obj", ".stl")
        )
    folder.mkdir(parents=True, exist_ok=True)
    files = sorted(p for p in folder.rglob("*") if p.is_file())
    if len(files) == N_MESHES:
        return files
    shutil.rmtree(folder)
    (folder / "real").mkdir(parents=True)
    (folder / "generated").mkdir()
    for i in range(N_REAL):
        src = real[i % len(real)]
        shutil.copy(src, folder / "real" / f"{i:02d}_{src.name}")
    rng = np.random.default_rng(15)
    for i in range(N_MESHES - N_REAL):
        kind = i % 3
        if kind == 0:
            V, F = _ellipsoid(int(rng.integers(2, 6)), rng.uniform(0.5, 3, 3))
        elif kind == 1:
            V, F = _box(int(rng.integers(1, 5)), rng.uniform(0.5, 3, 3))
        else:
            n = int(rng.integers(12, 96))
            V, F = _cylinder(n, int(rng.integers(1, 40)), rng.uniform(0.2, 2), rng.uniform(0.5, 4))
        ext = (".obj", ".off", ".ply", ".stl")[i % 4]
        igl.write_triangle_mesh(str(folder / "generated" / f"g{i:03d}{ext}"), V, F.astype(np.int64))
    return sorted(p for p in folder.rglob("*") if p.is_file())


def _cli() -> list[str]:
    exe = Path(sys.executable).with_name("igl-heatseg")
    return [str(exe)] if exe.exists() else [sys.executable, "-m", "igl_heatseg"]


def _cpu() -> float:
    """CPU seconds (user + system) of the waited-for descendants so far."""
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def core_probe() -> float:
    """Wall time of two CPU-bound processes (2 CPU s each) over that of one: 1.0 when this
    session can use 2 cores now, 2.0 when it gets one (other sessions busy)."""
    code = "import time\nt = time.process_time()\nwhile time.process_time() - t < 2: pass"
    walls = []
    for n in (1, 2):
        t = time.perf_counter()
        procs = [subprocess.Popen([sys.executable, "-c", code]) for _ in range(n)]
        for p in procs:
            p.wait()
        walls.append(time.perf_counter() - t)
    return walls[1] / walls[0]


def run_loop(meshes: list[Path], src: Path, out: Path) -> tuple[float, int]:
    """The plain loop: one ``igl-heatseg segment`` subprocess per mesh."""
    shutil.rmtree(out, ignore_errors=True)
    t = time.perf_counter()
    ok = 0
    for m in meshes:
        key = m.relative_to(src).with_suffix("")
        r = subprocess.run(
            _cli() + ["segment", str(m), "-o", str(out / key)],
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
        )
        ok += r.returncode == 0
    return time.perf_counter() - t, ok


def _complete(out: Path) -> int:
    """Complete output folders under ``out`` (os.walk: folders renamed meanwhile are skipped)."""
    return sum("report.json" in files for _, _, files in os.walk(out))


def run_batch_cli(src: Path, out: Path, workers: int, fresh: bool = True, kill_after=None):
    """``igl-heatseg batch SRC -o OUT --workers N``; with ``kill_after`` (a count), SIGKILL
    its process group once that many outputs are complete. Returns (seconds, summary or None)."""
    if fresh:
        shutil.rmtree(out, ignore_errors=True)
    t = time.perf_counter()
    proc = subprocess.Popen(
        _cli() + ["batch", str(src), "-o", str(out), "--workers", str(workers)],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
        start_new_session=True,
    )
    if kill_after is not None:
        while proc.poll() is None and _complete(out) < kill_after:
            time.sleep(0.05)
        os.killpg(proc.pid, signal.SIGKILL)
        proc.wait()
        return time.perf_counter() - t, None
    proc.wait()
    seconds = time.perf_counter() - t
    return seconds, json.loads((out / "summary.json").read_text())


def _labels_agree(a: Path, b: Path, keys) -> int:
    bad = 0
    for k in keys:
        la, lb = a / k / "labels.txt", b / k / "labels.txt"
        if la.is_file() != lb.is_file() or (la.is_file() and la.read_bytes() != lb.read_bytes()):
            bad += 1
    return bad


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--workdir", default="/tmp/bench_batch")
    ap.add_argument("--write", default=None, help="markdown results file")
    ap.add_argument("--skip-loop", action="store_true")
    args = ap.parse_args()
    work = Path(args.workdir)
    src = work / "meshes"
    meshes = make_set(src)
    faces = []
    for m in meshes:
        try:
            faces.append(len(igl.read_triangle_mesh(str(m))[1]))
        except Exception:  # noqa: BLE001
            faces.append(0)
    faces = np.array(faces)
    print(
        f"{len(meshes)} meshes, faces min {faces.min()} median {int(np.median(faces))} "
        f"max {faces.max()}, total {faces.sum()}",
        flush=True,
    )
    load0 = os.getloadavg()
    res: dict = {"meshes": len(meshes), "faces": faces.tolist(), "load_before": load0}

    res["core_probe"] = [core_probe()]
    print(f"core probe: {res['core_probe'][0]:.2f}", flush=True)
    if not args.skip_loop:
        c0 = _cpu()
        t_loop, ok = run_loop(meshes, src, work / "out_loop")
        res["loop"] = {"seconds": t_loop, "ok": ok, "cpu_seconds": _cpu() - c0}
        print(f"loop: {t_loop:.1f} s ({res['loop']['cpu_seconds']:.0f} CPU s), {ok} ok", flush=True)
    for n in (1, 2):
        c0 = _cpu()
        t, summary = run_batch_cli(src, work / f"out_batch{n}", n)
        res[f"batch{n}"] = {
            "cpu_seconds": _cpu() - c0,
            "seconds": t,
            "counts": summary["counts"],
            "wall_in_batch": summary["wall_seconds"],
        }
        per_worker: dict[str, float] = {}
        for r in summary["meshes"]:
            if r.get("peak_memory_mb") is not None and r.get("worker"):
                per_worker[r["worker"]] = max(per_worker.get(r["worker"], 0), r["peak_memory_mb"])
        res[f"batch{n}"]["peak_mb_per_worker"] = per_worker
        res[f"batch{n}"]["job_seconds_sum"] = sum(r.get("seconds") or 0 for r in summary["meshes"])
        print(
            f"batch --workers {n}: {t:.1f} s, {summary['counts']}, peak MB per worker "
            f"{ {k: round(v) for k, v in per_worker.items()} }",
            flush=True,
        )
    res["core_probe"].append(core_probe())
    print(f"core probe: {res['core_probe'][-1]:.2f}", flush=True)
    keys = [m.relative_to(src).with_suffix("") for m in meshes]
    if not args.skip_loop:
        res["labels_differ"] = {
            n: _labels_agree(work / "out_loop", work / f"out_batch{n}", keys) for n in (1, 2)
        }
        print(f"labels differing from the loop's: {res['labels_differ']}", flush=True)

    # resumption: kill the 2-worker batch a third of the way, restart
    out = work / "out_resume"
    t_killed, _ = run_batch_cli(src, out, 2, kill_after=len(meshes) // 3)
    complete = _complete(out)
    leftovers = len([p for p in out.rglob(".*.tmp")])
    t_rest, summary = run_batch_cli(src, out, 2, fresh=False)
    res["resume"] = {
        "killed_after_s": t_killed,
        "complete_at_kill": complete,
        "tmp_left_at_kill": leftovers,
        "restart_seconds": t_rest,
        "counts": summary["counts"],
        "labels_differ": _labels_agree(work / "out_batch2", out, keys),
    }
    print(
        f"resume: killed after {t_killed:.1f} s with {complete} complete "
        f"({leftovers} temporary folders), restart {t_rest:.1f} s: {summary['counts']}",
        flush=True,
    )
    res["load_after"] = os.getloadavg()
    (work / "results.json").write_text(json.dumps(res, indent=1, default=str))
    if args.write:
        write_markdown(Path(args.write), res, summary)
    return 0


def _autogroup_note() -> str:
    try:
        on = Path("/proc/sys/kernel/sched_autogroup_enabled").read_text().strip() == "1"
    except OSError:
        on = False
    if not on:
        return "CPU scheduling: no autogroup; every process competes for the cores."
    return (
        "CPU scheduling: `kernel.sched_autogroup_enabled = 1`: the kernel shares the cores "
        "equally between sessions, whatever their process counts. While other sessions keep "
        "the cores busy (see the load average), a 2-worker batch gets no more CPU than a "
        "1-worker one; the 2-worker wall time then says nothing about parallel scaling, and "
        "the CPU seconds are the better measure of the work each run does."
    )


def write_markdown(path: Path, res: dict, summary: dict) -> None:
    f = np.array(res["faces"])
    loop = res.get("loop", {}).get("seconds")
    b1, b2 = res["batch1"], res["batch2"]
    lines = [
        "# `igl-heatseg batch`: benchmark",
        "",
        f"Date: {datetime.now(timezone.utc).strftime('%Y-%m-%d %H:%M UTC')}. Machine: "
        f"{platform.machine()}, {os.cpu_count()} cores, "
        f"{os.sysconf('SC_PAGE_SIZE') * os.sysconf('SC_PHYS_PAGES') / 2**30:.0f} GiB, "
        f"Python {platform.python_version()}, {platform.system()}. Load average before / after "
        f"(other sessions share the machine): {', '.join(f'{x:.1f}' for x in res['load_before'])}"
        f" / {', '.join(f'{x:.1f}' for x in res['load_after'])}.",
        "",
        "Command: `python benchmarks/bench_batch.py --write benchmarks/batch_results.md`.",
        "",
        f"Set: {res['meshes']} meshes (60 copies of the repo's data/ and the shared mechanical "
        f"and scan meshes, 140 generated ellipsoids, boxes and cylinders); faces min "
        f"{f.min()}, median {int(np.median(f))}, max {f.max()}, total {f.sum()}.",
        "",
        "Every time is the wall time of the whole command (for the batch: cluster start, "
        "workers, job servers, summary); CPU s is the user + system time of the command's "
        "whole process tree.",
        "",
        _autogroup_note(),
        "",
        "Core probe (wall time of two CPU-bound processes in one session over that of one: "
        "1.0 = two cores free for this session, 2.0 = one): before the runs "
        f"{res['core_probe'][0]:.2f}, after the batches {res['core_probe'][-1]:.2f}.",
        "",
        "| run | wall s | CPU s | speed-up vs loop (wall) | outcome |",
        "| --- | ---: | ---: | ---: | --- |",
    ]
    if loop:
        lines.append(
            f"| loop: `igl-heatseg segment` per mesh, sequential | {loop:.1f} | "
            f"{res['loop'].get('cpu_seconds', 0):.0f} | 1.00x | {res['loop']['ok']} exit 0 |"
        )
    for name, b in (("batch --workers 1", b1), ("batch --workers 2", b2)):
        sp = f"{loop / b['seconds']:.2f}x" if loop else "-"
        c = ", ".join(f"{k} {v}" for k, v in sorted(b["counts"].items()))
        lines.append(
            f"| `igl-heatseg {name}` | {b['seconds']:.1f} | {b.get('cpu_seconds', 0):.0f} | "
            f"{sp} | {c} |"
        )
    lines += [
        "",
        "Target: the 2-worker batch at least 1.7x faster than the loop: "
        + (f"**{loop / b2['seconds']:.2f}x**." if loop else "not measured."),
        "",
        "Peak memory per worker (the largest peak RSS of one mesh's job process on that "
        "worker; each job is forked from a job server that has numpy, scipy and libigl loaded, "
        "about 85 MB of it):",
        "",
    ]
    for name, b in (("1 worker", b1), ("2 workers", b2)):
        lines.append(
            f"- {name}: "
            + ", ".join(f"{w}: {v:.0f} MB" for w, v in sorted(b["peak_mb_per_worker"].items()))
        )
    r = res["resume"]
    lines += [
        "",
        f"Labels (labels.txt) differing from the loop's: {res.get('labels_differ', '-')} "
        f"(per worker count); resumed batch vs uninterrupted: {r['labels_differ']}.",
        "",
        "Resumption: the 2-worker batch killed (SIGKILL to its process group) once "
        f"{res['meshes'] // 3} outputs were complete, after {r['killed_after_s']:.1f} s: "
        f"{r['complete_at_kill']} complete folders, {r['tmp_left_at_kill']} temporary folders "
        f"left. Restarted: {r['restart_seconds']:.1f} s, "
        + ", ".join(f"{k} {v}" for k, v in sorted(r["counts"].items()))
        + f" (uninterrupted 2-worker run: {b2['seconds']:.1f} s).",
        "",
    ]
    path.write_text("\n".join(lines))


if __name__ == "__main__":
    sys.exit(main())
