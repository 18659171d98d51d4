"""Least-squares fitting of planes, cylinders, cones, spheres and tori to mesh samples.

Every analytic fit minimises the weighted sum of squared *geometric* (true point-to-surface)
distances with Levenberg-Marquardt, from a seed computed in closed form from the points and their
normals (Lukacs, Marshall & Martin 1998, "Faithful least-squares fitting of spheres, cylinders,
cones and tori"; Eberly, "Least squares fitting of data"):

* plane: weighted principal axes (exact, no iteration);
* sphere: the point nearest to all normal lines (or an algebraic fit without normals);
* cylinder: axis = least eigenvector of the normals' scatter (normals lie on a great circle),
  then the point nearest to the normal lines in the cross-section;
* cone: axis = normal of the plane through the normal vectors (they lie on a small circle), then
  the cross-section centre and a line ``r = r0 + h tan(psi)`` through the (height, radius) pairs;
* torus: axis = the line meeting all normal lines (a 6x6 Pluecker eigenproblem), then the tube
  circle in the (radius, height) half-plane; or, robust to normal noise on thin tubes
  (fillets), the minor radius that makes the tube centres ``p - r n`` coplanar, their plane's
  normal as axis and their circle as spine. The seed that fits better is refined.

The iterations work on centred, unit-spread coordinates and use parameterisations that stay
regular as a kind degenerates into a simpler one (curvature instead of radius for spheres and
cylinders, signed half-angle for cones), so a fit never returns ``nan``; it returns ``None``
when its kind does not apply (a sphere through planar data, a cone on a cylinder, a torus whose
major radius is far beyond the data), and :func:`fit_surface` falls back to the simpler kind.

Signed distances, parameter names and ``outward`` follow :mod:`igl_heatseg.surfaces.model`.
"""

from __future__ import annotations

import logging
import math

import igl
import numpy as np
from scipy.optimize import minimize_scalar
from scipy.stats import chi2

from ..errors import MeshError
from .model import SURFACE_KINDS, Surface

__all__ = [
    "fit_plane",
    "fit_sphere",
    "fit_cylinder",
    "fit_cone",
    "fit_torus",
    "fit_surface",
    "surface_residual",
    "within_tolerance",
    "face_samples",
    "face_residuals",
    "noise_level",
    "fit_tolerance",
]

log = logging.getLogger(__name__)

#: A radius (or apex distance) beyond this many data spreads (RMS distance of the points to their
#: centroid) is indistinguishable from the simpler kind: the sagitta over the data is below
#: 1e-4 spread, under any tolerance this module derives, so the fit returns ``None``.
FAR_RATIO = 1e4
#: A torus whose major radius is below this fraction of its minor radius is a sphere.
TORUS_MIN_MAJOR = 1e-3
#: Levenberg-Marquardt: most iterations (a seeded fit of the right kind converges in 3-10;
#: a wrong kind creeps along a degenerate direction and is stopped here or by LM_RTOL).
LM_MAX_ITER = 30
#: Stop when an iteration lowers the cost by less than this fraction: the rms is then settled
#: to ~1e-7 relative, far below any tolerance decision (the right kind converges
#: quadratically to round-off anyway, see LM_EXACT_COST).
LM_RTOL = 1e-7
#: Stop when the step is below this (unit-spread coordinates).
LM_XTOL = 1e-10
#: Stop at this cost (weighted mean squared residual, unit-spread coordinates): residuals of
#: 1e-14 of the spread are round-off, and LM steps would only be rejected from there on.
LM_EXACT_COST = 1e-28
#: With a give-up level (fit_surface: GIVE_UP_FACTOR * tol), stop once the cost is above it and
#: an iteration gains less than this fraction.
LM_GIVE_UP_GAIN = 1e-2
#: ... but not before this many iterations (the right kind from a poor seed, e.g. a fillet on a
#: short arc with noisy normals, also starts slowly).
LM_GIVE_UP_AFTER = 10
#: At most this many points drive the iterations; a final polish uses all points. Beyond ~1,000
#: well-spread samples the fitted parameters change by far less than the noise.
LM_MAX_POINTS = 1500
#: fit_surface's candidates first iterate on this many samples: a wrong kind is given up there,
#: at a quarter of the cost.
LM_COARSE_POINTS = 400
#: Relative eigenvalue / determinant below which a seed's linear system counts as singular.
SEED_RCOND = 1e-9

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

#: fit_surface: a candidate whose normals agree with the data's less than this (weighted mean
#: |cos| of the angle; 0.8 ~ 37 degrees on average, far beyond the face-normal noise of a scan
#: fitted within tolerance) is rejected whatever its distances: a fan cap and a cylinder ring
#: lie close to a torus by position alone.
NORMAL_AGREEMENT = 0.8

#: fit_tolerance: multiple of the noise level (rms of vertex noise; a fit's rms over vertices and
#: face centroids is ~0.8 of it, so 2.5 leaves room for the noise estimate's own error).
K_NOISE = 2.5
#: fit_tolerance: multiple of the tessellation's chord (sagitta) error.
K_CHORD = 1.0
#: fit_tolerance: floor as a fraction of the mean edge length (float32 STL coordinates and
#: exporters' rounding; keeps the tolerance > 0 on a perfect mesh).
K_FLOOR = 1e-3
#: Dihedral angles (radians) above this are creases, not tessellated curvature (exporters
#: rarely use more than 30 degrees per facet).
CREASE_ANGLE = math.radians(40.0)
#: Dihedral angles below this are flat (no chord error to estimate).
FLAT_ANGLE = math.radians(0.5)
#: Quantile of the curved edges' chord errors taken as the mesh's chord error (robust to a few
#: badly shaped facets, covers the coarser curved surfaces).
CHORD_QUANTILE = 0.9
#: noise_level: least 1-ring size (vertex + neighbours) to fit a 6-coefficient quadric with
#: at least one residual degree of freedom.
QUAD_MIN_POINTS = 7

_MIN_POINTS = {"plane": 3, "sphere": 4, "cylinder": 5, "cone": 6, "torus": 7}


# ----------------------------------------------------------------------------- input checks


def _as_points(P, name: str = "P") -> np.ndarray:
    A = np.asarray(P, dtype=np.float64)
    if A.ndim != 2 or A.shape[1] != 3:
        raise MeshError(f"{name} must have shape (p, 3), got {A.shape}")
    if not np.all(np.isfinite(A)):
        raise MeshError(f"{name} (shape {A.shape}) has non-finite entries")
    return A


def _check_inputs(P, N, w, need_normals: bool):
    """Validated ``P``, ``N`` (or None) and weights normalised to sum 1."""
    P = _as_points(P)
    if N is None:
        if need_normals:
            raise MeshError(f"N is required for this fit (P has shape {P.shape})")
    else:
        N = _as_points(N, "N")
        if N.shape != P.shape:
            raise MeshError(f"N must have the shape of P {P.shape}, got {N.shape}")
    if w is None:
        w = np.full(len(P), 1.0 / max(len(P), 1))
    else:
        w = np.asarray(w, dtype=np.float64)
        if w.shape != (len(P),):
            raise MeshError(f"w must have shape ({len(P)},), got {w.shape}")
        if not np.all(np.isfinite(w)) or np.any(w < 0) or not w.sum() > 0:
            raise MeshError(f"w (shape {w.shape}) must be finite, >= 0, with a positive sum")
        w = w / w.sum()
    return P, N, w


def _check_mesh(V, F):
    V = _as_points(V, "V")
    F = np.asarray(F)
    if F.ndim != 2 or F.shape[1] != 3 or not np.issubdtype(F.dtype, np.integer):
        raise MeshError(f"F must be an integer array of shape (m, 3), got {F.dtype} {F.shape}")
    if len(F) == 0 or F.min() < 0 or F.max() >= len(V):
        raise MeshError(f"F (shape {F.shape}) must be non-empty with indices in [0, {len(V)})")
    return V, F.astype(np.int64)


# ----------------------------------------------------------------------------- small helpers


def _unit(v: np.ndarray) -> np.ndarray:
    n = np.linalg.norm(v)
    return v / n if n > 0 else np.array([0.0, 0.0, 1.0])


def _orth(*vs) -> np.ndarray:
    """A unit vector orthogonal to the given orthonormal vectors (the best-conditioned column
    of the complementary projector; cheaper than np.cross on single vectors)."""
    M = np.eye(3)
    for v in vs:
        M = M - np.outer(v, v)
    return _unit(M[:, int(np.argmax(np.diag(M)))])


def _frame(a: np.ndarray):
    """Two unit vectors completing ``a`` to an orthonormal frame."""
    u = _orth(a)
    return u, _orth(a, u)


def _chart(a0, u0, v0, s, t):
    """Unit vector near ``a0``: ``a0 + s u0 + t v0`` normalised (a chart of the sphere)."""
    return _unit(a0 + s * u0 + t * v0)


def _normalise(P, w):
    """Weighted centroid ``m`` and spread ``s`` (RMS distance to ``m``; 1 when all coincide)."""
    m = w @ P
    s = math.sqrt(max(float(w @ np.einsum("ij,ij->i", P - m, P - m)), 0.0))
    return m, (s if s > 0 else 1.0)


def _rownorm(X: np.ndarray) -> np.ndarray:
    return np.sqrt(np.einsum("ij,ij->i", X, X))


def _seed_sample(X, N, wn):
    """The strided subsample (weights renormalised) that seeds are computed from."""
    idx = _subsample(len(X))
    if len(idx) == len(X):
        return X, N, wn
    ws = wn[idx]
    return X[idx], None if N is None else N[idx], ws / max(ws.sum(), 1e-300)


def _subsample(p: int, most: int = LM_MAX_POINTS) -> np.ndarray:
    """Evenly strided indices of at most ``most`` of ``p`` points (deterministic)."""
    if p <= most:
        return np.arange(p)
    return np.linspace(0, p - 1, most).astype(np.int64)


def _least_eig(M: np.ndarray):
    """Eigenvalues (ascending) and the eigenvector of the least one, of a symmetric matrix."""
    lam, E = np.linalg.eigh(M)
    return lam, E[:, 0]


def _nearest_to_lines(X, D, w):
    """Point minimising the weighted squared distances to the lines ``X + t D`` (rows unit).

    Works in any dimension; ``None`` when the lines are (nearly) parallel.
    """
    wD = D * w[:, None]
    A = w.sum() * np.eye(X.shape[1]) - wD.T @ D  # sum w (I - d d^T)
    b = w @ X - wD.T @ np.einsum("ij,ij->i", D, X)
    lam = np.linalg.eigvalsh(A)
    if lam[0] <= SEED_RCOND * max(lam[-1], 1e-300):
        return None
    return np.linalg.solve(A, b)


def _lm(res, x0, max_iter: int = LM_MAX_ITER, give_up: float = math.inf):
    """Levenberg-Marquardt on weighted residuals ``res(x, True) -> (r (p,), J (p, k))``.
    Returns the parameters and the cost ``|r|^2``, or ``None`` if ``res(x0)`` is not finite.
    Stops early while the cost is above ``give_up`` and creeping."""
    x = np.asarray(x0, dtype=np.float64).copy()
    r, J = res(x, True)
    cost = float(r @ r)
    if not (math.isfinite(cost) and np.all(np.isfinite(J))):
        return None
    lam = 1e-3
    for it in range(max_iter):
        if cost <= LM_EXACT_COST:
            break
        g, H = J.T @ r, J.T @ J
        D = np.diag(np.diag(H) + 1e-12 * (np.trace(H) + 1e-300))
        while lam < 1e12:
            try:
                step = np.linalg.solve(H + lam * D, -g)
            except np.linalg.LinAlgError:
                step = np.linalg.lstsq(H + lam * D, -g, rcond=None)[0]
            rn, Jn = res(x + step, True)
            cn = float(rn @ rn)
            if math.isfinite(cn) and cn <= cost and np.all(np.isfinite(Jn)):
                break
            lam *= 10.0
        else:
            break
        gain = cost - cn
        x, r, J, cost = x + step, rn, Jn, cn
        lam = max(lam * 0.1, 1e-12)
        if it >= LM_GIVE_UP_AFTER and cost > give_up and gain < LM_GIVE_UP_GAIN * (cost + gain):
            break
        if gain <= LM_RTOL * cost + 1e-300 or np.linalg.norm(step) < LM_XTOL:
            break
    return x, cost


def _finish(kind, params, P, N, w, area) -> Surface:
    """A Surface with weighted rms, max_dev and outward from the normals."""
    s = Surface(kind, params)
    d = s.distance(P)
    rms = math.sqrt(float(w @ (d * d)))
    max_dev = float(np.max(np.abs(d[w > 0])))
    outward = True
    if N is not None and kind != "plane":
        idx = _subsample(len(P))  # a vote: the subsample is enough
        outward = bool(w[idx] @ np.einsum("ij,ij->i", N[idx], s.normals(P[idx])) >= 0)
    if not (math.isfinite(rms) and math.isfinite(max_dev)):
        return None
    return Surface(kind, params, rms=rms, max_dev=max_dev, area=area, outward=outward)


def _area(w_raw) -> float:
    return math.nan if w_raw is None else float(np.sum(w_raw))


def _curvature_seed(c, r, fallback_n):
    """Seed ``(n, rho, kappa)`` of the curvature form from a centre ``c`` and radius ``r``:
    ``n`` the outward normal at the surface point nearest the origin, ``rho`` its offset.
    Without a centre: the plane through 0 normal to ``fallback_n``; with the centre at 0 (a
    closed sphere or cylinder around the centroid): the point ``r fallback_n``."""
    if c is None or not math.isfinite(r) or r <= 0:
        return fallback_n, 0.0, 0.0
    dc = float(np.linalg.norm(c))
    if dc <= 1e-6 * r:
        return fallback_n, r, 1.0 / r
    return -np.asarray(c) / dc, r - dc, 1.0 / r


def _chart_d(a0, u0, v0, s, t):
    """:func:`_chart` and its derivatives ``(2, 3)`` in ``s`` and ``t``."""
    at = a0 + s * u0 + t * v0
    L = math.sqrt(at @ at)  # >= 1: u0, v0 are normal to the unit a0
    a = at / L
    return a, np.array([u0 - (a @ u0) * a, v0 - (a @ v0) * a]) / L


def _curv_dist_d(x, n, kappa):
    """:func:`_curv_dist` ``D`` and its partial derivatives: ``(p, 3)`` in ``x``, ``(p, 3)`` in
    ``n`` and ``(p,)`` in ``kappa``."""
    xx = np.einsum("ij,ij->i", x, x)
    wv = kappa * x + n
    W = np.maximum(_rownorm(wv), 1e-300)
    den = W + 1.0
    D = (kappa * xx + 2.0 * (x @ n)) / den
    q = D / den / W
    Gx = (2.0 * kappa * x + 2.0 * n) / den[:, None] - (q * kappa)[:, None] * wv
    Gn = 2.0 * x / den[:, None] - q[:, None] * wv
    Gk = xx / den - q * np.einsum("ij,ij->i", x, wv)
    return D, Gx, Gn, Gk


def _curv_dist(x, n, kappa):
    """Signed distance to the circle/sphere through ``0`` with normal ``n`` and curvature
    ``kappa`` (positive along ``n``), stable as kappa -> 0 (a plane): Lukacs et al. eq. (3)."""
    num = kappa * np.einsum("ij,ij->i", x, x) + 2.0 * (x @ n)
    return num / (_rownorm(kappa * x + n) + 1.0)


def _run_lm(make_res, X, wn, x0, give_up: float = math.inf):
    """LM on at most LM_MAX_POINTS strided samples, then a short polish on all points. With a
    give-up level, a first pass on LM_COARSE_POINTS samples drops hopeless candidates cheaply."""
    if math.isfinite(give_up) and len(X) > 2 * LM_COARSE_POINTS:
        idx = _subsample(len(X), LM_COARSE_POINTS)
        ws = wn[idx]
        sol = _lm(make_res(X[idx], np.sqrt(ws / max(ws.sum(), 1e-300))), x0, give_up=give_up)
        if sol is None or sol[1] > give_up:
            return sol
        x0 = sol[0]
    idx = _subsample(len(X))
    if len(idx) == len(X):
        return _lm(make_res(X, np.sqrt(wn)), x0, give_up=give_up)
    ws = wn[idx]
    sol = _lm(make_res(X[idx], np.sqrt(ws / max(ws.sum(), 1e-300))), x0, give_up=give_up)
    if sol is None or sol[1] > give_up:
        return sol
    return _lm(make_res(X, np.sqrt(wn)), sol[0], max_iter=1)


def _pca_normal(X, wn) -> np.ndarray:
    return _least_eig((X * wn[:, None]).T @ X)[1]


# ----------------------------------------------------------------------------- the fits


def fit_plane(P, N=None, w=None) -> Surface | None:
    """Weighted least-squares plane (exact: principal axes of the weighted scatter).

    Parameters
    ----------
    P : (p, 3) array_like of float64
        Points.
    N : (p, 3) array_like, optional
        Unit normals at the points; the plane normal is oriented like their weighted mean.
        Without them the normal's largest component is made positive.
    w : (p,) array_like, optional
        Non-negative weights (e.g. face areas); uniform by default.

    Returns
    -------
    Surface or None
        ``plane`` with ``point`` = weighted centroid, unit ``normal``; ``rms`` (weighted) and
        ``max_dev`` of the signed distances; ``area`` = sum of ``w`` (nan without weights).
        ``None`` for fewer than 3 points.

    Raises
    ------
    MeshError
        On arrays of the wrong shape, non-finite values or weights without a positive sum.

    Examples
    --------
    >>> import numpy as np
    >>> P = np.array([[0., 0, 1], [1, 0, 1], [0, 1, 1], [1, 1, 1]])
    >>> s = fit_plane(P, N=np.tile([0., 0, -1], (4, 1)))
    >>> (s.params["normal"] + 0.0).tolist(), round(s.rms, 12)
    ([0.0, 0.0, -1.0], 0.0)
    """
    P, N, wn = _check_inputs(P, N, w, False)
    if len(P) < _MIN_POINTS["plane"]:
        return None
    m = wn @ P
    n = _pca_normal(P - m, wn)
    if N is not None:
        n = n if wn @ (N @ n) >= 0 else -n
    else:
        n = n if n[int(np.argmax(np.abs(n)))] > 0 else -n
    return _finish("plane", {"point": m, "normal": n}, P, N, wn, _area(w))


def _algebraic_sphere(X, wn):
    """Centre and radius of the algebraic (Kasa) sphere or circle ``|x|^2 = 2 c.x + k`` (any
    dimension); None if the points are (nearly) on a hyperplane."""
    sw = np.sqrt(wn)[:, None]
    A = np.c_[2.0 * X, np.ones(len(X))] * sw
    b = np.einsum("ij,ij->i", X, X) * sw[:, 0]
    sol, _, rank, sv = np.linalg.lstsq(A, b, rcond=None)
    if rank < A.shape[1] or sv[-1] <= SEED_RCOND * sv[0]:
        return None, math.nan
    c = sol[:-1]
    return c, math.sqrt(max(sol[-1] + c @ c, 0.0))


def fit_sphere(P, N=None, w=None, *, give_up_rms: float | None = None) -> Surface | None:
    """Geometric least-squares sphere.

    Seeded by the point nearest to all normal lines (or an algebraic fit without normals), then
    Levenberg-Marquardt on the true distances in the curvature form of Lukacs et al. (a point
    ``q = rho n`` near the centroid, its normal ``n`` and the signed curvature ``kappa``), which
    stays regular as the sphere flattens into a plane.

    Parameters
    ----------
    P : (p, 3) array_like of float64
        Points.
    N : (p, 3) array_like, optional
        Unit normals (seed and ``outward``).
    w : (p,) array_like, optional
        Non-negative weights.
    give_up_rms : float, optional
        Stop iterating once the rms (model units) stays above this and improves by less than
        LM_GIVE_UP_GAIN per iteration (:func:`fit_surface` passes GIVE_UP_FACTOR * tol); the
        result is then a partly refined fit.

    Returns
    -------
    Surface or None
        ``sphere`` (``center``, ``radius``) with weighted ``rms``, ``max_dev``, ``area`` = sum of
        ``w``, ``outward`` True when the normals point away from the centre. ``None`` for fewer
        than 4 points or when the radius exceeds FAR_RATIO data spreads (a plane).

    Examples
    --------
    >>> import numpy as np
    >>> rng = np.random.default_rng(0)
    >>> U = rng.normal(size=(50, 3)); U /= np.linalg.norm(U, axis=1)[:, None]
    >>> s = fit_sphere(2.0 * U + [1, 2, 3], U)
    >>> np.round(s.params["center"], 9), round(s.params["radius"], 9), s.outward
    (array([1., 2., 3.]), 2.0, True)
    """
    P, N, wn = _check_inputs(P, N, w, False)
    if len(P) < _MIN_POINTS["sphere"]:
        return None
    m, sc = _normalise(P, wn)
    X = (P - m) / sc
    give_up = math.inf if give_up_rms is None else (give_up_rms / sc) ** 2
    Xs, Ns, ws = _seed_sample(X, N, wn)
    c = _nearest_to_lines(Xs, Ns, ws) if N is not None else None
    r = math.nan
    if c is None:
        c, r = _algebraic_sphere(Xs, ws)
    if c is not None and not math.isfinite(r):
        r = float(ws @ _rownorm(Xs - c))
    n0, rho0, k0 = _curvature_seed(c, r, _pca_normal(Xs, ws))
    sol = _run_lm(_sphere_res(n0), X, wn, [0.0, 0.0, rho0, k0], give_up)
    if sol is None or abs(sol[0][3]) * FAR_RATIO <= 1.0:
        return None
    t = sol[0]
    n = _chart(n0, *_frame(n0), t[0], t[1])
    center = m + sc * (t[2] * n - n / t[3])
    params = {"center": center, "radius": float(sc / abs(t[3]))}
    return _finish("sphere", params, P, N, wn, _area(w))


def _sphere_res(n0):
    """Residual factory of the sphere in curvature form, parameters ``[s, t, rho, kappa]``:
    normal ``n = chart(n0; s, t)``, surface point ``rho n``, signed curvature ``kappa``."""
    u0, v0 = _frame(n0)

    def make_res(Xa, sw):
        def res(t, jac=False):
            n, dn = _chart_d(n0, u0, v0, t[0], t[1])
            x = Xa - t[2] * n
            if not jac:
                return sw * _curv_dist(x, n, t[3])
            D, Gx, Gn, Gk = _curv_dist_d(x, n, t[3])
            Gt = Gn - t[2] * Gx  # total derivative in n (x moves with n)
            J = np.stack([Gt @ dn[0], Gt @ dn[1], -(Gx @ n), Gk], axis=1)
            return sw * D, J * sw[:, None]
        return res

    return make_res


def _cross_section_seed(X, N, wn, a):
    """Axis foot ``c`` (3,) in the plane through 0 normal to ``a`` where the projected normal
    lines meet, or None."""
    u, v = _frame(a)
    B = np.c_[u, v]
    N2 = N @ B
    ln = np.linalg.norm(N2, axis=1)
    ok = ln > 1e-6
    if ok.sum() < 2:
        return None
    c2 = _nearest_to_lines((X @ B)[ok], N2[ok] / ln[ok, None], wn[ok])
    return None if c2 is None else B @ c2


def fit_cylinder(P, N, w=None, *, give_up_rms: float | None = None) -> Surface | None:
    """Geometric least-squares cylinder.

    Seed: the axis is the least eigenvector of the normals' weighted scatter (a cylinder's
    normals lie on a great circle), the axis point is where the normal lines meet in the cross
    section. Then Levenberg-Marquardt on the true distances, the cross-section circle in
    curvature form (regular as the radius grows without bound).

    Parameters
    ----------
    P : (p, 3) array_like of float64
        Points.
    N : (p, 3) array_like
        Unit normals at the points (required: they seed the axis).
    w : (p,) array_like, optional
        Non-negative weights.
    give_up_rms : float, optional
        Stop iterating once the rms (model units) stays above this and improves by less than
        LM_GIVE_UP_GAIN per iteration (:func:`fit_surface` passes GIVE_UP_FACTOR * tol); the
        result is then a partly refined fit.

    Returns
    -------
    Surface or None
        ``cylinder`` (``point`` = foot of the weighted centroid on the axis, unit ``axis``,
        ``radius``) with weighted ``rms``, ``max_dev``, ``area``, ``outward``. ``None`` for fewer
        than 5 points or a radius beyond FAR_RATIO data spreads (a plane).

    Examples
    --------
    >>> import numpy as np
    >>> t, z = np.meshgrid(np.linspace(0, 1, 10), np.linspace(0, 2, 5))
    >>> U = np.c_[np.cos(t.ravel()), np.sin(t.ravel()), 0 * t.ravel()]
    >>> s = fit_cylinder(3 * U + np.c_[0 * z.ravel(), 0 * z.ravel(), z.ravel()], -U)
    >>> round(s.params["radius"], 9), np.round(np.abs(s.params["axis"]), 9), s.outward
    (3.0, array([0., 0., 1.]), False)
    """
    P, N, wn = _check_inputs(P, N, w, True)
    if len(P) < _MIN_POINTS["cylinder"]:
        return None
    m, sc = _normalise(P, wn)
    X = (P - m) / sc
    give_up = math.inf if give_up_rms is None else (give_up_rms / sc) ** 2
    Xs, Ns, ws = _seed_sample(X, N, wn)
    a0 = _least_eig((Ns * ws[:, None]).T @ Ns)[1]
    c = _cross_section_seed(Xs, Ns, ws, a0)
    r = math.nan if c is None else float(ws @ _rownorm(_perp(Xs - c, a0)))
    u0, v0 = _frame(a0)
    pn = _perp(_pca_normal(Xs, ws)[None], a0)[0]  # along a0 for a closed cylinder
    fallback = pn / np.linalg.norm(pn) if np.linalg.norm(pn) > 1e-6 else u0
    n0, rho0, k0 = _curvature_seed(c, r, fallback)
    make_res, geometry = _cylinder_res(a0, _unit(n0 - (n0 @ a0) * a0))
    sol = _run_lm(make_res, X, wn, [0.0, 0.0, 0.0, rho0, k0], give_up)
    if sol is None or abs(sol[0][4]) * FAR_RATIO <= 1.0:
        return None
    t = sol[0]
    a, _, _, n, _ = geometry(t)
    foot = _perp((t[3] - 1.0 / t[4]) * n[None], a)[0]
    params = {"point": m + sc * foot, "axis": a, "radius": float(sc / abs(t[4]))}
    return _finish("cylinder", params, P, N, wn, _area(w))


def _cylinder_res(a0, n0):
    """Residual factory of the cylinder in curvature form (and its geometry), parameters
    ``[s, t, phi, rho, kappa]``: axis ``a = chart(a0; s, t)``, cross-section normal ``n`` (``n0``
    turned by ``phi`` about ``a0``, made normal to ``a``), point ``rho n``, curvature ``kappa``."""
    u0, v0 = _frame(a0)
    b0 = _orth(a0, n0)

    def geometry(t):
        a, da = _chart_d(a0, u0, v0, t[0], t[1])
        mv = math.cos(t[2]) * n0 + math.sin(t[2]) * b0
        mm = mv - (mv @ a) * a
        L = max(math.sqrt(mm @ mm), 1e-300)  # 0 only if the axis turned onto n: rejected
        return a, da, mv, mm / L, L

    def make_res(Xa, sw):
        def res(t, jac=False):
            a, da, mv, n, L = geometry(t)
            Xa_a = Xa @ a
            xp = Xa - t[3] * n - np.outer(Xa_a, a)  # n is normal to a
            if not jac:
                return sw * _curv_dist(xp, n, t[4])
            D, Gx, Gn, Gk = _curv_dist_d(xp, n, t[4])
            Pn = np.eye(3) - np.outer(n, n)
            dmv = -math.sin(t[2]) * n0 + math.cos(t[2]) * b0
            dns = [Pn @ (-(mv @ d) * a - (mv @ a) * d) / L for d in da]
            dns.append(Pn @ (dmv - (dmv @ a) * a) / L)
            Ga = Gx @ a
            cols = [Gn @ dn - t[3] * (Gx @ dn) for dn in dns]
            for j in (0, 1):  # xp also moves with a directly
                cols[j] = cols[j] - (Xa @ da[j]) * Ga - Xa_a * (Gx @ da[j])
            J = np.stack(cols + [-(Gx @ n), Gk], axis=1)
            return sw * D, J * sw[:, None]
        return res

    return make_res, geometry


def _perp(X, a):
    """Components of the rows of ``X`` normal to the unit vector ``a``."""
    return X - np.outer(X @ a, a)


def _cone_seed(X, N, wn, a0):
    """Cone seed ``[0, 0, c1, c2, r0, psi]`` for the axis ``a0`` (None if the normals do not
    meet in the cross section): the axis foot from the normal lines, then the weighted line
    ``r = r0 + h tan(psi)`` through the (height, radius) pairs."""
    c = _cross_section_seed(X, N, wn, a0)
    if c is None:
        return None
    h = X @ a0
    r = np.linalg.norm(_perp(X - c, a0), axis=1)
    hm, rm = wn @ h, wn @ r
    vh = wn @ (h - hm) ** 2
    slope = (wn @ ((h - hm) * (r - rm))) / vh if vh > SEED_RCOND else 0.0
    u0, v0 = _frame(a0)
    return np.array([0.0, 0.0, c @ u0, c @ v0, rm - slope * hm, math.atan(slope)])


def fit_cone(P, N, w=None, *, give_up_rms: float | None = None) -> Surface | None:
    """Geometric least-squares cone (one nappe).

    Seeds: the axis is the normal of the plane fitted to the normal vectors (a cone's normals
    lie on a small circle), and, for short arcs where that plane is ill-defined, the least
    eigenvector of the normals' scatter (the cylinder seed); the one that fits better as
    seeded is refined. The iterations minimise ``(r - r0) cos(psi) - h sin(psi)`` (distance to the
    generatrix in the axis half-plane), regular at ``psi = 0`` (a cylinder).

    Parameters
    ----------
    P : (p, 3) array_like of float64
        Points.
    N : (p, 3) array_like
        Unit normals (required).
    w : (p,) array_like, optional
        Non-negative weights.
    give_up_rms : float, optional
        Stop iterating once the rms (model units) stays above this and improves by less than
        LM_GIVE_UP_GAIN per iteration (:func:`fit_surface` passes GIVE_UP_FACTOR * tol); the
        result is then a partly refined fit.

    Returns
    -------
    Surface or None
        ``cone`` (``apex``, unit ``axis`` from the apex into the opening, ``half_angle`` in
        (0, pi/2)) with weighted ``rms``, ``max_dev``, ``area``, ``outward``. ``None`` for fewer
        than 6 points, when the apex is beyond FAR_RATIO data spreads (a cylinder) or the
        half-angle is within 1e-6 of pi/2 (a plane).

    Examples
    --------
    >>> import numpy as np
    >>> t, h = np.meshgrid(np.linspace(0, 6, 24), np.linspace(1, 2, 5))
    >>> t, h = t.ravel(), h.ravel()
    >>> P = np.c_[0.5 * h * np.cos(t), 0.5 * h * np.sin(t), h]       # apex 0, tan = 0.5
    >>> N = np.c_[np.cos(t), np.sin(t), -0.5 * np.ones_like(t)] / np.sqrt(1.25)
    >>> s = fit_cone(P, N)
    >>> np.round(s.params["apex"], 9) + 0.0, round(math.tan(s.params["half_angle"]), 9)
    (array([0., 0., 0.]), 0.5)
    """
    P, N, wn = _check_inputs(P, N, w, True)
    if len(P) < _MIN_POINTS["cone"]:
        return None
    m, sc = _normalise(P, wn)
    X = (P - m) / sc
    give_up = math.inf if give_up_rms is None else (give_up_rms / sc) ** 2
    Xs, Ns, ws = _seed_sample(X, N, wn)
    Nc = Ns - ws @ Ns
    axes = (_least_eig((Nc * ws[:, None]).T @ Nc)[1], _least_eig((Ns * ws[:, None]).T @ Ns)[1])
    seeds = []
    for a0 in axes:  # refine only the seed that fits better to begin with
        x0 = _cone_seed(Xs, Ns, ws, a0)
        if x0 is not None:
            r = _cone_res(a0)(Xs, np.sqrt(ws))(x0)
            seeds.append((float(r @ r), a0, x0))
    if not seeds:
        return None
    _, a0, x0 = min(seeds, key=lambda e: e[0])
    sol = _run_lm(_cone_res(a0), X, wn, x0, give_up)
    if sol is None:
        return None
    t = sol[0]
    u0, v0 = _frame(a0)
    a, c = _chart(a0, u0, v0, t[0], t[1]), t[2] * u0 + t[3] * v0
    psi, r0 = t[5], t[4]
    if abs(math.tan(psi)) * FAR_RATIO <= abs(r0) or math.cos(psi) < 1e-6:
        return None
    if psi < 0:
        a, psi = -a, -psi
    apex = c - (r0 / math.tan(psi)) * a
    params = {"apex": m + sc * apex, "axis": a, "half_angle": float(psi)}
    return _finish("cone", params, P, N, wn, _area(w))


def _cone_res(a0):
    u0, v0 = _frame(a0)

    def make_res(Xa, sw):
        def res(t, jac=False):
            a, da = _chart_d(a0, u0, v0, t[0], t[1])
            x = Xa - (t[2] * u0 + t[3] * v0)
            h = x @ a
            Rv = x - np.outer(h, a)
            r = _rownorm(Rv)
            cp, sp = math.cos(t[5]), math.sin(t[5])
            d = (r - t[4]) * cp - h * sp
            if not jac:
                return sw * d
            U = Rv / np.maximum(r, 1e-300)[:, None]
            gx = cp * U - sp * a  # d(d)/dx
            ga = -cp * h[:, None] * U - sp * x  # d(d)/da (dr/da = -h U)
            J = np.stack([ga @ da[0], ga @ da[1], -(gx @ u0), -(gx @ v0),
                          np.full(len(d), -cp), -(r - t[4]) * sp - h * cp], axis=1)
            return sw * d, J * sw[:, None]
        return res

    return make_res


def _revolution_axis(X, N, wn):
    """Unit axis and a point on it of the line meeting all normal lines (least squares in
    Pluecker coordinates: ``a . (x_i x n_i) + n_i . m = 0``, ``|a| = 1``)."""
    G = np.c_[np.cross(X, N), N]
    M = (G * wn[:, None]).T @ G
    A, B, C = M[:3, :3], M[:3, 3:], M[3:, 3:]
    Cp = np.linalg.pinv(C, rcond=SEED_RCOND, hermitian=True)
    a = _least_eig(A - B @ Cp @ B.T)[1]
    mom = -Cp @ B.T @ a
    return a, np.cross(a, mom)


def fit_torus(P, N, w=None, *, give_up_rms: float | None = None) -> Surface | None:
    """Geometric least-squares torus.

    Seeds: the axis is the line meeting all normal lines (each normal line of a surface of
    revolution meets its axis), the tube circle is where the normal lines meet in the
    (radius, height) half-plane; or the tube centres ``p - r n`` for the minor radius ``r``
    that makes them coplanar (robust to noisy normals on fillets). The better seed is refined
    by Levenberg-Marquardt on ``hypot(r - major, h) - minor``, the torus parameterised about
    its spine point nearest the data (turning the axis turns it about the data).

    Parameters
    ----------
    P : (p, 3) array_like of float64
        Points.
    N : (p, 3) array_like
        Unit normals (required).
    w : (p,) array_like, optional
        Non-negative weights.
    give_up_rms : float, optional
        Stop iterating once the rms (model units) stays above this and improves by less than
        LM_GIVE_UP_GAIN per iteration (:func:`fit_surface` passes GIVE_UP_FACTOR * tol); the
        result is then a partly refined fit.

    Returns
    -------
    Surface or None
        ``torus`` (``center``, unit ``axis``, ``major_radius``, ``minor_radius``) with weighted
        ``rms``, ``max_dev``, ``area``, ``outward``. ``None`` for fewer than 7 points, a major
        radius beyond FAR_RATIO data spreads (a cylinder) or below TORUS_MIN_MAJOR of the
        minor one (a sphere).

    Examples
    --------
    >>> import numpy as np
    >>> u, v = np.meshgrid(np.linspace(0, 6, 30), np.linspace(0, 6, 12))
    >>> u, v = u.ravel(), v.ravel()
    >>> Nt = np.c_[np.cos(v) * np.cos(u), np.cos(v) * np.sin(u), np.sin(v)]
    >>> C = np.c_[3 * np.cos(u), 3 * np.sin(u), 0 * u]
    >>> s = fit_torus(C + Nt, Nt)
    >>> round(s.params["major_radius"], 9), round(s.params["minor_radius"], 9), s.outward
    (3.0, 1.0, True)
    """
    P, N, wn = _check_inputs(P, N, w, True)
    if len(P) < _MIN_POINTS["torus"]:
        return None
    m, sc = _normalise(P, wn)
    X = (P - m) / sc
    give_up = math.inf if give_up_rms is None else (give_up_rms / sc) ** 2
    Xs, Ns, ws = _seed_sample(X, N, wn)
    seeds = [_torus_seed(Xs, Ns, ws, *_revolution_axis(Xs, Ns, ws)), _spine_seed(Xs, Ns, ws)]
    costs = []
    for a0, x0 in (e for e in seeds if e is not None and e[1][5] > 0):
        u0, v0 = _frame(a0)  # seeds give the centre as c1 u0 + c2 v0 + h0 a0, then R, r
        make_res, geometry = _torus_res(a0, x0[2] * u0 + x0[3] * v0 + x0[4] * a0, x0[5])
        x0 = np.r_[np.zeros(5), x0[5:]]
        r = make_res(Xs, np.sqrt(ws))(x0)
        costs.append((float(r @ r), make_res, geometry, x0))
    if not costs:
        return None
    _, make_res, geometry, x0 = min(costs, key=lambda e: e[0])  # refine the better seed only
    sol = _run_lm(make_res, X, wn, x0, give_up)
    if sol is None:
        return None
    t = sol[0]
    a, _, _, _, _, center = geometry(t)
    R, r = float(t[5]), abs(float(t[6]))
    if not (TORUS_MIN_MAJOR * r < R < FAR_RATIO) or r == 0:
        return None
    params = {"center": m + sc * center, "axis": a, "major_radius": sc * R,
              "minor_radius": sc * r}
    return _finish("torus", params, P, N, wn, _area(w))


def _torus_seed(X, N, wn, a0, q):
    """Torus seed ``(a0, [0, 0, c1, c2, h0, R, r])`` from the axis ``(a0, q)``, or None."""
    u0, v0 = _frame(a0)
    c = q - (q @ a0) * a0
    x = X - c
    h = x @ a0
    Rv = x - np.outer(h, a0)
    rho = np.linalg.norm(Rv, axis=1)
    U = Rv / np.maximum(rho, 1e-300)[:, None]
    D = np.c_[np.einsum("ij,ij->i", N, U), N @ a0]
    ln = np.linalg.norm(D, axis=1)
    ok = ln > 1e-6
    if ok.sum() < 2:
        return None
    Y = np.c_[rho, h]
    tube = _nearest_to_lines(Y[ok], D[ok] / ln[ok, None], wn[ok])
    if tube is None:
        return None
    r = float(wn @ np.linalg.norm(Y - tube, axis=1))
    return a0, np.array([0.0, 0.0, c @ u0, c @ v0, tube[1], tube[0], r])


def _spine_seed(X, N, wn):
    """Torus seed from the tube centres ``X - r N``: for the minor radius ``r`` they lie on a
    circle (the spine), so their scatter is flat; ``r`` minimises the ratio of its least to its
    largest eigenvalue (grid over |r| in [1e-2, 1e2] spreads, both signs, then a bounded 1-D
    search around an interior grid minimum; as |r| grows the scatter tends to that of the
    normals, flat for cylinders and cones). Insensitive to normal noise for thin tubes, where
    the Pluecker axis (lever arm: the major radius) is not. Returns ``(axis, seed)`` or None."""
    Xc, Nc = X - wn @ X, N - wn @ N
    Cxx, Cxn, Cnn = (Xc * wn[:, None]).T @ Xc, (Xc * wn[:, None]).T @ Nc, (Nc * wn[:, None]).T @ Nc

    def flatness(r):
        lam = np.linalg.eigvalsh(Cxx - r[..., None, None] * (Cxn + Cxn.T)
                                 + (r * r)[..., None, None] * Cnn)
        return lam[..., 0] / np.maximum(lam[..., 2], 1e-300)

    g = np.geomspace(1e-2, 1e2, 41)
    grid = np.r_[-g[::-1], g]
    f = flatness(grid)
    i = int(np.argmin(f[1:-1])) + 1  # the ends: normals on a circle (cylinder, cone), no tube
    if f[i] >= min(f[i - 1], f[i + 1]):
        return None
    lo, hi = grid[i - 1], grid[i + 1]
    r = float(minimize_scalar(lambda x: float(flatness(np.array(x))), bounds=(lo, hi),
                              method="bounded", options={"xatol": 1e-6}).x)
    Q = X - r * N
    lam, E = np.linalg.eigh(Cxx - r * (Cxn + Cxn.T) + r * r * Cnn)
    if lam[1] <= 1e-6 * lam[2]:  # centres on a line (a cylinder) or a point (a sphere)
        return None
    a = E[:, 0]
    u0, v0 = _frame(a)
    c2, R = _algebraic_sphere(Q @ np.c_[u0, v0], wn)
    if c2 is None or not R > 0:
        return None
    return a, np.array([0.0, 0.0, c2[0], c2[1], wn @ (Q @ a), R, abs(r)])


def _torus_res(a0, C0, R0):
    """Residual factory of the torus (and its geometry) about the spine point ``q`` nearest
    the data: parameters ``[s, t, q1, q2, phi, R, r]``, axis ``a = chart(a0; s, t)``, spine
    point ``q = q0 + q1 u0 + q2 a0``, radial direction ``u`` (``u0`` turned by ``phi`` about
    ``a0``, made normal to ``a``), centre ``q - R u``. Turning the axis turns the torus about
    the data, not about its far centre, so fillets on short arcs converge quadratically."""
    u0 = _perp(-C0[None], a0)[0]
    u0 = u0 / np.linalg.norm(u0) if np.linalg.norm(u0) > 1e-9 else _frame(a0)[0]
    t0 = _orth(a0, u0)
    q0 = C0 + R0 * u0
    e1, e2 = _frame(a0)

    def geometry(t):
        a, da = _chart_d(a0, e1, e2, t[0], t[1])
        mv = math.cos(t[4]) * u0 + math.sin(t[4]) * t0
        mm = mv - (mv @ a) * a
        L = max(math.sqrt(mm @ mm), 1e-300)  # 0 only if the axis turned onto u: rejected
        u = mm / L
        return a, da, mv, u, L, q0 + t[2] * u0 + t[3] * a0 - t[5] * u

    def make_res(Xa, sw):
        def res(t, jac=False):
            a, da, mv, u, L, C = geometry(t)
            x = Xa - C
            h = x @ a
            Rv = x - np.outer(h, a)
            rho = _rownorm(Rv)
            e = np.hypot(rho - t[5], h)
            if not jac:
                return sw * (e - t[6])
            es = np.maximum(e, 1e-300)
            g0, g1 = (rho - t[5]) / es, h / es  # unit direction in the half-plane
            U = Rv / np.maximum(rho, 1e-300)[:, None]
            gx = g0[:, None] * U + g1[:, None] * a  # d(d)/dx = -d(d)/dC
            ga = -(g0 * h)[:, None] * U + g1[:, None] * x  # d(d)/da at fixed x
            Pu = np.eye(3) - np.outer(u, u)
            dmv = -math.sin(t[4]) * u0 + math.cos(t[4]) * t0
            du = [Pu @ (-(mv @ d) * a - (mv @ a) * d) / L for d in da]
            du.append(Pu @ (dmv - (dmv @ a) * a) / L)
            J = np.stack([ga @ da[0] + t[5] * (gx @ du[0]), ga @ da[1] + t[5] * (gx @ du[1]),
                          -(gx @ u0), -(gx @ a0), t[5] * (gx @ du[2]), gx @ u - g0,
                          np.full(len(e), -1.0)], axis=1)
            return sw * (e - t[6]), J * sw[:, None]
        return res

    return make_res, geometry


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


def fit_surface(P, N, w=None, tol: float | None = None, kinds=SURFACE_KINDS) -> Surface:
    """The simplest adequate surface kind for one segment's samples.

    Kinds are tried simplest first (plane < cylinder < cone < sphere < torus). A candidate
    replaces the current choice only if it is *clearly* better (its RMS below the choice's by a
    factor BEAT_FACTOR and by BEAT_ABS * tol, or it is within the max-deviation bound that the
    choice breaks): the kinds are nested (a huge sphere is a plane, a thin cone a cylinder), so
    a more complex kind always fits a little better and must beat the noise to be chosen. The
    search stops at the first candidate within tolerance (``rms <= tol`` and
    ``max_dev <= MAX_DEV_FACTOR * tol``) and returns the current choice (that candidate, or a
    simpler kind it does not clearly beat, whose rms is then below BEAT_FACTOR * tol); when
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
    P, N, wn = _check_inputs(P, N, w, True)
    bad = [k for k in kinds if k not in SURFACE_KINDS]
    if bad:
        raise MeshError(f"kinds {tuple(kinds)} has unknown kinds {bad}; expected {SURFACE_KINDS}")
    m, spread = _normalise(P, wn)
    tol = DEFAULT_REL_TOL * spread if tol is None else float(tol)
    if not (math.isfinite(tol) and tol > 0):
        raise MeshError(f"tol must be a finite positive float, got {tol!r}")
    chosen = best = None
    for kind in (k for k in SURFACE_KINDS[:-1] if k in kinds):
        kw = {} if kind == "plane" else {"give_up_rms": GIVE_UP_FACTOR * tol}
        s = _FITTERS[kind](P, N, wn, **kw)
        if s is None or _normal_agreement(s, P, N, wn) < NORMAL_AGREEMENT:
            continue
        best = s if best is None or s.rms < best.rms else best
        if chosen is None or _clearly_better(s, chosen, tol):
            chosen = s
        if _ok(s, tol):
            log.debug("fit_surface: %s (rms %.3g, tol %.3g; %s within)", chosen.kind,
                      chosen.rms, tol, kind)
            return _with_area(chosen, w)
    rms, dev = (best.rms, best.max_dev) if best is not None else (math.nan, math.nan)
    return Surface("freeform", {"centroid": m}, rms=rms, max_dev=dev, area=_area(w))


def _normal_agreement(s: Surface, P, N, wn) -> float:
    """Weighted mean ``|N . n|`` of the data normals and the surface's normals (on the strided
    subsample): 1 when they agree, whatever the orientation."""
    idx = _subsample(len(P))
    return float(wn[idx] @ np.abs(np.einsum("ij,ij->i", N[idx], s.normals(P[idx])))
                 / max(wn[idx].sum(), 1e-300))


def _with_area(s: Surface, w) -> Surface:
    return Surface(s.kind, s.params, rms=s.rms, max_dev=s.max_dev, area=_area(w),
                   outward=s.outward)


# ----------------------------------------------------------------------------- mesh helpers


def _check_faces(faces, m: int) -> np.ndarray:
    faces = np.asarray(faces)
    if faces.dtype == bool:
        if faces.shape != (m,):
            raise MeshError(f"faces as a mask must have shape ({m},), got {faces.shape}")
        return np.flatnonzero(faces)
    if faces.ndim != 1 or not np.issubdtype(faces.dtype, np.integer):
        raise MeshError(f"faces must be a 1-D integer array, got {faces.dtype} {faces.shape}")
    if len(faces) and (faces.min() < 0 or faces.max() >= m):
        raise MeshError(f"faces (shape {faces.shape}) must index [0, {m})")
    return faces.astype(np.int64)


def face_samples(V, F, faces):
    """Samples to fit one segment: its vertices and its face centroids, with normals and weights.

    Vertex normals are computed from the segment's faces only (a crease with the neighbouring
    segment does not bend them). Weights sum to the segment's area: half on the face centroids
    (each face's area / 2), half on the vertices (a third of the incident faces' areas / 2).

    Parameters
    ----------
    V : (n, 3) array_like of float64
        Vertices.
    F : (m, 3) array_like of int
        Triangles.
    faces : (k,) array_like of int, or (m,) bool
        The segment's faces.

    Returns
    -------
    P : (q + k, 3) float64
        The q distinct vertices of the faces, then the k face centroids.
    N : (q + k, 3) float64
        Unit normals (area-weighted vertex normals, face normals); zero rows with zero weight
        where undefined (degenerate faces).
    w : (q + k,) float64
        Non-negative weights.

    Examples
    --------
    >>> import numpy as np
    >>> V = np.array([[0., 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]])
    >>> P, N, w = face_samples(V, np.array([[0, 1, 2], [1, 3, 2]]), [0, 1])
    >>> P.shape, (N[-1] + 0.0).tolist(), float(w.sum())
    ((6, 3), [0.0, 0.0, 1.0], 1.0)
    """
    V, F = _check_mesh(V, F)
    Fs = F[_check_faces(faces, len(F))]
    if len(Fs) == 0:
        return np.zeros((0, 3)), np.zeros((0, 3)), np.zeros(0)
    verts, inv = np.unique(Fs, return_inverse=True)  # the segment as a small mesh
    Vl, Fl = V[verts], inv.reshape(-1, 3).astype(np.int64)
    dbl = igl.doublearea(Vl, Fl)
    FN = igl.per_face_normals(Vl, Fl, np.zeros(3))
    VN = igl.per_vertex_normals(Vl, Fl, igl.PER_VERTEX_NORMALS_WEIGHTING_TYPE_AREA)
    wv = np.bincount(Fl.ravel(), weights=np.repeat(dbl / 12.0, 3), minlength=len(verts))
    P = np.r_[Vl, Vl[Fl].mean(axis=1)]
    N = np.r_[VN, FN]
    w = np.r_[wv, dbl / 4.0]
    bad = ~np.all(np.isfinite(N), axis=1) | (np.abs(np.linalg.norm(N, axis=1) - 1) > 1e-6)
    N[bad], w[bad] = 0.0, 0.0
    return P, N, w


def face_residuals(V, F, faces, surface: Surface) -> np.ndarray:
    """Largest absolute distance of each face's corners and centroid to a surface.

    Parameters
    ----------
    V : (n, 3) array_like of float64
        Vertices.
    F : (m, 3) array_like of int
        Triangles.
    faces : (k,) array_like of int, or (m,) bool
        Faces to evaluate.
    surface : Surface
        The segment's surface.

    Returns
    -------
    r : (k,) float64
        Per-face residual in model units (``nan`` for ``freeform``). Compare with
        ``MAX_DEV_FACTOR * tol``; the centroid sees the chord error of coarse facets.

    Examples
    --------
    >>> import numpy as np
    >>> V = np.array([[0., 0, 0], [1, 0, 0], [0, 1, 0.3]])
    >>> s = Surface("plane", {"point": np.zeros(3), "normal": np.array([0., 0, 1])})
    >>> face_residuals(V, np.array([[0, 1, 2]]), [0], s)
    array([0.3])
    """
    V, F = _check_mesh(V, F)
    Fs = F[_check_faces(faces, len(F))]
    corners = V[Fs]  # (k, 3, 3)
    pts = np.concatenate([corners, corners.mean(axis=1, keepdims=True)], axis=1)
    d = surface.distance(pts.reshape(-1, 3)).reshape(len(Fs), 4)
    return np.max(np.abs(d), axis=1)


def noise_level(V, F) -> float:
    """Noise of the mesh's vertex positions (model units), near 0 on a clean tessellation.

    Each vertex with at least QUAD_MIN_POINTS - 1 neighbours gets a height-field quadric
    ``z = a x^2 + b xy + c y^2 + d x + e y + f`` fitted to itself and its 1-ring in their
    principal-axes frame; its residual variance ``RSS / dof`` (dof = ring size - 6) is divided
    by the median of ``chi2(dof) / dof`` and the noise is the square root of the median over the
    vertices (robust to creases and corners, which are a minority). The 1-ring is small enough
    that a quadric reproduces a coarsely tessellated cylinder or sphere (its vertices lie on
    the surface; the facets' chord error is not noise), yet has residual freedom everywhere but
    at low-valence vertices, which are skipped. Where the curvature varies (tori, freeform) a
    clean tessellation still leaves an O(h^3) cubic misfit: about 1 % of the edge length on a
    torus gridded at 15 degrees (0.4 of its chord error), 6 % at 36 degrees.

    Parameters
    ----------
    V : (n, 3) array_like of float64
        Vertices.
    F : (m, 3) array_like of int
        Triangles.

    Returns
    -------
    float
        Estimated standard deviation of the vertices' normal displacement (0 when no vertex has
        a large enough ring).

    Examples
    --------
    >>> import numpy as np
    >>> x, y = np.meshgrid(np.arange(8.0), np.arange(8.0))
    >>> V = np.c_[x.ravel(), y.ravel(), 0.1 * x.ravel() ** 2]     # a clean parabolic cylinder
    >>> i = np.arange(64).reshape(8, 8)[:-1, :-1].ravel()
    >>> F = np.r_[np.c_[i, i + 1, i + 9], np.c_[i, i + 9, i + 8]]
    >>> noise_level(V, F) < 1e-9
    True
    """
    V, F = _check_mesh(V, F)
    A = igl.adjacency_matrix(F).tocsr()
    val = np.diff(A.indptr)
    h = igl.avg_edge_length(V, F)
    if not h > 0:
        return 0.0
    ratios = [_ring_quadric_ratios(V, A, val, n, h) for n in np.unique(val)
              if n + 1 >= QUAD_MIN_POINTS]
    ratios = np.concatenate(ratios) if ratios else np.zeros(0)
    return float(h * math.sqrt(np.median(ratios))) if len(ratios) else 0.0


def _ring_quadric_ratios(V, A, val, n, h):
    """``RSS / dof / median(chi2(dof) / dof)`` of the 1-ring quadric of every vertex of
    valence ``n`` (lengths in units of ``h``)."""
    vs = np.flatnonzero(val == n)
    nb = A.indices[A.indptr[vs][:, None] + np.arange(n)]
    X = np.concatenate([V[vs][:, None], V[nb]], axis=1) / h  # (g, n + 1, 3)
    X -= X.mean(axis=1, keepdims=True)
    _, E = np.linalg.eigh(np.einsum("gki,gkj->gij", X, X))
    L = np.einsum("gki,gij->gkj", X, E)  # columns: normal, minor, major tangent
    z, x, y = L[..., 0], L[..., 2], L[..., 1]
    B = np.stack([x * x, x * y, y * y, x, y, np.ones_like(x)], axis=-1)  # (g, n + 1, 6)
    BtB = np.einsum("gki,gkj->gij", B, B) + 1e-10 * np.eye(6)
    coef = np.linalg.solve(BtB, np.einsum("gki,gk->gi", B, z)[..., None])[..., 0]
    rss = np.sum((z - np.einsum("gki,gi->gk", B, coef)) ** 2, axis=1)
    dof = n + 1 - 6
    return rss / dof / (chi2.median(dof) / dof)


def _segment_chord_error(V, F, faces) -> float:
    """Chord error of one segment, known to be one surface (no crease cut): each edge, a chord
    of length ``c`` between vertices whose normals (from the segment's faces only) differ by
    ``theta``, has sagitta ``c / 2 tan(theta / 4)``; the CHORD_QUANTILE quantile of the edges
    with ``theta >= FLAT_ANGLE`` (so a few mislabelled faces across a crease do not count)."""
    verts, inv = np.unique(F[faces], return_inverse=True)
    Vl, Fl = V[verts], inv.reshape(-1, 3).astype(np.int64)
    VN = igl.per_vertex_normals(Vl, Fl, igl.PER_VERTEX_NORMALS_WEIGHTING_TYPE_AREA)
    E = igl.edges(Fl)
    theta = np.arccos(np.clip(np.einsum("ij,ij->i", VN[E[:, 0]], VN[E[:, 1]]), -1.0, 1.0))
    keep = theta >= FLAT_ANGLE  # also drops nan normals of degenerate faces
    if not np.any(keep):
        return 0.0
    c = _rownorm(Vl[E[keep, 0]] - Vl[E[keep, 1]])
    return float(np.quantile(0.5 * c * np.tan(theta[keep] / 4.0), CHORD_QUANTILE))


def _chord_error(V, F) -> float:
    """Chord (sagitta) error of the tessellation's curved facets: for each interior edge whose
    dihedral angle ``theta`` lies in [FLAT_ANGLE, CREASE_ANGLE], a circular arc through the two
    faces with their mean height ``c`` across the edge as chords has sagitta
    ``c / 2 tan(theta / 4)``; the CHORD_QUANTILE quantile of those."""
    TT = igl.triangle_triangle_adjacency(F)[0]
    f, e = np.nonzero(TT > np.arange(len(F))[:, None])  # each interior edge once
    g = TT[f, e]
    FN = igl.per_face_normals(V, F, np.zeros(3))
    theta = np.arccos(np.clip(np.einsum("ij,ij->i", FN[f], FN[g]), -1.0, 1.0))
    keep = (theta >= FLAT_ANGLE) & (theta <= CREASE_ANGLE)
    if not np.any(keep):
        return 0.0
    f, e, g, theta = f[keep], e[keep], g[keep], theta[keep]
    length = np.linalg.norm(V[F[f, (e + 1) % 3]] - V[F[f, e]], axis=1)
    dbl = igl.doublearea(V, F)
    c = 0.5 * (dbl[f] + dbl[g]) / np.maximum(length, 1e-300)
    return float(np.quantile(0.5 * c * np.tan(theta / 4.0), CHORD_QUANTILE))


def fit_tolerance(V, F, noise: float | None = None, faces=None) -> float:
    """Fit tolerance of a mesh, from its own noise, tessellation and size.

    ``tol = sqrt((K_NOISE * noise)^2 + (K_CHORD * chord)^2) + K_FLOOR * mean_edge``

    * ``noise`` (:func:`noise_level`) — a fit's residual on noisy samples is about the noise;
    * ``chord`` — the sagitta of the curved facets: a cylinder of radius r tessellated with
      facets of width c has its vertices on it but its face centroids up to
      ``r (1 - cos(c / 2r))`` inside, which a fit must accept (see :func:`_chord_error`);
    * ``K_FLOOR * mean_edge`` — keeps a perfect mesh's tolerance above round-off.

    Every term is a length of the mesh, so the tolerance scales with the mesh (scaled by 1000,
    the tolerance is 1000 times larger) and no constant is in model units.

    Parameters
    ----------
    V : (n, 3) array_like of float64
        Vertices.
    F : (m, 3) array_like of int
        Triangles.
    noise : float, optional
        Noise level if known (model units); estimated by :func:`noise_level` otherwise (over
        the whole mesh: pass it once computed when calling per segment).
    faces : (k,) array_like of int, or (m,) bool, optional
        One segment's faces: its own chord error instead of the whole mesh's (a coarse small
        hole next to a finely tessellated large fillet), from the turn of its vertex normals
        along each edge, without a crease cut (facets of a thin fillet may turn by 90 degrees).

    Returns
    -------
    float
        Tolerance (model units) for :func:`fit_surface` and :func:`within_tolerance`.

    Examples
    --------
    >>> import numpy as np
    >>> V = np.array([[0., 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]])
    >>> F = np.array([[0, 1, 2], [1, 3, 2]])
    >>> round(fit_tolerance(V, F, noise=0.01), 5)   # 2.5 * noise + 1e-3 * mean edge length
    0.02608
    """
    V, F = _check_mesh(V, F)
    if noise is None:
        noise = noise_level(V, F)
    elif not (math.isfinite(noise) and noise >= 0):
        raise MeshError(f"noise must be a finite float >= 0, got {noise!r}")
    if faces is None:
        chord = _chord_error(V, F)
    else:
        chord = _segment_chord_error(V, F, _check_faces(faces, len(F)))
    h = igl.avg_edge_length(V, F)
    return float(math.hypot(K_NOISE * noise, K_CHORD * chord) + K_FLOOR * h)
