"""Surface-recovery table: methods x parts of a benchmark set -> markdown + JSON.

Reads a set written by ``tools/make_benchmark_sets.py`` (``SET/manifest.json`` with the
parts' OBJ, face labels and surface types) and scores every method on every part against the
exact B-Rep face labels:

* ``purity``, ``coverage``: area-weighted (``igl_heatseg.evaluation``);
* ``seg/true``: predicted segments over true (B-Rep) faces;
* ``type acc``: share of the area whose predicted segment type equals the true surface type
  (``surface_metrics_draft.type_accuracy``; "-" while a method gives no types);
* ``bnd ratio``: total predicted segment boundary length over total true face boundary length
  (``surface_metrics_draft.boundary_length_ratio``);
* ``s``: wall seconds of the method (heat modes: the whole CLI process, start-up included;
  the in-process time from ``report.json`` is in the JSON as ``seconds_inproc``).

Methods:

* ``paper``, ``robust``: ``igl-heatseg segment MESH -o DIR --mode MODE`` in a subprocess
  (``--cli`` sets the command; labels from ``DIR/labels.txt``, types from ``report.json``'s
  ``surfaces[i]["type"]`` when present, else ``primitive_types`` when it has one per segment);
* ``cgal``: CGAL Efficient RANSAC with CGAL's default parameters (``benchmarks/peers.py``);
* ``cgal-spacing``: the same with ``cluster_epsilon`` from the mesh's edge lengths.

Aggregates per method: means, and the number of parts with purity >= 0.90 and coverage >=
0.85 ("pass"), overall and by tessellation and noise level.

Usage::

    python benchmarks/surface_table.py /work/parts/tuning --out benchmarks/surface_results
    python benchmarks/surface_table.py /work/parts/tuning/manifest.json --methods paper cgal \\
        --limit 5 --out /tmp/t
"""

from __future__ import annotations

import argparse
import datetime
import json
import math
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

import surface_metrics_draft as sm  # noqa: E402

try:  # the evaluation module moves during the restructuring
    from igl_heatseg.evaluation import coverage, purity
except ImportError:  # pragma: no cover - before the restructuring
    from igl_heatseg.evaluate import coverage, purity

METHODS_ALL = ("paper", "robust", "cgal", "cgal-spacing")
METHODS_DEFAULT = METHODS_ALL

#: "Pass" thresholds of the aggregate counts.
PURITY_PASS, COVERAGE_PASS = 0.90, 0.85

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
        kinds=sm.face_kinds(labels, types),
        area=area,
        true_boundary=sm.boundary_length(V, F, labels),
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
    _, labels = np.unique(labels, return_inverse=True)
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
    """Metrics of one prediction against the part's truth."""
    truth, area = part["labels"], part["area"]
    k_true = int(truth.max()) + 1
    k_pred = int(np.unique(labels).size)
    row = dict(
        segments=k_pred,
        seg_ratio=k_pred / k_true,
        purity=purity(labels, truth, area),
        coverage=coverage(labels, truth, area),
        type_acc=None,
    )
    if types is not None:
        row["type_acc"] = sm.type_accuracy(sm.face_kinds(labels, types), part["kinds"], area)
    bp = sm.boundary_length(part["V"], part["F"], labels)
    bt = part["true_boundary"]
    row["bnd_ratio"] = bp / bt if bt > 0 else (1.0 if bp == 0 else math.inf)
    return row


def run_method(method: str, folder: Path, entry: dict, part: dict, args) -> dict:
    """One method on one part: the scored row (``error`` set and metrics None on failure)."""
    base = {k: entry.get(k) for k in ("name", "family", "seed", "tessellation", "noise")}
    base.update(method=method, faces=len(part["F"]), true_faces=int(part["labels"].max()) + 1)
    try:
        if method in ("paper", "robust"):
            labels, types, seconds, extra = run_cli(
                folder / entry["obj"], method, args.cli, args.timeout
            )
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


def _passes(r: dict) -> bool:
    return r.get("error") is None and r["purity"] >= PURITY_PASS and r["coverage"] >= COVERAGE_PASS


def aggregate(rows: list[dict], methods: list[str]) -> dict:
    """Per method: means, pass counts, and pass counts by tessellation and by noise."""
    out = {}
    for m in methods:
        rs = [r for r in rows if r["method"] == m]
        ok = [r for r in rs if r.get("error") is None]
        agg = dict(
            parts=len(rs),
            failed=len(rs) - len(ok),
            purity=_mean(r["purity"] for r in ok),
            coverage=_mean(r["coverage"] for r in ok),
            seg_ratio=_mean(r["seg_ratio"] for r in ok),
            seg_ratio_median=float(np.median([r["seg_ratio"] for r in ok])) if ok else None,
            type_acc=_mean(r["type_acc"] for r in ok),
            type_acc_parts=sum(r["type_acc"] is not None for r in ok),
            bnd_ratio=_mean(r["bnd_ratio"] for r in ok),
            seconds=_mean(r["seconds"] for r in ok),
            passed=sum(_passes(r) for r in rs),
        )
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
    if isinstance(x, float) and not np.isfinite(x):
        return "inf"
    return fmt.format(x)


def markdown(meta: dict, rows: list[dict], agg: dict, methods: list[str]) -> str:
    """The markdown report: header, aggregate table, pass counts by variant, per-part rows."""
    lines = [
        f"# Surface-recovery table: {meta['set']} set ({meta['parts']} parts)",
        "",
        f"- date: {meta['date']}",
        f"- machine: {meta['machine']}",
        f"- command: `{meta['command']}`",
        f"- CLI: `{meta['cli']}`; igl_heatseg from `{meta['igl_heatseg']}`",
        f"- pass: purity >= {PURITY_PASS:.2f} and coverage >= {COVERAGE_PASS:.2f} "
        "(area-weighted, against the exact B-Rep faces)",
        "- type acc: area share whose predicted segment type equals the true surface type "
        "(plane, cylinder, cone, sphere, torus, freeform); '-' when a method reports no types",
        "- bnd ratio: predicted / true boundary length; seg/true: segments / B-Rep faces; "
        "s: wall seconds per part (CLI: whole process)",
        "",
        "## Aggregate",
        "",
        "| method | parts | failed | purity | coverage | pass | seg/true (mean, median) "
        "| type acc (parts) | bnd ratio | s |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for m in methods:
        a = agg[m]
        lines.append(
            f"| {m} | {a['parts']} | {a['failed']} | {_f(a['purity'])} | {_f(a['coverage'])} "
            f"| {a['passed']}/{a['parts']} | {_f(a['seg_ratio'], '{:.2f}')}, "
            f"{_f(a['seg_ratio_median'], '{:.2f}')} | {_f(a['type_acc'])} "
            f"({a['type_acc_parts']}) | {_f(a['bnd_ratio'], '{:.2f}')} "
            f"| {_f(a['seconds'], '{:.1f}')} |"
        )
    lines += ["", "## Passes by tessellation and noise", ""]
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
        "| bnd ratio | s |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        if r.get("error"):
            lines.append(
                f"| {r['name']} | {r['faces']} | {r['true_faces']} | {r['method']} "
                f"| failed: {r['error'][:80]} | | | | | |"
            )
            continue
        lines.append(
            f"| {r['name']} | {r['faces']} | {r['true_faces']} | {r['method']} "
            f"| {_f(r['purity'])} | {_f(r['coverage'])} | {_f(r['seg_ratio'], '{:.2f}')} "
            f"| {_f(r['type_acc'])} | {_f(r['bnd_ratio'], '{:.2f}')} "
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
    args = ap.parse_args(argv)
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

    t_all = time.perf_counter()
    rows = []
    for i, entry in enumerate(entries):
        part = load_part(folder, entry)
        for m in args.methods:
            r = run_method(m, folder, entry, part, args)
            rows.append(r)
            status = (
                f"failed: {r['error']}"
                if r.get("error")
                else f"purity {r['purity']:.3f} coverage {r['coverage']:.3f} "
                f"seg/true {r['seg_ratio']:.2f} {r['seconds']:.1f} s"
            )
            print(f"[{i + 1}/{len(entries)}] {entry['name']} {m}: {status}", flush=True)
    meta = dict(
        set=manifest.get("set", folder.name),
        manifest=str(folder / "manifest.json"),
        parts=len(entries),
        methods=args.methods,
        date=datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC"),
        machine=machine(),
        command="python " + " ".join(shlex.quote(a) for a in [sys.argv[0], *sys.argv[1:]]),
        cli=" ".join(args.cli),
        igl_heatseg=str(Path(igl_heatseg.__file__).parent),
        seconds=round(time.perf_counter() - t_all, 1),
    )
    agg = aggregate(rows, args.methods)
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.with_suffix(".md").write_text(markdown(meta, rows, agg, args.methods))
    out.with_suffix(".json").write_text(
        json.dumps(_json_safe(dict(meta=meta, aggregate=agg, rows=rows)), indent=1) + "\n"
    )
    print(f"{len(entries)} parts x {len(args.methods)} methods in {meta['seconds']:.0f} s")
    for m in args.methods:
        a = agg[m]
        print(
            f"  {m}: purity {_f(a['purity'])} coverage {_f(a['coverage'])} "
            f"pass {a['passed']}/{a['parts']} seg/true {_f(a['seg_ratio'], '{:.2f}')} "
            f"type acc {_f(a['type_acc'])}"
        )
    print(f"wrote {out.with_suffix('.md')} and {out.with_suffix('.json')}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
