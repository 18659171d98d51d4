"""Which segments to facet for a defect of the sewn B-Rep: the segment of an invalid or open
face, or, when that face is a triangle of a faceted patch, the built segments next to it (the
built faces it touches in the sewn shape; when it touches none, every built segment next to
its patch). A triangle of a faceted patch that sewing closed up (:func:`collapsed`) is
not blamed on anyone: it is left out of the next build."""

from __future__ import annotations

from ._ocp import require_ocp, shapes_in

require_ocp()

from OCP.BRep import BRep_Tool  # noqa: E402
from OCP.collections import (  # noqa: E402
    IndexedDataMap_TopoDS_Shape_List_TopoDS_Shape_TopTools_ShapeMapHasher as _AncestorMap,
)
from OCP.TopAbs import TopAbs_EDGE, TopAbs_FACE, TopAbs_VERTEX, TopAbs_WIRE  # noqa: E402
from OCP.TopExp import TopExp, TopExp_Explorer  # noqa: E402
from OCP.TopoDS import TopoDS  # noqa: E402

from .roundtrip import invalid_faces  # noqa: E402

__all__ = ["surface_owners", "blame", "open_segments", "touching_segments", "collapsed",
           "invalid_segments"]


def surface_owners(faces, owner) -> dict:
    """Surface -> segment of the faces built (sewing and fixing keep the surfaces; OCP gives
    one Python object per surface, so the objects are the keys).

    Parameters
    ----------
    faces : list of TopoDS_Face
        The faces handed to the sewing.
    owner : list of int
        The segment of every face.

    Returns
    -------
    dict of Geom_Surface -> int

    Examples
    --------
    >>> from OCP.BRepPrimAPI import BRepPrimAPI_MakeBox
    >>> from igl_heatseg.cad.fidelity import faces_of
    >>> faces = faces_of(BRepPrimAPI_MakeBox(1.0, 1.0, 1.0).Shape())
    >>> sorted(surface_owners(faces, [0, 0, 1, 1, 2, 2]).values())
    [0, 0, 1, 1, 2, 2]
    """
    out: dict = {}
    for f, a in zip(faces, owner, strict=True):
        out.setdefault(BRep_Tool.Surface_s(f), a)
    return out


def touching_segments(shape, owners):
    """The segments of the faces that share a vertex with a face of a sewn shape.

    Parameters
    ----------
    shape : TopoDS_Shape
        The sewn shape.
    owners : dict
        :func:`surface_owners` of the faces sewn.

    Returns
    -------
    callable
        ``touching(f)``: the set of segments (ints) of the faces of ``shape`` other than
        ``f`` that share a vertex with ``f`` (a face of ``shape``).

    Examples
    --------
    >>> from OCP.BRepPrimAPI import BRepPrimAPI_MakeBox
    >>> from igl_heatseg.cad.fidelity import faces_of
    >>> box = BRepPrimAPI_MakeBox(1.0, 1.0, 1.0).Shape()
    >>> faces = faces_of(box)
    >>> touching = touching_segments(box, surface_owners(faces, [0, 1, 2, 3, 4, 5]))
    >>> sorted(touching(faces[0]))            # every face of a box but the opposite one
    [2, 3, 4, 5]
    """
    vmap = _AncestorMap()
    TopExp.MapShapesAndAncestors_s(shape, TopAbs_VERTEX, TopAbs_FACE, vmap)

    def touching(f) -> set:
        out: set = set()
        ex = TopExp_Explorer(f, TopAbs_VERTEX)
        while ex.More():
            v = ex.Current()
            if vmap.Contains(v):
                for g in shapes_in(vmap.FindFromKey(v)):
                    if not g.IsSame(f):
                        a = owners.get(BRep_Tool.Surface_s(TopoDS.Face(g)))
                        if a is not None:
                            out.add(a)
            ex.Next()
        return out

    return touching


def collapsed(f) -> bool:
    """Whether sewing closed up a triangle's face: a loop of fewer than three edges, or more
    than one loop (two of its corners merged with the same vertex of a neighbour; BRepCheck
    then fails on the face's orientation or the imbrication of its loops).

    Parameters
    ----------
    f : TopoDS_Face
        A face of a sewn shape, made from one triangle
        (:func:`~igl_heatseg.cad.faceted.triangle_faces`).

    Returns
    -------
    bool

    Examples
    --------
    >>> import numpy as np
    >>> from igl_heatseg.cad.faceted import triangle_faces
    >>> [f] = triangle_faces(np.eye(3), np.array([[0, 1, 2]]), 1e-7)
    >>> collapsed(f)
    False
    """
    loops = 0
    wires = TopExp_Explorer(f, TopAbs_WIRE)
    while wires.More():
        loops += 1
        edges, ex = 0, TopExp_Explorer(wires.Current(), TopAbs_EDGE)
        while ex.More():
            edges += 1
            ex.Next()
        if edges < 3:
            return True
        wires.Next()
    return loops != 1


def blame(f, owners, status, neighbours, touching=None, narrowed=None, made=None):
    """Built segments accountable for a face of a sewn shape.

    Parameters
    ----------
    f : TopoDS_Face
        A face of the sewn shape.
    owners : dict
        :func:`surface_owners` of the faces sewn.
    status : list of dict
        Per segment, ``status`` is ``"built"`` or ``"faceted"``.
    neighbours : dict of int -> set of int
        Segments sharing an edge with each segment.
    touching : callable, optional
        :func:`touching_segments` of the sewn shape.
    narrowed : set, optional
        Gets the segment of a triangle whose blame ``touching`` narrowed (fewer segments than
        without it).
    made : callable, optional
        :func:`touching_segments` of the sewn shape, for a face on a surface that no segment
        was built on (sewing, fixing or unifying made it anew): the built segments whose
        faces it touches are to blame. Without it such a face is no one's.

    Returns
    -------
    set of int or None
        Its own segment when built, else (a triangle of a faceted segment) the built segments
        whose faces it touches (with ``touching``), or when it touches none, the built
        segments next to its segment; for a face made anew, the built segments it touches
        (with ``made``); None when no built segment accounts for it.

    Examples
    --------
    >>> from OCP.BRepPrimAPI import BRepPrimAPI_MakeBox
    >>> from igl_heatseg.cad.fidelity import faces_of
    >>> faces = faces_of(BRepPrimAPI_MakeBox(1.0, 1.0, 1.0).Shape())
    >>> owners = surface_owners(faces, [0, 1, 2, 2, 2, 2])
    >>> status = [{"status": "built"}, {"status": "faceted"}, {"status": "built"}]
    >>> blame(faces[0], owners, status, {}), blame(faces[1], owners, status, {1: {0, 2}})
    ({0}, {0, 2})
    """
    a = owners.get(BRep_Tool.Surface_s(f))
    if a is None:  # (a sliver ShapeFix split off, a face unified from several)
        if made is None:
            return None
        return {b for b in made(f) if status[b]["status"] == "built"} or None
    if status[a]["status"] == "built":
        return {a}
    near = {b for b in (neighbours or {}).get(a, ()) if status[b]["status"] == "built"}
    if touching is not None:  # the built faces the triangle was sewn to, not all its patch's
        sewn = {b for b in touching(f) if status[b]["status"] == "built"}
        if sewn:
            if narrowed is not None and not near <= sewn:
                narrowed.add(a)
            return sewn
    return near or None


def open_segments(shape, faces, owner, status, neighbours, narrow=False, narrowed=None) -> set:
    """Built segments along the free edges of a sewn shape, found as :func:`blame` finds
    them (edges of one face only; seams and degenerate edges are not free).

    Parameters
    ----------
    shape : TopoDS_Shape
        The sewn shape.
    faces, owner, status, neighbours
        As for :func:`surface_owners` and :func:`blame`.
    narrow : bool
        Blame a faceted triangle's free edge on the built faces the triangle touches
        (:func:`touching_segments`), not on every built segment next to its patch.
    narrowed : set, optional
        As for :func:`blame`.

    Returns
    -------
    set of int
        Empty when no built segment is accountable.

    Examples
    --------
    >>> from OCP.BRepPrimAPI import BRepPrimAPI_MakeBox
    >>> from igl_heatseg.cad.fidelity import faces_of
    >>> box = BRepPrimAPI_MakeBox(1.0, 1.0, 1.0).Shape()
    >>> open_segments(box, faces_of(box), [0] * 6, [{"status": "built"}], {})
    set()
    """
    amap = _AncestorMap()
    TopExp.MapShapesAndAncestors_s(shape, TopAbs_EDGE, TopAbs_FACE, amap)
    owners = surface_owners(faces, owner)
    touching = touching_segments(shape, owners) if narrow else None
    out: set = set()
    for i in range(1, amap.Extent() + 1):
        ancestors = amap.FindFromIndex(i)
        edge = TopoDS.Edge(amap.FindKey(i))
        if ancestors.Extent() != 1 or BRep_Tool.Degenerated_s(edge):
            continue
        face = TopoDS.Face(ancestors.First())
        if BRep_Tool.IsClosed_s(edge, face):  # a seam of a periodic face
            continue
        out |= blame(face, owners, status, neighbours, touching, narrowed) or set()
    return out


def invalid_segments(shape, faces, owner, status, neighbours=None, valid=None, narrow=True,
                     narrowed=None, exempt=None, droppable=None, closed_up=None):
    """Segments to facet for the faces of a sewn shape that fail BRepCheck.

    Parameters
    ----------
    shape : TopoDS_Shape
        The sewn shape.
    faces, owner, status, neighbours
        As for :func:`surface_owners` and :func:`blame`.
    valid : bool, optional
        The shape's BRepCheck verdict when known
        (:func:`~igl_heatseg.cad.roundtrip.invalid_faces`).
    narrow : bool
        Blame an invalid triangle of a faceted segment on the built faces it touches in
        ``shape`` (else, or when it touches none, on the built segments next to its segment).
    narrowed : set, optional
        Gets the faceted segments whose blame touching narrowed.
    exempt : dict, optional
        Faceted triangles by surface, left out of the STEP round trip.
    droppable : callable, optional
        ``Geom_Surface -> int or None``: the mesh face of a triangle of a faceted patch that
        may be left out (one along the patch's border), else None.
    closed_up : set, optional
        Gets the mesh faces of the droppable triangles that sewing closed up
        (:func:`collapsed`): those are blamed on no one.

    Returns
    -------
    set of int, [] or None
        The segments to facet (empty when only triangles went to ``closed_up``); [] when the
        shape is valid; None when a face is to blame that no built segment accounts for (an
        isolated faceted patch, a face made anew that touches no built face, the shell
        itself). A face made anew (on a surface no segment was built on: a sliver ShapeFix
        split off, a unified face) is blamed on the built faces it touches.

    Examples
    --------
    >>> from OCP.BRepPrimAPI import BRepPrimAPI_MakeBox
    >>> from igl_heatseg.cad.fidelity import faces_of
    >>> box = BRepPrimAPI_MakeBox(1.0, 1.0, 1.0).Shape()
    >>> invalid_segments(box, faces_of(box), [0] * 6, [{"status": "built"}])
    []
    """
    bad_faces = invalid_faces(shape, valid, exempt)
    if not bad_faces:
        return bad_faces
    owners = surface_owners(faces, owner)
    touching = touching_segments(shape, owners)
    bad: set = set()
    for f in bad_faces:
        row = droppable(BRep_Tool.Surface_s(f)) if droppable is not None else None
        if row is not None and closed_up is not None and collapsed(f):
            closed_up.add(row)
            continue
        who = blame(f, owners, status, neighbours, touching if narrow else None, narrowed,
                    made=touching)
        if who is None:
            return None
        bad |= who
    return bad if bad or closed_up else None
