"""Faces of revolution bounded by coaxial circles, built on a parametric rectangle.

A cylinder between two circles, a cone frustum or drill point, a torus band: every loop is one
closed edge at constant ``v``. Trimming such a face with ShapeFix_Face needs a seam through
both circles' vertices, which two slightly different fitted axes never give exactly (ShapeFix
then splits a circle next to its vertex and the sliver edge is lost in sewing). Here the face
is ``BRepBuilderAPI_MakeFace(surface, u0, u0 + 2 pi, v0, v1)`` with its own seam and circles,
and sewing merges those circles with the neighbours' edges.
"""

from __future__ import annotations

import math

import numpy as np

from igl_heatseg.surfaces.model import Surface

from ._ocp import require_ocp

require_ocp()

from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeFace  # noqa: E402

from .geometry import seam_frame  # noqa: E402

__all__ = ["revolved_face"]

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


def revolved_face(s: Surface, geom, loop_points: list, seg_points: np.ndarray, tol: float):
    """Face of revolution on a (u, v) rectangle, or None when the loops are not circles.

    Parameters
    ----------
    s : Surface
        Cylinder, cone or torus.
    geom : Geom_Surface
        Its OCC surface (``geometry.occ_surface(s)``).
    loop_points : list of (q, 3) float64
        Per loop, points along its one closed edge (first point: the edge's vertex); a loop
        made of several edges disqualifies the face (pass None).
    seg_points : (p, 3) float64
        The segment's mesh vertices (they decide which side of the circles the face is).
    tol : float
        Distance by which loop points may leave their constant-v circle (model units).

    Returns
    -------
    TopoDS_Face or None
    """
    if s.kind not in REVOLVED_KINDS or not loop_points or any(P is None for P in loop_points):
        return None
    vs = surface_uv(s, seg_points)[1]
    v0, v1 = _v_range(s, vs)
    vscale = s.params["minor_radius"] if s.kind == "torus" else 1.0
    ends, levels = [], []
    for P in loop_points:
        u, v = surface_uv(s, P)
        if np.ptp(np.unwrap(u)) < 1.5 * math.pi:
            return None  # not around the axis
        dv = [np.abs(np.angle(np.exp(1j * (v - e)))) if s.kind == "torus" else np.abs(v - e)
              for e in (v0, v1)]
        which = int(np.argmin([d.max() for d in dv]))
        mid = (v0, v1)[which] + _mean_offset(v - (v0, v1)[which], s.kind == "torus")
        spread = np.abs(v - mid)
        if s.kind == "torus":
            spread = np.abs(np.angle(np.exp(1j * (v - mid))))
        if spread.max() * vscale > tol:
            return None  # not at constant v on the segment's border
        ends.append(which)
        levels.append(mid)
    if len(set(ends)) != len(ends) or (len(ends) == 1 and not _reaches_apex(s, v0, v1, ends, tol)):
        return None
    lv = dict(zip(ends, levels))  # each circle at its loop's mean v
    v0, v1 = lv.get(0, 0.0), lv.get(1, 0.0)  # one circle: the drill point runs to the apex
    u0 = float(surface_uv(s, loop_points[0][:1])[0][0])
    mk = BRepBuilderAPI_MakeFace(geom, u0, u0 + 2 * math.pi, v0, v1, 1e-7)
    return mk.Face() if mk.IsDone() else None


def _mean_offset(d: np.ndarray, circular: bool) -> float:
    """Mean of v differences (angles wrapped to (-pi, pi] on the torus)."""
    return float(np.angle(np.exp(1j * d)).mean()) if circular else float(d.mean())


def _reaches_apex(s: Surface, v0: float, v1: float, ends: list, tol: float) -> bool:
    """One circle bounds a face of revolution only on a cone whose other end is the apex
    (v is the distance from the apex along the generatrix)."""
    if s.kind != "cone":
        return False
    other = v1 if ends[0] == 0 else v0
    return abs(other) <= tol
