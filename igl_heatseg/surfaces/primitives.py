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

import math

import numpy as np
from scipy.optimize import minimize_scalar

from .checks import check_inputs, weights_area
from .lm import (
    SEED_RCOND,
    least_eig,
    nearest_to_lines,
    normalise,
    rownorm,
    run_lm,
    seed_sample,
    subsample,
)
from .model import Surface

__all__ = ["fit_plane", "fit_sphere", "fit_cylinder", "fit_cone", "fit_torus",
           "fitted_surface"]

#: A radius (or apex distance) beyond this many data spreads (RMS distance of the points to their
#: centroid) is indistinguishable from the simpler kind: the sagitta over the data is below
#: 1e-4 spread, under any tolerance this module derives, so the fit returns ``None``.
FAR_RATIO = 1e4
#: A torus whose major radius is below this fraction of its minor radius is a sphere.
TORUS_MIN_MAJOR = 1e-3

_MIN_POINTS = {"plane": 3, "sphere": 4, "cylinder": 5, "cone": 6, "torus": 7}


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


def fitted_surface(kind, params, P, N, w, area) -> Surface | None:
    """The Surface of ``kind`` and ``params`` with its fit statistics over weighted samples.

    Parameters
    ----------
    kind : str
        An analytic kind.
    params : dict
        Its parameters (:mod:`igl_heatseg.surfaces.model`).
    P : (p, 3) float64
        Points.
    N : (p, 3) float64 or None
        Unit normals at the points (for ``outward``, a weighted vote on an evenly strided
        subsample); ``None``, or a plane: outward.
    w : (p,) float64
        Non-negative weights summing to 1.
    area : float
        The ``area`` to record.

    Returns
    -------
    Surface or None
        ``rms`` (weighted), ``max_dev`` (over the points of positive weight), ``outward``;
        None when either statistic is not finite.

    Examples
    --------
    >>> import numpy as np
    >>> P = np.array([[1.0, 0, 0], [0, 3, 0]]); N = np.array([[1.0, 0, 0], [0, 1, 0]])
    >>> s = fitted_surface("sphere", {"center": np.zeros(3), "radius": 2.0}, P, N,
    ...                    np.array([0.5, 0.5]), 1.0)
    >>> s.rms, s.max_dev, s.outward
    (1.0, 1.0, True)
    """
    s = Surface(kind, params)
    d = s.distance(P)
    rms = math.sqrt(float(w @ (d * d)))
    max_dev = float(np.max(np.abs(d[w > 0])))
    outward = True
    if N is not None and kind != "plane":
        idx = subsample(len(P))  # a vote: the subsample is enough
        outward = bool(w[idx] @ np.einsum("ij,ij->i", N[idx], s.normals(P[idx])) >= 0)
    if not (math.isfinite(rms) and math.isfinite(max_dev)):
        return None
    return Surface(kind, params, rms=rms, max_dev=max_dev, area=area, outward=outward)


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
    W = np.maximum(rownorm(wv), 1e-300)
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
    return num / (rownorm(kappa * x + n) + 1.0)


def _pca_normal(X, wn) -> np.ndarray:
    return least_eig((X * wn[:, None]).T @ X)[1]


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
    P, N, wn = check_inputs(P, N, w, False)
    if len(P) < _MIN_POINTS["plane"]:
        return None
    m = wn @ P
    n = _pca_normal(P - m, wn)
    if N is not None:
        n = n if wn @ (N @ n) >= 0 else -n
    else:
        n = n if n[int(np.argmax(np.abs(n)))] > 0 else -n
    return fitted_surface("plane", {"point": m, "normal": n}, P, N, wn, weights_area(w))


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
    P, N, wn = check_inputs(P, N, w, False)
    if len(P) < _MIN_POINTS["sphere"]:
        return None
    m, sc = normalise(P, wn)
    X = (P - m) / sc
    give_up = math.inf if give_up_rms is None else (give_up_rms / sc) ** 2
    Xs, Ns, ws = seed_sample(X, N, wn)
    c = nearest_to_lines(Xs, Ns, ws) if N is not None else None
    r = math.nan
    if c is None:
        c, r = _algebraic_sphere(Xs, ws)
    if c is not None and not math.isfinite(r):
        r = float(ws @ rownorm(Xs - c))
    n0, rho0, k0 = _curvature_seed(c, r, _pca_normal(Xs, ws))
    sol = run_lm(_sphere_res(n0), X, wn, [0.0, 0.0, rho0, k0], give_up)
    if sol is None or abs(sol[0][3]) * FAR_RATIO <= 1.0:
        return None
    t = sol[0]
    n = _chart(n0, *_frame(n0), t[0], t[1])
    center = m + sc * (t[2] * n - n / t[3])
    params = {"center": center, "radius": float(sc / abs(t[3]))}
    return fitted_surface("sphere", params, P, N, wn, weights_area(w))


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
    c2 = nearest_to_lines((X @ B)[ok], N2[ok] / ln[ok, None], wn[ok])
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
    P, N, wn = check_inputs(P, N, w, True)
    if len(P) < _MIN_POINTS["cylinder"]:
        return None
    m, sc = normalise(P, wn)
    X = (P - m) / sc
    give_up = math.inf if give_up_rms is None else (give_up_rms / sc) ** 2
    Xs, Ns, ws = seed_sample(X, N, wn)
    a0 = least_eig((Ns * ws[:, None]).T @ Ns)[1]
    c = _cross_section_seed(Xs, Ns, ws, a0)
    r = math.nan if c is None else float(ws @ rownorm(_perp(Xs - c, a0)))
    u0, v0 = _frame(a0)
    pn = _perp(_pca_normal(Xs, ws)[None], a0)[0]  # along a0 for a closed cylinder
    fallback = pn / np.linalg.norm(pn) if np.linalg.norm(pn) > 1e-6 else u0
    n0, rho0, k0 = _curvature_seed(c, r, fallback)
    make_res, geometry = _cylinder_res(a0, _unit(n0 - (n0 @ a0) * a0))
    sol = run_lm(make_res, X, wn, [0.0, 0.0, 0.0, rho0, k0], give_up)
    if sol is None or abs(sol[0][4]) * FAR_RATIO <= 1.0:
        return None
    t = sol[0]
    a, _, _, n, _ = geometry(t)
    foot = _perp((t[3] - 1.0 / t[4]) * n[None], a)[0]
    params = {"point": m + sc * foot, "axis": a, "radius": float(sc / abs(t[4]))}
    return fitted_surface("cylinder", params, P, N, wn, weights_area(w))


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
    P, N, wn = check_inputs(P, N, w, True)
    if len(P) < _MIN_POINTS["cone"]:
        return None
    m, sc = normalise(P, wn)
    X = (P - m) / sc
    give_up = math.inf if give_up_rms is None else (give_up_rms / sc) ** 2
    Xs, Ns, ws = seed_sample(X, N, wn)
    Nc = Ns - ws @ Ns
    axes = (least_eig((Nc * ws[:, None]).T @ Nc)[1], least_eig((Ns * ws[:, None]).T @ Ns)[1])
    seeds = []
    for a0 in axes:  # refine only the seed that fits better to begin with
        x0 = _cone_seed(Xs, Ns, ws, a0)
        if x0 is not None:
            r = _cone_res(a0)(Xs, np.sqrt(ws))(x0)
            seeds.append((float(r @ r), a0, x0))
    if not seeds:
        return None
    _, a0, x0 = min(seeds, key=lambda e: e[0])
    sol = run_lm(_cone_res(a0), X, wn, x0, give_up)
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
    return fitted_surface("cone", params, P, N, wn, weights_area(w))


def _cone_res(a0):
    u0, v0 = _frame(a0)

    def make_res(Xa, sw):
        def res(t, jac=False):
            a, da = _chart_d(a0, u0, v0, t[0], t[1])
            x = Xa - (t[2] * u0 + t[3] * v0)
            h = x @ a
            Rv = x - np.outer(h, a)
            r = rownorm(Rv)
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
    a = least_eig(A - B @ Cp @ B.T)[1]
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
    P, N, wn = check_inputs(P, N, w, True)
    if len(P) < _MIN_POINTS["torus"]:
        return None
    m, sc = normalise(P, wn)
    X = (P - m) / sc
    give_up = math.inf if give_up_rms is None else (give_up_rms / sc) ** 2
    Xs, Ns, ws = seed_sample(X, N, wn)
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
    sol = run_lm(make_res, X, wn, x0, give_up)
    if sol is None:
        return None
    t = sol[0]
    a, _, _, _, _, center = geometry(t)
    R, r = float(t[5]), abs(float(t[6]))
    if not (TORUS_MIN_MAJOR * r < R < FAR_RATIO) or r == 0:
        return None
    params = {"center": m + sc * center, "axis": a, "major_radius": sc * R,
              "minor_radius": sc * r}
    return fitted_surface("torus", params, P, N, wn, weights_area(w))


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
    tube = nearest_to_lines(Y[ok], D[ok] / ln[ok, None], wn[ok])
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
            rho = rownorm(Rv)
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
