"""The fitted-surface type shared by the surface, CAD and report stages.

A :class:`Surface` is one analytic (or freeform) surface fitted to one segment of a mesh. Its
parameters are plain numpy arrays and floats, keyed by name in :attr:`Surface.params`:

============  =================================================================================
kind          params
============  =================================================================================
plane         ``point (3,)`` a point on the plane (the fitted points' centroid); ``normal (3,)``
              unit normal, oriented like the segment's mesh normals (outward on a closed part)
cylinder      ``point (3,)`` a point on the axis (the foot of the points' centroid);
              ``axis (3,)`` unit axis direction; ``radius`` > 0
cone          ``apex (3,)``; ``axis (3,)`` unit direction from the apex into the opening;
              ``half_angle`` in (0, pi/2) radians
sphere        ``center (3,)``; ``radius`` > 0
torus         ``center (3,)``; ``axis (3,)`` unit; ``major_radius`` > 0 (centre to tube
              centre); ``minor_radius`` > 0 (tube radius). A spindle torus (minor > major) is
              allowed.
freeform      no analytic parameters (``centroid (3,)`` only); the CAD stage fits a B-spline over
              the segment's chart
============  =================================================================================

Signed distance (:meth:`Surface.distance`): for a plane, positive on the side the normal points
to; for the other analytic kinds, positive away from the axis / centre / tube centre (outside the
solid cylinder, cone, ball or tube), whatever the mesh orientation. :attr:`Surface.outward` says
whether the segment's mesh normals point to positive distance (a boss or ball: ``True``) or to
negative distance (a hole or socket: ``False``); planes are always ``True``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

__all__ = ["SURFACE_KINDS", "ANALYTIC_KINDS", "Surface"]

#: Every kind, simplest first (the order in which a fit selects the simplest adequate type).
SURFACE_KINDS: tuple[str, ...] = ("plane", "cylinder", "cone", "sphere", "torus", "freeform")

#: The kinds with a closed-form distance.
ANALYTIC_KINDS: tuple[str, ...] = SURFACE_KINDS[:-1]

_REQUIRED = {
    "plane": ("point", "normal"),
    "cylinder": ("point", "axis", "radius"),
    "cone": ("apex", "axis", "half_angle"),
    "sphere": ("center", "radius"),
    "torus": ("center", "axis", "major_radius", "minor_radius"),
    "freeform": ("centroid",),
}


@dataclass(frozen=True)
class Surface:
    """One fitted surface.

    Attributes
    ----------
    kind : str
        One of :data:`SURFACE_KINDS`.
    params : dict
        Parameters by name (see the module docstring); vectors are ``(3,) float64``.
    rms : float
        RMS geometric distance of the fitted points to the surface (model units); ``nan`` for
        ``freeform``.
    max_dev : float
        Largest absolute distance of a fitted point (model units); ``nan`` for ``freeform``.
    area : float
        Area of the segment the surface was fitted to.
    outward : bool
        Mesh normals point towards positive :meth:`distance`.

    Examples
    --------
    >>> import numpy as np
    >>> s = Surface("sphere", {"center": np.zeros(3), "radius": 2.0})
    >>> s.distance(np.array([[3.0, 0.0, 0.0], [0.0, 1.0, 0.0]]))
    array([ 1., -1.])
    >>> s.project(np.array([[3.0, 0.0, 0.0]]))
    array([[2., 0., 0.]])
    """

    kind: str
    params: dict = field(default_factory=dict)
    rms: float = math.nan
    max_dev: float = math.nan
    area: float = math.nan
    outward: bool = True

    def __post_init__(self):
        if self.kind not in _REQUIRED:
            raise ValueError(f"unknown surface kind {self.kind!r}; expected one of {SURFACE_KINDS}")
        missing = [k for k in _REQUIRED[self.kind] if k not in self.params]
        if missing:
            raise ValueError(f"{self.kind} surface needs parameters {missing}")

    @property
    def is_analytic(self) -> bool:
        """True for every kind but ``freeform``."""
        return self.kind in ANALYTIC_KINDS

    def _radial(self, P: np.ndarray, origin: np.ndarray, axis: np.ndarray):
        Q = P - origin
        h = Q @ axis
        R = Q - np.outer(h, axis)
        r = np.linalg.norm(R, axis=1)
        return h, r, R

    def distance(self, P) -> np.ndarray:
        """Signed distance of points to the surface.

        Parameters
        ----------
        P : (p, 3) array_like
            Points.

        Returns
        -------
        d : (p,) float64
            Signed distance (sign convention in the module docstring). ``nan`` for ``freeform``.
        """
        P = np.atleast_2d(np.asarray(P, dtype=np.float64))
        p = self.params
        if self.kind == "plane":
            return (P - p["point"]) @ p["normal"]
        if self.kind == "sphere":
            return np.linalg.norm(P - p["center"], axis=1) - p["radius"]
        if self.kind == "cylinder":
            _, r, _ = self._radial(P, p["point"], p["axis"])
            return r - p["radius"]
        if self.kind == "cone":
            h, r, _ = self._radial(P, p["apex"], p["axis"])
            ca, sa = math.cos(p["half_angle"]), math.sin(p["half_angle"])
            along = h * ca + r * sa  # coordinate along the generatrix from the apex
            d = r * ca - h * sa
            behind = along < 0  # nearest point of the one-nappe cone is the apex
            d = np.where(behind, np.sign(d) * np.hypot(h, r), d)
            return d
        if self.kind == "torus":
            h, r, _ = self._radial(P, p["center"], p["axis"])
            return np.hypot(r - p["major_radius"], h) - p["minor_radius"]
        return np.full(len(P), np.nan)

    def project(self, P) -> np.ndarray:
        """Closest points on the surface.

        Parameters
        ----------
        P : (p, 3) array_like
            Points.

        Returns
        -------
        X : (p, 3) float64
            Closest points (a point on an axis goes to an arbitrary one of its closest points).
            ``P`` itself for ``freeform``.
        """
        P = np.atleast_2d(np.asarray(P, dtype=np.float64))
        p = self.params
        if self.kind == "plane":
            return P - np.outer(self.distance(P), p["normal"])
        if self.kind == "sphere":
            D = P - p["center"]
            n = np.linalg.norm(D, axis=1)
            D = np.where(n[:, None] > 0, D / np.maximum(n, 1e-300)[:, None], _any_perp(None))
            return p["center"] + p["radius"] * D
        if self.kind in ("cylinder", "cone", "torus"):
            origin = p["point"] if self.kind == "cylinder" else p.get("apex", p.get("center"))
            a = p["axis"]
            h, r, R = self._radial(P, origin, a)
            U = np.where(r[:, None] > 0, R / np.maximum(r, 1e-300)[:, None], _any_perp(a))
            if self.kind == "cylinder":
                return origin + np.outer(h, a) + p["radius"] * U
            if self.kind == "torus":
                C = origin + p["major_radius"] * U  # tube centre in the point's half-plane
                D = P - C
                n = np.linalg.norm(D, axis=1)
                D = np.where(n[:, None] > 0, D / np.maximum(n, 1e-300)[:, None], U)
                return C + p["minor_radius"] * D
            ca, sa = math.cos(p["half_angle"]), math.sin(p["half_angle"])
            g = np.outer(ca * np.ones(len(P)), a) + sa * U  # unit generatrix direction
            t = np.maximum(h * ca + r * sa, 0.0)
            return origin + t[:, None] * g
        return P.copy()

    def normals(self, P) -> np.ndarray:
        """Unit gradient of :meth:`distance`: the surface normal at each point's closest point,
        pointing towards positive distance.

        Parameters
        ----------
        P : (p, 3) array_like
            Points.

        Returns
        -------
        G : (p, 3) float64
            Unit vectors (for a point on an axis or at a centre, an arbitrary one of the
            candidate directions). ``nan`` for ``freeform``.

        Examples
        --------
        >>> import numpy as np
        >>> s = Surface("cylinder", {"point": np.zeros(3), "axis": np.array([0.0, 0.0, 1.0]),
        ...                          "radius": 1.0})
        >>> s.normals(np.array([[0.0, 3.0, 5.0]]))
        array([[0., 1., 0.]])
        """
        P = np.atleast_2d(np.asarray(P, dtype=np.float64))
        p = self.params
        if self.kind == "plane":
            return np.tile(np.asarray(p["normal"], dtype=np.float64), (len(P), 1))
        if self.kind == "sphere":
            return _unit_rows(P - p["center"], _any_perp(None))
        if self.kind == "freeform":
            return np.full((len(P), 3), np.nan)
        origin = p["point"] if self.kind == "cylinder" else p.get("apex", p.get("center"))
        a = p["axis"]
        h, r, R = self._radial(P, origin, a)
        U = _unit_rows(R, _any_perp(a))
        if self.kind == "cylinder":
            return U
        if self.kind == "torus":
            return _unit_rows(P - (origin + p["major_radius"] * U), U)
        ca, sa = math.cos(p["half_angle"]), math.sin(p["half_angle"])
        G = ca * U - sa * np.asarray(a, dtype=np.float64)
        behind = h * ca + r * sa < 0  # closest point is the apex
        return np.where(behind[:, None], _unit_rows(P - origin, G), G)

    def to_dict(self) -> dict:
        """JSON-ready description: kind, parameters as lists, rms, max_dev, area, outward."""
        out = {"type": self.kind}
        for k, v in self.params.items():
            out[k] = np.asarray(v).tolist() if np.ndim(v) else float(v)
        out.update(rms=_f(self.rms), max_dev=_f(self.max_dev), area=_f(self.area),
                   outward=bool(self.outward))
        return out


def _f(x: float):
    return None if x is None or not math.isfinite(x) else float(x)


def _unit_rows(D: np.ndarray, fallback) -> np.ndarray:
    """Rows of ``D`` normalised; zero rows replaced by ``fallback`` (broadcast to ``D``)."""
    n = np.linalg.norm(D, axis=1)
    return np.where(n[:, None] > 0, D / np.maximum(n, 1e-300)[:, None], fallback)


def _any_perp(a):
    """A unit vector perpendicular to ``a`` (or the x axis when ``a`` is None)."""
    if a is None:
        return np.array([1.0, 0.0, 0.0])
    a = np.asarray(a, dtype=np.float64)
    e = np.eye(3)[int(np.argmin(np.abs(a)))]
    v = np.cross(a, e)
    return v / np.linalg.norm(v)
