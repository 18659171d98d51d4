"""Faces of revolution bounded by coaxial circles, built on a parametric rectangle.

A cylinder between two circles, a cone frustum or drill point, a torus band: every loop is one
closed edge at constant ``v``. Trimming such a face with ShapeFix_Face needs a seam through
both circles' vertices, which two slightly different fitted axes never give exactly (ShapeFix
then splits a circle next to its vertex and the sliver edge is lost in sewing). Here the face
is ``BRepBuilderAPI_MakeFace(surface, 0, 2 pi, v0, v1)`` with its own seam and circles; the
shared edges of its loops are made those exact circles (vertex on the seam), so sewing merges
identical curves.
"""

from __future__ import annotations

import math

import numpy as np

from igl_heatseg.surfaces.model import Surface

from ._ocp import require_ocp

require_ocp()

from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeFace  # noqa: E402
from OCP.Geom import Geom_Circle  # noqa: E402
from OCP.gp import gp_Ax2, gp_Dir, gp_Pnt  # noqa: E402

from .geometry import seam_frame  # noqa: E402

__all__ = ["surface_uv", "wraps_axis", "seam_at", "revolved_plan", "revolved_face",
           "iso_circle"]

#: Kinds whose u direction is the rotation about the axis (the sphere's frame axis is a fixed
#: z, unrelated to its loops, so spheres go through ShapeFix_Face).
REVOLVED_KINDS = ("cylinder", "cone", "torus")


def surface_uv(s: Surface, P: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """OCC parameters ``(u, v)`` of points on a surface built by ``geometry.occ_surface``."""
    o, a, x = seam_frame(s)
    y = np.cross(a, x) * (1.0 if s.outward else -1.0)  # left-handed frame: y reversed
    Q = P - o
    h = Q @ a
    u = np.mod(np.arctan2(Q @ y, Q @ x), 2 * math.pi)
    if s.kind == "cylinder":
        return u, h
    if s.kind == "cone":
        return u, h / math.cos(s.params["half_angle"])
    rho = np.linalg.norm(Q - np.outer(h, a), axis=1)
    return u, np.mod(np.arctan2(h, rho - s.params["major_radius"]), 2 * math.pi)


def _v_range(s: Surface, v: np.ndarray):
    """Interval covered by the segment's v values (circular for the torus)."""
    if s.kind != "torus":
        return float(v.min()), float(v.max())
    w = np.sort(v)
    gaps = np.diff(np.r_[w, w[0] + 2 * math.pi])
    i = int(np.argmax(gaps))
    lo = w[(i + 1) % len(w)]
    return float(lo), float(lo + 2 * math.pi - gaps[i])


def wraps_axis(s: Surface, loop_points: list) -> bool:
    """Every loop is one closed edge going around the surface's axis."""
    if s.kind not in REVOLVED_KINDS or not loop_points or any(P is None for P in loop_points):
        return False
    return all(np.ptp(np.unwrap(surface_uv(s, P)[0])) >= 1.5 * math.pi for P in loop_points)


def seam_at(s: Surface, u0: float):
    """:func:`~.geometry.seam_frame` turned to the surface's ``u = u0``."""
    o, a, x0 = seam_frame(s)
    y0 = np.cross(a, x0) * (1.0 if s.outward else -1.0)  # the u direction of the surface
    return o, a, math.cos(u0) * x0 + math.sin(u0) * y0


def revolved_plan(s: Surface, loop_points: list, seg_points: np.ndarray, tol: float):
    """Whether a face of revolution is bounded by circles at constant v, and where.

    Parameters
    ----------
    s : Surface
        Cylinder, cone or torus (others give None).
    loop_points : list of (q, 3) float64
        Per loop, points along its one closed edge; None for a loop of several edges (which
        gives None).
    seg_points : (p, 3) float64
        The segment's mesh vertices (they decide which side of the circles the face is).
    tol : float
        Distance by which loop points may leave their mean-v circle (model units).

    Returns
    -------
    dict or None
        ``levels`` (v of each loop's circle, in loop order), ``v0 < v1`` (the face's v range;
        a drill point's apex end is 0).
    """
    if s.kind not in REVOLVED_KINDS or not loop_points or any(P is None for P in loop_points):
        return None
    vs = surface_uv(s, seg_points)[1]
    v0, v1 = _v_range(s, vs)
    vscale = s.params["minor_radius"] if s.kind == "torus" else 1.0
    circular = s.kind == "torus"
    ends, levels = [], []
    for P in loop_points:
        u, v = surface_uv(s, P)
        if np.ptp(np.unwrap(u)) < 1.5 * math.pi:
            return None  # not around the axis
        which = int(np.argmin([np.abs(_wrap(v - e, circular)).max() for e in (v0, v1)]))
        mid = (v0, v1)[which] + float(_wrap(v - (v0, v1)[which], circular).mean())
        if np.abs(_wrap(v - mid, circular)).max() * vscale > tol:
            return None  # not at constant v on the segment's border
        ends.append(which)
        levels.append(mid)
    if len(set(ends)) != len(ends) or (len(ends) == 1 and not _reaches_apex(s, v0, v1, ends, tol)):
        return None
    lv = dict(zip(ends, levels, strict=True))  # one circle: a drill point, apex at v = 0
    return {"levels": levels, "v0": lv.get(0, 0.0), "v1": lv.get(1, 0.0)}


def revolved_face(geom, plan: dict):
    """Face ``u in [u0, u0 + 2 pi], v in [v0, v1]`` of a :func:`revolved_plan` (``u0`` from
    ``plan.get('u0', 0)``), or None."""
    u0 = float(plan.get("u0", 0.0))
    mk = BRepBuilderAPI_MakeFace(geom, u0, u0 + 2 * math.pi, plan["v0"], plan["v1"], 1e-7)
    return mk.Face() if mk.IsDone() else None


def iso_circle(s: Surface, v: float, P: np.ndarray | None = None, u0: float = 0.0):
    """The circle ``v = const`` of a surface of revolution, oriented like the points P
    (``(q, 3)``, around the axis; default: counter-clockwise about the axis).

    Returns
    -------
    curve : Geom_Circle
        Parameter 0 at the surface's ``u = u0``.
    start : (3,) float64
        Its point at parameter 0.
    """
    o, a, x = seam_at(s, u0)
    p = s.params
    if s.kind == "cylinder":
        C, R = o + v * a, p["radius"]
    elif s.kind == "cone":
        C, R = o + v * math.cos(p["half_angle"]) * a, v * math.sin(p["half_angle"])
    else:
        C = o + p["minor_radius"] * math.sin(v) * a
        R = p["major_radius"] + p["minor_radius"] * math.cos(v)
    n = a if P is None or np.cross(P[:-1] - C, P[1:] - C).sum(axis=0) @ a > 0 else -a
    ax = gp_Ax2(gp_Pnt(*map(float, C)), gp_Dir(*map(float, n)), gp_Dir(*map(float, x)))
    return Geom_Circle(ax, abs(float(R))), C + abs(R) * x


def _wrap(d: np.ndarray, circular: bool) -> np.ndarray:
    """Differences of v, wrapped to (-pi, pi] on the torus."""
    return np.angle(np.exp(1j * d)) if circular else d


def _reaches_apex(s: Surface, v0: float, v1: float, ends: list, tol: float) -> bool:
    """One circle bounds a face of revolution only on a cone whose other end is the apex
    (v is the distance from the apex along the generatrix)."""
    if s.kind != "cone":
        return False
    other = v1 if ends[0] == 0 else v0
    return abs(other) <= tol
