"""``igl-heatseg run MESH -o DIR``: segment, cut to disks, parameterize, pack, write, render."""

from __future__ import annotations

import argparse
import logging
import sys
from pathlib import Path

from ..batch.jobs import run_file, write_pictures
from ..parameterization.atlas import GUTTER_DEFAULT, GUTTER_MAX
from .cad import cad_summary
from .common import (
    add_progress_argument,
    add_repair_argument,
    add_segment_arguments,
    add_solver_argument,
    add_time_limit_argument,
    progress_for,
    repair_summary,
)

__all__ = ["register", "parse_cut_path", "write_pictures"]

log = logging.getLogger(__name__)


def parse_cut_path(text: str) -> tuple[int, int]:
    """Parse ``"V0:V1"`` (two input vertex ids) for ``--cut-path``.

    Raises
    ------
    argparse.ArgumentTypeError
    """
    parts = text.split(":")
    try:
        if len(parts) != 2:
            raise ValueError
        v0, v1 = int(parts[0]), int(parts[1])
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"cut path must be V0:V1 (two vertex ids), got {text!r}"
        ) from None
    return v0, v1


def run(args: argparse.Namespace) -> int:
    """Load, run the pipeline, write the files and pictures; one summary line on stderr."""
    try:
        job = _run_file(args)
    except ImportError as exc:  # --step without OCP (the `cad` extra)
        print(f"igl-heatseg: error: {exc}", file=sys.stderr)
        return 2
    report, mesh, res = job.report, job.mesh, job.result
    s = report["parameterization"]
    sys.stderr.write(
        f"{Path(args.mesh).name}{repair_summary(mesh)}: {res.segmentation.num_segments} segments, "
        f"{s['charts_total']} charts ({s['charts_cut']} cut), {s['charts_bijective']} bijective, "
        f"{s['charts_fallback']} via fallback, in {report['timings']['total']:.2f} s; "
        f"wrote {args.out}/\n"
    )
    if "cad" in report:
        sys.stderr.write(f"{cad_summary(report['cad'])}; wrote {args.out}/model.step\n")
    if s["charts_bijective"] < s["charts_total"]:
        sys.stderr.write(
            f"igl-heatseg: warning: {s['charts_total'] - s['charts_bijective']} chart(s) without "
            "a bijective map (see report.json `charts`)\n"
        )
    return 0


def _run_file(args: argparse.Namespace):
    return run_file(
        args.mesh,
        args.out,
        mode=args.mode,
        theta=args.theta,
        eps=args.eps,
        solver=args.solver,
        energy=args.energy,
        cut=args.cut,
        cut_paths=args.cut_path or [],
        pictures=args.pictures,
        repair=bool(getattr(args, "repair", False)),
        step=bool(getattr(args, "step", False)),
        tol=getattr(args, "tol", None),
        progress=progress_for(args),
        gutter=args.gutter,
        time_limit=getattr(args, "time_limit", None),
    )


def _gutter(text: str) -> float:
    """``--gutter``: a number in ``[0, GUTTER_MAX]``."""
    try:
        g = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
    if not 0 <= g <= GUTTER_MAX:
        raise argparse.ArgumentTypeError(f"must be in [0, {GUTTER_MAX}], got {text}")
    return g


def register(subparsers) -> None:
    """Add ``igl-heatseg run MESH -o DIR [--theta] [--eps] [--energy] [--cut] [--cut-path] ...``.

    Parameters
    ----------
    subparsers : argparse._SubParsersAction
        From ``parser.add_subparsers()``; the subcommand sets ``func`` (``args -> int``).
        Exit code 0 (a chart without a bijective map is reported in report.json and warned
        about on stderr).
    """
    p = subparsers.add_parser(
        "run",
        help="segment, cut to disks, parameterize and pack a mesh",
        description="Segment MESH, cut every chart to a disk, map it to the plane (Hessian "
        "eigenmap with a certified-bijective fallback), pack an atlas and write everything "
        "`segment` writes plus charts/chart_NNN.obj, atlas.obj and a `charts` list in "
        "report.json.",
    )
    p.add_argument("mesh", help="input mesh file")
    p.add_argument("-o", "--out", required=True, metavar="DIR", help="output directory")
    add_segment_arguments(p)
    add_solver_argument(p)
    add_repair_argument(p)
    p.add_argument(
        "--energy",
        choices=("auto", "hlle", "curved"),
        default="auto",
        help="Hessian energy: the paper's HLLE, libigl's curved Hessian, or auto (default): "
        "HLLE, then the curved Hessian where HLLE's map is not bijective",
    )
    p.add_argument(
        "--cut",
        choices=("auto", "none"),
        default="auto",
        help="cut charts that are not disks automatically (default), or only along --cut-path",
    )
    p.add_argument(
        "--cut-path",
        type=parse_cut_path,
        action="append",
        metavar="V0:V1",
        help="cut the chart holding input vertices V0 and V1 along the shortest path between "
        "them (the ends of a generatrix, paper §3.5); repeatable",
    )
    p.add_argument(
        "--gutter",
        type=_gutter,
        default=None,
        metavar="G",
        help=f"gap between charts in the atlas, relative to its side, in [0, {GUTTER_MAX}] "
        f"(default {GUTTER_DEFAULT}: about 4 texels of a 1024 px texture)",
    )
    p.add_argument(
        "--no-pictures",
        dest="pictures",
        action="store_false",
        help="do not render segmentation.png and checker.png (rendered by default when the "
        "`viz` extra and an OpenGL/EGL library are available; skipped with a warning otherwise)",
    )
    p.add_argument(
        "--step",
        action="store_true",
        help="also build the B-Rep (freeform faces over the certified chart maps) and write "
        "model.step, brep.png and a `cad` section in report.json, as `igl-heatseg cad` does "
        "(needs the `cad` extra)",
    )
    p.add_argument(
        "--tol",
        type=float,
        default=None,
        metavar="T",
        help="--step: modelling tolerance in model units (default 1 %% of the bbox diagonal)",
    )
    add_time_limit_argument(p, "--step: ")
    add_progress_argument(p)
    p.set_defaults(func=run)
