"""Faceted stand-ins: a segment's triangles as planar OCC faces (for faces that cannot be
built, or the whole model when the build fails)."""

from __future__ import annotations

import logging

import numpy as np

from ._ocp import require_ocp

require_ocp()

from OCP.BRep import BRep_Builder  # noqa: E402
from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeEdge, BRepBuilderAPI_MakeFace  # noqa: E402
from OCP.gp import gp_Pnt  # noqa: E402
from OCP.TopoDS import TopoDS_Vertex, TopoDS_Wire  # noqa: E402

logger = logging.getLogger(__name__)

__all__ = ["triangle_faces"]

#: Triangles with a doubled area below this fraction of the squared bbox diagonal are skipped
#: (OCC cannot make a plane through them; the sewing closes the sliver), and so are those with
#: a side whose ends lie within the vertex tolerance of each other (OCC makes no such edge).
DEGENERATE_AREA_REL = 1e-14


def triangle_faces(V: np.ndarray, F: np.ndarray, tol: float, return_index: bool = False):
    """Planar faces of triangles, sharing vertices and edges between adjacent triangles.

    Parameters
    ----------
    V : (n, 3) float64
    F : (m, 3) int64
        Triangles (orientation kept: face normals follow the triangle order).
    tol : float
        Vertex and edge tolerance.
    return_index : bool
        Also return the row of ``F`` of every face (degenerate triangles make none).

    Returns
    -------
    faces : list of TopoDS_Face
    index : (len(faces),) int64
        Only with ``return_index``.

    Examples
    --------
    >>> import numpy as np
    >>> V = np.array([[0., 0, 0], [1, 0, 0], [0, 1, 0], [2, 0, 0]])
    >>> faces, index = triangle_faces(V, np.array([[0, 1, 2], [0, 1, 3]]), 1e-7,
    ...                               return_index=True)
    >>> len(faces), index.tolist()        # the second triangle has no area
    (1, [0])
    """
    builder = BRep_Builder()
    verts, edges, faces = {}, {}, []
    diag2 = float(np.sum((V.max(axis=0) - V.min(axis=0)) ** 2)) if len(V) else 1.0

    def vertex(i):
        if i not in verts:
            v = TopoDS_Vertex()
            builder.MakeVertex(v, gp_Pnt(*map(float, V[i])), tol)
            verts[i] = v
        return verts[i]

    def edge(i, j):
        key = (min(i, j), max(i, j))
        if key not in edges:
            a, b = key
            mk = BRepBuilderAPI_MakeEdge(vertex(a), vertex(b))
            edges[key] = mk.Edge() if mk.IsDone() else None  # ends within the tolerance
        e = edges[key]
        return e if e is None or i < j else e.Reversed()

    skipped, index = 0, []
    F = np.asarray(F, dtype=np.int64).reshape(-1, 3)
    cross = np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]])
    flat = np.sum(cross ** 2, axis=1) <= (DEGENERATE_AREA_REL * diag2) ** 2
    for row, tri in enumerate(F.tolist()):
        if flat[row]:
            continue
        sides = [edge(i, j) for i, j in ((tri[0], tri[1]), (tri[1], tri[2]), (tri[2], tri[0]))]
        if any(e is None for e in sides):  # a side shorter than the tolerance: a sliver
            skipped += 1
            continue
        w = TopoDS_Wire()
        builder.MakeWire(w)
        for e in sides:
            builder.Add(w, e)
        w.Closed(True)
        mk = BRepBuilderAPI_MakeFace(w, True)
        if mk.IsDone():
            faces.append(mk.Face())
            index.append(row)
    if skipped:
        logger.info("faceted patch: %d triangle(s) with a side shorter than the tolerance "
                    "skipped (the sewing closes them)", skipped)
    return (faces, np.asarray(index, dtype=np.int64)) if return_index else faces
