"""Edge curves on faces (pcurves) that sewing left away from their edge, projected again.

Sewing merges the coincident edges of two faces into one and computes the pcurve of the kept
3D curve on the other face by an adaptive approximation. Near a slow stretch of a fitted curve
that approximation can ring: a pcurve of a cylinder edge that stays within 0.1 mm of its
curve at its ends ran 25 mm along the axis and back in between (measured on a generated pipe
elbow). BRepCheck samples too few points to see it, but the face's parametric domain is then
wrong: its area came out 1,018 instead of 1,615 mm^2, the solid's volume 13.8 % short, and the
face was left out of fine tessellations, in OCC and in any CAD program reading the STEP file.

:func:`mend_pcurves` samples every pcurve of every curved face (and every B-spline pcurve on
a plane: UnifySameDomain's joined pcurves can ring too) against its edge's 3D curve, and
replaces one that strays by the projection of the 3D curve's points onto the surface,
interpolated at the same parameters (same-parameter by construction). The sewing mends after
sewing and again after unifying faces.
"""

from __future__ import annotations

import logging

import numpy as np

from ._ocp import require_ocp

require_ocp()

from OCP.BRep import BRep_Builder, BRep_Tool  # noqa: E402
from OCP.BRepAdaptor import BRepAdaptor_Surface  # noqa: E402
from OCP.collections import Array1_double, Array1_gp_Pnt2d  # noqa: E402
from OCP.Geom2d import Geom2d_BSplineCurve  # noqa: E402
from OCP.Geom2dAPI import Geom2dAPI_PointsToBSpline  # noqa: E402
from OCP.GeomAbs import GeomAbs_Plane, GeomAbs_Shape  # noqa: E402
from OCP.gp import gp_Pnt2d  # noqa: E402
from OCP.ShapeAnalysis import ShapeAnalysis_Surface  # noqa: E402
from OCP.TopAbs import TopAbs_EDGE, TopAbs_FACE  # noqa: E402
from OCP.TopExp import TopExp_Explorer  # noqa: E402
from OCP.TopoDS import TopoDS  # noqa: E402

logger = logging.getLogger(__name__)

__all__ = ["pcurve_deviation", "pcurve_through", "mend_pcurves"]

#: Points at which a pcurve is compared with its edge's 3D curve.
CHECK_SAMPLES = 100
#: Points of the 3D curve projected for a new pcurve (its parameters are those of the edge).
PROJECT_SAMPLES = 200
#: A pcurve is mended when it strays farther than this many times its edge's tolerance (and
#: than ``min_stray``): sewing leaves many a few tolerances off (40 of a generated gear's
#: edges at 2-5 x), harmless, and projecting those again moved a B-spline face's loop.
STRAY_FACTOR = 10.0


def _sample(pcurve, surface, curve, T) -> np.ndarray:
    out = np.empty(len(T))
    for i, t in enumerate(T):
        p = pcurve.Value(float(t))
        out[i] = surface.Value(p.X(), p.Y()).Distance(curve.Value(float(t)))
    return out


def pcurve_deviation(edge, face, samples: int = CHECK_SAMPLES) -> float:
    """Largest distance between an edge's 3D curve and its pcurve on a face, mapped to 3D.

    Parameters
    ----------
    edge : TopoDS_Edge
    face : TopoDS_Face
    samples : int, optional
        Parameters compared, evenly spaced over the edge's range on the face.

    Returns
    -------
    float
        Model units; 0 for a degenerated edge or an edge without a 3D curve, ``inf`` for an
        edge without a pcurve on the face.

    Examples
    --------
    >>> from OCP.BRepPrimAPI import BRepPrimAPI_MakeCylinder
    >>> from igl_heatseg.cad.fidelity import faces_of
    >>> side = faces_of(BRepPrimAPI_MakeCylinder(1.0, 2.0).Shape())[0]
    >>> ex = TopExp_Explorer(side, TopAbs_EDGE)
    >>> round(pcurve_deviation(TopoDS.Edge(ex.Current()), side), 12)
    0.0
    """
    if BRep_Tool.Degenerated_s(edge) or not BRep_Tool.IsGeometric_s(edge):
        return 0.0
    pcurve = BRep_Tool.CurveOnSurface_s(edge, face, 0.0, 0.0)
    if pcurve is None:
        return float("inf")
    a, b = BRep_Tool.Range_s(edge, face)
    curve = BRep_Tool.Curve_s(edge, 0.0, 0.0)
    if curve is None:  # pcurves only: nothing to compare with
        return 0.0
    return float(_sample(pcurve, BRep_Tool.Surface_s(face), curve,
                         np.linspace(a, b, samples)).max())


def pcurve_through(UV: np.ndarray, T: np.ndarray):
    """A 2D B-spline through parameter-plane points at given curve parameters.

    Parameters
    ----------
    UV : (q, 2) float64
        Surface parameters ``(u, v)`` of the points, ``q >= 2``, in order.
    T : (q,) float64
        Increasing curve parameters of the points; the curve runs over ``[T[0], T[-1]]``.

    Returns
    -------
    Geom2d_BSplineCurve or None
        Degree 1 to 8, C2 where the degree allows, through the points within 1e-9 of their
        spread; None when OCC's approximation fails.

    Examples
    --------
    >>> T = np.linspace(2.0, 4.0, 9)
    >>> c = pcurve_through(np.c_[T, T ** 2], T)
    >>> p = c.Value(3.0)
    >>> c.FirstParameter(), c.LastParameter(), round(p.X(), 9), round(p.Y(), 9)
    (2.0, 4.0, 3.0, 9.0)
    """
    span = float(np.ptp(UV, axis=0).max()) or 1.0
    points, params = Array1_gp_Pnt2d(1, len(T)), Array1_double(1, len(T))
    for i, (t, uv) in enumerate(zip(T, UV, strict=True)):
        points.SetValue(i + 1, gp_Pnt2d(float(uv[0]), float(uv[1])))
        params.SetValue(i + 1, float(t))
    fit = Geom2dAPI_PointsToBSpline(points, params, 1, 8, GeomAbs_Shape.GeomAbs_C2, 1e-9 * span)
    if not fit.IsDone():
        return None
    curve = fit.Curve()  # its knots span [0, 1] (the parameters mapped there): map them back
    k0, k1 = curve.FirstParameter(), curve.LastParameter()
    knots = Array1_double(1, curve.NbKnots())
    for i in range(1, curve.NbKnots() + 1):
        knots.SetValue(i, float(T[0] + (curve.Knot(i) - k0) * (T[-1] - T[0]) / (k1 - k0)))
    curve.SetKnots(knots)
    return curve


def _bspline_pcurve(edge, face) -> bool:
    """Whether the edge's pcurve on the face is a B-spline curve."""
    pcurve = BRep_Tool.CurveOnSurface_s(edge, face, 0.0, 0.0)
    return pcurve is not None and isinstance(pcurve, Geom2d_BSplineCurve)


def _projected(edge, face):
    """A pcurve of ``edge`` on ``face`` through the projections of its 3D curve's points, at
    their parameters, on the same sheet of a periodic surface as the old pcurve's start; None
    when its end is not where the old one ends (another sheet: a closed loop would break)."""
    surface = BRep_Tool.Surface_s(face)
    old = BRep_Tool.CurveOnSurface_s(edge, face, 0.0, 0.0)
    a, b = BRep_Tool.Range_s(edge, face)
    curve = BRep_Tool.Curve_s(edge, 0.0, 0.0)
    T = np.linspace(a, b, PROJECT_SAMPLES)
    analysis = ShapeAnalysis_Surface(surface)
    prec = BRep_Tool.Tolerance_s(edge)
    start, end = old.Value(a), old.Value(b)
    prev, UV = start, np.empty((len(T), 2))
    for i, t in enumerate(T):
        uv = analysis.NextValueOfUV(prev, curve.Value(float(t)), prec, -1.0)
        UV[i] = uv.X(), uv.Y()
        prev = uv
    ends = np.array([[start.X(), start.Y()], [end.X(), end.Y()]])
    periods = (surface.UPeriod() if surface.IsUPeriodic() else 0.0,
               surface.VPeriod() if surface.IsVPeriodic() else 0.0)
    for k, period in enumerate(periods):
        if period:  # one sheet along the curve, the old pcurve's start's
            UV[:, k] = np.unwrap(UV[:, k], period=period)
            UV[:, k] += period * np.round((ends[0, k] - UV[0, k]) / period)
    if np.abs(UV[[0, -1]] - ends).max() > 1e-3 * (float(np.ptp(UV, axis=0).max()) or 1.0):
        return None
    return pcurve_through(UV, T)


def mend_pcurves(shape, min_stray: float = 0.0) -> tuple[int, int]:
    """Replace, in place, the pcurves that stray from their edge.

    Every edge of every face that is not a plane, and every B-spline pcurve on a plane (the
    others there are exact projections: lines and circles; UnifySameDomain joined the pcurves
    of merged edges on a plane into one of degree 11 with 282 poles, out to 1e12), is
    compared with :func:`pcurve_deviation`; one farther than :data:`STRAY_FACTOR` times its
    tolerance and than ``min_stray`` gets :func:`_projected`'s pcurve when that one is
    closer, and its tolerance is raised to what is left. Seam edges (two pcurves on one
    face) are left alone.

    Parameters
    ----------
    shape : TopoDS_Shape
        Sewn faces, a shell or a solid. Modified in place (its edges are shared).
    min_stray : float, optional
        Deviations up to this are left (model units; the sewing tolerance: gaps it closes).

    Returns
    -------
    mended, left : int
        Pcurves replaced, and pcurves found straying that no projection brought closer.

    Examples
    --------
    >>> from OCP.BRepPrimAPI import BRepPrimAPI_MakeTorus
    >>> mend_pcurves(BRepPrimAPI_MakeTorus(3.0, 1.0).Shape())
    (0, 0)
    """
    builder, mended, left = BRep_Builder(), 0, 0
    faces = TopExp_Explorer(shape, TopAbs_FACE)
    while faces.More():
        face = TopoDS.Face(faces.Current())
        faces.Next()
        plane = BRepAdaptor_Surface(face, False).GetType() == GeomAbs_Plane
        edges = TopExp_Explorer(face, TopAbs_EDGE)
        while edges.More():
            edge = TopoDS.Edge(edges.Current())
            edges.Next()
            if BRep_Tool.IsClosed_s(edge, face) or (plane and not _bspline_pcurve(edge, face)):
                continue
            tol = BRep_Tool.Tolerance_s(edge)
            worst = pcurve_deviation(edge, face)
            if not (np.isfinite(worst) and worst > max(STRAY_FACTOR * tol, min_stray)):
                continue
            pcurve = _projected(edge, face)
            if pcurve is None:
                left += 1
                continue
            old = BRep_Tool.CurveOnSurface_s(edge, face, 0.0, 0.0)
            builder.UpdateEdge(edge, pcurve, face, tol)
            # between the points it was fitted through too (a spline can ring there)
            now = pcurve_deviation(edge, face, 2 * PROJECT_SAMPLES - 1)
            if now >= worst:
                builder.UpdateEdge(edge, old, face, tol)
                left += 1
                continue
            if now > tol:
                builder.UpdateEdge(edge, 1.05 * now)
            logger.info("pcurve %.3g from its edge projected again (%.3g now)", worst, now)
            mended += 1
    return mended, left
