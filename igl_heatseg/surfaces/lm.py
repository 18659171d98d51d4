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
    """Weighted centroid ``m`` and spread ``s`` (RMS distance to ``m``; 1 when all coincide)."""
    m = w @ P
    s = math.sqrt(max(float(w @ np.einsum("ij,ij->i", P - m, P - m)), 0.0))
    return m, (s if s > 0 else 1.0)


def rownorm(X: np.ndarray) -> np.ndarray:
    return np.sqrt(np.einsum("ij,ij->i", X, X))


def seed_sample(X, N, wn):
    """The strided subsample (weights renormalised) that seeds are computed from."""
    idx = subsample(len(X))
    if len(idx) == len(X):
        return X, N, wn
    ws = wn[idx]
    return X[idx], None if N is None else N[idx], ws / max(ws.sum(), 1e-300)


def subsample(p: int, most: int = LM_MAX_POINTS) -> np.ndarray:
    """Evenly strided indices of at most ``most`` of ``p`` points (deterministic)."""
    if p <= most:
        return np.arange(p)
    return np.linspace(0, p - 1, most).astype(np.int64)


def least_eig(M: np.ndarray):
    """Eigenvalues (ascending) and the eigenvector of the least one, of a symmetric matrix."""
    lam, E = np.linalg.eigh(M)
    return lam, E[:, 0]


def nearest_to_lines(X, D, w):
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
    give-up level, a first pass on LM_COARSE_POINTS samples drops hopeless candidates cheaply."""
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
