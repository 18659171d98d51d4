"""``igl-heatseg run MESH -o DIR``: segment, cut to disks, parameterize, pack, write, render."""

from __future__ import annotations

import argparse
import logging
import sys
import time
from pathlib import Path

from ..io import atomic_dir, write_run
from ..pipeline import run_pipeline
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

__all__ = ["register", "parse_cut_path"]

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


def write_pictures(out: Path, res) -> dict:
    """Render ``segmentation.png`` and ``checker.png`` into ``out`` (needs the ``viz`` extra;
    skipped with a warning without it). Returns ``{"files": {...}, "seconds": float}``."""
    t = time.perf_counter()
    try:
        from ..viz import write_run_pictures

        out.mkdir(parents=True, exist_ok=True)
        written = write_run_pictures(out, res.mesh, res.segmentation, res.charts)
    except ImportError as exc:  # viz needs the `viz` extra
        log.warning("no pictures: %s", exc)
        written = {}
    return {"files": written, "seconds": time.perf_counter() - t}


def run(args: argparse.Namespace) -> int:
    """Load, run the pipeline, write the files and pictures; one summary line on stderr."""
    t0 = time.perf_counter()
    progress = progress_for(args)
    mesh = load_input(args)
    t_load = time.perf_counter() - t0
    progress.sized(mesh.F.shape[0])
    res = named(
        mesh,
        run_pipeline,
        mesh,
        theta=args.theta,
        eps=args.eps,
        solver=args.solver,
        mode=args.mode,
        energy=args.energy,
        cut=args.cut,
        cut_paths=args.cut_path or [],
        progress=progress,
    )
    extra = {"input": str(Path(args.mesh).resolve()), "timings": {"load": t_load}}
    extra.update(input_report(mesh, res.segmentation.labels))
    with atomic_dir(args.out) as tmp:
        pictures = write_pictures(tmp, res) if args.pictures else None
        report = write_run(tmp, res, extra, t_start=t0, pictures=pictures)
        write_input_labels(tmp, mesh, res.segmentation.labels)
    s = report["parameterization"]
    sys.stderr.write(
        f"{Path(args.mesh).name}{repair_summary(mesh)}: {res.segmentation.num_segments} segments, "
        f"{s['charts_total']} charts ({s['charts_cut']} cut), {s['charts_bijective']} bijective, "
        f"{s['charts_fallback']} via fallback, in {report['timings']['total']:.2f} s; "
        f"wrote {args.out}/\n"
    )
    if s["charts_bijective"] < s["charts_total"]:
        sys.stderr.write(
            f"igl-heatseg: warning: {s['charts_total'] - s['charts_bijective']} chart(s) without "
            "a bijective map (see report.json `charts`)\n"
        )
    return 0


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
        "--no-pictures",
        dest="pictures",
        action="store_false",
        help="do not render segmentation.png and checker.png (rendered by default when the "
        "`viz` extra and an OpenGL/EGL library are available; skipped with a warning otherwise)",
    )
    add_progress_argument(p)
    p.set_defaults(func=run)
