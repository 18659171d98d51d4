"""``igl-heatseg segment MESH -o DIR``: the paper's segmentation (§3.1-3.4), or robust mode."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from ..batch.jobs import segment_file
from .common import (
    add_progress_argument,
    add_repair_argument,
    add_segment_arguments,
    add_solver_argument,
    progress_for,
    repair_summary,
)

__all__ = ["register"]


def run(args: argparse.Namespace) -> int:
    """Load, segment, write; one summary line on stderr."""
    out = Path(args.out)
    job = segment_file(
        args.mesh,
        out,
        mode=args.mode,
        theta=args.theta,
        eps=args.eps,
        solver=args.solver,
        refine=args.refine,
        repair=bool(getattr(args, "repair", False)),
        progress=progress_for(args),
    )
    report, mesh = job.report, job.mesh
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
    p.add_argument(
        "--refine",
        action=argparse.BooleanOptionalAction,
        default=None,
        help="robust mode: refine the segments by their surface fits (split what no surface "
        "explains, merge what one explains, move boundaries onto the surfaces); default: on",
    )
    add_repair_argument(p)
    add_progress_argument(p)
    p.set_defaults(func=run)
