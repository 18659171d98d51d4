"""Surface-recovery table: methods x parts of a benchmark set -> markdown + JSON.

Reads a set written by ``tools/make_benchmark_sets.py`` (``SET/manifest.json`` with the
parts' OBJ, face labels and surface types) and scores every method on every part against the
exact B-Rep face labels:

* ``purity``, ``coverage``: area-weighted (``igl_heatseg.evaluation``);
* ``seg/true``: predicted segments over true (B-Rep) faces
  (``igl_heatseg.evaluation.segment_ratio``);
* ``type acc``: share of the area whose predicted segment type equals the true surface type
  (``igl_heatseg.evaluation.type_accuracy``; "-" when a method gives no types);
* ``bnd ratio``: total predicted segment boundary length over total true face boundary length
  (``igl_heatseg.evaluation.boundary_length_ratio``);
* ``s``: wall seconds of the method per part (heat modes: the whole CLI process, start-up
  included; the in-process time from ``report.json`` is in the JSON as ``seconds_inproc``;
  CGAL: the forked child, point-set construction and post-processing included).

Pass bars per part (issue 11, "Done means"): ``pc`` purity >= 0.90 and coverage >= 0.85;
``seg`` 0.8 <= seg/true <= 1.5; ``bnd`` 0.9 <= bnd ratio <= 1.15; ``type`` type acc >= 0.90
(a method without types fails it); ``all`` every bar.  Aggregate targets per method: mean
purity >= 0.95, mean coverage >= 0.92, mean type acc >= 0.90, every part ``pc``, every part
``seg``, ``bnd`` on >= 90 % of the parts.

Methods:

* ``paper``, ``robust``: ``igl-heatseg segment MESH -o DIR --mode MODE`` in a subprocess
  (``--cli`` sets the command; labels from ``DIR/labels.txt``, types from ``report.json``'s
  ``surfaces[i]["type"]`` when present, else ``primitive_types`` when it has one per segment);
* ``cgal``: CGAL Efficient RANSAC with CGAL's default parameters (``benchmarks/peers.py``);
* ``cgal-spacing``: the same with ``cluster_epsilon`` from the mesh's edge lengths.

Aggregates per method: means, pass counts per bar and the targets, overall and by
tessellation and noise level.  ``--jobs N`` runs N (part, method) tasks at a time, each in a
worker process (spawned; each heat mode runs its CLI in a further subprocess, CGAL in a forked
child); seconds then include the contention between them.

Usage::

    python benchmarks/surface_table.py /work/parts/tuning --out benchmarks/surface_results
    python benchmarks/surface_table.py /work/parts/tuning/manifest.json --methods paper cgal \\
        --limit 5 --jobs 2 --out /tmp/t
"""

from __future__ import annotations

import argparse
import concurrent.futures
import datetime
import functools
import json
import math
import multiprocessing
import platform
import shlex
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(HERE.parent / "tools"))

from igl_heatseg.evaluation import (  # noqa: E402
    boundary_length_ratio,
    coverage,
    face_kinds,
    purity,
    segment_ratio,
    type_accuracy,
)
from igl_heatseg.mesh.topology import edge_topology  # noqa: E402

METHODS_ALL = ("paper", "robust", "cgal", "cgal-spacing")
METHODS_DEFAULT = METHODS_ALL

#: Per-part pass bars (issue 11): purity and coverage, segments per B-Rep face, boundary
#: length ratio, type accuracy.
PURITY_PASS, COVERAGE_PASS = 0.90, 0.85
SEG_RATIO_RANGE = (0.8, 1.5)
BND_RATIO_RANGE = (0.9, 1.15)
TYPE_PASS = 0.90

#: Aggregate targets (issue 11): mean purity, mean coverage, mean type accuracy, and the share
#: of the parts whose boundary ratio is within range.
PURITY_TARGET, COVERAGE_TARGET, TYPE_TARGET, BND_SHARE_TARGET = 0.95, 0.92, 0.90, 0.90

#: The per-part bars, in report order.
BARS = ("pc", "seg", "bnd", "type", "all")

#: Seconds before a CLI run is abandoned (scored as failed).
TIMEOUT_DEFAULT = 900.0


# --------------------------------------------------------------------------------------------
# Inputs
# --------------------------------------------------------------------------------------------


def load_manifest(path: str | Path) -> tuple[Path, dict]:
    """The set folder and its manifest, from the folder or the ``manifest.json`` path."""
    path = Path(path)
    mpath = path / "manifest.json" if path.is_dir() else path
    if not mpath.exists():
        raise FileNotFoundError(f"no manifest.json at {path}")
    return mpath.parent, json.loads(mpath.read_text())


def load_part(folder: Path, entry: dict) -> dict:
    """Mesh, true labels and true per-face kinds of one manifest entry."""
    from make_parts import read_part

    V, F, labels, types = read_part(folder / entry["obj"])
    if len(labels) != len(F):
        raise ValueError(f"{entry['name']}: {len(labels)} labels for {len(F)} faces")
    P = V[F]
    area = 0.5 * np.linalg.norm(np.cross(P[:, 1] - P[:, 0], P[:, 2] - P[:, 0]), axis=1)
    return dict(
        V=V,
        F=F,
        labels=labels,
        kinds=face_kinds(labels, types) if types else None,
        area=area,
        topo=edge_topology(F),
    )


# --------------------------------------------------------------------------------------------
# Methods: each returns (labels, per-segment types or None, seconds, extra dict)
# --------------------------------------------------------------------------------------------


def default_cli() -> list[str]:
    """``igl-heatseg`` from PATH, else ``python -m igl_heatseg``."""
    exe = shutil.which("igl-heatseg")
    return [exe] if exe else [sys.executable, "-m", "igl_heatseg"]


def _report_types(report: dict, k: int) -> tuple[list | None, str | None]:
    """Per-segment types from a CLI report: ``surfaces[i].type``, else ``primitive_types``."""
    surfaces = report.get("surfaces")
    if isinstance(surfaces, list) and len(surfaces) == k:
        return [s.get("type") for s in surfaces], "surfaces"
    prim = report.get("primitive_types")
    if isinstance(prim, list) and len(prim) == k:
        return list(prim), "primitive_types"
    return None, None


def run_cli(obj: Path, mode: str, cli: list[str], timeout: float) -> tuple:
    """Segment ``obj`` with the CLI in ``mode``; labels, types, wall seconds, extra."""
    with tempfile.TemporaryDirectory(prefix="surface_table_") as tmp:
        out = Path(tmp) / "seg"
        cmd = [*cli, "segment", str(obj), "-o", str(out), "--mode", mode]
        t0 = time.perf_counter()
        # cwd outside the repository: ``python -m`` puts the cwd first on sys.path
        proc = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout, cwd=tmp)
        seconds = time.perf_counter() - t0
        if proc.returncode != 0:
            tail = (proc.stderr or proc.stdout).strip().splitlines()[-1:] or ["?"]
            raise RuntimeError(f"exit {proc.returncode}: {tail[0]}")
        labels = np.loadtxt(out / "labels.txt", dtype=np.int64).reshape(-1)
        report = json.loads((out / "report.json").read_text())
    # types are indexed by label value (the CLI writes labels 0..k-1, one surface per label)
    k = int(labels.max()) + 1 if labels.size else 0
    types, source = _report_types(report, k)
    inproc = report.get("timings", {}).get("total")
    return labels, types, seconds, dict(types_source=source, seconds_inproc=inproc)


def run_cgal(V: np.ndarray, F: np.ndarray, spacing: bool) -> tuple:
    """CGAL Efficient RANSAC (isolated in a child process); labels, types, seconds, extra."""
    import peers

    ce = peers.spacing_cluster_epsilon(V, F) if spacing else None
    t0 = time.perf_counter()
    r = peers.cgal_ransac_isolated(V, F, cluster_epsilon=ce)
    seconds = time.perf_counter() - t0
    extra = dict(
        types_source="ransac",
        unassigned=round(r.unassigned, 4),
        shapes=len(r.shapes),
        crashes=r.crashes,
        cluster_epsilon=ce,
    )
    return r.labels, r.types, seconds, extra


# --------------------------------------------------------------------------------------------
# Scoring
# --------------------------------------------------------------------------------------------


def score(part: dict, labels: np.ndarray, types: list | None) -> dict:
    """Metrics of one prediction against the part's truth (``igl_heatseg.evaluation``).

    ``types[k]`` is the surface type of label ``k`` (``None``: the method gives no types).
    """
    truth, area = part["labels"], part["area"]
    row = dict(
        segments=int(np.unique(labels).size),
        seg_ratio=segment_ratio(labels, truth),
        purity=purity(labels, truth, area),
        coverage=coverage(labels, truth, area),
        type_acc=None,
        bnd_ratio=boundary_length_ratio(part["V"], part["F"], labels, truth, part.get("topo")),
    )
    if types is not None and part.get("kinds") is not None:
        row["type_acc"] = type_accuracy(face_kinds(labels, types), part["kinds"], area)
    row.update(bars(row))
    return row


def bars(r: dict) -> dict:
    """The per-part pass bars of a scored row: ``pass_pc``, ``pass_seg``, ... ``pass_all``."""
    pc = r["purity"] >= PURITY_PASS and r["coverage"] >= COVERAGE_PASS
    seg = SEG_RATIO_RANGE[0] <= r["seg_ratio"] <= SEG_RATIO_RANGE[1]
    bnd = BND_RATIO_RANGE[0] <= r["bnd_ratio"] <= BND_RATIO_RANGE[1]
    typ = r["type_acc"] is not None and r["type_acc"] >= TYPE_PASS
    return dict(
        pass_pc=pc, pass_seg=seg, pass_bnd=bnd, pass_type=typ, pass_all=pc and seg and bnd and typ
    )


def _base(method: str, entry: dict, part: dict | None = None) -> dict:
    base = {k: entry.get(k) for k in ("name", "family", "seed", "tessellation", "noise")}
    base.update(method=method, faces=entry.get("faces"), true_faces=entry.get("true_faces"))
    if part is not None:
        base.update(faces=len(part["F"]), true_faces=int(part["labels"].max()) + 1)
    return base


def _remaining(args) -> float:
    """Seconds left before ``args.deadline`` (epoch seconds; ``inf`` without one)."""
    deadline = getattr(args, "deadline", None)
    return math.inf if deadline is None else deadline - time.time()


def unfinished_row(method: str, entry: dict, why: str = "deadline") -> dict:
    """The row of a task the deadline stopped: left out of every aggregate."""
    return dict(_base(method, entry), unfinished=why, error=None, seconds=None)


def run_method(method: str, folder: Path, entry: dict, part: dict, args) -> dict:
    """One method on one part: the scored row (``error`` set and metrics None on failure;
    ``unfinished`` set when ``args.deadline`` passed before or during the run)."""
    base = _base(method, entry, part)
    left = _remaining(args)
    if left <= 0:
        return unfinished_row(method, entry)
    try:
        if method in ("paper", "robust"):
            timeout = min(args.timeout, left)
            try:
                labels, types, seconds, extra = run_cli(
                    folder / entry["obj"], method, args.cli, timeout
                )
            except subprocess.TimeoutExpired:
                if timeout < args.timeout:  # stopped by the deadline, not by its own timeout
                    return unfinished_row(method, entry)
                raise
        elif method in ("cgal", "cgal-spacing"):
            labels, types, seconds, extra = run_cgal(part["V"], part["F"], method != "cgal")
        else:
            raise ValueError(f"unknown method {method!r}")
        if labels.shape != (len(part["F"]),):
            raise RuntimeError(f"{labels.shape[0]} labels for {len(part['F'])} faces")
    except (RuntimeError, OSError, ValueError, subprocess.TimeoutExpired) as exc:
        return dict(base, error=str(exc)[:300], seconds=None)
    return dict(base, **score(part, labels, types), seconds=seconds, error=None, **extra)


# --------------------------------------------------------------------------------------------
# Aggregation and output
# --------------------------------------------------------------------------------------------


def _mean(values) -> float | None:
    v = [x for x in values if x is not None and np.isfinite(x)]
    return float(np.mean(v)) if v else None


def _median(values) -> float | None:
    v = [x for x in values if x is not None and not (isinstance(x, float) and np.isnan(x))]
    return float(np.median(v)) if v else None


def _passes(r: dict, bar: str = "pc") -> bool:
    return r.get("error") is None and bool(r.get(f"pass_{bar}"))


def _group(rs: list[dict]) -> dict:
    """Means, medians and pass counts of a group of rows of one method."""
    ok = [r for r in rs if r.get("error") is None]
    g = dict(
        parts=len(rs),
        failed=len(rs) - len(ok),
        purity=_mean(r["purity"] for r in ok),
        coverage=_mean(r["coverage"] for r in ok),
        seg_ratio=_mean(r["seg_ratio"] for r in ok),
        seg_ratio_median=_median(r["seg_ratio"] for r in ok),
        type_acc=_mean(r["type_acc"] for r in ok),
        type_acc_parts=sum(r["type_acc"] is not None for r in ok),
        bnd_ratio=_mean(r["bnd_ratio"] for r in ok),
        bnd_ratio_median=_median(r["bnd_ratio"] for r in ok),
        seconds=_mean(r["seconds"] for r in ok),
        seconds_median=_median(r["seconds"] for r in ok),
        passed=sum(_passes(r) for r in rs),
    )
    for bar in BARS[1:]:
        g[f"passed_{bar}"] = sum(_passes(r, bar) for r in rs)
    return g


def targets(g: dict) -> dict:
    """The aggregate targets of issue 11 for one group: ``name -> (value, met)``."""
    n = g["parts"]

    def at_least(x, bar):
        return (x, x is not None and x >= bar)

    return {
        f"mean purity >= {PURITY_TARGET:.2f}": at_least(g["purity"], PURITY_TARGET),
        f"mean coverage >= {COVERAGE_TARGET:.2f}": at_least(g["coverage"], COVERAGE_TARGET),
        f"mean type acc >= {TYPE_TARGET:.2f}": at_least(
            g["type_acc"] if g["type_acc_parts"] == n - g["failed"] else None, TYPE_TARGET
        ),
        "every part purity/coverage >= .90/.85": (f"{g['passed']}/{n}", g["passed"] == n),
        "every part seg/true in [0.8, 1.5]": (f"{g['passed_seg']}/{n}", g["passed_seg"] == n),
        f"bnd ratio in [0.9, 1.15] on >= {BND_SHARE_TARGET:.0%} of parts": (
            f"{g['passed_bnd']}/{n}",
            n > 0 and g["passed_bnd"] >= BND_SHARE_TARGET * n,
        ),
    }


def common_rows(rows: list[dict], methods: list[str]) -> tuple[list[dict], int]:
    """The rows of the parts every method finished (scored or failed, not stopped by the
    deadline), and how many such parts there are."""
    done: dict[str, set] = {}
    for r in rows:
        if not r.get("unfinished"):
            done.setdefault(r["name"], set()).add(r["method"])
    names = {n for n, ms in done.items() if set(methods) <= ms}
    return [r for r in rows if r["name"] in names and not r.get("unfinished")], len(names)


def aggregate(rows: list[dict], methods: list[str]) -> dict:
    """Per method: means, pass counts per bar, targets; and the same by noise level, plus the
    purity/coverage pass counts by tessellation and by noise."""
    out = {}
    for m in methods:
        rs = [r for r in rows if r["method"] == m]
        agg = _group(rs)
        agg["targets"] = targets(agg)
        agg["targets_met"] = all(met for _, met in agg["targets"].values())
        agg["by_noise"] = {
            str(g): _group([r for r in rs if r["noise"] == g])
            for g in sorted({r["noise"] for r in rs}, key=lambda x: (x is None, x))
        }
        for key in ("tessellation", "noise"):
            groups = sorted({r[key] for r in rs}, key=str)
            agg[f"passed_by_{key}"] = {
                str(g): f"{sum(_passes(r) for r in rs if r[key] == g)}/"
                f"{sum(r[key] == g for r in rs)}"
                for g in groups
            }
        out[m] = agg
    return out


def _f(x, fmt="{:.3f}") -> str:
    if x is None:
        return "-"
    if isinstance(x, str):
        return x
    if isinstance(x, float) and not np.isfinite(x):
        return "inf"
    return fmt.format(x)


def _bars_cell(r: dict) -> str:
    return " ".join(b if r.get(f"pass_{b}") else "-" for b in BARS[:-1])


def markdown(meta: dict, rows: list[dict], agg: dict, methods: list[str]) -> str:
    """The markdown report: header, aggregate, targets, by noise, by variant, per-part rows."""
    lines = [
        f"# Surface-recovery table: {meta['set']} set ({meta['parts']} parts)",
        "",
        *(
            [
                f"- **finished: {meta['parts_scored']} of {meta['parts']} parts by every method "
                f"(deadline {meta.get('deadline_utc')}); the aggregates cover those parts only**"
            ]
            if meta.get("parts_scored", meta["parts"]) != meta["parts"]
            else []
        ),
        f"- date: {meta['date']}; wall time of the table {meta.get('seconds', '?')} s "
        f"with --jobs {meta.get('jobs', 1)}",
        f"- machine: {meta['machine']}",
        f"- command: `{meta['command']}`",
        f"- commit: {meta.get('commit', '?')}; CLI: `{meta['cli']}`; igl_heatseg from "
        f"`{meta['igl_heatseg']}`",
        "- bars per part: pc = purity >= 0.90 and coverage >= 0.85 (area-weighted, against the "
        "exact B-Rep faces); seg = segments / B-Rep faces in [0.8, 1.5]; bnd = predicted / true "
        "boundary length in [0.9, 1.15]; type = area typed right (plane, cylinder, cone, "
        "sphere, torus, freeform) >= 0.90; all = every bar",
        "- s: wall seconds per part (heat modes: the whole CLI process; CGAL: its forked "
        "child with the post-processing); failed runs are left out of the means and fail "
        "every bar",
        "",
        "## Aggregate",
        "",
        "| method | parts | failed | purity | coverage | type acc (parts) "
        "| seg/true mean, median | bnd ratio median (mean) | pc | seg | bnd | type | all "
        "| s/part mean (median) |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for m in methods:
        a = agg[m]
        n = a["parts"]
        lines.append(
            f"| {m} | {n} | {a['failed']} | {_f(a['purity'])} | {_f(a['coverage'])} "
            f"| {_f(a['type_acc'])} ({a['type_acc_parts']}) "
            f"| {_f(a['seg_ratio'], '{:.2f}')}, {_f(a['seg_ratio_median'], '{:.2f}')} "
            f"| {_f(a['bnd_ratio_median'], '{:.2f}')} ({_f(a['bnd_ratio'], '{:.2f}')}) "
            f"| {a['passed']}/{n} | {a['passed_seg']}/{n} | {a['passed_bnd']}/{n} "
            f"| {a['passed_type']}/{n} | {a['passed_all']}/{n} "
            f"| {_f(a['seconds'], '{:.1f}')} ({_f(a['seconds_median'], '{:.1f}')}) |"
        )
    names = list(agg[methods[0]]["targets"])
    lines += ["", "## Targets (issue 11)", ""]
    lines.append("| method | " + " | ".join(names) + " | all met |")
    lines.append("|---|" + "---|" * (len(names) + 1))
    for m in methods:
        cells = []
        for name in names:
            value, met = agg[m]["targets"][name]
            cells.append(f"{_f(value)} {'yes' if met else 'no'}")
        met = "yes" if agg[m]["targets_met"] else "no"
        lines.append(f"| {m} | " + " | ".join(cells) + f" | {met} |")
    lines += [
        "",
        "## By noise level",
        "",
        "| noise | method | parts | purity | coverage | type acc | bnd ratio median "
        "| pc | all | s/part |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    levels = sorted({k for m in methods for k in agg[m]["by_noise"]}, key=float)
    for lv in levels:
        for m in methods:
            g = agg[m]["by_noise"].get(lv)
            if g is None:
                continue
            lines.append(
                f"| {lv} | {m} | {g['parts']} | {_f(g['purity'])} | {_f(g['coverage'])} "
                f"| {_f(g['type_acc'])} | {_f(g['bnd_ratio_median'], '{:.2f}')} "
                f"| {g['passed']}/{g['parts']} | {g['passed_all']}/{g['parts']} "
                f"| {_f(g['seconds'], '{:.1f}')} |"
            )
    lines += ["", "## Purity/coverage passes by tessellation and noise", ""]
    keys = [("tessellation", k) for k in agg[methods[0]]["passed_by_tessellation"]] + [
        ("noise", k) for k in agg[methods[0]]["passed_by_noise"]
    ]
    lines.append("| method | " + " | ".join(f"{k} {v}" for k, v in keys) + " |")
    lines.append("|---|" + "---|" * len(keys))
    for m in methods:
        cells = [agg[m][f"passed_by_{k}"].get(v, "-") for k, v in keys]
        lines.append(f"| {m} | " + " | ".join(cells) + " |")
    lines += [
        "",
        "## Per part",
        "",
        "| part | faces | B-Rep | method | purity | coverage | seg/true | type acc "
        "| bnd ratio | bars passed | s |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        if r.get("unfinished"):
            lines.append(
                f"| {r['name']} | {_f(r['faces'], '{}')} | {_f(r['true_faces'], '{}')} "
                f"| {r['method']} | not finished ({r['unfinished']}) | | | | | | |"
            )
            continue
        if r.get("error"):
            lines.append(
                f"| {r['name']} | {r['faces']} | {r['true_faces']} | {r['method']} "
                f"| failed: {r['error'][:80]} | | | | | | |"
            )
            continue
        lines.append(
            f"| {r['name']} | {r['faces']} | {r['true_faces']} | {r['method']} "
            f"| {_f(r['purity'])} | {_f(r['coverage'])} | {_f(r['seg_ratio'], '{:.2f}')} "
            f"| {_f(r['type_acc'])} | {_f(r['bnd_ratio'], '{:.2f}')} | {_bars_cell(r)} "
            f"| {_f(r['seconds'], '{:.1f}')} |"
        )
    return "\n".join(lines) + "\n"


def _json_safe(x):
    if isinstance(x, dict):
        return {k: _json_safe(v) for k, v in x.items()}
    if isinstance(x, list | tuple):
        return [_json_safe(v) for v in x]
    if isinstance(x, np.integer):
        return int(x)
    if isinstance(x, float | np.floating):
        return float(x) if np.isfinite(x) else str(x)
    return x


def machine() -> str:
    """CPU model, core count and OS, for the report header."""
    cpu = platform.processor() or platform.machine()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    import os

    return f"{cpu}, {os.cpu_count()} cores, {platform.system()} {platform.release()}"


def commit_of(package_dir: Path) -> str:
    """``git describe --always --dirty`` of the repository holding the package, or ``?``."""
    try:
        out = subprocess.run(
            ["git", "-C", str(package_dir), "describe", "--always", "--dirty", "--abbrev=12"],
            capture_output=True,
            text=True,
            timeout=30,
        )
    except (OSError, subprocess.TimeoutExpired):
        return "?"
    return out.stdout.strip() if out.returncode == 0 and out.stdout.strip() else "?"


@functools.lru_cache(maxsize=2)
def _cached_part(folder: str, obj: str, name: str) -> dict:
    return load_part(Path(folder), dict(obj=obj, name=name))


def _task(method: str, folder: Path, entry: dict, args) -> dict:
    """One (part, method) in a worker process (``--jobs`` > 1)."""
    if _remaining(args) <= 0:
        return unfinished_row(method, entry)
    part = _cached_part(str(folder), entry["obj"], entry["name"])
    return run_method(method, folder, entry, part, args)


def _status(r: dict) -> str:
    if r.get("unfinished"):
        return f"not finished ({r['unfinished']})"
    if r.get("error"):
        return f"failed: {r['error']}"
    return (
        f"purity {r['purity']:.3f} coverage {r['coverage']:.3f} seg/true {r['seg_ratio']:.2f} "
        f"type {_f(r['type_acc'])} bnd {_f(r['bnd_ratio'], '{:.2f}')} {r['seconds']:.1f} s"
    )


def run_all(entries: list[dict], folder: Path, args, log: Path | None = None) -> list[dict]:
    """Every method on every part; rows part by part, methods in ``args.methods`` order.

    Each row is also appended to ``log`` (JSON lines) as soon as it is scored, so a run that
    is stopped still leaves its rows (``--from-rows`` rebuilds the report from them).
    """
    n = len(entries)

    def keep(r: dict) -> dict:
        if log is not None:
            with log.open("a") as fh:
                fh.write(json.dumps(_json_safe(r)) + "\n")
        return r

    if args.jobs <= 1:
        rows = []
        for i, entry in enumerate(entries):
            if _remaining(args) <= 0:
                rows += [keep(unfinished_row(m, entry)) for m in args.methods]
                continue
            part = load_part(folder, entry)
            for m in args.methods:
                r = keep(run_method(m, folder, entry, part, args))
                rows.append(r)
                print(f"[{i + 1}/{n}] {entry['name']} {m}: {_status(r)}", flush=True)
        return rows
    tasks = [(i, j) for i in range(n) for j in range(len(args.methods))]
    results: dict[tuple[int, int], dict] = {}
    ctx = multiprocessing.get_context("spawn")  # CGAL forks inside the workers
    with concurrent.futures.ProcessPoolExecutor(args.jobs, mp_context=ctx) as ex:
        futures = {
            ex.submit(_task, args.methods[j], folder, entries[i], args): (i, j) for i, j in tasks
        }
        for fut in concurrent.futures.as_completed(futures):
            i, j = futures[fut]
            entry, m = entries[i], args.methods[j]
            try:
                r = fut.result()
            except Exception as exc:  # a worker died: the task is scored as failed
                r = {k: entry.get(k) for k in ("name", "family", "seed", "tessellation", "noise")}
                r.update(method=m, faces=entry.get("faces"), true_faces=entry.get("true_faces"))
                r.update(error=f"worker: {type(exc).__name__}: {exc}"[:300], seconds=None)
            results[i, j] = keep(r)
            print(f"[{len(results)}/{len(tasks)}] {entry['name']} {m}: {_status(r)}", flush=True)
    return [results[t] for t in tasks]


def parse_deadline(text: str) -> float:
    """Epoch seconds of ``HH:MM`` (UTC, today) or of ``+SECONDS`` (from now)."""
    if text.startswith("+"):
        return time.time() + float(text[1:])
    now = datetime.datetime.now(datetime.timezone.utc)
    hh, mm = (int(x) for x in text.split(":"))
    return now.replace(hour=hh, minute=mm, second=0, microsecond=0).timestamp()


def main(argv: list[str] | None = None) -> int:
    """Command line: score the methods on a set; write OUT.md and OUT.json."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("set", help="set folder (with manifest.json) or the manifest path")
    ap.add_argument("--methods", nargs="+", choices=METHODS_ALL, default=list(METHODS_DEFAULT))
    ap.add_argument("--out", default="surface_table", help="output stem: OUT.md and OUT.json")
    ap.add_argument("--limit", type=int, default=None, help="first N parts only")
    ap.add_argument("--only", nargs="+", default=None, help="parts whose name contains any")
    ap.add_argument(
        "--cli", default=None, help="segmentation command (default: igl-heatseg from PATH)"
    )
    ap.add_argument("--timeout", type=float, default=TIMEOUT_DEFAULT)
    ap.add_argument(
        "--jobs", type=int, default=1, help="(part, method) tasks run at a time (default 1)"
    )
    ap.add_argument(
        "--commit", default=None, help="commit to report (default: git describe of igl_heatseg)"
    )
    ap.add_argument(
        "--deadline",
        default=None,
        metavar="HH:MM",
        help="UTC time (today; or +SECONDS from now) after which no task starts and running "
        "CLI runs are stopped; "
        "their rows are 'not finished' and the aggregates cover the parts every method finished",
    )
    ap.add_argument(
        "--from-rows",
        default=None,
        metavar="JSONL",
        help="no runs: rebuild the report from the rows a (stopped) run appended to OUT.rows.jsonl",
    )
    args = ap.parse_args(argv)
    deadline_utc = args.deadline
    if args.deadline:
        args.deadline = parse_deadline(args.deadline)
    args.cli = shlex.split(args.cli) if args.cli else default_cli()
    folder, manifest = load_manifest(args.set)
    entries = manifest["parts"]
    if args.only:
        entries = [e for e in entries if any(s in e["name"] for s in args.only)]
    if args.limit is not None:
        entries = entries[: args.limit]
    if not entries:
        ap.error("no parts selected")
    import igl_heatseg

    pkg = Path(igl_heatseg.__file__).parent
    t_all = time.perf_counter()
    date = datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    if args.from_rows:
        by_key = {(r["name"], r["method"]): r for r in map(json.loads, open(args.from_rows))}
        rows = [
            by_key.get((e["name"], m)) or unfinished_row(m, e, "not run")
            for e in entries
            for m in args.methods
        ]
    else:
        log = out.with_suffix(".rows.jsonl")
        log.write_text("")
        rows = run_all(entries, folder, args, log)
    scored, n_scored = common_rows(rows, args.methods)
    meta = dict(
        set=manifest.get("set", folder.name),
        manifest=str(folder / "manifest.json"),
        parts=len(entries),
        methods=args.methods,
        date=date,
        machine=machine(),
        command="python " + " ".join(shlex.quote(a) for a in [sys.argv[0], *sys.argv[1:]]),
        cli=" ".join(args.cli),
        igl_heatseg=str(pkg),
        commit=args.commit or commit_of(pkg),
        jobs=args.jobs,
        deadline_utc=deadline_utc,
        parts_scored=n_scored,
        seconds=round(time.perf_counter() - t_all, 1),
    )
    if args.from_rows:
        meta["seconds"] = None
        meta["rebuilt_from"] = args.from_rows
    agg = aggregate(scored, args.methods)
    out.with_suffix(".md").write_text(markdown(meta, rows, agg, args.methods))
    out.with_suffix(".json").write_text(
        json.dumps(_json_safe(dict(meta=meta, aggregate=agg, rows=rows)), indent=1) + "\n"
    )
    print(
        f"{len(entries)} parts x {len(args.methods)} methods in {_f(meta['seconds'], '{:.0f}')} s; "
        f"{n_scored} parts finished by every method"
    )
    for m in args.methods:
        a = agg[m]
        print(
            f"  {m}: purity {_f(a['purity'])} coverage {_f(a['coverage'])} "
            f"pass {a['passed']}/{a['parts']} all bars {a['passed_all']}/{a['parts']} "
            f"seg/true {_f(a['seg_ratio'], '{:.2f}')} type acc {_f(a['type_acc'])} "
            f"bnd median {_f(a['bnd_ratio_median'], '{:.2f}')} s/part {_f(a['seconds'], '{:.1f}')}"
        )
    print(f"wrote {out.with_suffix('.md')} and {out.with_suffix('.json')}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
