"""Levenberg-Marquardt for the surface fits, and the numerical helpers they share.

The fits iterate on centred, unit-spread coordinates (:func:`normalise`) and on at most
LM_MAX_POINTS evenly strided samples (:func:`subsample`), then polish on all points
(:func:`run_lm`).
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["normalise", "rownorm", "seed_sample", "subsample", "least_eig", "nearest_to_lines",
           "run_lm"]

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


# ----------------------------------------------------------------------------- small helpers


def normalise(P, w):
    """Weighted centroid ``m`` and spread ``s`` (RMS distance to ``m``; 1 when all coincide).

    Parameters
    ----------
    P : (p, 3) ndarray of float64
        Points.
    w : (p,) ndarray of float64
        Non-negative weights summing to 1.

    Returns
    -------
    m : (3,) ndarray
        Weighted centroid.
    s : float
        Weighted RMS distance of the points to ``m``; 1.0 when it is 0 (so ``(P - m) / s`` is
        always defined).

    Examples
    --------
    >>> import numpy as np
    >>> m, s = normalise(np.array([[0., 0, 0], [2, 0, 0]]), np.array([0.5, 0.5]))
    >>> m.tolist(), s
    ([1.0, 0.0, 0.0], 1.0)
    """
    m = w @ P
    s = math.sqrt(max(float(w @ np.einsum("ij,ij->i", P - m, P - m)), 0.0))
    return m, (s if s > 0 else 1.0)


def rownorm(X: np.ndarray) -> np.ndarray:
    """Euclidean norms of the rows of a 2-D array.

    Parameters
    ----------
    X : (p, k) ndarray of float64
        Rows.

    Returns
    -------
    (p,) ndarray of float64
        ``|X[i]|``.

    Examples
    --------
    >>> import numpy as np
    >>> rownorm(np.array([[3., 4, 0], [0, 0, 1]]))
    array([5., 1.])
    """
    return np.sqrt(np.einsum("ij,ij->i", X, X))


def seed_sample(X, N, wn):
    """The strided subsample (weights renormalised) that seeds are computed from.

    Parameters
    ----------
    X : (p, 3) ndarray of float64
        Points (normalised coordinates).
    N : (p, 3) ndarray of float64 or None
        Unit normals, if any.
    wn : (p,) ndarray of float64
        Non-negative weights summing to 1.

    Returns
    -------
    Xs, Ns, ws : ndarray
        The rows :func:`subsample` picks (all of them, the inputs themselves, for at most
        LM_MAX_POINTS points), ``Ns`` None when ``N`` is, and their weights rescaled to sum 1.
    """
    idx = subsample(len(X))
    if len(idx) == len(X):
        return X, N, wn
    ws = wn[idx]
    return X[idx], None if N is None else N[idx], ws / max(ws.sum(), 1e-300)


def subsample(p: int, most: int = LM_MAX_POINTS) -> np.ndarray:
    """Evenly strided indices of at most ``most`` of ``p`` points (deterministic).

    Parameters
    ----------
    p : int
        Number of points.
    most : int, optional
        Largest number of indices; LM_MAX_POINTS by default.

    Returns
    -------
    (min(p, most),) ndarray of int
        ``arange(p)`` when ``p <= most``, else ``most`` indices evenly spaced over
        ``[0, p - 1]``, first and last included.

    Examples
    --------
    >>> subsample(10, most=4).tolist()
    [0, 3, 6, 9]
    """
    if p <= most:
        return np.arange(p)
    return np.linspace(0, p - 1, most).astype(np.int64)


def least_eig(M: np.ndarray):
    """Eigenvalues (ascending) and the eigenvector of the least one, of a symmetric matrix.

    Parameters
    ----------
    M : (k, k) ndarray of float64
        Symmetric matrix.

    Returns
    -------
    lam : (k,) ndarray
        Eigenvalues in ascending order.
    e : (k,) ndarray
        Unit eigenvector of ``lam[0]``.
    """
    lam, E = np.linalg.eigh(M)
    return lam, E[:, 0]


def nearest_to_lines(X, D, w):
    """Point minimising the weighted squared distances to the lines ``X + t D`` (rows unit).

    Works in any dimension; ``None`` when the lines are (nearly) parallel.

    Parameters
    ----------
    X : (p, k) ndarray of float64
        A point on each line.
    D : (p, k) ndarray of float64
        Unit directions of the lines.
    w : (p,) ndarray of float64
        Non-negative weights.

    Returns
    -------
    (k,) ndarray or None
        The point, or ``None`` when the normal equations' least eigenvalue is below SEED_RCOND
        times their largest (parallel lines: no single nearest point).

    Examples
    --------
    >>> import numpy as np
    >>> X = np.array([[0., 0], [1, 1]])
    >>> nearest_to_lines(X, np.array([[1., 0], [0, 1]]), np.ones(2)).tolist()
    [1.0, 0.0]
    """
    wD = D * w[:, None]
    A = w.sum() * np.eye(X.shape[1]) - wD.T @ D  # sum w (I - d d^T)
    b = w @ X - wD.T @ np.einsum("ij,ij->i", D, X)
    lam = np.linalg.eigvalsh(A)
    if lam[0] <= SEED_RCOND * max(lam[-1], 1e-300):
        return None
    return np.linalg.solve(A, b)


# ----------------------------------------------------------------------------- the solver


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


def run_lm(make_res, X, wn, x0, give_up: float = math.inf):
    """LM on at most LM_MAX_POINTS strided samples, then a short polish on all points. With a
    give-up level, a first pass on LM_COARSE_POINTS samples drops hopeless candidates cheaply.

    Parameters
    ----------
    make_res : callable
        ``make_res(Xa, sw)`` returns the residual function ``res(x, jac=False)`` of the points
        ``Xa`` with square-root weights ``sw``: the weighted residuals ``(p,)``, and with
        ``jac`` also their Jacobian ``(p, k)`` in the parameters ``x``.
    X : (p, 3) ndarray of float64
        Points (centred, unit-spread coordinates).
    wn : (p,) ndarray of float64
        Non-negative weights summing to 1 (renormalised on each subsample).
    x0 : (k,) array_like of float64
        Initial parameters.
    give_up : float, optional
        Cost (weighted mean squared residual, the coordinates of ``X``) above which a creeping
        iteration stops after LM_GIVE_UP_AFTER iterations; a pass that ends above it is
        returned without the later passes.

    Returns
    -------
    tuple of ((k,) ndarray, float) or None
        The parameters and their cost (of the last pass), or ``None`` when the residuals at the
        start of a pass are not finite.
    """
    if math.isfinite(give_up) and len(X) > 2 * LM_COARSE_POINTS:
        idx = subsample(len(X), LM_COARSE_POINTS)
        ws = wn[idx]
        sol = _lm(make_res(X[idx], np.sqrt(ws / max(ws.sum(), 1e-300))), x0, give_up=give_up)
        if sol is None or sol[1] > give_up:
            return sol
        x0 = sol[0]
    idx = subsample(len(X))
    if len(idx) == len(X):
        return _lm(make_res(X, np.sqrt(wn)), x0, give_up=give_up)
    ws = wn[idx]
    sol = _lm(make_res(X[idx], np.sqrt(ws / max(ws.sum(), 1e-300))), x0, give_up=give_up)
    if sol is None or sol[1] > give_up:
        return sol
    return _lm(make_res(X, np.sqrt(wn)), sol[0], max_iter=1)
