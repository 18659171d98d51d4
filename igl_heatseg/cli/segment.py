"""``igl-heatseg segment MESH -o DIR``: the paper's segmentation (§3.1-3.4), or robust mode."""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from ..io import atomic_dir, load_mesh, write_segmentation
from ..segmentation import segment_with_mode
from .common import add_progress_argument, add_segment_arguments, add_solver_argument, progress_for

__all__ = ["register"]


def run(args: argparse.Namespace) -> int:
    """Load, segment, write; one summary line on stderr."""
    t0 = time.perf_counter()
    progress = progress_for(args)
    progress("loading", 0.0)
    mesh = load_mesh(args.mesh)
    t_load = time.perf_counter() - t0
    progress.sized(mesh.F.shape[0])("loading", 1.0)
    seg = segment_with_mode(
        mesh, args.mode, args.theta, args.eps, progress=progress, solver=args.solver
    )
    out = Path(args.out)
    extra = {"input": str(Path(args.mesh).resolve()), "timings": {"load": t_load}}
    with atomic_dir(out) as tmp:
        report = write_segmentation(tmp, mesh, seg, extra, t_start=t0)
    progress("done", 1.0)
    print(
        f"{Path(args.mesh).name}: {report['faces']} faces, {report['initial_groups']} initial "
        f"groups -> {report['segments']} segments in {report['timings']['total']:.2f} s; "
        f"wrote {out}/",
        file=sys.stderr,
    )
    return 0


def register(subparsers) -> None:
    """Add ``igl-heatseg segment MESH -o DIR [--mode] [--theta] [--eps] [--solver]``."""
    p = subparsers.add_parser(
        "segment",
        help="segment a mesh (paper §3.1-3.4)",
        description="Segment MESH (.obj .off .ply .stl) and write labels.txt, vertex_labels.txt, "
        "segmented.ply and report.json into DIR.",
    )
    p.add_argument("mesh", help="input mesh file")
    p.add_argument("-o", "--out", required=True, metavar="DIR", help="output directory")
    add_segment_arguments(p)
    add_solver_argument(p)
    add_progress_argument(p)
    p.set_defaults(func=run)
