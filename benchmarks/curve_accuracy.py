"""Trimming-curve accuracy: robust mode's boundary curves against the parts' true B-Rep edges.

For every part of a set written by ``tools/make_benchmark_sets.py``, the part is generated again
with noise 0 (same seed, same tessellation: only the vertex positions differ), so the true B-Rep
edges are the mesh edges between two true labels at their *clean* positions. ``segment_robust``
runs on the part as stored (noisy or not); for every curve between two segments
(``RobustSegmentation.boundary_curves``, right side >= 0) the distance of each of its points to
the nearest true edge is taken, and the same for the mesh chain it came from (its vertices at
their stored, noisy positions). Distances are in mean edge lengths of the part.

Output: one JSON line per part (``OUT``) with, per method (``intersection``, ``smoothed``, ``chain``), the
number of curves, their length, and mean / 90th percentile distance of the curve points and of
the chain vertices; and a summary on stdout (length-weighted over the parts).

Usage::

    python benchmarks/curve_accuracy.py /tmp/curves_tuning.jsonl /work/parts/tuning
    python benchmarks/curve_accuracy.py /tmp/c.jsonl /work/parts/validation --only knob --jobs 1
"""

from __future__ import annotations

import argparse
import concurrent.futures
import json
import multiprocessing
import os
import sys
import time
from pathlib import Path

import numpy as np

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tools"))

METHODS = ("intersection", "smoothed", "chain")


def segment_distance(P: np.ndarray, A: np.ndarray, B: np.ndarray) -> np.ndarray:
    """Distance of each point ``P (p,3)`` to the nearest of the segments ``A[i]-B[i]``."""
    out = np.full(len(P), np.inf)
    D = B - A
    L2 = np.maximum((D * D).sum(axis=1), 1e-300)
    for i in range(0, len(P), 256):
        Q = P[i:i + 256]
        t = np.clip(np.einsum("psk,sk->ps", Q[:, None, :] - A[None], D) / L2, 0.0, 1.0)
        C = A[None] + t[..., None] * D[None]
        out[i:i + 256] = np.sqrt(((Q[:, None] - C) ** 2).sum(axis=-1)).min(axis=1)
    return out


def score_part(args) -> dict:
    """Curve and chain distances to the true edges of one manifest entry."""
    import igl
    import make_parts as mp

    import igl_heatseg as ih

    folder, e = args
    V, F, T, _ = mp.read_part(Path(folder) / e["obj"])
    clean = mp.make_part(e["seed"], e["family"],
                         target_faces=e["target_faces"] or mp.TARGET_FACES_DEFAULT,
                         irregular=e["irregular"], noise=0.0, cad_facets=e["cad_facets"])
    if clean.V.shape != V.shape or not np.array_equal(clean.F, F):
        return dict(name=e["name"], error="the clean part has another tessellation")
    mesh = ih.validate_mesh(V, F)
    t0 = time.perf_counter()
    seg = ih.segment_robust(mesh)
    seconds = time.perf_counter() - t0
    T = np.asarray(T) if mesh.face_map is None else np.asarray(T)[mesh.face_map]
    TT = igl.triangle_triangle_adjacency(mesh.F)[0]
    f, j = np.nonzero((TT >= 0) & (T[np.maximum(TT, 0)] != T[:, None]))
    V0 = np.zeros_like(mesh.V)
    used = mesh.vertex_map >= 0
    V0[mesh.vertex_map[used]] = np.asarray(clean.V)[used]
    A, B = V0[mesh.F[f, j]], V0[mesh.F[f, (j + 1) % 3]]
    h = float(igl.avg_edge_length(mesh.V, mesh.F))
    row = dict(name=e["name"], family=e["family"], noise=e["noise"],
               tessellation=e["tessellation"], mean_edge=h, seconds=round(seconds, 2),
               seconds_curves=round(seg.timings.get("boundary_curves", 0.0), 3))
    for m in METHODS:
        cs = [c for c in seg.boundary_curves if c.right >= 0 and c.method == m]
        d = np.concatenate([segment_distance(c.points, A, B) for c in cs]) if cs else np.zeros(0)
        d0 = (np.concatenate([segment_distance(mesh.V[c.verts], A, B) for c in cs])
              if cs else np.zeros(0))
        row[m] = dict(curves=len(cs), length=float(sum(c.length for c in cs)), points=len(d),
                      curve_mean=float(d.mean() / h) if len(d) else None,
                      chain_mean=float(d0.mean() / h) if len(d0) else None,
                      curve_p90=float(np.quantile(d, 0.9) / h) if len(d) else None,
                      chain_p90=float(np.quantile(d0, 0.9) / h) if len(d0) else None)
    return row


def summary(rows: list) -> str:
    """Point-weighted means over the parts, per method and noise level."""
    lines = []
    ok = [r for r in rows if "error" not in r]
    for noisy in (False, True):
        part = [r for r in ok if (r["noise"] > 0) == noisy]
        for m in METHODS:
            w = np.array([r[m]["points"] for r in part], dtype=float)
            if not w.sum():
                continue
            cur = np.array([r[m]["curve_mean"] or 0.0 for r in part])
            cha = np.array([r[m]["chain_mean"] or 0.0 for r in part])
            length = sum(r[m]["length"] for r in part)
            total = sum(r[x]["length"] for r in part for x in METHODS)
            lines.append(
                f"{'noisy' if noisy else 'clean'} {m}: {int(sum(r[m]['curves'] for r in part))} "
                f"curves, {length / max(total, 1e-300):.0%} of the curve length; mean distance "
                f"to the true edges {float(w @ cur / w.sum()):.3f} mean edges (mesh chains "
                f"{float(w @ cha / w.sum()):.3f})")
    lines.append(f"{len(ok)} parts, {len(rows) - len(ok)} skipped; curves "
                 f"{sum(r['seconds_curves'] for r in ok):.1f} s of "
                 f"{sum(r['seconds'] for r in ok):.0f} s segmenting")
    return "\n".join(lines)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("out", help="JSON lines, one per part")
    ap.add_argument("set", help="set folder with manifest.json")
    ap.add_argument("--only", nargs="+", default=None, help="parts whose name contains any")
    ap.add_argument("--jobs", type=int, default=2)
    a = ap.parse_args(argv)
    manifest = json.loads((Path(a.set) / "manifest.json").read_text())
    tasks = [(a.set, e) for e in manifest["parts"]
             if not a.only or any(o in e["name"] for o in a.only)]
    rows = []
    ctx = multiprocessing.get_context("spawn")
    pool = concurrent.futures.ProcessPoolExecutor(a.jobs, mp_context=ctx)
    with open(a.out, "w") as fo, pool as ex:
        for r in ex.map(score_part, tasks):
            rows.append(r)
            fo.write(json.dumps(r) + "\n")
            fo.flush()
    print(summary(rows))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
