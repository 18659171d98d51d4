"""``igl-heatseg segment MESH -o DIR``: the paper's segmentation (§3.1-3.4), or robust mode."""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from ..io import atomic_dir, write_segmentation
from ..segmentation import segment_with_mode
from .common import (
    add_progress_argument,
    add_repair_argument,
    add_segment_arguments,
    add_solver_argument,
    input_report,
    load_input,
    named,
    progress_for,
    repair_summary,
    write_input_labels,
)

__all__ = ["register"]


def run(args: argparse.Namespace) -> int:
    """Load, segment, write; one summary line on stderr."""
    t0 = time.perf_counter()
    progress = progress_for(args)
    progress("loading", 0.0)
    mesh = load_input(args)
    t_load = time.perf_counter() - t0
    progress.sized(mesh.F.shape[0])("loading", 1.0)
    seg = named(
        mesh,
        segment_with_mode,
        mesh,
        args.mode,
        args.theta,
        args.eps,
        progress=progress,
        solver=args.solver,
    )
    out = Path(args.out)
    extra = {"input": str(Path(args.mesh).resolve()), "timings": {"load": t_load}}
    extra.update(input_report(mesh, seg.labels))
    with atomic_dir(out) as tmp:
        report = write_segmentation(tmp, mesh, seg, extra, t_start=t0)
        write_input_labels(tmp, mesh, seg.labels)
    progress("done", 1.0)
    print(
        f"{Path(args.mesh).name}: {report['faces']} faces{repair_summary(mesh)}, "
        f"{report['initial_groups']} initial groups -> {report['segments']} segments in "
        f"{report['timings']['total']:.2f} s; wrote {out}/",
        file=sys.stderr,
    )
    return 0


def register(subparsers) -> None:
    """Add ``igl-heatseg segment MESH -o DIR [--mode] [--theta] [--eps] [--solver]``."""
    p = subparsers.add_parser(
        "segment",
        help="segment a mesh (paper §3.1-3.4)",
        description="Segment MESH (.obj .off .ply .stl; polygon faces are triangulated) and "
        "write labels.txt (one label per input face), vertex_labels.txt, segmented.ply (the "
        "triangles segmented, in input face order) and report.json into DIR.",
    )
    p.add_argument("mesh", help="input mesh file")
    p.add_argument("-o", "--out", required=True, metavar="DIR", help="output directory")
    add_segment_arguments(p)
    add_solver_argument(p)
    add_repair_argument(p)
    add_progress_argument(p)
    p.set_defaults(func=run)
