"""Sparse Cholesky factorization of the heat systems, one class for both solvers.

:class:`SparseCholesky` factors a symmetric positive definite ``A`` (the free block of
``-L``, or a patch's part of it) with libigl's ``min_quad_with_fixed`` (Eigen simplicial LLT)
or, for many right-hand sides, with CHOLMOD through ``cholespy`` (extra ``fast``).
:class:`~igl_heatseg.heat.exact.HeatSolver` uses it for the global system and
:class:`~igl_heatseg.heat.fast.FastHeatSolver` for its patch and refinement domains.
"""

from __future__ import annotations

import igl
import numpy as np
import scipy.sparse as sp

__all__ = ["SparseCholesky", "CHOLESPY_MIN_RHS"]

#: Fewest right-hand sides for which CHOLMOD (cholespy) beats libigl's LLT (see
#: :class:`SparseCholesky`).
CHOLESPY_MIN_RHS = 80


class SparseCholesky:
    """Sparse SPD factorization of ``A`` for ``nrhs`` right-hand sides (a hint).

    Two backends, measured on this project's systems: libigl's ``min_quad_with_fixed`` (Eigen
    simplicial LLT) factors 2.6-4x faster than CHOLMOD through ``cholespy`` (iron.ply,
    80k free vertices: 0.35 s vs 0.92 s; a 5k-vertex patch: 6-10 ms vs 25-30 ms) but solves
    3-5x slower per right-hand side (8 ms vs 1.7 ms; 0.4 ms vs 0.15 ms).  Below
    :data:`CHOLESPY_MIN_RHS` right-hand sides libigl wins; cholespy (extra ``fast``) is
    used above it when installed.

    Parameters
    ----------
    A : (N, N) sparse
        Symmetric positive definite.
    nrhs : int
        How many right-hand sides will be solved in all (chooses the backend).

    Raises
    ------
    RuntimeError
        If the factorization fails (from the backend).

    Examples
    --------
    >>> import scipy.sparse as sp, numpy as np
    >>> fac = SparseCholesky(sp.diags([2.0, 4.0]).tocsc())
    >>> fac.backend, fac.solve(np.array([2.0, 2.0])).tolist()
    ('libigl', [1.0, 0.5])
    """

    def __init__(self, A: sp.spmatrix, nrhs: int = 1) -> None:
        self.n = A.shape[0]
        cholespy = None
        if nrhs >= CHOLESPY_MIN_RHS:
            try:
                import cholespy
            except ImportError:  # soft dependency (extra "fast")
                cholespy = None
        self._chol = None
        self._igl = None
        if cholespy is not None:
            A = sp.csr_matrix(A)
            A.sort_indices()
            self._chol = cholespy.CholeskySolverD(
                self.n,
                A.indptr.astype(np.int32),
                A.indices.astype(np.int32),
                np.ascontiguousarray(A.data, dtype=np.float64),
                cholespy.MatrixType.CSR,
            )
        else:
            self._igl = igl.min_quad_with_fixed_data()
            igl.min_quad_with_fixed_precompute(
                sp.csc_matrix(A),
                np.zeros(0, dtype=np.int64),
                sp.csc_matrix((0, self.n)),
                True,
                self._igl,
            )

    @property
    def backend(self) -> str:
        """``"cholespy"`` or ``"libigl"``."""
        return "cholespy" if self._chol is not None else "libigl"

    def solve(self, B: np.ndarray) -> np.ndarray:
        """Solve ``A X = B`` for ``B`` of shape (n,) or (n, r)."""
        B = np.ascontiguousarray(B, dtype=np.float64)
        if self._chol is not None:
            X = np.empty_like(B)
            self._chol.solve(B, X)
            return X
        B2 = B.reshape(self.n, -1)
        r = B2.shape[1]
        X = igl.min_quad_with_fixed_solve(self._igl, -B2, np.zeros((0, r)), np.zeros((0, r)))
        return np.asarray(X).reshape(B.shape)
