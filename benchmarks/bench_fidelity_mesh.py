"""Speed target of the B-Rep measurement tessellation (``igl_heatseg.cad.fidelity``).

``data/bspline_standin_slow_mesh.brep.gz`` is a B-spline stand-in fitted to a noisy plane
(59 x 52 poles, 56 trim edges; from tuning bolt_s1007_irregular_n0.2). OCC's mesher at its
default smallest triangle size worked on it for 67-183 s; ``fidelity.MESH_MIN_SIZE`` (0.15
deflections) brought it to about 0.6 s. This script meshes the face as the fidelity measure
does, prints seconds, triangles and OCC's reported deflection, and exits 1 when the meshing
takes longer than ``--target`` seconds (default 5) or misses the deflection asked.

Usage::

    python benchmarks/bench_fidelity_mesh.py
    python benchmarks/bench_fidelity_mesh.py --min-size 0.1    # OCC's default (minutes)
"""

from __future__ import annotations

import argparse
import gzip
import sys
import tempfile
import time
from pathlib import Path

DATA = Path(__file__).resolve().parent.parent / "data" / "bspline_standin_slow_mesh.brep.gz"
#: The deflection the fidelity measure meshes this face with (MESH_DEFLECTION_REL x diagonal,
#: raised to the face's edge tolerance).
DEFLECTION = 0.2883


def main(argv: list | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--target", type=float, default=5.0, help="seconds allowed (default 5)")
    ap.add_argument("--min-size", type=float, default=None,
                    help="MESH_MIN_SIZE to try instead of the package's")
    args = ap.parse_args(argv)
    from OCP.BRep import BRep_Builder, BRep_Tool
    from OCP.BRepTools import BRepTools
    from OCP.TopLoc import TopLoc_Location
    from OCP.TopoDS import TopoDS, TopoDS_Shape

    from igl_heatseg.cad import fidelity

    if args.min_size is not None:
        fidelity.MESH_MIN_SIZE = args.min_size
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "face.brep"
        path.write_bytes(gzip.decompress(DATA.read_bytes()))
        shape = TopoDS_Shape()
        if not BRepTools.Read_s(shape, str(path), BRep_Builder()):
            print(f"cannot read {DATA}", file=sys.stderr)
            return 2
    face = TopoDS.Face(shape)
    t = time.perf_counter()
    fidelity.mesh_faces(face, DEFLECTION)
    dt = time.perf_counter() - t
    tri = BRep_Tool.Triangulation_s(face, TopLoc_Location())
    ok = tri is not None and dt <= args.target and tri.Deflection() <= DEFLECTION
    print(f"MESH_MIN_SIZE {fidelity.MESH_MIN_SIZE}: {dt:.2f} s, "
          f"{tri.NbTriangles() if tri is not None else 0} triangles, deflection "
          f"{tri.Deflection() if tri is not None else float('nan'):.4g} (asked {DEFLECTION}); "
          f"target {args.target} s: {'met' if ok else 'MISSED'}")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
