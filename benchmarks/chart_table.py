"""Per-mesh chart quality table (issue 13): charts, bijective, worst and mean symmetric
Dirichlet energy, charts cut for distortion, atlas fill, seconds; and xatlas's square fill on
the same mesh.

Usage::

    python benchmarks/chart_table.py MESH [MESH ...] [--modes paper robust] [--xatlas]
        [--md OUT.md] [--json OUT.json]

Each mesh runs ``run_pipeline`` in this process (one mesh after another, so seconds include no
start-up).  The mean energy is area-weighted over the charts that have a map; xatlas's fill is
its charts' UV area over the square of its atlas's longer side (``xatlas`` package, default
options).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np


def xatlas_fill(V: np.ndarray, F: np.ndarray) -> tuple[float, float]:
    """xatlas's (square fill, seconds) on a mesh with its default options."""
    import xatlas

    t = time.perf_counter()
    atlas = xatlas.Atlas()
    atlas.add_mesh(V.astype(np.float32), F.astype(np.uint32))
    atlas.generate()
    dt = time.perf_counter() - t
    _vm, ind, uv = atlas[0]
    P = uv * [atlas.width, atlas.height]
    e1 = P[ind[:, 1]] - P[ind[:, 0]]
    e2 = P[ind[:, 2]] - P[ind[:, 0]]
    area = 0.5 * np.abs(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]).sum()
    return float(area / max(atlas.width, atlas.height) ** 2), dt


def load(path: str):
    """The mesh, strictly read, or repaired when the strict reader refuses it (the shared
    ABC STL files have non-manifold edges); ``(mesh, repaired)``."""
    from igl_heatseg.errors import MeshError
    from igl_heatseg.io import load_mesh

    try:
        return load_mesh(path), False
    except MeshError:
        return load_mesh(path, repair=True), True


def chart_row(path: str, mesh, repaired: bool, mode: str) -> dict:
    """Run the pipeline on one loaded mesh (:func:`load`) and summarise its charts."""
    from igl_heatseg.pipeline import run_pipeline

    t = time.perf_counter()
    result = run_pipeline(mesh, mode=mode)
    dt = time.perf_counter() - t
    rep = result.to_report()
    charts = [c for c in rep["charts"] if c.get("parameterized")]
    sd = np.array([c["distortion"].get("sym_dirichlet", np.nan) for c in charts], dtype=float)
    area = np.array([c["area"] for c in charts], dtype=float)
    ok = np.isfinite(sd)
    s = rep["parameterization"]
    return {
        "mesh": Path(path).stem + (" (repaired)" if repaired else ""),
        "mode": mode,
        "faces": int(mesh.F.shape[0]),
        "charts": int(s["charts_total"]),
        "bijective": int(s["charts_bijective"]),
        "worst_sd": float(sd[ok].max()) if ok.any() else float("nan"),
        "mean_sd": float((sd[ok] * area[ok]).sum() / area[ok].sum()) if ok.any() else float("nan"),
        "charts_over_6": int((sd[ok] > 6).sum()),
        "cut_for_distortion": int(s.get("charts_cut_for_distortion", 0)),
        "fill": float(s["atlas_fill"]),
        "seconds": dt,
    }


def to_markdown(rows: list) -> str:
    head = (
        "| mesh | mode | faces | charts | bijective | worst SD | mean SD | >6 | cut for dist. | "
        "fill | xatlas fill | s |\n|---|---|---|---|---|---|---|---|---|---|---|---|\n"
    )
    lines = []
    for r in rows:
        xf = r.get("xatlas_fill")
        lines.append(
            f"| {r['mesh']} | {r['mode']} | {r['faces']} | {r['charts']} | {r['bijective']} | "
            f"{r['worst_sd']:.2f} | {r['mean_sd']:.2f} | {r['charts_over_6']} | "
            f"{r['cut_for_distortion']} | {r['fill']:.3f} | "
            f"{'' if xf is None else f'{xf:.3f}'} | {r['seconds']:.1f} |"
        )
    ok = [r for r in rows if r["charts"]]
    summary = (
        f"\n{len(ok)} runs: all bijective {sum(r['bijective'] == r['charts'] for r in ok)}, "
        f"mean SD <= 4.3 {sum(r['mean_sd'] <= 4.3 for r in ok)}, "
        f"worst SD <= 6 {sum(r['worst_sd'] <= 6 for r in ok)}, "
        f"fill >= 0.65 {sum(r['fill'] >= 0.65 for r in ok)}\n"
    )
    return head + "\n".join(lines) + "\n" + summary


def main(argv: list | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("meshes", nargs="+")
    ap.add_argument("--modes", nargs="+", default=["paper"], choices=["paper", "robust"])
    ap.add_argument("--xatlas", action="store_true", help="also measure xatlas's square fill")
    ap.add_argument("--md", help="write the table as markdown")
    ap.add_argument("--json", help="write the rows as JSON")
    args = ap.parse_args(argv)
    rows = []
    from igl_heatseg.errors import MeshError

    for path in args.meshes:
        try:
            mesh, repaired = load(path)
        except MeshError as exc:  # one line per unreadable mesh
            print(f"{Path(path).stem}: not read: {exc}", flush=True)
            continue
        xf = xatlas_fill(mesh.V, mesh.F)[0] if args.xatlas else None
        for mode in args.modes:
            try:
                row = chart_row(path, mesh, repaired, mode)
            except Exception as exc:  # a benchmark row, not a crash
                print(f"{Path(path).stem} {mode}: FAILED {type(exc).__name__}: {exc}", flush=True)
                continue
            row["xatlas_fill"] = xf
            rows.append(row)
            print(
                f"{row['mesh'][:36]:36s} {mode:6s} charts {row['charts']:4d} "
                f"bij {row['bijective']:4d} worst {row['worst_sd']:7.2f} "
                f"mean {row['mean_sd']:5.2f} cut {row['cut_for_distortion']:3d} "
                f"fill {row['fill']:.3f} xatlas {'' if xf is None else f'{xf:.3f}'} "
                f"{row['seconds']:5.1f}s",
                flush=True,
            )
    if args.md:
        Path(args.md).write_text(to_markdown(rows))
    if args.json:
        Path(args.json).write_text(json.dumps(rows, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
