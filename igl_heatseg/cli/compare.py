"""``igl-heatseg compare-param MESH``: parameterization methods side by side on every chart."""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path

import numpy as np

from ..evaluation.compare import DEFAULT_METHODS, compare_param, format_table
from ..io import load_mesh
from ..parameterization.param import METHODS, PIPELINE_METHODS
from .common import add_segment_arguments

__all__ = ["register"]


def run(args) -> int:
    """Segment, cut and map every chart with several methods; print the table."""
    t0 = time.perf_counter()
    mesh = load_mesh(args.mesh)
    methods = [m.strip() for m in args.methods.split(",") if m.strip()]
    rows = compare_param(mesh, args.theta, args.eps, methods, args.min_faces, mode=args.mode)
    sys.stdout.write(format_table(rows) + "\n")
    sys.stdout.write(
        f"\n{Path(args.mesh).name}: {len({r['chart'] for r in rows})} charts, "
        f"{time.perf_counter() - t0:.1f} s total\n"
    )
    if args.json:
        clean = [
            {k: (v if not isinstance(v, float) or np.isfinite(v) else None) for k, v in r.items()}
            for r in rows
        ]
        Path(args.json).write_text(json.dumps(clean, indent=1))
    return 0


def register(subparsers) -> None:
    """Add ``igl-heatseg compare-param MESH [--methods] [--theta] [--eps] [--json]``.

    Parameters
    ----------
    subparsers : argparse._SubParsersAction
        From ``parser.add_subparsers()``; the subcommand sets ``func`` (``args -> int``).
    """
    p = subparsers.add_parser(
        "compare-param",
        help="compare parameterization methods on the charts of a segmented mesh",
        description="Segment MESH, cut every chart to a disk and map it with several methods "
        "(no fallback), all checked by the same bijectivity certificate; print one table "
        "(chart, method, flips, overlaps, distortions, time).",
    )
    p.add_argument("mesh", help="input mesh file")
    add_segment_arguments(p)
    p.add_argument(
        "--methods",
        default=",".join(DEFAULT_METHODS),
        help=f"comma-separated methods out of {', '.join(METHODS)} (one map, no fallback) and "
        f"{', '.join(PIPELINE_METHODS)} (the full chart parameterization with repair and "
        f"certified fallbacks) (default {','.join(DEFAULT_METHODS)})",
    )
    p.add_argument("--min-faces", type=int, default=1, help="skip charts with fewer faces")
    p.add_argument("--json", metavar="PATH", help="also write the rows as JSON")
    p.set_defaults(func=run)
