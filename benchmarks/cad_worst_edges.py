"""Where a CAD run loses its distance to the part: per noisy part of a generated set, the B-Rep
edge farthest from the part (the noise-free mesh) and the faces on either side of it.

The Hausdorff distance to the part (``cad_batch_score.py``) is one number per part; on noisy
parts whose segments are all built it is often an edge: an intersection of two fitted surfaces
that ill-conditioning left on noisy mesh points, or an arc that runs past a tangent corner.
Each edge with two faces is sampled (SAMPLES points) and measured to the part; the farthest is
printed with the two faces' types and the angle between their normals there (near 0: a
tangent join), as a percentage of the part's bounding-box diagonal.

Usage::

    python benchmarks/cad_worst_edges.py /work/parts/tuning OUT [NAME ...]
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

_HERE = Path(__file__).resolve().parent
sys.path[:0] = [str(_HERE), str(_HERE.parent / "tools")]

SAMPLES = 30


def _normal(face, p):
    """Unit normal of ``face``'s surface at the projection of ``p``, or None."""
    from OCP.BRep import BRep_Tool
    from OCP.BRepAdaptor import BRepAdaptor_Surface
    from OCP.BRepLProp import BRepLProp_SLProps
    from OCP.GeomAPI import GeomAPI_ProjectPointOnSurf
    from OCP.gp import gp_Pnt

    proj = GeomAPI_ProjectPointOnSurf(gp_Pnt(*map(float, p)), BRep_Tool.Surface_s(face))
    if not proj.NbPoints():
        return None
    u, v = proj.LowerDistanceParameters()
    props = BRepLProp_SLProps(BRepAdaptor_Surface(face), u, v, 1, 1e-7)
    if not props.IsNormalDefined():
        return None
    n = props.Normal()
    return np.array([n.X(), n.Y(), n.Z()])


def worst_edge(shape, V: np.ndarray, F: np.ndarray) -> dict | None:
    """The edge of ``shape`` shared by two faces that runs farthest from the mesh ``V, F``:
    ``distance`` (model units), ``point`` (3,), ``types`` of its two faces and ``angle``
    (degrees) between their normals there; None without such an edge."""
    import igl
    from OCP.BRepAdaptor import BRepAdaptor_Curve
    from OCP.collections import (
        IndexedDataMap_TopoDS_Shape_List_TopoDS_Shape_TopTools_ShapeMapHasher as AncestorMap,
    )
    from OCP.TopAbs import TopAbs_EDGE, TopAbs_FACE
    from OCP.TopExp import TopExp
    from OCP.TopoDS import TopoDS

    from igl_heatseg.cad.fidelity import face_type

    amap = AncestorMap()
    TopExp.MapShapesAndAncestors_s(shape, TopAbs_EDGE, TopAbs_FACE, amap)
    best = None
    for i in range(1, amap.Extent() + 1):
        if amap.FindFromIndex(i).Extent() != 2:
            continue
        c = BRepAdaptor_Curve(TopoDS.Edge(amap.FindKey(i)))
        T = np.linspace(c.FirstParameter(), c.LastParameter(), SAMPLES)
        P = np.array([(lambda q: (q.X(), q.Y(), q.Z()))(c.Value(t)) for t in T])
        d = np.sqrt(igl.point_mesh_squared_distance(P, V, F)[0])
        if best is None or d.max() > best[0]:
            best = (float(d.max()), P[d.argmax()], i)
    if best is None:
        return None
    dist, p, i = best
    faces = [TopoDS.Face(f) for f in amap.FindFromIndex(i)]
    n = [_normal(f, p) for f in faces]
    angle = (float(np.degrees(np.arccos(np.clip(abs(n[0] @ n[1]), 0.0, 1.0))))
             if all(x is not None for x in n) else float("nan"))
    return dict(distance=dist, point=p, types=[face_type(f) for f in faces], angle=angle)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("set", type=Path, help="the set's folder (with manifest.json)")
    ap.add_argument("out", type=Path, help="a batch output folder of `--command cad`")
    ap.add_argument("names", nargs="*", help="parts (default: every noisy part of the run)")
    ap.add_argument("--clean", type=Path, default=None,
                    help="cache of noise-free meshes (default: SET/../clean)")
    args = ap.parse_args(argv)
    from bench_cad import clean_mesh

    from igl_heatseg.cad import read_step
    from igl_heatseg.io import load_mesh

    cache = args.clean or args.set.parent / "clean"
    manifest = {p["name"]: p for p in json.loads((args.set / "manifest.json").read_text())["parts"]}
    names = args.names or sorted(d.name for d in args.out.iterdir()
                                 if (d / "model.step").exists() and d.name in manifest)
    for name in names:
        entry = manifest[name]
        if not entry["noise"]:
            continue
        ref = load_mesh(clean_mesh(entry, cache))
        diag = float(np.linalg.norm(ref.V.max(axis=0) - ref.V.min(axis=0)))
        w = worst_edge(read_step(args.out / name / "model.step"), ref.V, ref.F)
        faceted = sum(f["status"] != "built" for f in
                      json.loads((args.out / name / "report.json").read_text())["cad"]["faces"])
        if w is None:
            print(f"{name:42s} faceted {faceted:3d} no shared edge")
            continue
        print(f"{name:42s} faceted {faceted:3d} worst edge {100 * w['distance'] / diag:.3f} % "
              f"{'/'.join(w['types'])}, normals {w['angle']:.1f} deg apart, at "
              f"{np.round(w['point'], 2).tolist()}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
