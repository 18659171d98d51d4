"""Hessian eigenmaps: lowest eigenpairs of ``K y = lambda M y``, Gram correction, the map.

ALGORITHM.md section 6; paper §3.6:

1. Hessian energy ``K`` (:mod:`igl_heatseg.parameterization.hessian`, ``"hlle"`` or
   ``"curved"``) and the Voronoi mass matrix ``M``; lowest eigenpairs of ``K y = lambda M y``
   (:func:`lowest_eigenpairs`: shift-invert Lanczos with a slightly negative shift, LOBPCG if
   ARPACK fails, dense ``eigh`` on small charts).  The constant is removed by M-centring the
   eigenvectors and dropping the direction it occupied.
2. Gram (affine) correction (:func:`gram_correction`).  The eigenvectors ``Y`` are an affine
   image of an isometric layout, so ``l_e^2 ~ d_e^T G d_e`` for every edge ``e`` (``d_e`` the
   edge in eigen coordinates, ``G`` symmetric).  ``G`` is fitted by least squares with relative
   weights (equations divided by ``l_e^2``) and the map is ``Y G^(1/2)``.  When the numerical
   null space has dimension ``d > 2`` (relative eigenvalues below :data:`NULLSPACE_TOL`, e.g.
   tiny charts) the same fit is done for a ``d x d`` ``G`` over all ``d`` null vectors and its
   best rank-2 part is used, which reduces to the 2 x 2 correction when ``d = 2``.
"""

from __future__ import annotations

import logging
from typing import Literal

import igl
import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ..errors import MeshError
from .hessian import curved_hessian_energy, hlle_energy
from .prepare import unique_edges

__all__ = [
    "hessian_map",
    "gram_correction",
    "lowest_eigenpairs",
    "mass_diagonal",
    "NULLSPACE_TOL",
    "EIGEN_SHIFT",
    "DENSE_EIGEN_MAX",
    "EXTRA_EIGENPAIRS",
    "MAX_NULL_DIM",
]

log = logging.getLogger(__name__)

#: Generalized eigenvalues at or below ``NULLSPACE_TOL * max(|computed eigenvalues|)`` are
#: "null": beyond the constant and two coordinates, such eigenvectors join the Gram fit (null
#: space of dimension > 3, e.g. on tiny charts).
NULLSPACE_TOL: float = 1e-8

#: Shift of the shift-invert Lanczos solve, ``sigma = -EIGEN_SHIFT`` (unit-area chart): just
#: below the zero eigenvalues so that ``K - sigma M`` is positive definite.
EIGEN_SHIFT: float = 1e-4

#: Charts with at most this many vertices use a dense generalized eigen-solve.
DENSE_EIGEN_MAX: int = 600

#: Eigenpairs computed beyond the constant and the two coordinates (to detect a larger null
#: space).
EXTRA_EIGENPAIRS: int = 3

#: Largest null-space dimension used in the generalized Gram fit.
MAX_NULL_DIM: int = 6


def mass_diagonal(V: np.ndarray, F: np.ndarray) -> np.ndarray:
    """Diagonal of the Voronoi mass matrix (barycentric where a Voronoi area is not positive).

    Examples
    --------
    >>> import numpy as np
    >>> x, y = np.meshgrid(np.arange(4.0), np.arange(4.0))
    >>> V = np.stack([x.ravel(), y.ravel(), 0 * x.ravel()], 1)
    >>> i = np.arange(16).reshape(4, 4)[:-1, :-1].ravel()
    >>> F = np.concatenate([np.stack([i, i + 1, i + 5], 1), np.stack([i, i + 5, i + 4], 1)])
    >>> round(float(mass_diagonal(V, F).sum()), 12)  # the chart's area
    9.0
    """
    m = np.asarray(igl.massmatrix(V, F, igl.MASSMATRIX_TYPE_VORONOI).diagonal()).ravel()
    if not np.all(m > 0):
        m = np.asarray(igl.massmatrix(V, F, igl.MASSMATRIX_TYPE_BARYCENTRIC).diagonal()).ravel()
    return m


def lowest_eigenpairs(
    K: sp.spmatrix, m: np.ndarray, k: int, psd: bool = True
) -> tuple[np.ndarray, np.ndarray]:
    """Lowest ``k`` eigenpairs of ``K y = lambda diag(m) y`` (eigenvectors M-orthonormal).

    Dense ``eigh`` for small charts; otherwise shift-invert Lanczos (``eigsh``) around
    ``-EIGEN_SHIFT`` with one sparse LU of ``K + EIGEN_SHIFT M`` in symmetric mode (minimum
    degree ordering on ``A + A^T``: 3x less fill than the default column ordering on HLLE's
    4-ring sparsity), LOBPCG if ARPACK fails.  ``psd=False`` (a matrix that may be
    indefinite, as libigl's curved Hessian on doubly curved charts) allows threshold pivoting
    (0.1, still preferring the diagonal; without symmetric mode SuperLU's minimum degree
    ordering was 40x slower on a 25k-vertex chart).

    Examples
    --------
    >>> import numpy as np, scipy.sparse as sp
    >>> lam, Y = lowest_eigenpairs(sp.diags([3.0, 1.0, 2.0]), np.ones(3), 2)
    >>> lam.tolist()
    [1.0, 2.0]
    """
    n = K.shape[0]
    k = min(k, n)
    if n <= DENSE_EIGEN_MAX:
        # Only the k wanted pairs (LAPACK sygvx): 2x faster than all of them on a 492-vertex
        # chart (0.017 vs 0.036 s).  The standard form D^-1/2 K D^-1/2 was faster still
        # (0.010 s) but, on the 119 charts of <= 600 vertices of 18 meshes, turned one
        # cut flat annulus (psb_352_bearing chart 3, seams touching at rounding level) from
        # a bijective Hessian map into a fallback; this solve matches the full one there.
        return sla.eigh(K.toarray(), np.diag(m), subset_by_index=[0, k - 1])
    M = sp.diags(m).tocsc()
    A = (K + EIGEN_SHIFT * M).tocsc()
    lu = spla.splu(
        A,
        permc_spec="MMD_AT_PLUS_A",
        diag_pivot_thresh=0.0 if psd else 0.1,
        options={"SymmetricMode": True},
    )
    OP = spla.LinearOperator((n, n), matvec=lu.solve, dtype=np.float64)
    try:
        # Fixed start vector: ARPACK's default one comes from a generator whose state depends
        # on earlier calls in the process, so the eigenvectors' signs (and the maps' rigid
        # motions) changed from run to run.
        v0 = np.random.default_rng(0).standard_normal(n)
        lam, Y = spla.eigsh(
            K.tocsc(), k=k, M=M, sigma=-EIGEN_SHIFT, which="LM", OPinv=OP, tol=0.0, v0=v0
        )
    except (RuntimeError, spla.ArpackNoConvergence) as exc:
        log.warning("eigsh failed (%s); retrying with LOBPCG", exc)
        X0 = np.random.default_rng(0).standard_normal((n, k))
        lam, Y = spla.lobpcg(K, X0, B=M, M=OP, largest=False, tol=1e-10, maxiter=500)
    order = np.argsort(lam)
    return lam[order], Y[:, order]


def gram_correction(Y: np.ndarray, V: np.ndarray, F: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Affine (Gram) correction of eigen-coordinates to an isometric-as-possible layout.

    Fits a symmetric ``G`` (d x d) with ``l_e^2 ~ d_e^T G d_e`` over the edges (least squares,
    each equation divided by ``l_e^2``) and returns ``Y C`` with ``C C^T`` the best rank-2
    positive part of ``G`` (``C = G^(1/2)`` for ``d = 2``, up to a rotation).

    Parameters
    ----------
    Y : (n, d) float64
        Eigen-coordinates, ``d >= 2``.
    V : (n, 3) float64
        Vertex positions (edge lengths ``l_e``).
    F : (m, 3) int64
        Triangles.

    Returns
    -------
    UV : (n, 2) float64
        Corrected coordinates (unit: those of ``V``).
    G : (d, d) float64
        The fitted Gram matrix.

    Examples
    --------
    >>> import numpy as np
    >>> x, y = np.meshgrid(np.arange(4.0), np.arange(4.0))
    >>> V = np.stack([x.ravel(), y.ravel(), 0 * x.ravel()], 1)
    >>> i = np.arange(16).reshape(4, 4)[:-1, :-1].ravel()
    >>> F = np.concatenate([np.stack([i, i + 1, i + 5], 1), np.stack([i, i + 5, i + 4], 1)])
    >>> UV, G = gram_correction(V[:, :2] @ [[2.0, 1.0], [0.0, 1.0]], V, F)  # an affine image
    >>> bool(np.allclose(np.linalg.norm(UV[1] - UV[0]), 1.0))
    True
    """
    E = unique_edges(F)
    D = Y[E[:, 1]] - Y[E[:, 0]]  # (ne, d)
    l2 = ((V[E[:, 1]] - V[E[:, 0]]) ** 2).sum(axis=1)
    d = Y.shape[1]
    iu, ju = np.triu_indices(d)
    coef = D[:, iu] * D[:, ju] * np.where(iu == ju, 1.0, 2.0)[None, :]
    w = 1.0 / l2
    sol, *_ = np.linalg.lstsq(coef * w[:, None], l2 * w, rcond=None)
    G = np.zeros((d, d))
    G[iu, ju] = sol
    G[ju, iu] = sol
    gl, gv = np.linalg.eigh(G)
    top = np.argsort(gl)[::-1][:2]
    gl2 = np.maximum(gl[top], 0.0)
    C = gv[:, top] * np.sqrt(gl2)[None, :]
    return Y @ C, G


def hessian_map(
    V: np.ndarray,
    F: np.ndarray,
    energy: Literal["hlle", "curved"] = "hlle",
    **energy_kwargs,
) -> tuple[np.ndarray, np.ndarray, int]:
    """Hessian eigenmap of a (unit-area, disk) chart, Gram-corrected.

    Parameters
    ----------
    V : (n, 3) float64
        Compact chart vertices (every vertex used by ``F``).
    F : (m, 3) int64
        Triangles.
    energy : {"hlle", "curved"}
        :func:`~igl_heatseg.parameterization.hessian.hlle_energy` or
        :func:`~igl_heatseg.parameterization.hessian.curved_hessian_energy`.

    Returns
    -------
    UV : (n, 2) float64
        Layout, not yet certified, orientation arbitrary.
    eigenvalues : (k,) float64
        Lowest generalized eigenvalues (the constant's included).
    null_dim : int
        Number of non-constant eigenvectors used in the Gram fit (2, or more when the
        numerical null space is larger).

    Examples
    --------
    >>> import numpy as np
    >>> x, y = np.meshgrid(np.arange(4.0), np.arange(4.0))
    >>> V = np.stack([x.ravel(), y.ravel(), 0 * x.ravel()], 1)
    >>> i = np.arange(16).reshape(4, 4)[:-1, :-1].ravel()
    >>> F = np.concatenate([np.stack([i, i + 1, i + 5], 1), np.stack([i, i + 5, i + 4], 1)])
    >>> UV, lam, null_dim = hessian_map(V / 3, F)  # unit area
    >>> null_dim, bool(np.isclose(np.linalg.norm(UV[1] - UV[0]), 1 / 3))
    (2, True)
    """
    n = V.shape[0]
    if energy == "hlle":
        K = hlle_energy(V, F, **energy_kwargs)
    elif energy == "curved":
        K = curved_hessian_energy(V, F)
    else:
        raise MeshError(f"hessian_map: `energy` must be 'hlle' or 'curved', got {energy!r}")
    m = mass_diagonal(V, F)
    lam, Y = lowest_eigenpairs(K, m, 3 + EXTRA_EIGENPAIRS, psd=energy == "hlle")
    null = int(np.count_nonzero(lam <= NULLSPACE_TOL * max(np.abs(lam).max(), 1e-300)))
    keep = min(max(3, null), MAX_NULL_DIM + 1, n)
    Yk = Y[:, :keep]
    # Remove the constant: M-centre, then keep the keep-1 dominant directions (M-weighted).
    Yk = Yk - (m @ Yk)[None, :] / m.sum()
    sq = np.sqrt(m)[:, None]
    U, s, Wt = np.linalg.svd(sq * Yk, full_matrices=False)
    basis = U[:, : keep - 1] / sq
    if keep - 1 < 2:
        basis = np.column_stack([basis, np.zeros(n)])
    UV, _ = gram_correction(basis, V, F)
    return UV, lam, keep - 1
