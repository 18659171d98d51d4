"""``igl-heatseg cad MESH -o DIR``: segment, fit one surface per segment, build a B-Rep, STEP."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from ..batch.jobs import cad_file
from .common import (
    add_progress_argument,
    add_repair_argument,
    add_segment_arguments,
    add_solver_argument,
    add_time_limit_argument,
    progress_for,
    repair_summary,
)

__all__ = ["register", "cad_summary"]


#: The summary explains a distance this many times the mesh vertices' as the chord error of
#: an exact tessellation (a coarse CAD export: an exact B-Rep bulges past its facets).
CHORD_NOTE_RATIO = 2.0


def cad_summary(cad: dict) -> str:
    """One line about a report's ``cad`` section: what was built and how close it is."""
    fid = cad.get("fidelity", {})
    solids, shells = fid.get("solids") or 0, fid.get("shells") or 0
    if shells <= 1 or solids == shells:
        kind = ("solid" if solids else "shell") + (f" x {shells}" if shells > 1 else "")
    else:
        kind = f"shell x {shells}" + (f" ({solids} of them closed solids)" if solids else "")
    valid = "valid" if fid.get("valid") else "INVALID"
    vol = fid.get("volume_rel_error")
    vol_txt = f", volume error {100 * vol:.2f} %" if vol is not None else ""
    stand_ins = sum(f.get("built_as") == "bspline" and f.get("kind") != "freeform"
                    for f in cad.get("faces", []))
    haus, at_vertices = fid.get("hausdorff_rel", float("nan")), fid.get("vertex_hausdorff_rel")
    chords = ""
    if fid.get("exact_tessellation") and at_vertices is not None and \
            haus > CHORD_NOTE_RATIO * at_vertices:
        chords = (f" (mesh vertices {100 * at_vertices:.2f} %: the mesh is an exact "
                  "tessellation, whose facets are chords of the curved faces)")
    return (
        f"B-Rep: {valid} {kind}, {fid.get('faces')} faces from {cad.get('segments')} segments "
        f"({len(cad.get('not_built', []))} faceted, {stand_ins} analytic as B-splines), "
        f"{fid.get('free_edges')} free edges, "
        f"Hausdorff {'' if fid.get('hausdorff_confirmed', True) else 'at most '}"
        f"{100 * haus:.2f} % of the diagonal{chords}{vol_txt}"
    )


def run(args: argparse.Namespace) -> int:
    """Segment, build, write; one summary line on stderr (exit 2 without OCP)."""
    out = Path(args.out)
    try:
        job = cad_file(
            args.mesh,
            out,
            mode=args.mode,
            theta=args.theta,
            eps=args.eps,
            solver=args.solver,
            tol=args.tol,
            repair=bool(getattr(args, "repair", False)),
            pictures=args.pictures,
            progress=progress_for(args),
            time_limit=args.time_limit,
        )
    except ImportError as exc:  # OCP (the `cad` extra) missing
        print(f"igl-heatseg: error: {exc}", file=sys.stderr)
        return 2
    report, mesh = job.report, job.mesh
    print(
        f"{Path(args.mesh).name}: {report['faces']} faces{repair_summary(mesh)} -> "
        f"{report['segments']} segments; {cad_summary(report['cad'])}; in "
        f"{report['timings']['total']:.2f} s; wrote {out}/model.step",
        file=sys.stderr,
    )
    return 0


def register(subparsers) -> None:
    """Add ``igl-heatseg cad MESH -o DIR [--mode robust|paper] [--tol T] [--time-limit S]
    [--repair] [--no-pictures]``."""
    p = subparsers.add_parser(
        "cad",
        help="segment a mesh and build its B-Rep (STEP)",
        description="Segment MESH (robust mode by default: it fits one plane, cylinder, cone, "
        "sphere, torus or freeform surface per segment; paper mode gets a surface fitted to "
        "each of the paper's segments), build one B-Rep face per segment (analytic faces, "
        "B-spline freeform faces, faceted patches for faces that cannot be built), sew it into "
        "a solid when the mesh is closed, and write DIR/model.step (AP214, mm), brep.png, "
        "everything `segment` writes and a `cad` section in report.json (validity, faces by "
        "type, distances, volume error, faces not built). Needs the `cad` extra: "
        "pip install 'igl_heatseg[cad]'.",
    )
    p.add_argument("mesh", help="input mesh file")
    p.add_argument("-o", "--out", required=True, metavar="DIR", help="output directory")
    add_segment_arguments(p, mode="robust")
    add_solver_argument(p)
    p.add_argument(
        "--tol",
        type=float,
        default=None,
        metavar="T",
        help="modelling tolerance in model units: a segment farther than this from its "
        "surface gets a B-spline face within it, else is faceted (default 1 %% of the "
        "bounding-box diagonal)",
    )
    add_time_limit_argument(p)
    add_repair_argument(p)
    p.add_argument(
        "--no-pictures",
        dest="pictures",
        action="store_false",
        help="do not render brep.png (the mesh by segment next to the B-Rep faces by type)",
    )
    add_progress_argument(p)
    p.set_defaults(func=run)
