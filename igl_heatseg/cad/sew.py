"""Faces to a shell or solid: sewing, shape fixing, pcurves sewing left off their edges
projected again (:mod:`.pcurves`), same-domain unification, solid making."""

from __future__ import annotations

import logging

import numpy as np

from ._ocp import require_ocp, shapes_in

require_ocp()

from OCP.BRep import BRep_Builder  # noqa: E402
from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeSolid, BRepBuilderAPI_Sewing  # noqa: E402
from OCP.BRepGProp import BRepGProp  # noqa: E402
from OCP.collections import (  # noqa: E402
    IndexedDataMap_TopoDS_Shape_List_TopoDS_Shape_TopTools_ShapeMapHasher as _AncestorMap,
)
from OCP.GProp import GProp_GProps  # noqa: E402
from OCP.ShapeFix import ShapeFix_Shape, ShapeFix_Solid  # noqa: E402
from OCP.ShapeUpgrade import ShapeUpgrade_UnifySameDomain  # noqa: E402
from OCP.TopAbs import (  # noqa: E402
    TopAbs_COMPOUND,
    TopAbs_EDGE,
    TopAbs_FACE,
    TopAbs_FORWARD,
    TopAbs_REVERSED,
    TopAbs_SHELL,
)
from OCP.TopExp import TopExp, TopExp_Explorer  # noqa: E402
from OCP.TopoDS import TopoDS, TopoDS_Compound  # noqa: E402

from .fidelity import (  # noqa: E402
    count_free_edges,
    face_area,
    faces_of,
    shell_of,
    shells_of,
)
from .pcurves import mend_pcurves  # noqa: E402
from .validity import shape_valid  # noqa: E402

logger = logging.getLogger(__name__)

__all__ = ["assemble", "face_groups", "orientation_conflicts"]

#: Sewing tolerance factors tried in turn while a closed part keeps free edges (ShapeFix can
#: split a closed edge next to its vertex; the sliver needs a wider sewing).
RETRY_FACTORS = (1.0, 2.0, 4.0)

#: A group of faces that sewing and fixing leave connected to nothing else in their shell,
#: together under this fraction of the shell's area, is a sliver split off a face, and is
#: left out: BRepCheck finds such a shell not connected and blames no face for it (two
#: sliver faces of 0.11 on a sprocket of 48 faces left the whole model faceted).
SLIVER_GROUP_AREA = 1e-4


def _shell_of(faces):
    shell = shell_of(faces)
    shell.Closed(count_free_edges(shell) == 0)
    return shell


def _compound(shapes):
    comp = TopoDS_Compound()
    builder = BRep_Builder()
    builder.MakeCompound(comp)
    for sh in shapes:
        builder.Add(comp, sh)
    return comp


def _unify(shape):
    """Merge faces on the same surface (and edges on the same curve); keep input on failure.
    Returns (shape, valid): its BRepCheck verdict, None when not checked."""
    try:
        uni = ShapeUpgrade_UnifySameDomain(shape, True, True, False)
        uni.Build()
        out = uni.Shape()
        if shape_valid(out):
            return out, True
        if not shape_valid(shape):
            return out, False
        return shape, True
    except Exception as exc:  # OCC raises Standard_Failure subclasses
        logger.warning("UnifySameDomain failed (%s); keeping the sewn faces", exc)
    return shape, None


def _solid(shell):
    """A solid from a closed shell, outward oriented (by the sign of its volume), and whether
    it is valid; (None, False) when none is made."""
    mk = BRepBuilderAPI_MakeSolid(shell)
    if not mk.IsDone():
        return None, False
    solid = mk.Solid()
    valid = shape_valid(solid)
    if not valid:
        # ShapeFix_Solid only when needed: 3 s on a 15k-face shell, and it has made an
        # invalid solid of a valid one (a 17k-face shell)
        fix = ShapeFix_Solid(solid)
        fix.Perform()
        solid = fix.Solid()
        valid = shape_valid(solid)
    props = GProp_GProps()
    BRepGProp.VolumeProperties_s(solid, props)
    if props.Mass() < 0:
        solid.Reverse()
    return solid, valid


def _face_edge_maps(shape):
    """``(faces, edges)``: the shape's faces indexed 1..n (as they are oriented in it, each
    with its shells), and its edges indexed 1..m, each with the faces using it."""
    fmap, emap = _AncestorMap(), _AncestorMap()
    TopExp.MapShapesAndAncestors_s(shape, TopAbs_FACE, TopAbs_SHELL, fmap)
    TopExp.MapShapesAndAncestors_s(shape, TopAbs_EDGE, TopAbs_FACE, emap)
    return fmap, emap


def face_groups(shell) -> list:
    """Faces of a shell in edge-connected groups, the group of most faces first.

    Parameters
    ----------
    shell : TopoDS_Shape
        A shell (or any shape with faces).

    Returns
    -------
    list of list of TopoDS_Face

    Examples
    --------
    >>> from OCP.BRepPrimAPI import BRepPrimAPI_MakeBox
    >>> [len(g) for g in face_groups(BRepPrimAPI_MakeBox(1.0, 1.0, 1.0).Shape())]
    [6]
    """
    fmap, amap = _face_edge_maps(shell)
    parent = list(range(fmap.Extent() + 1))

    def root(i):
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    for k in range(1, amap.Extent() + 1):
        ids = [fmap.FindIndex(f) for f in shapes_in(amap.FindFromIndex(k))]
        for j in ids[1:]:
            parent[root(j)] = root(ids[0])
    groups: dict = {}
    for i in range(1, fmap.Extent() + 1):
        groups.setdefault(root(i), []).append(TopoDS.Face(fmap.FindKey(i)))
    return sorted(groups.values(), key=len, reverse=True)


def orientation_conflicts(shape) -> list:
    """Faces of a sewn shape that no choice of face orientations makes consistent with their
    neighbours.

    Two faces sharing a manifold edge are oriented alike when they use the edge in opposite
    directions. Two faces that share several edges, used alike along some and oppositely along
    others, cannot be: when there are such pairs, their faces are the result. Otherwise the
    faces are coloured "kept" or "flipped" by a search from each component's first face, and
    an edge whose two faces the colouring cannot make alike (closing an odd cycle, at an edge
    the search order picks) puts both faces in the result. BRepCheck finds such a shell badly
    oriented but names no face (tuning bolt_s1007_irregular_n0.2: a torus fillet and its
    plane, 5 shared edges used alike, the whole model faceted after 400 s of rebuilds). Seam
    edges (twice in one face) and edges of more than two faces are left out.

    Parameters
    ----------
    shape : TopoDS_Shape
        A shell, solid or compound of faces.

    Returns
    -------
    list of TopoDS_Face
        Each face once, in the shape's face order; empty when the faces can be oriented alike.

    Examples
    --------
    >>> from OCP.BRepPrimAPI import BRepPrimAPI_MakeBox
    >>> faces = faces_of(BRepPrimAPI_MakeBox(1.0, 1.0, 1.0).Shape())
    >>> orientation_conflicts(shell_of(faces))
    []
    >>> len(orientation_conflicts(shell_of(faces[:5] + [faces[5].Reversed()])))  # one flip
    0
    """
    fmap, emap = _face_edge_maps(shape)
    n = fmap.Extent()
    uses: dict = {}  # edge index -> [(face index, +1 forward / -1 reversed)]
    for i in range(1, n + 1):
        face = fmap.FindKey(i)
        seen: dict = {}
        ex = TopExp_Explorer(face, TopAbs_EDGE)
        while ex.More():
            e = ex.Current()
            if e.Orientation() in (TopAbs_FORWARD, TopAbs_REVERSED):
                seen.setdefault(emap.FindIndex(e), []).append(
                    1 if e.Orientation() == TopAbs_FORWARD else -1)
            ex.Next()
        for k, signs in seen.items():
            if len(signs) == 1:  # (a seam is used twice by its face)
                uses.setdefault(k, []).append((i, signs[0]))
    pairs: dict = {}  # (face, face) -> {True: used alike along some edge, False: oppositely}
    for use in uses.values():
        if len(use) == 2:
            (a, sa), (b, sb) = sorted(use)
            pairs.setdefault((a, b), set()).add(sa == sb)  # alike: one of the two must flip
    bad = {f for pair, kinds in pairs.items() if len(kinds) == 2 for f in pair}
    if bad:  # two faces at odds along their own edges: no colouring is needed to blame them
        return [TopoDS.Face(fmap.FindKey(i)) for i in sorted(bad)]
    adj: list = [[] for _ in range(n + 1)]
    for (a, b), kinds in pairs.items():
        adj[a].append((b, True in kinds))
        adj[b].append((a, True in kinds))
    flip = [-1] * (n + 1)
    for start in range(1, n + 1):
        if flip[start] >= 0:
            continue
        flip[start], queue = 0, [start]
        while queue:
            a = queue.pop()
            for b, differ in adj[a]:
                want = flip[a] ^ int(differ)
                if flip[b] < 0:
                    flip[b] = want
                    queue.append(b)
                elif flip[b] != want:
                    bad |= {a, b}
    return [TopoDS.Face(fmap.FindKey(i)) for i in sorted(bad)]


def _drop_slivers(shape):
    """``(shape, faces left out)``: a shell (or a compound of shells) without the groups of
    faces connected to nothing else whose area is under SLIVER_GROUP_AREA of the whole; the
    groups kept are one shell each (a compound of them when several)."""
    if shape.ShapeType() not in (TopAbs_SHELL, TopAbs_COMPOUND):
        return shape, 0
    groups = face_groups(shape)
    if len(groups) < 2:
        return shape, 0
    area = [sum(abs(face_area(f)) for f in g) for g in groups]
    big = int(np.argmax(area))
    small = {i for i in range(len(groups))
             if i != big and area[i] < SLIVER_GROUP_AREA * sum(area)}
    if not small:
        return shape, 0
    shells = [_shell_of(g) for i, g in enumerate(groups) if i not in small]
    return (shells[0] if len(shells) == 1 else _compound(shells)), sum(
        len(groups[i]) for i in small)


def _sew(faces, tol: float, unify: bool):
    sew = BRepBuilderAPI_Sewing(tol)
    for f in faces:
        sew.Add(f)
    sew.Perform()
    fix = ShapeFix_Shape(sew.SewedShape())
    fix.SetPrecision(tol * 1e-2)
    fix.SetMaxTolerance(tol)
    fix.Perform()
    _mend(fix.Shape(), tol, "sewing")  # sewing's pcurves can stray (pcurves.py)
    if not unify:
        return fix.Shape(), None
    shape, valid = _unify(fix.Shape())
    if not shape.IsSame(fix.Shape()) and _mend(shape, tol, "unifying faces"):
        valid = None  # (checked before the pcurves were mended)
    return shape, valid


def _mend(shape, tol: float, what: str) -> int:
    """:func:`~.pcurves.mend_pcurves` of a sewn or unified shape, logged; pcurves replaced."""
    mended, left = mend_pcurves(shape, tol)
    if mended or left:
        logger.info("%s left %d pcurve(s) off their edges: %d projected again", what,
                    mended + left, mended)
    return mended


def assemble(faces: list, sew_tol: float, closed: bool, unify: bool = True,
             max_tol: float | None = None, connected: bool = False):
    """Sew faces into a shell (and a solid when ``closed`` and the shell closes).

    Parameters
    ----------
    faces : list of TopoDS_Face
    sew_tol : float
        Sewing tolerance (model units): gaps up to this size are closed.
    closed : bool
        Whether the mesh was closed (then a solid is attempted).
    unify : bool
        Run ``ShapeUpgrade_UnifySameDomain``.
    max_tol : float, optional
        When a closed mesh's faces leave free edges, sew again with the tolerance multiplied
        by :data:`RETRY_FACTORS`, up to this.
    connected : bool
        The faces share their edges already (one :func:`~igl_heatseg.cad.faceted.triangle_faces`
        call): a closed mesh's shell of them is made a solid as it is when that solid is
        valid, without sewing (a 21k-triangle mesh: 4.6 s instead of 38 s).

    Returns
    -------
    shape : TopoDS_Shape
        A solid (a compound of solids for several closed shells), a shell, or the sewn
        compound.
    info : dict
        ``free_edges_after_sewing``, ``solid`` (bool), ``sew_tol`` (the tolerance used),
        ``valid`` (the shape's BRepCheck verdict, None when it was not checked as returned).
    """
    if connected and closed:
        shell = _shell_of(faces)
        if shell.Closed():
            solid, valid = _solid(shell)
            if valid:
                return solid, {"free_edges_after_sewing": 0, "solid": True,
                               "sew_tol": float(sew_tol), "valid": True}
    for factor in RETRY_FACTORS:
        tol = float(sew_tol) * factor
        if max_tol is not None:
            tol = max(min(tol, float(max_tol)), float(sew_tol))
        shape, valid = _sew(faces, tol, unify)
        shape, slivers = _drop_slivers(shape)
        if slivers:
            logger.warning("left out %d sliver face(s) that sewing and fixing split off from "
                           "the shell", slivers)
            valid = None
        free = count_free_edges(shape)
        if free == 0 or not closed or max_tol is None or tol >= max_tol:
            break
        logger.info("sewing at %.3g left %d free edges; retrying wider", tol, free)
    info = {"free_edges_after_sewing": free, "solid": False, "sew_tol": tol, "valid": valid,
            "slivers_left_out": slivers}
    shells = shells_of(shape)
    if not shells:  # sewing one face returns the face
        shells = [_shell_of(faces_of(shape))]
    if closed and info["free_edges_after_sewing"] == 0:
        solids = [_solid(sh) for sh in shells]  # several shells: one solid per component
        if all(so is not None and ok for so, ok in solids):
            info["solid"] = info["valid"] = True
            solids = [so for so, _ in solids]
            return (solids[0] if len(solids) == 1 else _compound(solids)), info
        logger.warning("closed shell did not make a valid solid; returning the shell")
    if len(shells) == 1:
        if not shells[0].IsSame(shape):
            info["valid"] = None
        return shells[0], info
    return shape, info
