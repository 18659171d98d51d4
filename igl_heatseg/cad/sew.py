"""Faces to a shell or solid: sewing, shape fixing, pcurves sewing left off their edges
projected again (:mod:`.pcurves`), same-domain unification, solid making."""

from __future__ import annotations

import logging

from ._ocp import require_ocp

require_ocp()

from OCP.BRep import BRep_Builder  # noqa: E402
from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeSolid, BRepBuilderAPI_Sewing  # noqa: E402
from OCP.BRepGProp import BRepGProp  # noqa: E402
from OCP.GProp import GProp_GProps  # noqa: E402
from OCP.ShapeFix import ShapeFix_Shape, ShapeFix_Solid  # noqa: E402
from OCP.ShapeUpgrade import ShapeUpgrade_UnifySameDomain  # noqa: E402
from OCP.TopoDS import TopoDS_Compound  # noqa: E402

from .fidelity import count_free_edges, faces_of, shape_valid, shell_of, shells_of  # noqa: E402
from .pcurves import mend_pcurves  # noqa: E402

logger = logging.getLogger(__name__)

__all__ = ["assemble"]

#: Sewing tolerance factors tried in turn while a closed part keeps free edges (ShapeFix can
#: split a closed edge next to its vertex; the sliver needs a wider sewing).
RETRY_FACTORS = (1.0, 2.0, 4.0)


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


def _sew(faces, tol: float, unify: bool):
    sew = BRepBuilderAPI_Sewing(tol)
    for f in faces:
        sew.Add(f)
    sew.Perform()
    fix = ShapeFix_Shape(sew.SewedShape())
    fix.SetPrecision(tol * 1e-2)
    fix.SetMaxTolerance(tol)
    fix.Perform()
    mended, left = mend_pcurves(fix.Shape(), tol)  # sewing's pcurves can stray (pcurves.py)
    if mended or left:
        logger.info("sewing left %d pcurve(s) off their edges: %d projected again",
                    mended + left, mended)
    return _unify(fix.Shape()) if unify else (fix.Shape(), None)


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
        free = count_free_edges(shape)
        if free == 0 or not closed or max_tol is None or tol >= max_tol:
            break
        logger.info("sewing at %.3g left %d free edges; retrying wider", tol, free)
    info = {"free_edges_after_sewing": free, "solid": False, "sew_tol": tol, "valid": valid}
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
