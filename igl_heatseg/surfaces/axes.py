"""Coaxial typing: narrow bands of a turned part typed by the part's own axes.

A narrow band of a large cylinder (a gear's tip land, a flange's rim, a sprocket's root) lies
within the noise of its own plane: its sagitta ``w^2 / 8R`` is below the noise, so the
simplest kind within tolerance is a plane, and a free cylinder fitted to it is ill-conditioned
(its radius is barely determined). But a turned part has few axes, and its large cylinders,
cones and tori give them. About one of those axes, a cylinder has one parameter (its radius)
and a cone two (its radius at a height and its slope), against a plane's three: the coaxial
surface is the simpler model when it fits the band as well. The choice is made by
the Bayesian information criterion ``n log(rms^2) + k log(n)`` over the band's ``n`` vertices,
and only when the coaxial surface's RMS is below the plane's (a flat parallel to an axis is
never made a cylinder by the parameter count alone).
"""

from __future__ import annotations

import math

import numpy as np

from ..mesh.geometry import face_areas, face_normals
from .model import Surface
from .primitives import fitted_surface
from .samples import vertex_samples
from .segment_fit import explains, normals_agree

__all__ = ["part_axes", "coaxial_surfaces", "snap_to_axes"]

#: An axis comes from an analytic cylinder, cone or torus segment that its surface explains
#: and that holds at least this share of the part's area.
AXIS_MIN_SHARE = 0.005

#: Two axes are one when their directions are within AXIS_ANGLE and their lines within
#: AXIS_OFFSET x tol plus AXIS_OFFSET_REL x the part's size.
AXIS_ANGLE = math.radians(1.0)
AXIS_OFFSET = 2.0
AXIS_OFFSET_REL = 1e-3

#: A band needs this many vertices for the criterion to mean anything.
MIN_SAMPLES = 10

#: A coaxial cone's half angle lies in this range (steeper is a cylinder, flatter a plane;
#: both are tried on their own).
CONE_MIN_ANGLE = math.radians(5.0)
CONE_MAX_ANGLE = math.radians(80.0)


def _origin(s: Surface) -> np.ndarray:
    p = s.params
    return np.asarray(p["point"] if s.kind == "cylinder" else p.get("apex", p.get("center")),
                      dtype=np.float64)


def part_axes(V, F, labels, surfaces, tol: float) -> list:
    """The part's axes of revolution, from its analytic cylinders, cones and tori.

    Parameters
    ----------
    V : (n, 3) float64
    F : (m, 3) int64
    labels : (m,) int64
        Segment of each face, ``0..k-1``.
    surfaces : list of Surface, length k
    tol : float
        Fit tolerance (model units).

    Returns
    -------
    list of (point (3,), axis (3,)) float64 arrays
        A point on each axis and its unit direction, the axis of the largest segment of each
        group of coaxial segments, largest group first.

    Examples
    --------
    >>> import numpy as np
    >>> from igl_heatseg.surfaces.model import Surface
    >>> V = np.array([[0., 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]])
    >>> F = np.array([[0, 1, 2], [0, 1, 3]])
    >>> z = np.array([0., 0, 1])
    >>> cyl = Surface("cylinder", {"point": np.zeros(3), "axis": z, "radius": 1.0}, rms=0.0)
    >>> cone = Surface("cone", {"apex": 3 * z, "axis": -z, "half_angle": 0.5}, rms=0.0)
    >>> [a.tolist() for p, a in part_axes(V, F, np.array([0, 1]), [cyl, cone], 0.01)]
    [[0.0, 0.0, 1.0]]
    """
    A = np.bincount(labels, weights=face_areas(V, F), minlength=len(surfaces))
    size = float(np.ptp(V, axis=0).max())
    groups: list = []  # [point, axis, area]
    for k in np.argsort(-A, kind="stable").tolist():
        s = surfaces[k]
        if s.kind not in ("cylinder", "cone", "torus") or not explains(s, tol) or \
                A[k] < AXIS_MIN_SHARE * A.sum():
            continue
        o, a = _origin(s), np.asarray(s.params["axis"], dtype=np.float64)
        a = a / np.linalg.norm(a)
        for g in groups:
            if abs(float(g[1] @ a)) >= math.cos(AXIS_ANGLE) and np.linalg.norm(
                    np.cross(o - g[0], g[1])) <= AXIS_OFFSET * tol + AXIS_OFFSET_REL * size:
                g[2] += A[k]
                break
        else:
            groups.append([o, a, A[k]])
    groups.sort(key=lambda g: -g[2])
    return [(g[0], g[1]) for g in groups]


def coaxial_surfaces(P, N, w, point, axis, area: float = math.nan) -> list:
    """The least-squares cylinder, and cone when its slope is in range, about a given axis.

    Parameters
    ----------
    P : (p, 3) float64
        Points.
    N : (p, 3) float64
        Unit normals at the points (for ``outward``).
    w : (p,) float64
        Non-negative weights, summing to 1.
    point, axis : (3,) float64
        A point on the axis and its unit direction.
    area : float, optional
        The ``area`` the surfaces record (the segment's).

    Returns
    -------
    list of Surface
        The cylinder (radius: the weighted mean distance to the axis; point: the foot of the
        points' weighted centroid on the axis), then the cone whose radius is linear in the
        height along the axis (weighted least squares) when its half angle lies in
        [CONE_MIN_ANGLE, CONE_MAX_ANGLE]; ``rms``, ``max_dev`` and ``outward`` as
        :func:`~igl_heatseg.surfaces.primitives.fitted_surface` gives them (a surface whose
        statistics are not finite is left out).

    Examples
    --------
    >>> import numpy as np
    >>> t, h = np.meshgrid(np.linspace(0, 0.3, 5), np.linspace(0, 1, 4))
    >>> r = 2.0 + 0.5 * h.ravel()                               # a band of a cone
    >>> P = np.c_[r * np.cos(t.ravel()), r * np.sin(t.ravel()), h.ravel()]
    >>> N = np.c_[np.cos(t.ravel()), np.sin(t.ravel()), np.zeros(20)]
    >>> cyl, cone = coaxial_surfaces(P, N, np.full(20, 0.05), np.zeros(3), np.array([0., 0, 1]))
    >>> round(cyl.params["radius"], 6), cyl.params["point"].round(6).tolist()
    (2.25, [0.0, 0.0, 0.5])
    >>> round(cone.rms, 9), round(math.tan(cone.params["half_angle"]), 6)
    (0.0, 0.5)
    """
    point = np.asarray(point, dtype=np.float64)
    axis = np.asarray(axis, dtype=np.float64)
    Q = P - point
    h = Q @ axis
    d = np.linalg.norm(Q - np.outer(h, axis), axis=1)
    foot = point + float(w @ h) * axis  # the model's convention: the foot of the centroid
    out = [fitted_surface("cylinder", {"point": foot, "axis": axis, "radius": float(w @ d)},
                          P, N, w, area)]
    sw = np.sqrt(w)
    (c0, c1), *_ = np.linalg.lstsq(np.c_[sw, sw * h], sw * d, rcond=None)
    if math.tan(CONE_MIN_ANGLE) <= abs(c1) <= math.tan(CONE_MAX_ANGLE):
        apex = point - (c0 / c1) * axis  # where the radius c0 + c1 h is zero
        out.append(fitted_surface("cone", {"apex": apex, "axis": np.sign(c1) * axis,
                                           "half_angle": math.atan(abs(c1))}, P, N, w, area))
    return [s for s in out if s is not None]


def _bic(rms: float, n: int, k: int, floor: float) -> float:
    return n * math.log(rms * rms + floor) + k * math.log(n)


def snap_to_axes(V, F, labels, surfaces, tol: float, W=None, FN=None) -> tuple[list, int]:
    """Planes retyped as cylinders or cones about the part's axes where those fit better.

    For each ``plane`` segment with at least MIN_SAMPLES vertices, every axis of
    :func:`part_axes` gives a coaxial cylinder and cone (:func:`coaxial_surfaces`); the best
    replaces the plane when its RMS is below the plane's, within ``tol``, its normals agree
    with the faces' and its information criterion (1 or 2 parameters against the plane's 3)
    is lower.

    Parameters
    ----------
    V : (n, 3) float64
    F : (m, 3) int64
    labels : (m,) int64
        ``0..k-1``.
    surfaces : list of Surface, length k
    tol : float
        Fit tolerance (model units).
    W : (n, 3) float64, optional
        Positions the normals come from (a denoised copy of ``V``).
    FN : (m, 3) float64, optional
        Unit face normals (from ``W`` or ``V`` when not given).

    Returns
    -------
    surfaces : list of Surface
        A new list; retyped entries carry the segment's area.
    n : int
        Segments retyped.

    Examples
    --------
    >>> import numpy as np
    >>> th, z = np.meshgrid(np.linspace(0, 2 * np.pi, 61)[:-1], np.linspace(0, 2, 9))
    >>> V = np.c_[30 * np.cos(th.ravel()), 30 * np.sin(th.ravel()), z.ravel()]
    >>> V += np.random.default_rng(0).normal(0, 0.03, V.shape)      # a noisy ring
    >>> i = np.arange(60 * 8).reshape(8, 60); j = (i + 1) % 60 + 60 * (i // 60)
    >>> F = np.r_[np.c_[i.ravel(), j.ravel(), i.ravel() + 60],
    ...           np.c_[j.ravel(), j.ravel() + 60, i.ravel() + 60]]
    >>> labels = (th.ravel()[F[:, 0]] > 0.1).astype(np.int64)       # a one-column band
    >>> from igl_heatseg.surfaces.segment_fit import fit_faces
    >>> S = [fit_faces(V, F, np.flatnonzero(labels == k), 0.08) for k in (0, 1)]
    >>> [s.kind for s in S]
    ['plane', 'cylinder']
    >>> S2, n = snap_to_axes(V, F, labels, S, 0.08)
    >>> [s.kind for s in S2], n, round(S2[0].params["radius"])
    (['cylinder', 'cylinder'], 1, 30)
    """
    surfaces = list(surfaces)
    axes = part_axes(V, F, labels, surfaces, tol)
    if not axes:
        return surfaces, 0
    FN = face_normals(V if W is None else W, F) if FN is None else FN
    floor = (1e-6 * tol) ** 2  # round-off: an exact plane is not beaten by parameter count
    n = 0
    for k, s in enumerate(surfaces):
        if s.kind != "plane":
            continue
        faces = np.flatnonzero(labels == k)
        P, N, w = vertex_samples(V, F, faces, W)
        if len(P) < MIN_SAMPLES:
            continue
        area = float(w.sum())
        w = w / area
        d = s.distance(P)
        best, best_rms = None, math.sqrt(float(w @ (d * d)))
        best_bic = _bic(best_rms, len(P), 3, floor)
        for point, axis in axes:
            for c in coaxial_surfaces(P, N, w, point, axis, area):
                b = _bic(c.rms, len(P), 1 if c.kind == "cylinder" else 2, floor)
                if c.rms < best_rms and c.rms <= tol and b < best_bic and \
                        normals_agree(V, F, FN, faces, c, raw=W is not None):
                    best, best_rms, best_bic = c, c.rms, b
        if best is not None:
            surfaces[k] = best
            n += 1
    return surfaces, n
