"""Harmonic "temperature" fields, one per seed group (paper §3.2), and their argmax (§3.3).

For group ``i``: ``L_ff u_f = -L_fs u_s`` with ``u_s = 1`` on ``S_i`` and ``0`` on every other
group.  The Dirichlet set (all seeds) is the same for every ``i``: with ``A = -L_ff`` (positive
definite once every component holds a seed) the system ``A u_f = L_fs 1_{S_i}`` is factored
once (:class:`~igl_heatseg.heat.factor.SparseCholesky`) and solved for batches of right-hand
sides.  The paper's ``3/A_i`` row scaling of ``L`` is left out: it multiplies each row of the
system by a positive constant and does not change the solution.

Memory stays bounded: fields are produced in batches of columns and reduced on the fly to the
per-vertex and per-face argmax, never kept as a dense ``n x k`` matrix.  The same streaming
argmax serves :class:`HeatSolver` (all groups, every vertex and face) and the exact fallback of
:class:`~igl_heatseg.heat.fast.FastHeatSolver` (a few groups at a few vertices and faces).
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import NamedTuple

import igl
import numpy as np
import scipy.sparse as sp

from ..constants import HEAT_SUM_TOL, TIE_RTOL
from ..mesh.topology import vertex_components
from .factor import SparseCholesky

__all__ = [
    "HeatSolver",
    "HeatSystem",
    "HeatLabels",
    "heat_fields",
    "corner_means",
    "argmax_update",
    "argmax_update_ids",
    "seed_face_labels",
    "require_seeded_components",
    "SOLVE_BATCH",
]

log = logging.getLogger(__name__)

#: Right-hand sides per global solve (cholespy's multi-RHS solve is fastest per column at
#: 16-32 columns; 256 at once is 2.7x slower per column, measured).  Dense work arrays per
#: batch are ``(2n + m) x SOLVE_BATCH`` float64 at most.
SOLVE_BATCH = 32


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


class PartialArgmax(NamedTuple):
    """Exact argmax over some groups at some free vertices and faces (:meth:`HeatSolver.argmax`).

    ``vertex_labels``, ``vertex_max`` (one per vertex asked), ``face_labels`` (one per face
    asked), and ``error``: ``max |sum_i u_i - 1|`` over the free vertices when all groups were
    solved, else the largest relative residual ``|A X - B| / |B|`` of the solves.
    """

    vertex_labels: np.ndarray
    vertex_max: np.ndarray
    face_labels: np.ndarray
    error: float


class HeatSystem:
    """The Dirichlet problem of one seed set, factored on first use.

    ``A = -L_ff`` on the free vertices ``f`` and ``B[:, i] = L_fs 1_{S_i}``: the field of
    group ``i`` on the free vertices solves ``A u = B[:, i]``.  Shared by the exact solver and
    the fast solver (whose patch and refinement domains are blocks of ``A`` and ``B``).

    Parameters
    ----------
    V : (n, 3) float64
    F : (m, 3) int64
    group : (n,) int64
        Seed group of each vertex, ``0..k-1``, or ``-1`` for a free vertex.
    L : (n, n) sparse, optional
        Cotangent Laplacian (``igl.cotmatrix``); computed if not given.

    Attributes
    ----------
    n, k, nf : int
        Vertices, groups, free vertices.
    group, known, free : int64 arrays
        Seed group per vertex, seed vertex ids, free vertex ids.
    fidx : (n,) int64
        Free index of each vertex, ``-1`` at seeds.
    A : (nf, nf) csr_matrix
    B : (nf, k) csc_matrix
    factor_s : float or None
        Seconds spent in the global factorization, once done.

    Raises
    ------
    ValueError
        If some connected component holds no seed.
    """

    def __init__(
        self, V: np.ndarray, F: np.ndarray, group: np.ndarray, L: sp.spmatrix | None = None
    ) -> None:
        self.n = V.shape[0]
        self.group = np.asarray(group, dtype=np.int64)
        self.known = np.flatnonzero(self.group >= 0)
        self.k = int(self.group.max()) + 1 if len(self.known) else 0
        require_seeded_components(self.n, F, self.known)
        if L is None:
            L = igl.cotmatrix(V, F)
        self.L = sp.csr_matrix(L)
        self.free = np.flatnonzero(self.group < 0)
        self.nf = len(self.free)
        self.fidx = np.full(self.n, -1, dtype=np.int64)
        self.fidx[self.free] = np.arange(self.nf)
        Lf = self.L[self.free]
        self.A = sp.csr_matrix(-Lf[:, self.free])  # A_ff, (nf, nf), SPD
        # B[:, i] = L_fs 1_{S_i}: right-hand side of group i, (nf, k) sparse.
        G = sp.csr_matrix(
            (np.ones(len(self.known)), (np.arange(len(self.known)), self.group[self.known])),
            shape=(len(self.known), self.k),
        )
        self.B = sp.csc_matrix(Lf[:, self.known] @ G)
        self._factor: SparseCholesky | None = None
        self.factor_s: float | None = None

    def factor(self, nrhs: int = 1) -> SparseCholesky:
        """The factorization of ``A``, built on the first call (``nrhs`` picks the backend)."""
        if self._factor is None:
            t = time.perf_counter()
            try:
                self._factor = SparseCholesky(self.A, nrhs)
            except RuntimeError as exc:
                raise ValueError(
                    f"factorization of the heat system failed ({len(self.known)} seeds, "
                    f"{self.nf} free vertices): {exc}"
                ) from exc
            self.factor_s = time.perf_counter() - t
        return self._factor

    def seed_values(self, vertices: np.ndarray, groups: np.ndarray) -> np.ndarray:
        """Fields of ``groups`` at seed ``vertices``: 1 for their own group, else 0."""
        return (self.group[vertices][:, None] == groups[None, :]).astype(np.float64)

    def free_fields(self, groups: np.ndarray, nrhs: int = 1) -> np.ndarray:
        """Exact fields of ``groups`` on the free vertices, shape (nf, len(groups)).

        ``nrhs``: how many fields will be asked for in all (chooses the factorization).
        """
        if self.nf == 0 or len(groups) == 0:
            return np.zeros((self.nf, len(groups)))
        return self.factor(max(nrhs, len(groups))).solve(self.B[:, groups].toarray())

    def temperatures(self, groups: Sequence[int], nrhs: int = 1) -> np.ndarray:
        """Exact fields of ``groups`` at every vertex, shape (n, len(groups))."""
        groups = np.asarray(groups, dtype=np.int64).reshape(-1)
        U = np.zeros((self.n, len(groups)))
        U[self.known] = self.seed_values(self.known, groups)
        U[self.free] = self.free_fields(groups, nrhs)
        return U


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
    system : HeatSystem, optional
        The problem, already built (then ``V``'s size, ``group`` and ``L`` are taken from
        it); its factorization is reused if done.
    nrhs : int, optional
        How many fields will be solved in all (picks the factorization; default ``k``).

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
        self,
        V: np.ndarray,
        F: np.ndarray,
        group: np.ndarray,
        L: sp.spmatrix | None = None,
        *,
        system: HeatSystem | None = None,
        nrhs: int | None = None,
    ) -> None:
        self.V, self.F = V, F
        self.system = HeatSystem(V, F, group, L) if system is None else system
        s = self.system
        self.n, self.k, self.group, self.known, self.L = s.n, s.k, s.group, s.known, s.L
        self.nrhs = s.k if nrhs is None else int(nrhs)
        if s.nf:
            s.factor(self.nrhs)

    def temperatures(self, groups: Sequence[int]) -> np.ndarray:
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
        return self.system.temperatures(groups, self.nrhs)

    def temperature(self, i: int) -> np.ndarray:
        """One temperature field ``u_i``, shape (n,)."""
        return self.temperatures([i])[:, 0]

    def labels(self, progress: Callable[[float], None] | None = None) -> HeatLabels:
        """Argmax labels over all groups, streaming batches of fields.

        Seeds are labelled by their group (value exactly 1, all others 0); faces whose
        corners are all seeds by :func:`seed_face_labels`.

        Parameters
        ----------
        progress : callable, optional
            Called with the fraction of groups done, in ``(0, 1]``.

        Returns
        -------
        HeatLabels
        """
        s, F = self.system, self.F
        has_free = (s.fidx[F] >= 0).any(axis=1)
        hf = np.flatnonzero(has_free)
        r = self._stream(np.arange(s.k), None, hf, progress)
        face_labels = np.zeros(F.shape[0], dtype=np.int64)
        face_labels[hf] = r.face_labels
        allseed = np.flatnonzero(~has_free)
        if len(allseed):  # exact: corner counts / 3, ties to the lowest id
            face_labels[allseed] = seed_face_labels(s.group[F[allseed]])
        vertex_labels = s.group.copy()
        vertex_labels[s.free] = r.vertex_labels
        vertex_max = np.ones(s.n)
        vertex_max[s.free] = r.vertex_max
        if r.error > HEAT_SUM_TOL:
            log.warning(
                "heat fields sum to 1 only within %.3g (tolerance %.1g)", r.error, HEAT_SUM_TOL
            )
        return HeatLabels(
            vertex_labels=vertex_labels,
            face_labels=face_labels,
            vertex_max=vertex_max,
            sum_error=r.error,
        )

    def argmax(self, groups: np.ndarray, vertices: np.ndarray, faces: np.ndarray) -> PartialArgmax:
        """Exact argmax over a few groups at a few free vertices and faces.

        Parameters
        ----------
        groups : (c,) int64
            Increasing group ids; ties go to the lowest.
        vertices : (a,) int64
            Free indices (rows of ``system.A``).
        faces : (b,) int64
            Face ids.

        Returns
        -------
        PartialArgmax
            ``error`` is the largest relative residual of the solves.
        """
        return self._stream(np.asarray(groups, dtype=np.int64), vertices, faces, None)

    def _stream(self, groups, vertices, faces, progress) -> PartialArgmax:
        """Solve ``groups`` in batches of :data:`SOLVE_BATCH` and fold them into running
        argmaxes at ``vertices`` (free indices; ``None``: all, and the sum check) and
        ``faces``.

        A face is only re-evaluated for a batch if some corner's batch maximum beats the
        face's best mean so far (a mean never exceeds the largest corner value), so after
        the first batches each batch touches few faces: no ``m x batch`` work per batch.
        """
        s, F = self.system, self.F
        full = vertices is None
        nv = s.nf if full else len(vertices)
        best_v = np.full(nv, -np.inf)
        arg_v = np.zeros(nv, dtype=np.int64)
        Fh = F[faces]
        best_f = np.full(len(faces), -np.inf)
        arg_f = np.zeros(len(faces), dtype=np.int64)
        # rows of the corner values: every vertex (all faces), or the faces' corners
        need = np.arange(s.n) if full else np.unique(Fh.ravel())
        pos = np.full(s.n, -1, dtype=np.int64)
        pos[need] = np.arange(len(need))
        isf = s.fidx[need] >= 0
        need_f, need_s = s.fidx[need[isf]], need[~isf]
        usum = np.zeros(s.nf) if full else None
        resid = 0.0
        vm = np.zeros(s.n)
        in_batch = np.zeros(s.k, dtype=bool)
        for j0 in range(0, len(groups), SOLVE_BATCH):
            gs = groups[j0 : j0 + SOLVE_BATCH]
            X = s.free_fields(gs, len(groups))  # (nf, b)
            if full:
                usum += X.sum(axis=1)
            else:
                Bg = s.B[:, gs].toarray()
                bn = np.abs(Bg).max() if Bg.size else 0.0
                if bn > 0:
                    resid = max(resid, float(np.abs(s.A @ X - Bg).max() / bn))
            argmax_update_ids(X if full else X[vertices], gs, best_v, arg_v)
            in_batch[gs] = True
            vm[s.free] = X.max(axis=1)
            vm[s.known] = in_batch[s.group[s.known]]
            in_batch[gs] = False
            cmax = np.maximum(np.maximum(vm[Fh[:, 0]], vm[Fh[:, 1]]), vm[Fh[:, 2]])
            sel = np.flatnonzero(cmax > best_f)
            if len(sel):
                U = np.empty((len(need), len(gs)))
                U[isf] = X if full else X[need_f]  # full: need_f is 0..nf-1
                U[~isf] = s.seed_values(need_s, gs)
                best, arg = best_f[sel], arg_f[sel]
                argmax_update_ids(corner_means(U, pos[Fh[sel]]), gs, best, arg)
                best_f[sel] = best
                arg_f[sel] = arg
            if progress is not None:
                progress((j0 + len(gs)) / len(groups))
        if full:
            resid = float(np.abs(usum - 1.0).max()) if s.nf else 0.0
        return PartialArgmax(arg_v, best_v, arg_f, resid)


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


def argmax_update(U: np.ndarray, offset: int, best: np.ndarray, arg: np.ndarray) -> None:
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


def argmax_update_ids(U: np.ndarray, gids: np.ndarray, best: np.ndarray, arg: np.ndarray) -> None:
    """Running argmax over columns with increasing group ids ``gids``; lower ids win ties
    (within :data:`~igl_heatseg.constants.TIE_RTOL`, as :func:`argmax_update`)."""
    if U.shape[0] == 0:
        return
    pos = np.full(len(best), -1, dtype=np.int64)  # column that improved each row, or -1
    argmax_update(U, 0, best, pos)
    upd = pos >= 0
    arg[upd] = gids[pos[upd]]


def seed_face_labels(Gc: np.ndarray) -> np.ndarray:
    """Face label of faces whose three corners are seeds: the group with most corners.

    ``Gc`` (r, 3) corner groups.  Ties (three different groups) go to the lowest id, as the
    exact argmax of the corner means (1/3 each) does.

    Examples
    --------
    >>> seed_face_labels(np.array([[3, 3, 1], [4, 2, 9]])).tolist()
    [3, 2]
    """
    a, b, c = Gc[:, 0], Gc[:, 1], Gc[:, 2]
    lab = np.minimum(np.minimum(a, b), c)
    lab = np.where(b == c, b, lab)
    lab = np.where(a == c, a, lab)
    lab = np.where(a == b, a, lab)
    return lab


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
