"""Which segments to facet for a defect of the sewn B-Rep: the segment of an invalid or open
face, or, when that face is a triangle of a faceted patch, the built segments next to it."""

from __future__ import annotations

from ._ocp import require_ocp

require_ocp()

from OCP.BRep import BRep_Tool  # noqa: E402
from OCP.collections import (  # noqa: E402
    IndexedDataMap_TopoDS_Shape_List_TopoDS_Shape_TopTools_ShapeMapHasher as _AncestorMap,
)
from OCP.TopAbs import TopAbs_EDGE, TopAbs_FACE  # noqa: E402
from OCP.TopExp import TopExp  # noqa: E402
from OCP.TopoDS import TopoDS  # noqa: E402

__all__: list = []


def _surface_owners(faces, owner) -> dict:
    """Surface -> segment of the built faces (sewing and fixing keep the surfaces; OCP gives
    one Python object per surface, so the objects are the keys)."""
    out: dict = {}
    for f, a in zip(faces, owner, strict=True):
        out.setdefault(BRep_Tool.Surface_s(f), a)
    return out


def _blame(f, owners, status, neighbours):
    """Built segments accountable for a face of a sewn shape (``owners``:
    :func:`_surface_owners`): its own segment when built, else (a triangle of a faceted
    segment) the built segments next to it; None when no built segment accounts for it."""
    a = owners.get(BRep_Tool.Surface_s(f))
    if a is None:
        return None
    if status[a]["status"] == "built":
        return {a}
    near = {b for b in (neighbours or {}).get(a, ()) if status[b]["status"] == "built"}
    return near or None


def _open_segments(shape, faces, owner, status, neighbours) -> set:
    """Built segments along the free edges of a sewn shape (edges of one face only, seams
    and degenerate edges excluded), found as :func:`_blame` finds them; empty when none is
    accountable."""
    amap = _AncestorMap()
    TopExp.MapShapesAndAncestors_s(shape, TopAbs_EDGE, TopAbs_FACE, amap)
    owners = _surface_owners(faces, owner)
    out: set = set()
    for i in range(1, amap.Extent() + 1):
        ancestors = amap.FindFromIndex(i)
        edge = TopoDS.Edge(amap.FindKey(i))
        if ancestors.Extent() != 1 or BRep_Tool.Degenerated_s(edge):
            continue
        face = TopoDS.Face(ancestors.First())
        if BRep_Tool.IsClosed_s(edge, face):  # a seam of a periodic face
            continue
        out |= _blame(face, owners, status, neighbours) or set()
    return out
