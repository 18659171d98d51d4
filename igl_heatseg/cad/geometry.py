"""OpenCASCADE geometry from our types: surfaces, edge curves, B-spline patches.

Analytic :class:`~igl_heatseg.surfaces.model.Surface` objects become ``Geom_*`` surfaces whose
normal (``D1u x D1v``) points like the segment's mesh normals; points are moved onto one or
several surfaces by Gauss-Newton on the signed distances (:func:`onto_surfaces`); edge curves
are exact lines and circles when the points allow it, else least-squares B-splines; freeform
segments get a B-spline surface in :mod:`.freeform`.
"""

from __future__ import annotations

import dataclasses
import logging
import math

import numpy as np

from ._ocp import require_ocp

require_ocp()

from OCP.collections import Array1_gp_Pnt  # noqa: E402
from OCP.Extrema import Extrema_ExtFlag_MIN  # noqa: E402
from OCP.GC import GC_MakeSegment  # noqa: E402
from OCP.Geom import (  # noqa: E402
    Geom_Circle,
    Geom_ConicalSurface,
    Geom_CylindricalSurface,
    Geom_Plane,
    Geom_SphericalSurface,
    Geom_ToroidalSurface,
)
from OCP.GeomAbs import GeomAbs_Shape  # noqa: E402
from OCP.GeomAPI import (  # noqa: E402
    GeomAPI_PointsToBSpline,
    GeomAPI_ProjectPointOnCurve,
    GeomAPI_ProjectPointOnSurf,
)
from OCP.GeomLProp import GeomLProp_SLProps  # noqa: E402
from OCP.gp import gp_Ax2, gp_Ax3, gp_Dir, gp_Pnt  # noqa: E402

from igl_heatseg.surfaces.boundaries import GN_ITERS, GN_RCOND  # noqa: E402
from igl_heatseg.surfaces.boundaries import onto_surfaces as gauss_newton  # noqa: E402
from igl_heatseg.surfaces.model import Surface  # noqa: E402

logger = logging.getLogger(__name__)

__all__ = ["any_perp", "occ_surface", "seam_away_from", "seam_frame", "settle_on_surfaces",
           "sphere_poles_away", "start_at_seam", "Projector",
           "onto_surfaces", "edge_curve", "curve_distance", "polyline_distance"]

#: Points on a line or circle within this fraction of the bbox diagonal make an exact
#: Geom_Line / Geom_Circle edge (points on an analytic intersection sit at ~1e-12).
EXACT_CURVE_REL = 1e-8

#: B-spline degree bounds for edge curves and freeform patches (cubic up to OCC's default 8).
DEG_MIN, DEG_MAX = 3, 8
#: edge_curve: the fitted B-spline is sampled this many times per point and must stay within
#: OVERSHOOT_FACTOR x its tolerance of the points' polyline, else the polyline is the curve.
OVERSHOOT_SAMPLES = 4
OVERSHOOT_FACTOR = 10.0


def _pnt(p) -> gp_Pnt:
    return gp_Pnt(float(p[0]), float(p[1]), float(p[2]))


def _dir(d) -> gp_Dir:
    return gp_Dir(float(d[0]), float(d[1]), float(d[2]))


def any_perp(a) -> np.ndarray:
    """A unit vector perpendicular to ``a`` ((3,) float64, nonzero).

    Examples
    --------
    >>> any_perp([0.0, 0.0, 2.0]).tolist()
    [0.0, 1.0, 0.0]
    """
    a = np.asarray(a, dtype=np.float64)
    v = np.cross(a, np.eye(3)[int(np.argmin(np.abs(a)))])
    return v / np.linalg.norm(v)


#: Reference direction for the seam (u = 0) of every periodic surface: its component normal to
#: the surface axis.  One global choice puts the seams of (nearly) coaxial surfaces - a hole's
#: cylinder and its drill-point cone - in the same half-plane, so the closed edge between
#: them has its vertex on both seams.  Skewed so that no usual part axis is parallel to it.
SEAM_REFERENCE = np.array([0.8, 0.5, 0.33]) / np.linalg.norm([0.8, 0.5, 0.33])


def _seam_x(axis) -> np.ndarray:
    """Unit x direction of a periodic surface's frame (SEAM_REFERENCE made normal to axis)."""
    a = np.asarray(axis, dtype=np.float64)
    x = SEAM_REFERENCE - (SEAM_REFERENCE @ a) * a
    n = np.linalg.norm(x)
    return x / n if n > 1e-6 else any_perp(a)


def _ax3(origin, axis, outward: bool, seam_angle: float = 0.0) -> gp_Ax3:
    """Right-handed frame (normal away from the axis) or, for ``outward=False``, left-handed;
    x is the seam direction turned by ``seam_angle`` about the axis."""
    a = np.asarray(axis, dtype=np.float64)
    x0 = _seam_x(a)
    x = math.cos(seam_angle) * x0 + math.sin(seam_angle) * np.cross(a, x0)
    ax = gp_Ax3(_pnt(origin), _dir(a), _dir(x))
    if not outward:
        ax.YReverse()
    return ax


def seam_frame(s: Surface):
    """(origin, axis, x direction) of the seam half-plane ``u = 0`` of a periodic surface
    built by :func:`occ_surface`, or None for a plane or freeform surface."""
    p = s.params
    if s.kind in ("cylinder", "cone", "torus"):
        axis = np.asarray(p["axis"], dtype=np.float64)
        origin = p["point"] if s.kind == "cylinder" else p.get("apex", p.get("center"))
    elif s.kind == "sphere":
        axis, origin = np.asarray(p.get("axis", (0.0, 0.0, 1.0)), dtype=np.float64), p["center"]
    else:
        return None
    return np.asarray(origin, dtype=np.float64), axis, _seam_x(axis)


def start_at_seam(P: np.ndarray, frame):
    """Restart a closed polyline where it crosses the seam half-plane of a periodic surface.

    Parameters
    ----------
    P : (q, 3) float64
        Closed polyline, ``P[0] == P[-1]``.
    frame : tuple
        :func:`seam_frame` of the surface.

    Returns
    -------
    (q + 1, 3) float64 or None
        The polyline from the crossing point around to it again; None when it does not
        cross the half-plane (a circle not around the axis).
    """
    o, a, x = frame
    y = np.cross(a, x)
    th = np.arctan2((P - o) @ y, (P - o) @ x)
    d = np.diff(th)
    hit = np.flatnonzero((np.sign(th[:-1]) != np.sign(th[1:])) & (np.abs(d) < np.pi)
                         & (th[1:] != 0))
    if len(hit) != 1:
        return None
    i = int(hit[0])
    # where the chord meets the seam's plane (interpolating the angle instead puts the point
    # off the seam by the chord's curvature: 1e-4 rad on a boss's saddle loop, and ShapeFix
    # then splits the closed edge into a sliver next to its vertex)
    s0, s1 = (P[i] - o) @ y, (P[i + 1] - o) @ y
    t = s0 / (s0 - s1)
    Q = P[i] + t * (P[i + 1] - P[i])
    return np.vstack([Q, P[i + 1:-1], P[:i + 1], Q])


def occ_surface(s: Surface, seam_angle: float = 0.0):
    """OCC surface of an analytic :class:`Surface`, normal oriented like its mesh normals.

    Parameters
    ----------
    s : Surface
        Kind plane, cylinder, cone, sphere or torus.
    seam_angle : float
        Rotation (radians, right-handed about the axis) of a periodic surface's seam from
        its :func:`seam_frame` direction.

    Returns
    -------
    Geom_Surface
        ``Geom_Plane`` (normal = ``params['normal']``), or a cylinder, cone, sphere or torus
        whose frame is right-handed (normal pointing away from the axis / centre) when
        ``s.outward`` and left-handed otherwise.
    """
    p = s.params
    if s.kind == "plane":
        return Geom_Plane(_ax3(p["point"], p["normal"], True))
    if s.kind == "cylinder":
        return Geom_CylindricalSurface(_ax3(p["point"], p["axis"], s.outward, seam_angle),
                                       float(p["radius"]))
    if s.kind == "cone":
        return Geom_ConicalSurface(_ax3(p["apex"], p["axis"], s.outward, seam_angle),
                                   float(p["half_angle"]), 0.0)
    if s.kind == "sphere":
        return Geom_SphericalSurface(_ax3(p["center"], p.get("axis", (0.0, 0.0, 1.0)),
                                          s.outward, seam_angle), float(p["radius"]))
    if s.kind == "torus":
        return Geom_ToroidalSurface(_ax3(p["center"], p["axis"], s.outward, seam_angle),
                                    float(p["major_radius"]), float(p["minor_radius"]))
    raise ValueError(f"no analytic OCC surface for kind {s.kind!r}")


#: A sphere segment all within this angle (radians) of its mean direction from the centre is
#: built on a sphere whose poles lie square to that direction (:func:`sphere_poles_away`).
SPHERE_CAP_ANGLE = math.radians(80.0)


def sphere_poles_away(s: Surface, P: np.ndarray) -> Surface:
    """A sphere whose frame puts the segment on its equator, far from both poles.

    OCC's sphere has its poles on the frame's axis (z by default) and its seam on a meridian.
    A rounded box's corner is an octant of a sphere: on the default frame its corner vertex is a
    pole and one of its edges the seam, and its trim fails. When every point of the segment lies
    within :data:`SPHERE_CAP_ANGLE` of their mean direction from the centre, the returned
    sphere carries an ``axis`` parameter square to that direction (used by :func:`seam_frame`
    and :func:`occ_surface`); otherwise, or for another kind, ``s`` itself.

    Parameters
    ----------
    s : Surface
    P : (p, 3) float64
        The segment's vertices.

    Returns
    -------
    Surface

    Examples
    --------
    >>> s = Surface("sphere", {"center": np.zeros(3), "radius": 1.0})
    >>> P = np.array([[1.0, 1, 0.5], [1, 0.5, 1], [0.5, 1, 1]]) / 1.5   # about (1, 1, 1)
    >>> a = sphere_poles_away(s, P).params["axis"]
    >>> round(float(a @ [1, 1, 1]), 9), round(float(np.linalg.norm(a)), 9)
    (0.0, 1.0)
    >>> sphere_poles_away(s, np.array([[0.0, 0, 1], [0, 0, -1], [1, 0, 0]])) is s
    True
    """
    if s.kind != "sphere" or len(P) == 0:
        return s
    d = P - s.params["center"]
    d = d / np.maximum(np.linalg.norm(d, axis=1, keepdims=True), 1e-300)
    m = d.mean(axis=0)
    if np.linalg.norm(m) < 1e-9:
        return s
    m /= np.linalg.norm(m)
    if (d @ m).min() < math.cos(SPHERE_CAP_ANGLE):
        return s
    return dataclasses.replace(s, params={**s.params, "axis": any_perp(m)})


def seam_away_from(s: Surface, P: np.ndarray) -> float:
    """Seam angle (for :func:`occ_surface`) in the middle of the widest angular gap between
    points around the surface's axis: ShapeFix_Face's seam then cuts the face's edges far from
    their vertices (a cut next to a vertex leaves a sliver edge that sewing loses)."""
    frame = seam_frame(s)
    if frame is None or len(P) == 0:
        return 0.0
    o, a, x = frame
    th = np.sort(np.mod(np.arctan2((P - o) @ np.cross(a, x), (P - o) @ x), 2 * math.pi))
    gaps = np.diff(np.r_[th, th[0] + 2 * math.pi])
    i = int(np.argmax(gaps))
    return float(th[i] + 0.5 * gaps[i])


class Projector:
    """Signed distance and its gradient for one segment's surface (analytic or B-spline).

    Parameters
    ----------
    surface : Surface or None
        The analytic surface; None for a B-spline given as ``geom``.
    geom : Geom_Surface, optional
        The OCC surface (required for B-splines; its normal defines the distance sign).
    """

    def __init__(self, surface: Surface | None, geom=None):
        self.surface = surface if surface is not None and surface.is_analytic else None
        self.geom = geom
        if self.surface is None:
            self._proj = GeomAPI_ProjectPointOnSurf()
            self._proj.Init(geom, *geom.Bounds())
            # the nearest point is a minimum: OCC's gradient search skips the maxima (the same
            # model on 103 of 104 generated parts; edge building 0.8-1.1 s faster on 30 s builds)
            self._proj.SetExtremaFlag(Extrema_ExtFlag_MIN)

    def residual(self, P: np.ndarray):
        """Signed distances ``(p,)`` and unit gradients ``(p,3)`` at points ``P (p,3)``."""
        if self.surface is not None:
            X = self.surface.project(P)
            return self.surface.distance(P), self.surface.normals(X)
        d = np.zeros(len(P))
        N = np.zeros((len(P), 3))
        for i, q in enumerate(P):
            pt = _pnt(q)
            self._proj.Perform(pt)
            if not self._proj.IsDone() or self._proj.NbPoints() == 0:
                d[i], N[i] = 0.0, 0.0
                continue
            u, v = self._proj.LowerDistanceParameters()
            props = GeomLProp_SLProps(self.geom, u, v, 1, 1e-9)
            if not props.IsNormalDefined():
                continue
            n = props.Normal()
            X = props.Value()
            N[i] = (n.X(), n.Y(), n.Z())
            d[i] = (q - np.array([X.X(), X.Y(), X.Z()])) @ N[i]
        return d, N


def onto_surfaces(P: np.ndarray, projectors: list, iters: int = GN_ITERS):
    """Move points to the nearest common point of several surfaces (Gauss-Newton,
    :func:`igl_heatseg.surfaces.boundaries.onto_surfaces` on the projectors' residuals).

    Parameters
    ----------
    P : (p, 3) float64
        Start points (mesh vertices or boundary samples).
    projectors : list of Projector
        One to three surfaces.

    Returns
    -------
    X : (p, 3) float64
        Moved points; directions the surfaces do not pin down (ill-conditioned intersections,
        see :data:`~igl_heatseg.surfaces.boundaries.GN_RCOND`) keep the start point's coordinate.
    res : (p,) float64
        Largest absolute signed distance of each moved point to the surfaces.
    """
    return gauss_newton(P, [pr.residual for pr in projectors], iters)


def settle_on_surfaces(P: np.ndarray, projectors: list, tol: float, limit: float,
                       nearer: bool = True):
    """Points moved onto the common point of their surfaces, or between them.

    A point goes where :func:`onto_surfaces` takes it when that is within ``tol`` of every
    surface. With ``nearer``, also where the surfaces pass each other without meeting (their
    normals there nearly parallel, :data:`~igl_heatseg.surfaces.boundaries.GN_RCOND`: two
    fitted surfaces of a tangent join on noise), when that is nearer to all of them than
    where the point started: Gauss-Newton then moves it across the surfaces, to midway
    between them, which is smooth along the join where a noisy mesh point is not (a torus
    fillet's edge through the mesh vertices: 0.79 % of the diagonal off the true part,
    0.31 % through the midway points). A point that would move farther than ``limit`` stays
    (the surfaces meet elsewhere than the mesh shows).

    Parameters
    ----------
    P : (p, 3) float64
        Start points (mesh vertices or boundary samples).
    projectors : list of Projector
        One to three surfaces.
    tol : float
        Largest distance to a surface of a point on all of them (model units).
    limit : float
        Largest move (model units).
    nearer : bool
        Also move between surfaces that do not meet (for noisy points: the vertices of an
        exact tessellation lie on their surfaces already).

    Returns
    -------
    X : (p, 3) float64
        The settled points (a copy of ``P`` where they stay).
    moved : (p,) bool
        Moved onto the common point or between the surfaces.
    between : (p,) bool
        Moved between surfaces that do not meet (a subset of ``moved``).

    Examples
    --------
    >>> import numpy as np
    >>> from igl_heatseg.surfaces.model import Surface
    >>> z0 = Surface("plane", {"point": np.zeros(3), "normal": np.array([0.0, 0, 1])})
    >>> z1 = Surface("plane", {"point": np.array([0, 0, 0.1]), "normal": np.array([0.0, 0, 1])})
    >>> X, moved, between = settle_on_surfaces(np.array([[1.0, 2, 0.4]]), [Projector(z0),
    ...                                        Projector(z1)], tol=1e-3, limit=1.0)
    >>> X.round(12).tolist(), between.tolist()   # midway between two parallel planes
    ([[1.0, 2.0, 0.05]], [True])
    """
    P = np.asarray(P, dtype=np.float64)
    X, res = onto_surfaces(P, projectors)
    on = res <= tol
    between = np.zeros(len(P), dtype=bool)
    if nearer and len(projectors) > 1 and not on.all():
        sv = np.linalg.svd(np.stack([pr.residual(X)[1] for pr in projectors], axis=1),
                           compute_uv=False)
        # where the surfaces cross at an angle, a point Gauss-Newton did not bring onto both
        # is off their crossing: it stays
        tangent = sv[:, -1] < GN_RCOND * sv[:, 0]
        res0 = np.abs(np.stack([pr.residual(P)[0] for pr in projectors], axis=1)).max(axis=1)
        between = ~on & tangent & (res < res0)
    close = np.linalg.norm(X - P, axis=1) <= limit
    moved, between = (on | between) & close, between & close
    return np.where(moved[:, None], X, P), moved, between


def _circle_fit(P: np.ndarray):
    """Centre, unit normal and radius of the least-squares circle through P, and residual."""
    c0 = P.mean(axis=0)
    _, sv, Vt = np.linalg.svd(P - c0)
    n = Vt[2]
    planar = np.abs((P - c0) @ n).max()
    e1, e2 = Vt[0], Vt[1]
    xy = np.c_[(P - c0) @ e1, (P - c0) @ e2]
    A = np.c_[2 * xy, np.ones(len(xy))]
    sol, *_ = np.linalg.lstsq(A, (xy**2).sum(axis=1), rcond=None)
    cxy = sol[:2]
    R = math.sqrt(max(sol[2] + cxy @ cxy, 0.0))
    C = c0 + cxy[0] * e1 + cxy[1] * e2
    res = max(planar, np.abs(np.linalg.norm(xy - cxy, axis=1) - R).max())
    return C, n, R, res


def edge_curve(P: np.ndarray, tol: float, scale: float):
    """An OCC curve through ordered points, exact line or circle when possible.

    Parameters
    ----------
    P : (q, 3) float64
        Points along the edge, ``q >= 2``; ``P[0] == P[-1]`` for a closed edge.
    tol : float
        Approximation tolerance of a B-spline curve (model units).
    scale : float
        Model size (bbox diagonal) for the exact-curve test (:data:`EXACT_CURVE_REL`).

    Returns
    -------
    curve : Geom_Curve
    t0, t1 : float
        Parameters of ``P[0]`` and ``P[-1]`` (``t1 > t0``).
    """
    closed = bool(np.linalg.norm(P[0] - P[-1]) <= EXACT_CURVE_REL * scale)
    exact = EXACT_CURVE_REL * scale
    d = P[-1] - P[0]
    L = float(np.linalg.norm(d))
    if not closed and L > exact:
        u = d / L
        off = (P - P[0]) - np.outer((P - P[0]) @ u, u)
        if np.linalg.norm(off, axis=1).max() <= exact:
            seg = GC_MakeSegment(_pnt(P[0]), _pnt(P[-1])).Value()
            return seg, seg.FirstParameter(), seg.LastParameter()
    if len(P) >= 4:
        C, n, R, res = _circle_fit(P[:-1] if closed else P)
        if res <= exact and R > exact:
            turn = np.cross(P[:-1] - C, P[1:] - C).sum(axis=0)
            if turn @ n < 0:
                n = -n
            x = (P[0] - C) / np.linalg.norm(P[0] - C)
            circ = Geom_Circle(gp_Ax2(_pnt(C), _dir(n), _dir(x)), R)
            if closed:
                return circ, 0.0, 2 * math.pi
            e = P[-1] - C
            t1 = math.atan2(e @ np.cross(n, x), e @ x) % (2 * math.pi)
            return circ, 0.0, t1 if t1 > 0 else 2 * math.pi
    arr = Array1_gp_Pnt(1, len(P))
    for i, q in enumerate(P):
        arr.SetValue(i + 1, _pnt(q))
    deg_min = min(DEG_MIN, len(P) - 1)
    fit = GeomAPI_PointsToBSpline(arr, deg_min, max(DEG_MAX, deg_min), GeomAbs_Shape.GeomAbs_C2,
                                  float(tol))
    curve = fit.Curve()
    t0, t1 = curve.FirstParameter(), curve.LastParameter()
    Q = np.array([[q.X(), q.Y(), q.Z()] for q in
                  (curve.Value(float(t)) for t in np.linspace(t0, t1, OVERSHOOT_SAMPLES * len(P)))])
    if polyline_distance(Q, P).max() > OVERSHOOT_FACTOR * tol:
        # a smooth spline rings where the points turn sharply (a corner the chain runs through):
        # the polyline itself, as a degree-1 B-spline, stays on the points
        fit = GeomAPI_PointsToBSpline(arr, 1, 1, GeomAbs_Shape.GeomAbs_C0, float(tol))
        curve = fit.Curve()
        t0, t1 = curve.FirstParameter(), curve.LastParameter()
    return curve, t0, t1


def polyline_distance(Q: np.ndarray, P: np.ndarray) -> np.ndarray:
    """Distance of points to a polyline (chunked: memory ``O(256 q)``).

    Parameters
    ----------
    Q : (r, 3) float64
        Points.
    P : (q, 3) float64
        Polyline vertices in order, ``q >= 2``.

    Returns
    -------
    (r,) float64

    Examples
    --------
    >>> import numpy as np
    >>> P = np.array([[0.0, 0, 0], [1, 0, 0], [1, 1, 0]])
    >>> polyline_distance(np.array([[0.5, 0.5, 0], [2, 2, 0], [0.5, -1, 0]]), P).round(3)
    array([0.5  , 1.414, 1.   ])
    """
    A, D = P[:-1], P[1:] - P[:-1]
    DD = np.maximum(np.einsum("sk,sk->s", D, D), 1e-300)
    out = np.empty(len(Q))
    for i in range(0, len(Q), 256):
        R = Q[i:i + 256, None, :] - A[None]
        t = np.clip(np.einsum("qsk,sk->qs", R, D) / DD, 0.0, 1.0)
        out[i:i + 256] = np.linalg.norm(R - t[..., None] * D[None], axis=2).min(axis=1)
    return out


def curve_distance(curve, P: np.ndarray) -> np.ndarray:
    """Distance ``(p,)`` of points ``P (p, 3)`` to an OCC curve (``inf`` if projection fails)."""
    out = np.full(len(P), np.inf)
    for i, q in enumerate(P):
        proj = GeomAPI_ProjectPointOnCurve(_pnt(q), curve)
        if proj.NbPoints() > 0:
            out[i] = proj.LowerDistance()
    return out
