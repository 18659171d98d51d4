"""Harmonic "temperature" fields, one per seed group (paper §3.2), and their argmax (§3.3).

For group ``i``: ``L_ff u_f = -L_fs u_s`` with ``u_s = 1`` on ``S_i`` and ``0`` on every other
group.  The Dirichlet set (all seeds) is the same for every ``i``: the system is factored once
(libigl ``min_quad_with_fixed_precompute`` on the positive semidefinite ``-L``) and solved for
batches of right-hand sides.  The paper's ``3/A_i`` row scaling of ``L`` is left out: it
multiplies each row of the system by a positive constant and does not change the solution.

Memory stays bounded: fields are produced in batches of columns and reduced on the fly to the
per-vertex and per-face argmax, never kept as a dense ``n x k`` matrix.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from dataclasses import dataclass

import igl
import numpy as np
import scipy.sparse as sp

from ..constants import HEAT_SUM_TOL, TIE_RTOL
from ..mesh.topology import vertex_components

__all__ = ["HeatSolver", "HeatLabels", "heat_fields"]

log = logging.getLogger(__name__)

#: Dense work arrays per batch are about ``(n + m) * batch * 8`` bytes; keep them near this size.
_BATCH_BYTES = 256 * 2**20


@dataclass(frozen=True)
class HeatLabels:
    """Per-vertex and per-face argmax of the temperature fields.

    Attributes
    ----------
    vertex_labels : (n,) int64
        ``argmax_i u_i(v)``; ties go to the lowest group id.
    face_labels : (m,) int64
        ``argmax_i`` of the mean of ``u_i`` over the face's corners (temperature at centroid).
    vertex_max : (n,) float64
        The winning temperature at each vertex.
    sum_error : float
        ``max_v |sum_i u_i(v) - 1|`` (0 up to round-off for an exact solve).
    """

    vertex_labels: np.ndarray
    face_labels: np.ndarray
    vertex_max: np.ndarray
    sum_error: float


class HeatSolver:
    """Factor the Dirichlet problem once for a fixed seed set, then solve per group.

    Parameters
    ----------
    V : (n, 3) float64
    F : (m, 3) int64
        Validated mesh.
    group : (n,) int64
        Seed group of each vertex, ``0..k-1``, or ``-1`` for a free vertex.  Every connected
        component of the mesh must hold at least one seed (otherwise its free block is
        singular).
    L : (n, n) sparse, optional
        Cotangent Laplacian as from ``igl.cotmatrix`` (negative semidefinite).  Computed if
        not given.

    Raises
    ------
    ValueError
        If some component holds no seed, or the factorization fails.

    Examples
    --------
    >>> import igl, numpy as np
    >>> V, F = igl.triangulated_grid(5, 5)
    >>> V = np.c_[V, np.zeros(len(V))]
    >>> group = -np.ones(len(V), dtype=np.int64); group[0] = 0; group[-1] = 1
    >>> solver = HeatSolver(V, F, group)
    >>> u = solver.temperatures([0, 1])
    >>> bool(np.allclose(u.sum(axis=1), 1.0))
    True
    """

    def __init__(
        self, V: np.ndarray, F: np.ndarray, group: np.ndarray, L: sp.spmatrix | None = None
    ) -> None:
        self.V, self.F = V, F
        self.n = V.shape[0]
        self.group = np.asarray(group, dtype=np.int64)
        self.known = np.flatnonzero(self.group >= 0)
        self.k = int(self.group.max()) + 1 if len(self.known) else 0
        require_seeded_components(self.n, F, self.known)
        if L is None:
            L = igl.cotmatrix(V, F)
        self.L = L
        A = sp.csc_matrix(-L)
        self._data = igl.min_quad_with_fixed_data()
        try:
            igl.min_quad_with_fixed_precompute(
                A, self.known, sp.csc_matrix((0, self.n)), True, self._data
            )
        except RuntimeError as exc:
            raise ValueError(
                f"factorization of the heat system failed ({len(self.known)} seeds, "
                f"{self.n - len(self.known)} free vertices): {exc}"
            ) from exc
        self._known_group = self.group[self.known]

    def temperatures(self, groups) -> np.ndarray:
        """Temperature fields of the given groups.

        Parameters
        ----------
        groups : sequence of int
            Group ids in ``0..k-1``.

        Returns
        -------
        U : (n, len(groups)) float64
            ``U[:, j]`` is 1 on the seeds of ``groups[j]``, 0 on every other seed, harmonic
            (``L u = 0``) on free vertices; values in ``[0, 1]`` by the maximum principle
            (for cotangent weights that are non-negative).
        """
        groups = np.asarray(groups, dtype=np.int64)
        Y = (self._known_group[:, None] == groups[None, :]).astype(np.float64)
        B = np.zeros((self.n, len(groups)))
        return igl.min_quad_with_fixed_solve(self._data, B, Y, np.zeros((0, len(groups))))

    def temperature(self, i: int) -> np.ndarray:
        """One temperature field ``u_i``, shape (n,)."""
        return self.temperatures([i])[:, 0]

    def labels(self, progress: Callable[[float], None] | None = None) -> HeatLabels:
        """Argmax labels over all groups, streaming batches of fields.

        Parameters
        ----------
        progress : callable, optional
            Called with the fraction of groups done, in ``(0, 1]``.

        Returns
        -------
        HeatLabels
        """
        n, F = self.n, self.F
        m = F.shape[0]
        batch = int(np.clip(_BATCH_BYTES // (8 * (2 * n + m)), 1, 512))
        vmax = np.full(n, -np.inf)
        varg = np.zeros(n, dtype=np.int64)
        fmax = np.full(m, -np.inf)
        farg = np.zeros(m, dtype=np.int64)
        usum = np.zeros(n)
        for g0 in range(0, self.k, batch):
            g1 = min(self.k, g0 + batch)
            U = self.temperatures(np.arange(g0, g1))
            usum += U.sum(axis=1)
            _argmax_update(U, g0, vmax, varg)
            Uf = corner_means(U, F)
            _argmax_update(Uf, g0, fmax, farg)
            if progress is not None:
                progress(g1 / self.k)
        err = float(np.abs(usum - 1.0).max()) if n else 0.0
        if err > HEAT_SUM_TOL:
            log.warning("heat fields sum to 1 only within %.3g (tolerance %.1g)", err, HEAT_SUM_TOL)
        return HeatLabels(vertex_labels=varg, face_labels=farg, vertex_max=vmax, sum_error=err)


def corner_means(U: np.ndarray, F: np.ndarray) -> np.ndarray:
    """Mean of per-vertex values over each face's corners.

    Parameters
    ----------
    U : (n, c) float64
        Values per vertex (one column per field).
    F : (r, 3) int64
        Faces (indices into the rows of ``U``).

    Returns
    -------
    (r, c) float64
        ``(U[a] + U[b] + U[c]) / 3`` with that rounding, summed in place (2x faster than the
        expression on 168k faces x 32 fields).  Both heat solvers take face labels from it,
        so that they round face means, and so decide ties, identically.
    """
    out = U[F[:, 0]]
    out += U[F[:, 1]]
    out += U[F[:, 2]]
    out /= 3.0
    return out


def require_seeded_components(n: int, F: np.ndarray, known: np.ndarray) -> None:
    """Check that every connected component holds a Dirichlet (seed) vertex.

    Parameters
    ----------
    n : int
        Vertex count.
    F : (m, 3) int64
    known : (s,) int64
        Seed vertex ids.

    Raises
    ------
    ValueError
        Naming how many components hold no seed and one vertex of the first; their free
        block of the Laplacian is singular.
    """
    ncomp, comp = vertex_components(n, F)
    seeded = np.zeros(ncomp, dtype=bool)
    seeded[comp[known]] = True
    if not seeded.all():
        bad = np.flatnonzero(~seeded)
        raise ValueError(
            f"{len(bad)} connected component(s) hold no seed vertex (e.g. the one with "
            f"vertex {int(np.flatnonzero(comp == bad[0])[0])}); their heat problem is "
            "singular"
        )


def _argmax_update(U: np.ndarray, offset: int, best: np.ndarray, arg: np.ndarray) -> None:
    """Fold a batch of columns into a running argmax; earlier (lower) ids win ties.

    Values within :data:`~igl_heatseg.constants.TIE_RTOL` (relative) of the largest count
    as tied, so that the lowest id wins an exact tie whatever the round-off of the solve.
    """
    if U.shape[0] == 0 or U.shape[1] == 0:
        return
    top = U.max(axis=1)
    j = (U >= (top - TIE_RTOL * np.abs(top))[:, None]).argmax(axis=1)  # first near-maximum
    val = U[np.arange(U.shape[0]), j]
    upd = val > best + TIE_RTOL * np.abs(np.where(np.isfinite(best), best, 0.0))
    best[upd] = val[upd]
    arg[upd] = j[upd] + offset


def heat_fields(V: np.ndarray, F: np.ndarray, group: np.ndarray) -> np.ndarray:
    """All temperature fields at once (one-off wrapper; dense, for small ``k`` only).

    Parameters
    ----------
    V : (n, 3) float64
    F : (m, 3) int64
    group : (n,) int64
        Seed group per vertex, ``-1`` for free vertices.

    Returns
    -------
    U : (n, k) float64
        Rows sum to 1.

    See Also
    --------
    HeatSolver : factor once, solve per group, streaming argmax without an ``n x k`` matrix.
    """
    solver = HeatSolver(V, F, group)
    return solver.temperatures(np.arange(solver.k))
