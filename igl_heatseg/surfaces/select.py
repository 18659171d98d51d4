"""Choosing a segment's surface kind: the simplest analytic kind within tolerance, else freeform
(:func:`fit_surface`), and the residual checks of a given surface (:func:`surface_residual`,
:func:`within_tolerance`).
"""

from __future__ import annotations

import logging
import math

import numpy as np

from ..errors import MeshError
from .checks import check_inputs, weights_area
from .lm import normalise, subsample
from .model import SURFACE_KINDS, Surface
from .primitives import fit_cone, fit_cylinder, fit_plane, fit_sphere, fit_torus

__all__ = ["fit_surface", "surface_residual", "within_tolerance", "sphere_over_cone"]

log = logging.getLogger(__name__)

#: fit_surface: a candidate stops iterating once its rms stays above this multiple of tol and
#: creeps (a wrong kind slides along a degenerate valley for dozens of iterations otherwise);
#: such a candidate is never accepted, and its rms, a few percent high, only ranks it.
GIVE_UP_FACTOR = 3.0
#: fit_surface: a more complex kind replaces a simpler one only when its RMS is below the
#: simpler one's divided by this factor ...
BEAT_FACTOR = 1.5
#: ... and lower by at least this fraction of the tolerance (nested models: the complex kind
#: always fits at least as well; it must explain clearly more than the noise to be chosen).
BEAT_ABS = 0.25
#: A fit is within tolerance when rms <= tol and max_dev <= MAX_DEV_FACTOR * tol (the largest of
#: thousands of Gaussian residuals is ~4 sigma; a bump or a wrong kind shows up in max_dev).
MAX_DEV_FACTOR = 3.0

#: fit_surface: a cone within tolerance gives way to a sphere (4 parameters against 6, tried
#: after it) within tolerance whose RMS is this many times lower, on at least
#: SPHERE_MIN_SAMPLES points. Nested in neither direction, the two fit a narrow band of either
#: about equally (on the 24 true cones of 50+ faces of the tuning parts, the cone's RMS is
#: 0.41-1.11 times the sphere's); a noisy dome (noise 0.2 edge) is within tolerance of a cone
#: too, at 1.5-1.6 times the sphere's RMS.
SPHERE_OVER_CONE = 1.3
#: ... four samples per parameter of the cone (a dozen noisy faces fit anything).
SPHERE_MIN_SAMPLES = 24

#: fit_surface: a candidate whose normals agree with the data's less than this (weighted mean
#: |cos| of the angle; 0.8 ~ 37 degrees on average, far beyond the face-normal noise of a scan
#: fitted within tolerance) is rejected whatever its distances: a fan cap and a cylinder ring
#: lie close to a torus by position alone.
NORMAL_AGREEMENT = 0.8

_FITTERS = {"plane": fit_plane, "cylinder": fit_cylinder, "cone": fit_cone,
            "sphere": fit_sphere, "torus": fit_torus}

#: fit_surface without a tolerance: this fraction of the data spread.
DEFAULT_REL_TOL = 1e-3


# ----------------------------------------------------------------------------- choosing a kind


def surface_residual(surface: Surface, P, w=None) -> tuple[float, float]:
    """Weighted RMS and largest absolute distance of points to a surface (vectorised, no fit).

    Parameters
    ----------
    surface : Surface
        An analytic surface (``freeform`` gives ``(nan, nan)``).
    P : (p, 3) array_like of float64
        Points.
    w : (p,) array_like, optional
        Non-negative weights (need not sum to 1); uniform by default.

    Returns
    -------
    rms, max_dev : float
        ``sqrt(sum w d^2 / sum w)`` and ``max |d|`` over points of positive weight.

    Examples
    --------
    >>> import numpy as np
    >>> s = Surface("plane", {"point": np.zeros(3), "normal": np.array([0., 0, 1])})
    >>> surface_residual(s, np.array([[0., 0, 1], [0, 0, -1], [5, 5, 0]]), w=[1, 1, 2])
    (0.7071067811865476, 1.0)
    """
    d = surface.distance(np.asarray(P, dtype=np.float64))
    if w is None:
        return float(np.sqrt(np.mean(d * d))), float(np.max(np.abs(d)))
    w = np.asarray(w, dtype=np.float64)
    return float(np.sqrt((w @ (d * d)) / w.sum())), float(np.max(np.abs(d[w > 0])))


def within_tolerance(surface: Surface, P, tol: float, w=None) -> bool:
    """Quick check of one given surface: ``rms <= tol`` and ``max_dev <= MAX_DEV_FACTOR tol``.

    The test :func:`fit_surface` applies to its candidates; for region growing (one distance
    evaluation, no fit).

    Parameters
    ----------
    surface : Surface
        The surface to test.
    P : (p, 3) array_like of float64
        Points.
    tol : float
        Tolerance (model units), e.g. from :func:`fit_tolerance`.
    w : (p,) array_like, optional
        Non-negative weights.

    Returns
    -------
    bool
        False for ``freeform``.

    Examples
    --------
    >>> import numpy as np
    >>> s = Surface("sphere", {"center": np.zeros(3), "radius": 1.0})
    >>> within_tolerance(s, np.array([[0., 0, 1.001], [1, 0, 0]]), tol=0.01)
    True
    """
    rms, max_dev = surface_residual(surface, P, w)
    return bool(rms <= tol and max_dev <= MAX_DEV_FACTOR * tol)


def _ok(s: Surface, tol: float) -> bool:
    return s.rms <= tol and s.max_dev <= MAX_DEV_FACTOR * tol


def _clearly_better(s: Surface, simpler: Surface, tol: float) -> bool:
    """The more complex ``s`` explains clearly more than the nested ``simpler`` kind."""
    by_rms = s.rms * BEAT_FACTOR < simpler.rms and simpler.rms - s.rms > BEAT_ABS * tol
    by_max = simpler.max_dev > MAX_DEV_FACTOR * tol >= s.max_dev * BEAT_FACTOR
    return bool(by_rms or by_max)


def fit_surface(P, N, w=None, tol: float | None = None, kinds=SURFACE_KINDS,
                candidates: list | None = None) -> Surface:
    """The simplest adequate surface kind for one segment's samples.

    Kinds are tried simplest first (plane < cylinder < cone < sphere < torus). A candidate
    replaces the current choice only if it is *clearly* better (its RMS below the choice's by a
    factor BEAT_FACTOR and by BEAT_ABS * tol, or it is within the max-deviation bound that the
    choice breaks): the kinds are nested (a huge sphere is a plane, a thin cone a cylinder), so
    a more complex kind always fits a little better and must beat the noise to be chosen. The
    search stops at the first candidate within tolerance (``rms <= tol`` and
    ``max_dev <= MAX_DEV_FACTOR * tol``) and returns the current choice (that candidate, or a
    simpler kind it does not clearly beat, whose rms is then below BEAT_FACTOR * tol), except
    that a cone gives way to a sphere (fewer parameters, tried after it) within tolerance that
    fits SPHERE_OVER_CONE times closer on SPHERE_MIN_SAMPLES points or more; when
    none is within tolerance the result is ``freeform`` (with the best candidate's rms and
    max_dev, or nan). Candidates still above GIVE_UP_FACTOR * tol after LM_GIVE_UP_AFTER
    iterations stop refining once they creep (a wrong kind; its rms only ranks it). A candidate
    whose normals disagree with ``N`` (weighted mean ``|cos|`` below NORMAL_AGREEMENT) is
    dropped, however close the points.

    Parameters
    ----------
    P : (p, 3) array_like of float64
        Points (e.g. from :func:`face_samples`).
    N : (p, 3) array_like
        Unit normals at the points.
    w : (p,) array_like, optional
        Non-negative weights (face areas).
    tol : float, optional
        Tolerance in model units (:func:`fit_tolerance`); default DEFAULT_REL_TOL times the
        points' spread (RMS distance to their centroid).
    kinds : sequence of str
        Kinds to consider (a single kind checks that kind only); ``freeform`` in it or not, the
        fallback is ``freeform``.
    candidates : list, optional
        When given, every analytic candidate fitted (whose normals agree) is appended to it, in
        the order tried, whether chosen or not.

    Returns
    -------
    Surface

    Raises
    ------
    MeshError
        On bad arrays, an unknown kind or a non-positive tolerance.

    Examples
    --------
    >>> import numpy as np
    >>> rng = np.random.default_rng(0)
    >>> U = rng.normal(size=(200, 3)); U /= np.linalg.norm(U, axis=1)[:, None]
    >>> fit_surface(5 * U, U, tol=1e-3).kind
    'sphere'
    >>> P = np.c_[rng.uniform(size=(200, 2)), np.zeros(200)]
    >>> fit_surface(P, np.tile([0., 0, 1], (200, 1)), tol=1e-3).kind
    'plane'
    """
    P, N, wn = check_inputs(P, N, w, True)
    bad = [k for k in kinds if k not in SURFACE_KINDS]
    if bad:
        raise MeshError(f"kinds {tuple(kinds)} has unknown kinds {bad}; expected {SURFACE_KINDS}")
    m, spread = normalise(P, wn)
    tol = DEFAULT_REL_TOL * spread if tol is None else float(tol)
    if not (math.isfinite(tol) and tol > 0):
        raise MeshError(f"tol must be a finite positive float, got {tol!r}")
    chosen = best = None
    for kind in (k for k in SURFACE_KINDS[:-1] if k in kinds):
        kw = {} if kind == "plane" else {"give_up_rms": GIVE_UP_FACTOR * tol}
        s = _FITTERS[kind](P, N, wn, **kw)
        if s is None or _normal_agreement(s, P, N, wn) < NORMAL_AGREEMENT:
            continue
        if candidates is not None:
            candidates.append(s)
        best = s if best is None or s.rms < best.rms else best
        if chosen is None or _clearly_better(s, chosen, tol):
            chosen = s
        if _ok(s, tol):
            log.debug("fit_surface: %s (rms %.3g, tol %.3g; %s within)", chosen.kind,
                      chosen.rms, tol, kind)
            if chosen.kind == "cone" and "sphere" in kinds and len(P) >= SPHERE_MIN_SAMPLES:
                chosen = _sphere_over_cone(chosen, P, N, wn, tol, candidates)
            return _with_area(chosen, w)
    rms, dev = (best.rms, best.max_dev) if best is not None else (math.nan, math.nan)
    return Surface("freeform", {"centroid": m}, rms=rms, max_dev=dev, area=weights_area(w))


def _sphere_over_cone(cone: Surface, P, N, wn, tol, candidates) -> Surface:
    """The sphere fitted to the points when it is within tolerance and fits clearly closer than
    the chosen cone (:data:`SPHERE_OVER_CONE`); else the cone."""
    s = fit_sphere(P, N, wn, give_up_rms=GIVE_UP_FACTOR * tol)
    if s is None or _normal_agreement(s, P, N, wn) < NORMAL_AGREEMENT:
        return cone
    if candidates is not None:
        candidates.append(s)
    return s if _ok(s, tol) and sphere_over_cone(s, cone) else cone


def sphere_over_cone(s: Surface, c: Surface) -> bool:
    """Whether ``s`` is a sphere fitting SPHERE_OVER_CONE times closer than the cone ``c`` (the
    sphere, with fewer parameters, then wins although the cone is tried first).

    Examples
    --------
    >>> sph = Surface("sphere", {"center": np.zeros(3), "radius": 1.0}, rms=0.1)
    >>> cone = Surface("cone", {"apex": np.zeros(3), "axis": np.array([0., 0, 1]),
    ...                         "half_angle": 0.5}, rms=0.2)
    >>> sphere_over_cone(sph, cone), sphere_over_cone(cone, sph)
    (True, False)
    """
    return s.kind == "sphere" and c.kind == "cone" and s.rms * SPHERE_OVER_CONE <= c.rms


def _normal_agreement(s: Surface, P, N, wn) -> float:
    """Weighted mean ``|N . n|`` of the data normals and the surface's normals (on the strided
    subsample): 1 when they agree, whatever the orientation."""
    idx = subsample(len(P))
    return float(wn[idx] @ np.abs(np.einsum("ij,ij->i", N[idx], s.normals(P[idx])))
                 / max(wn[idx].sum(), 1e-300))


def _with_area(s: Surface, w) -> Surface:
    return Surface(s.kind, s.params, rms=s.rms, max_dev=s.max_dev, area=weights_area(w),
                   outward=s.outward)
