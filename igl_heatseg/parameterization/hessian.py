"""Sparse Hessian energies on triangle meshes (ALGORITHM.md section 6).

:func:`hlle_energy` builds the Hessian locally linear embedding energy of Donoho & Grimes as
adapted to meshes by Mejia et al. (GRAPP 2016, the paper's ref. [12])::

    K = sum_i A_i * S_i^T H_i^T H_i S_i

For every vertex ``i``: ``N_i`` is its 2-ring (grown ring by ring until it has at least
``min_neighbors`` vertices besides ``i``), ``(u, v)`` local coordinates of the vertices of
``N_i`` (relative to ``i``), and ``H_i`` (3 x |N_i|) the rows of the least-squares fit
``f ~ a + b u + c v + d u^2/2 + e u v + g v^2/2`` that give ``(d, sqrt(2) e, g)``, so that
``|H_i f|^2 = ||Hess f||_F^2`` at ``i``.  ``A_i`` is the Voronoi area of ``i`` and ``S_i`` selects
``N_i``.

Local coordinates (``coords``):

- ``"projection"`` (the paper's): a tangent frame ``(t1, t2, n)`` whose normal is the
  area-weighted mean of the incident face normals; ``(u, v)`` = orthogonal projection.  Its
  metric error is O(h^2 kappa^2): intrinsic coordinates of a developable chart are only
  approximately in the null space, and neighbourhoods that straddle a crease are wrong.
- ``"normal"``: projection corrected to second-order geodesic normal coordinates with a local
  quadric fit (much more accurate on smooth curved charts, still wrong across creases).
- ``"intrinsic"`` (default): the neighbourhood unfolded from edge lengths and corner angles
  (a discrete exponential map).  Exact on developable charts, also across creases (CAD charts
  often contain a narrow chamfer or a crease below the segmentation threshold), and as accurate
  as ``"normal"`` on doubly curved charts.

The quadratic rows are computed after projecting out the affine part (Frisch-Waugh-Lovell):
``H_i = pinv(R Q) R`` with ``R = I - X pinv(X)``, ``X = [1 u v]``, ``Q = [u^2/2, u v, v^2/2]``.
With a full-rank fit this equals the corresponding rows of ``pinv([X Q])``; it additionally keeps
``H_i X = 0`` *exactly* when the fit is under-determined (tiny charts), so affine functions of
the local coordinates are always in the null space of every ``H_i``.

``K`` is assembled as ``B^T diag(A) B`` with ``B`` the (3n x n) sparse stack of the ``H_i S_i``,
vertices batched by neighbourhood size (no Python loop over vertices).

:func:`curved_hessian_energy` wraps ``igl.curved_hessian_energy`` (Stein et al. 2020), whose
null space on a developable surface contains the intrinsic coordinates.
"""

from __future__ import annotations

import logging
from typing import Literal

import igl
import numpy as np
import scipy.sparse as sp
from numpy.typing import ArrayLike

from ..errors import MeshError
from ..mesh.checks import as_mesh_arrays

__all__ = [
    "hlle_energy",
    "curved_hessian_energy",
    "hessian_energy",
    "vertex_neighborhoods",
    "HLLE_MIN_NEIGHBORS",
]

log = logging.getLogger(__name__)

#: Smallest neighbourhood (vertices besides the centre) of the local quadratic fit; the fit has
#: 6 unknowns, so 6 neighbours + the centre make it over-determined.
HLLE_MIN_NEIGHBORS: int = 6

#: Rings beyond which neighbourhoods stop growing (a chart smaller than that uses everything).
_MAX_RINGS: int = 8

#: Vertices per batched pseudo-inverse call (memory bound: batch * k * k doubles).
_BATCH: int = 20000


def vertex_neighborhoods(
    n: int, F: np.ndarray, min_neighbors: int = HLLE_MIN_NEIGHBORS, rings: int = 2
) -> sp.csr_matrix:
    """Neighbourhood of every vertex: its ``rings``-ring, grown until ``min_neighbors``.

    Parameters
    ----------
    n : int
        Number of vertices.
    F : (m, 3) int64
        Triangles.
    min_neighbors : int
        Grow a vertex's neighbourhood ring by ring until it holds at least this many vertices
        besides itself (or stops growing: its component is exhausted).
    rings : int
        Starting ring count (2 for HLLE).

    Returns
    -------
    N : (n, n) scipy.sparse.csr_matrix of bool
        ``N[i, j]`` is True when ``j`` is in the neighbourhood of ``i``; the diagonal is set.
        Vertices not referenced by ``F`` have only themselves.

    Examples
    --------
    >>> import numpy as np
    >>> N = vertex_neighborhoods(4, np.array([[0, 1, 2], [0, 2, 3]]))
    >>> N.sum(axis=1).A1.tolist()  # a 4-vertex chart: everything
    [4, 4, 4, 4]
    """
    ii = F[:, [0, 1, 2, 1, 2, 0]].ravel()
    jj = F[:, [1, 2, 0, 0, 1, 2]].ravel()
    A = sp.csr_matrix((np.ones(len(ii), dtype=np.int32), (ii, jj)), shape=(n, n))
    A = (A + sp.identity(n, dtype=np.int32, format="csr")).astype(bool).astype(np.int32)
    N = A.copy()
    for _ in range(rings - 1):
        N = (N @ A).astype(bool).astype(np.int32)
    N = N.tocsr()
    for _ in range(_MAX_RINGS):
        size = np.diff(N.indptr) - 1
        small = np.flatnonzero(size < min_neighbors)
        if len(small) == 0:
            break
        sub = N[small]
        grown = (sub @ A).astype(bool).astype(np.int32).tocsr()
        if np.array_equal(np.diff(grown.indptr), np.diff(sub.indptr)):
            break  # every small neighbourhood already covers its component
        rows = np.ones(n, dtype=bool)
        rows[small] = False
        keep = sp.diags(rows.astype(np.int32), dtype=np.int32) @ N
        P = sp.csr_matrix(
            (np.ones(len(small), dtype=np.int32), (small, np.arange(len(small)))),
            shape=(n, len(small)),
        )
        N = (keep + P @ grown).astype(bool).astype(np.int32).tocsr()
    N.sort_indices()
    return N.astype(bool)  # int32 counts above: path counts cannot wrap to zero


def _vertex_normals(V: np.ndarray, F: np.ndarray) -> np.ndarray:
    """(n, 3) area-weighted vertex normals (unit; zero for unreferenced vertices)."""
    FN = np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]])  # length = 2 * area
    N = np.zeros_like(V)
    for j in range(3):
        np.add.at(N, F[:, j], FN)
    nrm = np.linalg.norm(N, axis=1)
    ok = nrm > 0
    N[ok] /= nrm[ok, None]
    return N


def _tangent_frames(N: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Orthonormal tangent vectors ``t1, t2`` (each (n, 3)) with ``t1 x t2 = N``."""
    axis = np.argmin(np.abs(N), axis=1)
    E = np.zeros_like(N)
    E[np.arange(len(N)), axis] = 1.0
    t1 = np.cross(N, E)
    t1 /= np.maximum(np.linalg.norm(t1, axis=1), 1e-300)[:, None]
    t2 = np.cross(N, t1)
    return t1, t2


def _fan_angles(V: np.ndarray, F: np.ndarray):
    """Cumulative corner angles around every vertex, in the faces' orientation (ccw).

    Returns
    -------
    keys : (h,) int64
        Sorted directed pairs ``a * n + b`` (``b`` a neighbour of ``a``).
    theta : (h,) float64
        Angle at ``a`` from the start of its fan to the edge ``(a, b)``.
    total : (n,) float64
        Angle sum at every vertex.
    boundary : (n,) bool
        Vertices whose fan is open.
    """
    n = V.shape[0]
    m = F.shape[0]
    a = F.T.ravel()  # wedge w = c * m + f: corner c of face f
    b = np.roll(F, -1, axis=1).T.ravel()
    d = np.roll(F, -2, axis=1).T.ravel()
    e1 = V[b] - V[a]
    e2 = V[d] - V[a]
    cosang = (e1 * e2).sum(1) / np.maximum(
        np.linalg.norm(e1, axis=1) * np.linalg.norm(e2, axis=1), 1e-300
    )
    alpha = np.arccos(np.clip(cosang, -1.0, 1.0))
    W = 3 * m
    start_key = a * n + b
    end_key = a * n + d
    order = np.argsort(start_key, kind="stable")
    sk = start_key[order]
    # successor: the wedge at a that starts where w ends; predecessor: the reverse.
    pos = np.clip(np.searchsorted(sk, end_key), 0, W - 1)
    succ = np.where(sk[pos] == end_key, order[pos], -1)
    pred = np.full(W, -1, dtype=np.int64)
    has = succ >= 0
    pred[succ[has]] = np.flatnonzero(has)
    boundary = np.zeros(n, dtype=bool)
    boundary[a[pred < 0]] = True
    # Cut closed fans at the smallest wedge id of each interior vertex.
    first = np.full(n, W, dtype=np.int64)
    np.minimum.at(first, a, np.arange(W))
    cut = ~boundary[a] & (np.arange(W) == first[a])
    pred[cut] = -1
    # Prefix sums along the chains by pointer jumping (list ranking).
    val = np.where(pred >= 0, alpha[np.maximum(pred, 0)], 0.0)
    ptr = pred.copy()
    while np.any(ptr >= 0):
        ok = ptr >= 0
        val[ok] += val[ptr[ok]]
        nxt = np.full(W, -1, dtype=np.int64)
        nxt[ok] = ptr[ptr[ok]]
        ptr = nxt
    total = np.zeros(n)
    np.maximum.at(total, a, val + alpha)
    keys = start_key
    theta = val
    # Open fans: the last wedge's end neighbour is no wedge's start.
    last = boundary[a] & (succ < 0)
    keys = np.concatenate([keys, end_key[last]])
    theta = np.concatenate([theta, (val + alpha)[last]])
    o = np.argsort(keys, kind="stable")
    keys, theta = keys[o], theta[o]
    keep = np.r_[True, keys[1:] != keys[:-1]]  # pinched vertices: first chain wins
    return keys[keep], theta[keep], total, boundary


def _lookup(keys: np.ndarray, values: np.ndarray, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Values for query keys (``found`` False where absent)."""
    pos = np.clip(np.searchsorted(keys, q), 0, max(len(keys) - 1, 0))
    found = keys[pos] == q
    return values[pos], found


def _intrinsic_layout(V: np.ndarray, F: np.ndarray, Nb: sp.csr_matrix) -> np.ndarray:
    """Unfolded 2D coordinates of every neighbourhood (a discrete exponential map).

    For centre ``i``: 1-ring vertices at their edge length in the direction of the cumulative
    corner angle (scaled by ``2 pi / angle sum`` at interior vertices); every further vertex
    ``j`` is unfolded from an already placed neighbour ``a`` (reached from ``q``): at distance
    ``|a j|`` in the direction of ``a -> q`` turned by the corner-angle sum at ``a`` between
    ``q`` and ``j`` (the shorter way round at interior vertices).  Positions reached from
    several ``a`` are averaged.  Exact on developable (intrinsically flat) charts, creases
    included.

    Returns
    -------
    X : (nnz(Nb), 2) float64
        Coordinates aligned with ``Nb.indices`` (centre at the origin).
    """
    n = V.shape[0]
    keys, theta, total, boundary = _fan_angles(V, F)
    scale = np.where(boundary | (total <= 0), 1.0, 2.0 * np.pi / np.where(total > 0, total, 1.0))
    adj_a = keys // n
    adj_b = keys % n
    adj_ptr = np.searchsorted(adj_a, np.arange(n + 1))
    nnz = Nb.nnz
    row = np.repeat(np.arange(n), np.diff(Nb.indptr))
    col = Nb.indices.astype(np.int64)  # scipy stores int32 indices: keys would overflow
    nkeys = row * n + col  # sorted (rows ascending, columns sorted)
    X = np.full((nnz, 2), np.nan)
    parent = np.full(nnz, -1, dtype=np.int64)  # vertex id through which an entry was placed
    level = np.full(nnz, -1, dtype=np.int64)
    centre = row == col
    X[centre] = 0.0
    level[centre] = 0
    # Level 1: polar coordinates around the centre.
    th, found = _lookup(keys, theta, nkeys)
    one = found & ~centre
    phi = scale[row[one]] * th[one]
    r = np.linalg.norm(V[col[one]] - V[row[one]], axis=1)
    X[one] = np.c_[r * np.cos(phi), r * np.sin(phi)]
    parent[one] = row[one]
    level[one] = 1
    L = 1
    while np.any(level < 0) and L < 64:
        src = np.flatnonzero(level == L)  # entries (i, a) placed at level L
        if len(src) == 0:
            break
        i_s, a_s = row[src], col[src]
        deg = adj_ptr[a_s + 1] - adj_ptr[a_s]
        t_src = np.repeat(src, deg)
        t_i = np.repeat(i_s, deg)
        t_a = np.repeat(a_s, deg)
        off = np.arange(len(t_src)) - np.repeat(np.cumsum(deg) - deg, deg)
        t_j = adj_b[np.repeat(adj_ptr[a_s], deg) + off]
        ent = np.clip(np.searchsorted(nkeys, t_i * n + t_j), 0, nnz - 1)
        ok = (nkeys[ent] == t_i * n + t_j) & (level[ent] < 0)
        t_src, t_i, t_a, t_j, ent = t_src[ok], t_i[ok], t_a[ok], t_j[ok], ent[ok]
        if len(ent) == 0:
            break
        q = parent[t_src]
        q_ent = np.searchsorted(nkeys, t_i * n + q)
        pa = X[t_src]
        pq = X[q_ent]
        psi = np.arctan2(pq[:, 1] - pa[:, 1], pq[:, 0] - pa[:, 0])
        th_j, f1 = _lookup(keys, theta, t_a * n + t_j)
        th_q, f2 = _lookup(keys, theta, t_a * n + q)
        beta = th_j - th_q
        interior = ~boundary[t_a]
        beta = np.where(interior, scale[t_a] * beta, beta)
        beta = np.where(interior, (beta + np.pi) % (2.0 * np.pi) - np.pi, beta)
        dist = np.linalg.norm(V[t_j] - V[t_a], axis=1)
        cand = pa + dist[:, None] * np.c_[np.cos(psi + beta), np.sin(psi + beta)]
        good = f1 & f2 & np.all(np.isfinite(cand), axis=1)
        ent, cand, t_a = ent[good], cand[good], t_a[good]
        cnt = np.bincount(ent, minlength=nnz)
        sx = np.bincount(ent, weights=cand[:, 0], minlength=nnz)
        sy = np.bincount(ent, weights=cand[:, 1], minlength=nnz)
        new = np.flatnonzero(cnt > 0)
        X[new] = np.c_[sx[new], sy[new]] / cnt[new, None]
        par = np.full(nnz, -1, dtype=np.int64)
        par[ent] = t_a  # any one of the sources
        parent[new] = par[new]
        level[new] = L + 1
        L += 1
    # Anything unreachable (should not happen in a connected chart): put at the centre.
    X[~np.isfinite(X).all(axis=1)] = 0.0
    return X


def _inv3(G: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Inverses of a batch of 3 x 3 matrices by cofactors, and their Frobenius condition
    numbers ``|G| |G^-1|`` (``inf``/``nan`` for singular ones)."""
    a, b, c = G[:, 0, 0], G[:, 0, 1], G[:, 0, 2]
    d, e, f = G[:, 1, 0], G[:, 1, 1], G[:, 1, 2]
    g, h, i = G[:, 2, 0], G[:, 2, 1], G[:, 2, 2]
    c00, c01, c02 = e * i - f * h, f * g - d * i, d * h - e * g
    adj = np.stack(
        [
            np.stack([c00, c * h - b * i, b * f - c * e], axis=1),
            np.stack([c01, a * i - c * g, c * d - a * f], axis=1),
            np.stack([c02, b * g - a * h, a * e - b * d], axis=1),
        ],
        axis=1,
    )
    det = a * c00 + b * c01 + c * c02
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        inv = adj / det[:, None, None]
        cond = np.sqrt((G * G).sum(axis=(1, 2)) * (inv * inv).sum(axis=(1, 2)))
    return inv, cond


#: Largest (Frobenius) condition number of the 3 x 3 normal matrices for which
#: :func:`_quadratic_rows` solves the normal equations (error ~ cond * eps relative);
#: beyond, batched ``pinv``.
_NORMAL_COND_MAX: float = 1e4


def _quadratic_rows(
    u: np.ndarray, v: np.ndarray, rcond: float = 1e-15
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Affine-annihilating quadratic-fit operators for a batch of local coordinates.

    Returns ``Hq = pinv(R Q) R`` (b, 3, k), giving ``(d, e, g)`` of
    ``f ~ a + b u + c v + d u^2/2 + e u v + g v^2/2``; ``Xp = pinv(X)`` (b, 3, k); and ``Q``.

    Both pseudo-inverses are of full-column-rank (k, 3) matrices almost always: they are
    computed from the 3 x 3 normal matrices (cofactor inverses, ``pinv(A) = (A^T A)^-1 A^T``),
    3-5x faster than batched SVDs (measured: 5000 neighbourhoods of 13 vertices, 0.066 ->
    0.020 s; :func:`hlle_energy` over all charts of fandisk, block, rocker-arm,
    psb_331_mech, bunny and iron: 5.3 -> 4.5 s, largest difference in ``K`` 4e-12 of its
    largest entry).  Neighbourhoods whose normal matrices have a condition number above
    :data:`_NORMAL_COND_MAX` (rank-deficient fits of tiny charts, points on a conic; 19 of
    279k on those meshes) use ``np.linalg.pinv`` with ``rcond`` as before.
    """
    k = u.shape[1]
    X = np.stack([np.ones_like(u), u, v], axis=2)  # (b, k, 3)
    Q = np.stack([0.5 * u * u, u * v, 0.5 * v * v], axis=2)  # (b, k, 3)
    Xt = X.transpose(0, 2, 1)
    with np.errstate(invalid="ignore", over="ignore", divide="ignore"):  # singular: redone
        Gi, c1 = _inv3(Xt @ X)
        Xp = Gi @ Xt  # (b, 3, k)
        R = np.eye(k)[None] - X @ Xp  # (b, k, k) projector onto the affine residual space
        RQ = R @ Q
        RQt = RQ.transpose(0, 2, 1)
        G2i, c2 = _inv3(RQt @ RQ)
        Hq = (G2i @ RQt) @ R  # (b, 3, k)
    bad = ~((c1 <= _NORMAL_COND_MAX) & (c2 <= _NORMAL_COND_MAX))  # nan/inf included
    if bad.any():
        Xb = X[bad]
        Xp[bad] = np.linalg.pinv(Xb)
        Rb = np.eye(k)[None] - Xb @ Xp[bad]
        Hq[bad] = _truncated_pinv(Rb @ Q[bad], k - np.linalg.matrix_rank(Xb), rcond) @ Rb
    return Hq, Xp, Q


def _truncated_pinv(A: np.ndarray, rank: np.ndarray, rcond: float) -> np.ndarray:
    """Batched pseudo-inverse of (b, k, 3) ``A`` keeping at most ``rank[i]`` singular values
    (and only those above ``rcond`` times the largest).

    ``A = R Q`` has rank at most ``rank(R) = k - rank(X)``: with fewer than 6 neighbourhood
    vertices (tiny charts) that is below 3, and the singular values beyond it are rounding
    noise of ``R`` (``R X`` ~ 1e-16, not 0).  A relative cutoff alone keeps such a value when
    it lands above ``rcond * s_max`` (5-vertex flat fan: 4.3e-16 against 3.7e-16), and its
    inverse, ~1e15, turns ``R X ~ 1e-16`` into ``H X ~ 1``: affine functions left the null
    space.  The structural rank drops it whatever its rounding.
    """
    U, s, Vt = np.linalg.svd(A, full_matrices=False)
    keep = (s > rcond * s[:, :1]) & (np.arange(s.shape[1])[None, :] < rank[:, None])
    sinv = np.where(keep, 1.0 / np.where(keep, s, 1.0), 0.0)
    return (Vt.transpose(0, 2, 1) * sinv[:, None, :]) @ U.transpose(0, 2, 1)


def _fit_graph(u, v, w):
    """Least-squares ``w ~ c + b.x + x^T A x / 2``: returns gradient (b, 2) and A (b, 2, 2)."""
    Hq, Xp, Q = _quadratic_rows(u, v)
    quad = np.einsum("bik,bk->bi", Hq, w)  # (d, e, g)
    lin = np.einsum("bik,bk->bi", Xp, w - np.einsum("bki,bi->bk", Q, quad))
    A = np.stack([np.stack([quad[:, 0], quad[:, 1]], 1), np.stack([quad[:, 1], quad[:, 2]], 1)], 1)
    return lin[:, 1:], A


def _rows_from_coords(u: np.ndarray, v: np.ndarray, rcond: float) -> np.ndarray:
    """Hessian rows ``(d, sqrt(2) e, g)`` for given local coordinates (b, k) each."""
    h = np.sqrt(np.mean(u**2 + v**2, axis=1))
    h = np.where(h > 0, h, 1.0)
    H, _, _ = _quadratic_rows(u / h[:, None], v / h[:, None], rcond)
    H[:, 1, :] *= np.sqrt(2.0)
    return H / (h**2)[:, None, None]


def _local_hessian_rows(
    P: np.ndarray, normal: np.ndarray, coords: str, rcond: float = 1e-15
) -> np.ndarray:
    """Hessian rows for a batch of neighbourhoods of equal size.

    Parameters
    ----------
    P : (b, k, 3) float64
        Neighbourhood positions relative to the centre (centre first, at the origin).
    normal : (b, 3) float64
        Unit normals at the centres.
    coords : {"projection", "chord", "normal"}
        Local coordinates: orthogonal projection onto the tangent plane (the paper's); the
        projected direction rescaled to the 3D distance to the centre; or second-order
        geodesic normal coordinates (see :func:`hlle_energy`).

    Returns
    -------
    H : (b, 3, k) float64
        Rows giving ``(d, sqrt(2) e, g)`` of the local quadratic fit.
    """
    # Scale-normalise each neighbourhood (conditioning); undone below: H scales as 1/h^2.
    h = np.sqrt(np.mean((P**2).sum(axis=2), axis=1))
    h = np.where(h > 0, h, 1.0)
    P = P / h[:, None, None]
    t1, t2 = _tangent_frames(normal)
    u = np.einsum("bkd,bd->bk", P, t1)
    v = np.einsum("bkd,bd->bk", P, t2)
    if coords == "chord":
        r3 = np.linalg.norm(P, axis=2)
        r2 = np.hypot(u, v)
        s = np.where(r2 > 0, r3 / np.where(r2 > 0, r2, 1.0), 1.0)
        u, v = u * s, v * s
    elif coords == "normal":
        # Tilt the frame to the fitted tangent plane, refit, then map the projection x to
        # geodesic normal coordinates to second order: x + (x^T A x) A x / 6.
        w = np.einsum("bkd,bd->bk", P, normal)
        g, _ = _fit_graph(u, v, w)
        n2 = normal - g[:, :1] * t1 - g[:, 1:] * t2
        n2 /= np.linalg.norm(n2, axis=1)[:, None]
        t1, t2 = _tangent_frames(n2)
        u = np.einsum("bkd,bd->bk", P, t1)
        v = np.einsum("bkd,bd->bk", P, t2)
        w = np.einsum("bkd,bd->bk", P, n2)
        _, A = _fit_graph(u, v, w)
        x = np.stack([u, v], axis=2)  # (b, k, 2)
        Ax = np.einsum("bij,bkj->bki", A, x)
        q = (x * Ax).sum(axis=2)
        x = x + q[:, :, None] * Ax / 6.0
        u, v = x[:, :, 0], x[:, :, 1]
    H, _, _ = _quadratic_rows(u, v, rcond)
    H[:, 1, :] *= np.sqrt(2.0)
    return H / (h**2)[:, None, None]


def hlle_energy(
    V: ArrayLike,
    F: ArrayLike,
    *,
    min_neighbors: int = HLLE_MIN_NEIGHBORS,
    coords: Literal["projection", "chord", "normal", "intrinsic"] = "intrinsic",
    area: Literal["voronoi", "barycentric"] = "voronoi",
    rcond: float = 1e-15,
    return_parts: bool = False,
):
    """HLLE Hessian energy matrix of a triangle mesh (Mejia et al. 2016).

    Parameters
    ----------
    V : (n, 3) array_like of float
        Vertex positions.
    F : (m, 3) array_like of int
        Triangles.
    min_neighbors : int
        Minimum neighbourhood size (besides the centre) of the local quadratic fit.
    coords : {"projection", "chord", "normal"}
        Local (u, v) coordinates of the neighbours: ``"projection"`` (the paper's choice),
        orthogonal projection on the tangent plane; ``"chord"``, the projected direction
        rescaled to the 3D distance; ``"normal"``, second-order geodesic normal coordinates:
        fit ``w ~ grad.x + x^T A x / 2`` to the heights, tilt the frame to the fitted tangent
        plane, refit, and use ``x + (x^T A x) A x / 6`` (exact to third order on a cylinder
        and a sphere), which removes most of the projection's metric error on curved charts;
        ``"intrinsic"``, the neighbourhood unfolded from edge lengths and corner angles (a
        discrete exponential map, exact on developable charts even across creases).
    area : {"voronoi", "barycentric"}
        Vertex area ``A_i`` (``igl.massmatrix`` type).
    rcond : float
        Relative cutoff of the pseudo-inverse of the (affine-projected) quadratic design matrix;
        raise it to drop ill-determined quadratic directions of near-degenerate neighbourhoods.
    return_parts : bool
        Also return ``B`` (3n x n, the stacked ``H_i S_i``) and the vertex areas ``A`` (n,).

    Returns
    -------
    K : (n, n) scipy.sparse.csr_matrix of float64
        Symmetric positive semidefinite; ``f^T K f ~ integral of ||Hess f||_F^2``.  Its null
        space contains the constants and, on a flat chart, the two coordinates.
        Unreferenced vertices give zero rows/columns.
    B, A : only with ``return_parts``
        ``K = B^T diag(repeat(A, 3)) B``.

    Raises
    ------
    MeshError
        On bad array shapes or indices.

    Examples
    --------
    >>> import numpy as np
    >>> x, y = np.meshgrid(np.linspace(0, 1, 6), np.linspace(0, 1, 6))
    >>> V = np.stack([x.ravel(), y.ravel(), 0 * x.ravel()], 1)
    >>> i = np.arange(36).reshape(6, 6)[:-1, :-1].ravel()
    >>> F = np.concatenate([np.stack([i, i + 1, i + 7], 1), np.stack([i, i + 7, i + 6], 1)])
    >>> K = hlle_energy(V, F)
    >>> bool(np.abs(K @ (2 * V[:, 0] - V[:, 1] + 3)).max() < 1e-8)
    True
    """
    V, F = as_mesh_arrays(V, F, "hlle_energy")
    n = V.shape[0]
    if F.shape[0] == 0:
        raise MeshError("hlle_energy: empty mesh (0 faces)")
    if F.min() < 0 or F.max() >= n:
        raise MeshError(f"hlle_energy: `F` indexes vertices outside 0..{n - 1}")
    if coords not in ("projection", "chord", "normal", "intrinsic"):
        raise MeshError(
            "hlle_energy: `coords` must be 'projection', 'chord', 'normal' or 'intrinsic', "
            f"got {coords!r}"
        )
    mtype = {
        "voronoi": igl.MASSMATRIX_TYPE_VORONOI,
        "barycentric": igl.MASSMATRIX_TYPE_BARYCENTRIC,
    }.get(area)
    if mtype is None:
        raise MeshError(f"hlle_energy: `area` must be 'voronoi' or 'barycentric', got {area!r}")

    Nb = vertex_neighborhoods(n, F, min_neighbors)
    used = np.zeros(n, dtype=bool)
    used[F.ravel()] = True
    A = np.asarray(igl.massmatrix(V, F, mtype).diagonal()).ravel()
    normals = _vertex_normals(V, F)
    size = np.diff(Nb.indptr)
    Xint = _intrinsic_layout(V, F, Nb) if coords == "intrinsic" else None

    rows, cols, vals = [], [], []
    for k in np.unique(size[used]).tolist():
        if k < 2:
            continue
        verts = np.flatnonzero((size == k) & used)
        for s in range(0, len(verts), _BATCH):
            vb = verts[s : s + _BATCH]
            ent = Nb.indptr[vb][:, None] + np.arange(k)[None, :]
            idx = Nb.indices[ent].astype(np.int64)  # (b, k) sorted
            # Put the centre first (it is somewhere in the sorted row).
            pos = np.argmax(idx == vb[:, None], axis=1)
            rr = np.arange(len(vb))
            idx[rr, pos] = idx[:, 0]
            idx[:, 0] = vb
            centre_ent = ent[rr, pos]
            ent[rr, pos] = ent[:, 0]
            ent[:, 0] = centre_ent
            if Xint is not None:
                XY = Xint[ent]  # centre entry is at the origin wherever it sits
                H = _rows_from_coords(XY[:, :, 0], XY[:, :, 1], rcond)
            else:
                P = V[idx] - V[vb][:, None, :]
                H = _local_hessian_rows(P, normals[vb], coords, rcond)  # (b, 3, k)
            r = (3 * vb[:, None, None] + np.arange(3)[None, :, None]) * np.ones((1, 1, k), int)
            c = np.broadcast_to(idx[:, None, :], H.shape)
            rows.append(r.ravel())
            cols.append(c.ravel())
            vals.append(H.ravel())
    if rows:
        B = sp.csr_matrix(
            (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(3 * n, n)
        )
    else:
        B = sp.csr_matrix((3 * n, n))
    W = sp.diags(np.repeat(A, 3).astype(np.float64))
    K = (B.T @ W @ B).tocsr()
    K = (0.5 * (K + K.T)).tocsr()  # exact symmetry against rounding in the product
    if return_parts:
        return K, B, A
    return K


def curved_hessian_energy(V: ArrayLike, F: ArrayLike) -> sp.csr_matrix:
    """libigl's curved Hessian energy (Stein, Jacobson, Wardetzky, Grinspun 2020).

    Parameters
    ----------
    V : (n, 3) array_like of float
        Vertex positions.
    F : (m, 3) array_like of int
        Triangles.

    Returns
    -------
    K : (n, n) scipy.sparse.csr_matrix of float64
        Symmetric (symmetrised against rounding).  Positive semidefinite on flat and
        developable charts, whose null space contains the constants and the intrinsic
        coordinates ``(s, t)``; on doubly curved charts libigl's matrix can be indefinite
        (measured on rocker-arm charts: generalized eigenvalues down to about -35 on a
        unit-area chart).

    Raises
    ------
    MeshError
        On bad array shapes or indices.

    Examples
    --------
    >>> import numpy as np
    >>> x, y = np.meshgrid(np.arange(4.0), np.arange(4.0))
    >>> V = np.stack([x.ravel(), y.ravel(), 0 * x.ravel()], 1)
    >>> i = np.arange(16).reshape(4, 4)[:-1, :-1].ravel()
    >>> F = np.concatenate([np.stack([i, i + 1, i + 5], 1), np.stack([i, i + 5, i + 4], 1)])
    >>> K = curved_hessian_energy(V, F)
    >>> bool(np.abs(K @ V[:, 0]).max() < 1e-8 * abs(K).max())
    True
    """
    V, F = as_mesh_arrays(V, F, "curved_hessian_energy")
    n = V.shape[0]
    if F.shape[0] == 0 or F.min() < 0 or F.max() >= n:
        raise MeshError(f"curved_hessian_energy: `F` is empty or indexes outside 0..{n - 1}")
    try:
        K = igl.curved_hessian_energy(V, F)
    except RuntimeError as exc:  # pragma: no cover - libigl failure
        raise MeshError(f"curved_hessian_energy: libigl failed: {exc}") from None
    K = sp.csr_matrix(K)
    return (0.5 * (K + K.T)).tocsr()


def hessian_energy(
    V: ArrayLike, F: ArrayLike, energy: Literal["hlle", "curved"] = "hlle", **kwargs
) -> sp.csr_matrix:
    """Dispatch to :func:`hlle_energy` (``"hlle"``) or :func:`curved_hessian_energy`.

    Returns
    -------
    K : (n, n) scipy.sparse.csr_matrix
        Symmetric Hessian energy (see the two functions for definiteness).

    Examples
    --------
    >>> import numpy as np
    >>> K = hessian_energy(np.eye(3), np.array([[0, 1, 2]]), "curved")
    >>> K.shape
    (3, 3)
    """
    if energy == "hlle":
        return hlle_energy(V, F, **kwargs)
    if energy == "curved":
        return curved_hessian_energy(V, F)
    raise MeshError(f"hessian_energy: `energy` must be 'hlle' or 'curved', got {energy!r}")
