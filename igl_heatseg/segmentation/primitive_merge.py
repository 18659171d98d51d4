"""The primitive fits of robust mode's merge step: plane, sphere and cylinder by algebraic least
squares, the type of a segment among them, and the greedy merge of adjacent segments that one
of them fits (:func:`merge_by_primitives`). The fitted surfaces of
:mod:`igl_heatseg.surfaces` (geometric fits of five kinds) are what the segments report; these
quick fits only decide merges and the legacy ``primitive_types``."""

from __future__ import annotations

import math

import numpy as np

from ..mesh.geometry import face_areas, face_normals
from ..mesh.topology import edge_topology

__all__ = [
    "fit_plane",
    "fit_sphere",
    "fit_cylinder",
    "primitive_type",
    "merge_by_primitives",
    "PRIMITIVE_TOL",
    "MERGE_RATIO",
    "MERGE_SLACK",
    "MERGE_NORMAL_OFF",
    "MERGE_NORMAL_ANGLE",
]

#: Primitive type: a simpler fit is chosen when its RMS distance is within this many mean edge
#: lengths of the best fit's.
PRIMITIVE_TOL: float = 0.05

#: ... or within this factor of the worse of the two pieces' own fits (noise level).
MERGE_RATIO: float = 1.3

#: Additive slack of the relative test, as a fraction of the absolute tolerance.
MERGE_SLACK: float = 0.1
#: Fewer points than this cannot be typed (``"Other"``).
_MIN_FIT_POINTS = 8

#: A union's fit is refused when the share of either piece's area with face normals over
#: MERGE_NORMAL_ANGLE off the fit's exceeds that share on the piece's own fit by more than this.
MERGE_NORMAL_OFF: float = 0.1
MERGE_NORMAL_ANGLE: float = math.radians(25.0)
_NORMAL_COS = math.cos(MERGE_NORMAL_ANGLE)


# --------------------------------------------------------------------------------------------
# Primitive fits
# --------------------------------------------------------------------------------------------


def fit_plane(P: np.ndarray) -> tuple[float, np.ndarray, np.ndarray]:
    """Least-squares plane.

    Parameters
    ----------
    P : (p, 3) float64
        Points.

    Returns
    -------
    rms : float
        RMS distance to the plane.
    center : (3,) float64
    normal : (3,) float64
    """
    c = P.mean(axis=0)
    _, s, Vt = np.linalg.svd(P - c, full_matrices=False)
    return float(s[-1] / math.sqrt(len(P))), c, Vt[-1]


def fit_sphere(P: np.ndarray) -> tuple[float, np.ndarray, float]:
    """Algebraic sphere fit ``|x|^2 = 2 c . x + (r^2 - |c|^2)``.

    Returns
    -------
    rms : float
        RMS of ``|x - c| - r``.
    center : (3,) float64
    radius : float
    """
    A = np.c_[2 * P, np.ones(len(P))]
    b = (P * P).sum(axis=1)
    x, *_ = np.linalg.lstsq(A, b, rcond=None)
    c = x[:3]
    r = math.sqrt(max(x[3] + c @ c, 0.0))
    return float(np.sqrt(((np.linalg.norm(P - c, axis=1) - r) ** 2).mean())), c, r


def fit_cylinder(P: np.ndarray, N: np.ndarray) -> tuple[float, np.ndarray, np.ndarray, float]:
    """Cylinder fit: axis from the normals, circle fit in the plane across it.

    The normals of a cylinder are perpendicular to its axis, so the axis is the eigenvector of
    ``sum n n^T`` with the smallest eigenvalue; the points projected across the axis are fitted
    with an algebraic circle.

    Parameters
    ----------
    P : (p, 3) float64
        Points.
    N : (q, 3) float64
        Unit normals sampled on the same surface.

    Returns
    -------
    rms : float
        RMS of distance-to-axis minus radius.
    point : (3,) float64
        A point on the axis.
    axis : (3,) float64
    radius : float
    """
    _, vecs = np.linalg.eigh(N.T @ N)
    a = vecs[:, 0]
    u = vecs[:, 1]
    v = vecs[:, 2]
    Q = np.c_[P @ u, P @ v]
    A = np.c_[2 * Q, np.ones(len(Q))]
    b = (Q * Q).sum(axis=1)
    x, *_ = np.linalg.lstsq(A, b, rcond=None)
    c2 = x[:2]
    r = math.sqrt(max(x[2] + c2 @ c2, 0.0))
    rms = float(np.sqrt(((np.linalg.norm(Q - c2, axis=1) - r) ** 2).mean()))
    return rms, c2[0] * u + c2[1] * v, a, r


def primitive_type(P: np.ndarray, N: np.ndarray, h: float, diag: float) -> tuple[str, float]:
    """The simplest of plane / cylinder / sphere that fits as well as the best (within tol).

    Parameters
    ----------
    P : (p, 3) float64
        The segment's vertices.
    N : (q, 3) float64
        The segment's unit face normals.
    h : float
        Mean edge length (tolerance unit, :data:`PRIMITIVE_TOL`).
    diag : float
        Part size; fits with a radius above ``10 * diag`` count as planes.

    Returns
    -------
    type : str
        ``"Plane"``, ``"Cylinder"``, ``"Sphere"`` or ``"Other"``.
    rms : float
        RMS distance of the chosen fit (``nan`` for ``"Other"`` with too few points).
    """
    if len(P) < _MIN_FIT_POINTS:
        return "Other", math.nan
    fits = [("Plane", fit_plane(P)[0])]
    rc = fit_cylinder(P, N)
    if rc[3] < 10 * diag:
        fits.append(("Cylinder", rc[0]))
    rs = fit_sphere(P)
    if rs[2] < 10 * diag:
        fits.append(("Sphere", rs[0]))
    best = min(r for _, r in fits)
    tol = PRIMITIVE_TOL * h
    for name, r in fits:  # simplest first
        if r <= best + tol and r <= 2 * tol + best:
            if r > 4 * tol:
                return "Other", float(best)
            return name, float(r)
    return "Other", float(best)


def _best_residuals(P: np.ndarray, N: np.ndarray, diag: float):
    """Point residuals of the best of the plane, cylinder and sphere fits and a function giving
    that fit's unit normals at points; (None, None) if too few points."""
    if len(P) < _MIN_FIT_POINTS:
        return None, None
    _, c, nrm = fit_plane(P)
    cands = [((P - c) @ nrm, lambda X: np.broadcast_to(nrm, X.shape))]
    rc = fit_cylinder(P, N)
    if rc[3] < 10 * diag:
        def radial(X, p=rc[1], a=rc[2]):
            Y = X - p
            return Y - np.outer(Y @ a, a)

        cands.append((np.linalg.norm(radial(P), axis=1) - rc[3],
                      lambda X: _unit(radial(X))))
    rs = fit_sphere(P)
    if rs[2] < 10 * diag:
        cands.append((np.linalg.norm(P - rs[1], axis=1) - rs[2],
                      lambda X, o=rs[1]: _unit(X - o)))
    res, normals = min(cands, key=lambda rn: float((rn[0] * rn[0]).mean()))
    return res, normals


def _unit(X: np.ndarray) -> np.ndarray:
    return X / np.maximum(np.linalg.norm(X, axis=1, keepdims=True), 1e-300)


def merge_by_primitives(
    V: np.ndarray,
    F: np.ndarray,
    labels: np.ndarray,
    tol: float,
    ratio: float = MERGE_RATIO,
    topo=None,
) -> tuple[np.ndarray, int]:
    """Greedily merge adjacent segments whose union one plane, cylinder or sphere fits.

    The union's best fit is judged on each piece separately (so a big plane cannot swallow a
    small curved piece whose points it misses, which a single RMS over the union allows): the
    worse of the two pieces' RMS distances to the union's fit must be at most ``tol`` and at
    most ``ratio * max(rms_a, rms_b) + MERGE_SLACK * tol`` (the pieces' own fits: the noise
    level), and each piece's share of area whose face normals are more than MERGE_NORMAL_ANGLE
    off the fit's may exceed that share on its own fit by at most MERGE_NORMAL_OFF. The pair
    with the smallest such RMS goes first; fits are recomputed after every merge.

    Parameters
    ----------
    V : (n, 3) float64
    F : (m, 3) int64
    labels : (m,) int64
        Face labels ``0..k-1``.
    tol : float
        Absolute RMS tolerance (model units).
    ratio : float
        Relative tolerance against the two pieces' own fits (noise level).
    topo : EdgeTopology, optional

    Returns
    -------
    labels : (m,) int64
        Merged labels (ids of the surviving segments, not renumbered).
    merged : int
        Number of merges.
    """
    topo = edge_topology(F) if topo is None else topo
    N = face_normals(V, F)
    area = face_areas(V, F)
    C = V[F].mean(axis=1)
    diag = float(np.linalg.norm(V.max(axis=0) - V.min(axis=0)))
    labels = labels.copy()
    faces = {int(s): np.flatnonzero(labels == s) for s in np.unique(labels)}

    def cosines(fs, normals) -> np.ndarray:
        """Cosine between each face's normal and the fit's normal at its centroid."""
        return np.einsum("ij,ij->i", N[fs], normals(C[fs]))

    def off_share(fs, cos) -> float:
        """Area share of the faces whose normals are over MERGE_NORMAL_ANGLE off the fit's."""
        return float(area[fs][np.abs(cos) < _NORMAL_COS].sum() / max(area[fs].sum(), 1e-300))

    def fit(fs):
        """RMS of the best fit and the share of the faces off its normals (1: no fit)."""
        res, normals = _best_residuals(V[np.unique(F[fs])], N[fs], diag)
        if res is None:
            return math.inf, 1.0
        return float(np.sqrt((res * res).mean())), off_share(fs, cosines(fs, normals))

    def union_fit(sa, sb):
        """RMS of the union's best fit over the points of each piece (the worse one); inf
        when the pieces face opposite ways on it (the two sides of a thin wall)."""
        fa, fb = faces[sa], faces[sb]
        va, vb = np.unique(F[fa]), np.unique(F[fb])
        vs = np.union1d(va, vb)
        res, normals = _best_residuals(V[vs], N[np.concatenate([fa, fb])], diag)
        if res is None:
            return math.inf
        cos_a, cos_b = cosines(fa, normals), cosines(fb, normals)
        if (area[fa] * cos_a).sum() * (area[fb] * cos_b).sum() < 0:
            return math.inf
        # the faces must lie along the fit as well as on their own piece's fit, not only their
        # corners: the corners of a coarse rounded box all lie near one sphere, while its
        # faces' normals are the box's (their own fits' normal noise is the reference)
        for f, cos, s in ((fa, cos_a, sa), (fb, cos_b, sb)):
            if off_share(f, cos) > own[s][1] + MERGE_NORMAL_OFF:
                return math.inf
        ra, rb = res[np.searchsorted(vs, va)], res[np.searchsorted(vs, vb)]
        return float(max(np.sqrt((ra * ra).mean()), np.sqrt((rb * rb).mean())))

    own = {s: fit(fs) for s, fs in faces.items()}  # (rms, share of faces off the fit's normals)
    inner = topo.interior
    ef = topo.EF[inner]

    def neighbours():
        la, lb = labels[ef[:, 0]], labels[ef[:, 1]]
        d = la != lb
        return {(int(min(a, b)), int(max(a, b))) for a, b in zip(la[d], lb[d], strict=True)}

    slack = MERGE_SLACK * tol
    cache: dict[tuple[int, int], float] = {}
    merged = 0
    while True:
        best, pair = math.inf, None
        for a, b in neighbours():
            if (a, b) not in cache:
                cache[(a, b)] = union_fit(a, b)
            r = cache[(a, b)]
            ok = r <= tol and (ratio <= 0 or r <= ratio * max(own[a][0], own[b][0]) + slack)
            if ok and r < best:
                best, pair = r, (a, b)
        if pair is None:
            return labels, merged
        a, b = pair
        faces[a] = np.concatenate([faces[a], faces.pop(b)])
        labels[faces[a]] = a
        own[a] = fit(faces[a])
        own.pop(b)
        cache = {k: v for k, v in cache.items() if a not in k and b not in k}
        merged += 1
