# ruff: noqa: T201  (a benchmark script: it prints its results)
"""Heat-solve benchmark (issue 5): floor vs exact reference vs fast default, and scaling.

Usage::

    python benchmarks/bench_heat.py                      # iron.ply: floor, exact, fast
    python benchmarks/bench_heat.py --skip-exact         # floor and fast only
    python benchmarks/bench_heat.py --scaling            # also 50k / 200k / 1M noisy meshes
    python benchmarks/bench_heat.py --scaling-only --sizes 50k 200k

Part 1 (one mesh, one process):

* **floor** -- what any heat-based method pays once: ``igl.cotmatrix``, one sparse Cholesky
  factorization (CHOLMOD via cholespy) of the free block ``-L_ff`` of the first round's
  Dirichlet problem, and one solve.
* **exact** -- ``segment_mesh`` with the exact reference solver (``HeatSolver``: one libigl
  factorization, one solve per group).
* **fast** -- ``segment_mesh`` with :class:`igl_heatseg.heat.fast.FastHeatSolver`.
* **end to end** -- ``igl-heatseg segment MESH -o DIR`` in a fresh interpreter.
* **whole-mesh floor** -- the issue's own floor: CHOLMOD of the whole mesh's (regularised)
  Laplacian, all vertices unknown; larger than the free-block floor above.

It prints the times, the ratios fast/floor and fast/exact, and the label agreement: the
area-weighted share of faces with identical final labels (and of identical initial labels).

Part 2 (``--scaling``): noisy remeshed irons of about 50k, 200k and 1M faces
(``benchmarks/make_meshes.py``, written to a temporary directory, never committed), each
segmented with the fast solver in a fresh subprocess that reports wall times and its peak
resident memory (``VmHWM``; see :func:`peak_rss_gb`).
"""

from __future__ import annotations

import argparse
import json
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
IRON = Path("/work/shared/data/scan/iron.ply")


def _segment(mesh, solver: str):
    """``segment_mesh`` with the named solver ("exact" or "fast")."""
    from igl_heatseg.segmentation import segment_mesh

    return segment_mesh(mesh, solver=solver, keep_solvers=False)


def _cholmod(A):
    """CHOLMOD (cholespy) factorization of the SPD CSR matrix ``A`` (indices sorted here)."""
    import cholespy

    A.sort_indices()
    return cholespy.CholeskySolverD(
        A.shape[0],
        A.indptr.astype(np.int32),
        A.indices.astype(np.int32),
        np.ascontiguousarray(A.data),
        cholespy.MatrixType.CSR,
    )


def floor_time(mesh) -> dict:
    """Seconds for cotmatrix + one CHOLMOD factorization of -L_ff + one solve."""
    import igl
    import scipy.sparse as sp

    from igl_heatseg.segmentation.seeds import seed_groups, seed_mask

    mask = seed_mask(mesh.V, mesh.F)
    k, group = seed_groups(mesh.F, mask)
    free = np.flatnonzero(~mask)
    known = np.flatnonzero(mask)
    t0 = time.perf_counter()
    L = igl.cotmatrix(mesh.V, mesh.F)
    t1 = time.perf_counter()
    Lr = sp.csr_matrix(L)[free]
    A = sp.csr_matrix(-Lr[:, free])
    solver = _cholmod(A)
    t2 = time.perf_counter()
    b = np.ascontiguousarray(Lr[:, known] @ (group[known] == 0).astype(np.float64))
    x = np.empty_like(b)
    solver.solve(b, x)
    t3 = time.perf_counter()
    return {
        "cotmatrix_s": t1 - t0,
        "factor_s": t2 - t1,
        "solve_s": t3 - t2,
        "floor_s": t3 - t0,
        "free": int(len(free)),
        "groups": int(k),
    }


def floor_full_time(mesh) -> dict:
    """The issue's floor: cotmatrix + CHOLMOD of the whole mesh's Laplacian + one solve.

    ``-L`` is singular (constants); ``-L + 1e-8 M`` (``M`` the Voronoi mass matrix, not
    timed) makes it definite with the same sparsity.  All ``n`` vertices are unknowns, so
    this costs more than :func:`floor_time`, which factors only the free block.
    """
    import igl
    import scipy.sparse as sp

    M = igl.massmatrix(mesh.V, mesh.F, igl.MASSMATRIX_TYPE_VORONOI)
    t0 = time.perf_counter()
    L = igl.cotmatrix(mesh.V, mesh.F)
    t1 = time.perf_counter()
    A = sp.csr_matrix(-L + 1e-8 * M)
    solver = _cholmod(A)
    t2 = time.perf_counter()
    b = np.ones(A.shape[0])
    x = np.empty_like(b)
    solver.solve(b, x)
    t3 = time.perf_counter()
    return {"cotmatrix_s": t1 - t0, "factor_s": t2 - t1, "solve_s": t3 - t2, "floor_s": t3 - t0}


def cli_time(path: Path) -> float:
    """Wall seconds of ``igl-heatseg segment PATH -o TMP`` in a fresh interpreter
    (start-up, imports, loading, segmentation and writing every output file)."""
    with tempfile.TemporaryDirectory() as tmp:
        t = time.perf_counter()
        subprocess.run(
            [sys.executable, "-m", "igl_heatseg", "segment", str(path), "-o", tmp],
            check=True,
            capture_output=True,
        )
        return time.perf_counter() - t


def agreement(area: np.ndarray, a: np.ndarray, b: np.ndarray) -> float:
    """Area-weighted share of faces where labels ``a`` and ``b`` agree."""
    return float(area[a == b].sum() / area.sum())


def part1(path: Path, skip_exact: bool, repeat: int = 1) -> dict:
    from igl_heatseg.io.meshes import load_mesh
    from igl_heatseg.mesh.geometry import face_areas

    t = time.perf_counter()
    mesh = load_mesh(path)
    t_load = time.perf_counter() - t
    out = {
        "mesh": str(path),
        "faces": int(mesh.F.shape[0]),
        "vertices": int(mesh.V.shape[0]),
        "load_s": t_load,
    }
    # best of `repeat` runs for floor and fast (the machine may be shared); exact runs once
    out["floor"] = min((floor_time(mesh) for _ in range(repeat)), key=lambda d: d["floor_s"])
    out["floor_full"] = min(
        (floor_full_time(mesh) for _ in range(repeat)), key=lambda d: d["floor_s"]
    )
    cli = [cli_time(path) for _ in range(repeat)]
    out["cli_s"] = min(cli)
    out["cli_runs_s"] = cli
    runs = []
    for _ in range(repeat):
        t = time.perf_counter()
        fast = _segment(mesh, "fast")
        runs.append(time.perf_counter() - t)
    out["fast_s"] = min(runs)
    out["fast_runs_s"] = runs
    out["fast_timings"] = fast.timings
    out["initial_groups"] = fast.initial_groups
    out["segments"] = fast.num_segments
    if not skip_exact:
        t = time.perf_counter()
        exact = _segment(mesh, "exact")
        out["exact_s"] = time.perf_counter() - t
        out["exact_timings"] = exact.timings
        area = face_areas(mesh.V, mesh.F)
        out["agreement_final"] = agreement(area, fast.labels, exact.labels)
        out["agreement_initial"] = agreement(area, fast.initial_labels, exact.initial_labels)
        out["faces_differing_final"] = int((fast.labels != exact.labels).sum())
        out["segments_exact"] = exact.num_segments
    return out


def peak_rss_gb() -> float:
    """Peak resident memory of this process in GiB.

    ``VmHWM`` from ``/proc/self/status`` (reset by ``exec``, so a fresh subprocess reports its
    own peak); else ``getrusage(RUSAGE_SELF).ru_maxrss``, which Linux carries across
    ``exec`` from the forking parent.  Both count C allocations, unlike tracemalloc.
    """
    try:
        for line in Path("/proc/self/status").read_text().splitlines():
            if line.startswith("VmHWM:"):
                return int(line.split()[1]) / 2**20  # kB -> GiB
    except OSError:
        pass
    import resource

    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 2**20


def one_size(path: Path) -> dict:
    """Run in a subprocess: load + fast segmentation; times and peak memory."""
    from igl_heatseg.io.meshes import load_mesh

    t0 = time.perf_counter()
    mesh = load_mesh(path)
    t1 = time.perf_counter()
    seg = _segment(mesh, "fast")
    t2 = time.perf_counter()
    return {
        "mesh": path.name,
        "faces": int(mesh.F.shape[0]),
        "vertices": int(mesh.V.shape[0]),
        "load_s": t1 - t0,
        "segment_s": t2 - t1,
        "total_s": t2 - t0,
        "initial_groups": seg.initial_groups,
        "segments": seg.num_segments,
        "timings": {k: round(v, 3) for k, v in seg.timings.items()},
        "peak_rss_gb": peak_rss_gb(),
    }


def part2(sizes: list[str], workdir: Path, noise: float | None) -> list[dict]:
    sys.path.insert(0, str(HERE))
    import make_meshes

    rows = []
    paths = [IRON]
    for name in sizes:
        p = workdir / f"iron_noisy_{name}.ply"
        if not p.exists():
            kw = {} if noise is None else {"noise": noise}
            V, F = make_meshes.make_noisy(*make_meshes.SIZES[name], **kw)
            make_meshes.write_ply(p, V, F)
        paths.append(p)
    for p in paths:
        res = subprocess.run(
            [sys.executable, __file__, "--one", str(p)], capture_output=True, text=True
        )
        if res.returncode != 0:
            rows.append({"mesh": p.name, "error": res.stderr.strip().splitlines()[-1:]})
        else:
            rows.append(json.loads(res.stdout.strip().splitlines()[-1]))
        print(json.dumps(rows[-1]), flush=True)
    return rows


def machine() -> str:
    cpu = platform.processor() or "?"
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    import os

    load = os.getloadavg() if hasattr(os, "getloadavg") else (float("nan"),) * 3
    return (
        f"{cpu}, {os.cpu_count()} cores, Python {platform.python_version()}, "
        f"load average {load[0]:.1f} at start"
    )


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    ap.add_argument("--mesh", type=Path, default=IRON)
    ap.add_argument("--skip-exact", action="store_true")
    ap.add_argument("--repeat", type=int, default=3, help="floor and fast: best of N runs")
    ap.add_argument("--scaling", action="store_true")
    ap.add_argument("--scaling-only", action="store_true")
    ap.add_argument("--sizes", nargs="*", default=["50k", "200k", "1M"])
    ap.add_argument("--noise", type=float, default=None, help="normal noise / mean edge")
    ap.add_argument("--workdir", type=Path, default=None, help="where meshes are cached")
    ap.add_argument("--one", type=Path, help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.one:
        print(json.dumps(one_size(args.one)))
        return 0
    print("machine:", machine(), flush=True)
    if not args.scaling_only:
        r = part1(args.mesh, args.skip_exact, args.repeat)
        fl = r["floor"]["floor_s"]
        print(json.dumps(r, default=float), flush=True)
        print(
            f"\n{Path(r['mesh']).name}: {r['faces']} faces, "
            f"{r['initial_groups']} initial groups, {r['segments']} segments"
        )
        ff = r["floor_full"]["floor_s"]
        print(
            f"floor (cotmatrix + CHOLMOD factor of the free block + 1 solve): {fl:.2f} s; "
            f"the issue's (whole mesh): {ff:.2f} s (best of {args.repeat})"
        )
        print(
            f"fast segment_mesh: {r['fast_s']:.2f} s = {r['fast_s'] / fl:.1f} x floor "
            f"(best of {args.repeat}; load {r['load_s']:.2f} s more)"
        )
        print(
            f"igl-heatseg segment end to end: {r['cli_s']:.2f} s = {r['cli_s'] / fl:.1f} x "
            f"floor, {r['cli_s'] / ff:.1f} x the whole-mesh floor (best of {args.repeat})"
        )
        if "exact_s" in r:
            print(
                f"exact segment_mesh: {r['exact_s']:.2f} s; fast/exact = "
                f"{r['fast_s'] / r['exact_s']:.3f} (speed-up {r['exact_s'] / r['fast_s']:.1f} x)"
            )
            print(
                f"label agreement (area-weighted): final {100 * r['agreement_final']:.4f} %, "
                f"initial {100 * r['agreement_initial']:.4f} %; "
                f"{r['faces_differing_final']} faces differ"
            )
    if args.scaling or args.scaling_only:
        with tempfile.TemporaryDirectory() as tmp:
            wd = args.workdir or Path(tmp)
            wd.mkdir(parents=True, exist_ok=True)
            rows = part2(args.sizes, wd, args.noise)
        print("\n| mesh | faces | groups (initial -> final) | load s | segment s | peak RSS GB |")
        print("|---|---|---|---|---|---|")
        for x in rows:
            if "error" in x:
                print(f"| {x['mesh']} | error: {x['error']} |")
                continue
            print(
                f"| {x['mesh']} | {x['faces']} | {x['initial_groups']} -> {x['segments']} | "
                f"{x['load_s']:.2f} | {x['segment_s']:.2f} | {x['peak_rss_gb']:.2f} |"
            )
    return 0


if __name__ == "__main__":
    sys.exit(main())
