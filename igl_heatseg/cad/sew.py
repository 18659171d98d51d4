"""Faces to a shell or solid: sewing, shape fixing, same-domain unification, solid making."""

from __future__ import annotations

import logging

from ._ocp import require_ocp

require_ocp()

from OCP.BRep import BRep_Builder  # noqa: E402
from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeSolid, BRepBuilderAPI_Sewing  # noqa: E402
from OCP.BRepCheck import BRepCheck_Analyzer  # noqa: E402
from OCP.BRepGProp import BRepGProp  # noqa: E402
from OCP.GProp import GProp_GProps  # noqa: E402
from OCP.ShapeFix import ShapeFix_Shape, ShapeFix_Solid  # noqa: E402
from OCP.ShapeUpgrade import ShapeUpgrade_UnifySameDomain  # noqa: E402
from OCP.TopAbs import TopAbs_SHELL  # noqa: E402
from OCP.TopExp import TopExp_Explorer  # noqa: E402
from OCP.TopoDS import TopoDS, TopoDS_Compound, TopoDS_Shell  # noqa: E402

from .fidelity import count_free_edges, faces_of  # noqa: E402

logger = logging.getLogger(__name__)

__all__ = ["assemble"]

#: Sewing tolerance factors tried in turn while a closed part keeps free edges (ShapeFix can
#: split a closed edge next to its vertex; the sliver needs a wider sewing).
RETRY_FACTORS = (1.0, 2.0, 4.0)


def _shells(shape) -> list:
    out, ex = [], TopExp_Explorer(shape, TopAbs_SHELL)
    while ex.More():
        out.append(TopoDS.Shell(ex.Current()))
        ex.Next()
    return out


def _shell_of(faces):
    shell = TopoDS_Shell()
    builder = BRep_Builder()
    builder.MakeShell(shell)
    for f in faces:
        builder.Add(shell, f)
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
    """Merge faces on the same surface (and edges on the same curve); keep input on failure."""
    try:
        uni = ShapeUpgrade_UnifySameDomain(shape, True, True, False)
        uni.Build()
        out = uni.Shape()
        if BRepCheck_Analyzer(out).IsValid() or not BRepCheck_Analyzer(shape).IsValid():
            return out
    except Exception as exc:  # OCC raises Standard_Failure subclasses
        logger.warning("UnifySameDomain failed (%s); keeping the sewn faces", exc)
    return shape


def _solid(shell):
    """A valid solid from a closed shell, outward oriented, or None."""
    mk = BRepBuilderAPI_MakeSolid(shell)
    if not mk.IsDone():
        return None
    raw = mk.Solid()
    fix = ShapeFix_Solid(raw)
    fix.Perform()
    solid = fix.Solid()
    if not BRepCheck_Analyzer(solid).IsValid() and BRepCheck_Analyzer(raw).IsValid():
        solid = raw  # the fix made an invalid solid of a valid one (a 17k-face shell)
    props = GProp_GProps()
    BRepGProp.VolumeProperties_s(solid, props)
    if props.Mass() < 0:
        solid.Reverse()
    return solid


def _sew(faces, tol: float, unify: bool):
    sew = BRepBuilderAPI_Sewing(tol)
    for f in faces:
        sew.Add(f)
    sew.Perform()
    fix = ShapeFix_Shape(sew.SewedShape())
    fix.SetPrecision(tol * 1e-2)
    fix.SetMaxTolerance(tol)
    fix.Perform()
    return _unify(fix.Shape()) if unify else fix.Shape()


def assemble(faces: list, sew_tol: float, closed: bool, unify: bool = True,
             max_tol: float | None = None):
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

    Returns
    -------
    shape : TopoDS_Shape
        A solid (a compound of solids for several closed shells), a shell, or the sewn
        compound.
    info : dict
        ``free_edges_after_sewing``, ``solid`` (bool), ``sew_tol`` (the tolerance used).
    """
    for factor in RETRY_FACTORS:
        tol = float(sew_tol) * factor
        if max_tol is not None:
            tol = max(min(tol, float(max_tol)), float(sew_tol))
        shape = _sew(faces, tol, unify)
        free = count_free_edges(shape)
        if free == 0 or not closed or max_tol is None or tol >= max_tol:
            break
        logger.info("sewing at %.3g left %d free edges; retrying wider", tol, free)
    info = {"free_edges_after_sewing": free, "solid": False, "sew_tol": tol}
    shells = _shells(shape)
    if not shells:  # sewing one face returns the face
        shells = [_shell_of(faces_of(shape))]
    if closed and info["free_edges_after_sewing"] == 0:
        solids = [_solid(sh) for sh in shells]  # several shells: one solid per component
        if all(so is not None and BRepCheck_Analyzer(so).IsValid() for so in solids):
            info["solid"] = True
            return (solids[0] if len(solids) == 1 else _compound(solids)), info
        logger.warning("closed shell did not make a valid solid; returning the shell")
    if len(shells) == 1:
        return shells[0], info
    return shape, info
