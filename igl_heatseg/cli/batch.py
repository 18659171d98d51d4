"""``igl-heatseg batch INPUTS... -o OUT``: many meshes on Dask, resumable, one summary."""

from __future__ import annotations

import argparse
import sys

from ..batch import JOB_KINDS, run_batch
from ..segmentation.params import MODES

__all__ = ["register"]


def run(args: argparse.Namespace) -> int:
    """Run the batch; exit 0 when every mesh has an output, 1 when some failed (see
    ``OUT/summary.csv``), 2 on bad arguments or a missing Dask."""
    try:
        res = run_batch(
            args.inputs,
            args.out,
            command=args.command_kind,
            scheduler=args.scheduler,
            workers=args.workers,
            mode=args.mode,
            options={"repair": True} if args.repair else None,
            memory_limit=args.memory_limit,
            timeout=args.timeout or None,
            force=args.force,
            pictures=args.pictures,
            progress=True,
        )
    except ImportError as exc:
        print(f"igl-heatseg: error: {exc}", file=sys.stderr)
        return 2
    return 1 if res.failed else 0


def register(subparsers) -> None:
    """Add ``igl-heatseg batch INPUTS... -o OUT [--command] [--mode] [--workers] [--scheduler]
    [--memory-limit] [--timeout] [--repair] [--force] [--no-pictures]``."""
    p = subparsers.add_parser(
        "batch",
        help="process many meshes on Dask (resumable, one summary)",
        description="Run a single-mesh command on every mesh of INPUTS (files, folders searched "
        "recursively for .obj .off .ply .stl, glob patterns) on a Dask cluster: a local one of "
        "--workers processes, or the scheduler at --scheduler. Each mesh goes to "
        "OUT/<relative path>/ with exactly what the command writes; a mesh whose folder is "
        "complete is skipped (--force redoes it). A mesh that is rejected, raises, exceeds its "
        "timeout or memory limit is recorded with the reason and the batch goes on. Writes "
        "OUT/summary.csv, OUT/summary.json and OUT/index.html. Exit code 0 when every mesh has "
        "an output, 1 when some failed. Needs the `batch` extra: "
        "pip install 'igl_heatseg[batch]'.",
    )
    p.add_argument("inputs", nargs="+", metavar="INPUTS", help="mesh files, folders, patterns")
    p.add_argument("-o", "--out", required=True, metavar="OUT", help="output folder")
    p.add_argument(
        "--command",
        dest="command_kind",
        choices=sorted(JOB_KINDS),
        default="segment",
        help="what to do with each mesh: segment (default), run (segment, cut, parameterize, "
        "pack, pictures) or cad (segment, fit, B-Rep as STEP)",
    )
    p.add_argument(
        "--mode",
        choices=MODES,
        default=None,
        help="segmentation mode (default: the command's own: paper for segment and run, "
        "robust for cad)",
    )
    p.add_argument(
        "--workers",
        type=int,
        default=None,
        metavar="N",
        help="worker processes of the local cluster (default: the CPUs available)",
    )
    p.add_argument(
        "--scheduler",
        default=None,
        metavar="ADDRESS",
        help="run on an existing Dask scheduler (tcp://host:8786) instead of a local cluster; "
        "inputs and OUT must be at the same paths on every worker",
    )
    p.add_argument(
        "--memory-limit",
        default="4GB",
        metavar="SIZE",
        help="address-space limit of each mesh's process (default 4GB; 'none' for no limit)",
    )
    p.add_argument(
        "--timeout",
        type=float,
        default=600.0,
        metavar="S",
        help="seconds a mesh may take before it is killed (default 600; 0 for no limit); "
        "--command cad starts no further rebuild of a B-Rep after half of it, so that a model "
        "is written",
    )
    p.add_argument(
        "--repair",
        action="store_true",
        help="repair what exports get wrong instead of refusing the mesh (as for segment and "
        "run: see `igl-heatseg segment --help`)",
    )
    p.add_argument("--force", action="store_true", help="redo meshes whose output is complete")
    p.add_argument(
        "--no-pictures",
        dest="pictures",
        action="store_false",
        help="--command run: do not render segmentation.png and checker.png",
    )
    p.set_defaults(func=run)
