"""Fast heat-field labels for meshes with thousands of seed groups (issue 5).

:class:`FastHeatSolver` has :class:`~igl_heatseg.heat.exact.HeatSolver`'s interface and returns the
same argmax labels, but never solves one global system per group.

The problem (ALGORITHM.md §2): with ``A = -L`` (``L = igl.cotmatrix``, negative
semidefinite) and ``f`` the free vertices, ``A_ff u_i = L_fs 1_{S_i}`` for every group ``i``.

Two regimes
-----------
*Few or sparse groups* (``k * n_free <= exact_work``, or more than
``LOCAL_MAX_FREE_PER_GROUP`` free vertices per group): one sparse Cholesky factorization of
``A_ff`` (libigl's LLT for fewer than 80 groups, else CHOLMOD through ``cholespy`` when
installed) and all ``k`` fields solved exactly in batches of 32, folded on the fly into the
argmax as ``HeatSolver`` does.

*Many groups* (noisy scans: thousands of one-vertex groups): local solves with certificates.

1. Free vertices are cut into *patches* of about ``patch_size`` vertices (consecutive runs in
   Morton order of their positions).  Each group is *owned* by the patch that holds most of the
   free neighbours of its seeds.
2. The *domain* ``D_c`` of patch ``c`` is the patch, plus the free neighbours of its groups'
   seeds, grown by ``halo`` edge hops through free vertices (halo and patch size grow with
   the free vertices per group, :func:`_local_params`).  One factorization of ``A_DD``
   per patch; one right-hand side per owned group.  The result ``w_i`` solves the problem with
   ``u = 0`` imposed on the free vertices outside ``D_c`` (``w_i = 0`` there).
3. Truncation error.  ``e_i = u_i - w_i`` is harmonic in ``D_c`` with boundary values
   ``u_i >= 0`` outside it.  When the cotangent weights are non-negative (``A_ff`` an
   M-matrix, inverse entrywise ``>= 0``) every ``e_i >= 0``; and since ``sum_i u_i = 1``,
   ``sum_i e_i = d := 1 - sum_i w_i``, so ``0 <= e_i(v) <= d(v)`` for every group at once.
   Hence ``w_i(v) <= u_i(v) <= w_i(v) + d(v)``: a vertex whose best lower bound beats every
   other group's upper bound is *certified*; faces likewise with the corner mean of ``d``.
4. Refinement: the groups that could still win at an uncertified vertex or face (upper bound
   >= best lower bound) are re-solved on domains grown ``refine_halo`` hops around it (20, or
   the halo if larger; nearby items share one domain).  With ``h`` the harmonic measure of
   that domain's outer boundary (one more right-hand side), ``w <= u <= w + h`` under the
   same M-matrix condition, and ``h`` is tiny that deep.  Where a group outside the kept
   top-K may win ("open" items), every group with a seed next to the domain is tried; all
   others sum to at most ``h`` there.  What is left gets up to :data:`REFINE_PASSES` deeper
   passes (2x, 3x the halo): only the few groups whose bounds still reach the best are
   re-solved, or, where a group not tried may win, every group seeded next to the domain.
5. Whatever is still uncertified is recomputed exactly: the groups that may still win there
   (all groups, if one that no pass tried may) are solved on the whole mesh with one global
   factorization, and the argmax is taken from exact values.

Real scans have a few negative cotangent weights (obtuse triangle pairs; iron.ply: 1.2 % of
its edges), where the maximum principle and so the bound of step 3 may fail; fields there even
go negative (down to -0.63 on iron.ply).  The certificate therefore demands a margin of
``CERT_FACTOR * |d| + CERT_ABS`` instead of ``d``; agreement with the exact solver on real
scans is measured by ``benchmarks/bench_heat.py`` and tested in ``tests/test_fastheat.py``.
On meshes with non-negative weights the labels are those of the exact solve.  An exact tie
is never certified; the fallback decides it for the lowest id, as the exact solver does
(values within :data:`~igl_heatseg.constants.TIE_RTOL` count as tied, since two
factorizations round differently).

Memory stays bounded: dense work arrays are ``|D_c| x (groups owned by c)`` per patch, plus
``TOPK`` candidates per vertex and per face.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable, Sequence
from typing import NamedTuple

import igl
import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

from ..constants import HEAT_SUM_TOL
from .exact import HeatLabels, _argmax_update, corner_means, require_seeded_components

__all__ = [
    "FastHeatSolver",
    "HALO_HOPS",
    "PATCH_VERTICES",
    "EXACT_WORK",
    "TOPK",
    "CERT_FACTOR",
    "CERT_ABS",
    "REFINE_HOPS",
    "LOCAL_MAX_FREE_PER_GROUP",
    "HALO_HOPS_MAX",
    "PATCH_VERTICES_MAX",
]

log = logging.getLogger(__name__)

#: Edge hops by which a patch's domain extends past its vertices and its groups' seeds.
#: Fields of one-vertex groups on iron.ply fall by about 2x per hop (measured), so 10 hops
#: leave about 1e-3 of the heat at the domain boundary.  This is the minimum; sparser
#: groups get more (:func:`_local_params`).
HALO_HOPS: int = 10

#: Largest halo chosen automatically.
HALO_HOPS_MAX: int = 30

#: Free vertices per patch (minimum; sparser groups get larger patches).  Measured on
#: iron.ply's first round (6,159 groups, 10 free vertices per group), labels of the local
#: mode: 2000 -> 2.1 s, 1000 -> 2.0 s, 600 -> 1.5 s (libigl's factorization, which is 3x
#: faster than CHOLMOD's, serves patches of fewer than 80 groups; smaller domains make each
#: of the 6,159 solves cheaper, at 1.6 domain vertices per free vertex more).
PATCH_VERTICES: int = 600

#: Largest patch chosen automatically.
PATCH_VERTICES_MAX: int = 16000

#: Use exact global solves when ``k * n_free`` is at most this (few groups).
EXACT_WORK: float = 2.0e7

#: Groups this sparse (free vertices per group) reach too far for local domains: solve
#: exactly.  Measured: first rounds on scans have 10-13 free vertices per group (90 % of
#: free vertices within 2-3 hops of a seed), second rounds 150 or more (6 hops).  Noisy
#: 200k mesh, second round (150 per group): halo 10 / patch 2000 left 16k vertices
#: uncertified, halo 30 / patch 7500 only 56 (local 4.4 s vs exact 6.4 s, same labels).
#: Noisy 1M mesh, second round (770 per group): halo 30 / patch 16000 left 28k uncertified
#: (local 51 s vs exact 38 s).
LOCAL_MAX_FREE_PER_GROUP: float = 300.0

#: Rows (vertices) where all of a patch's fields are below this skip the top-K bookkeeping
#: for that patch (they only raise the bound on groups not kept).  A winner's value is at
#: least 1 / (number of groups near), far above this; a wrong skip could only leave a label
#: uncertified (then refined or solved exactly), never change it.
SKIP_BELOW: float = 0.02

#: Candidates (lower bounds) kept per vertex and per face (at least 2).
TOPK: int = 4

#: A label is certified when its margin over every rival exceeds
#: ``CERT_FACTOR * |d| + CERT_ABS`` (``d``: truncated heat, see the module docstring).
#: ``CERT_FACTOR = 1`` is the bound for non-negative weights; 2 covers mild violations.
CERT_FACTOR: float = 2.0

#: Absolute margin covering round-off differences between two direct solves.
CERT_ABS: float = 1e-9

#: Dense work arrays per batch of exact fields (``(2n + m) x batch`` float64) stay below this.
_BATCH_BYTES = 512 * 2**20

#: Right-hand sides per global CHOLMOD solve in the fallback (cholespy's multi-RHS solve is
#: fastest per column at 16-32 columns; 256 at once is 2.7x slower per column, measured).
_SOLVE_BATCH = 32

#: Fewest right-hand sides for which CHOLMOD (cholespy) beats libigl's LLT (see _Factor).
_CHOLESPY_MIN_RHS = 80

#: Hops by which refinement domains extend past the uncertified vertices (step 4), at least;
#: a larger patch halo is used when there is one.  Measured on iron.ply's first round
#: (patch 600): 10 hops left 34 vertices and 81 faces to the exact fallback (210 global
#: solves), 15 left 1 and 3, 20 left none (refinement 0.25 s); 30 costs 0.3-1 s more.
REFINE_HOPS: int = 20

#: Deeper refinement passes (domains 2x, 3x, ... ``refine_halo``) for the items whose
#: possible winners are still too close to call, before the exact global fallback.
REFINE_PASSES: int = 2

#: Refinement clusters never span more than this many consecutive patches (Morton order), so
#: that a mesh with uncertified items everywhere does not refine in one mesh-wide domain with
#: hundreds of right-hand sides (noisy 50k mesh: refinement 0.61 s in one cluster, 0.33-0.40 s
#: with 3-8 patches per part; iron.ply 0.25-0.37 s, within the noise of a shared machine).
_REFINE_SPLIT = 4


# ------------------------------------------------------------------------------------------
# sparse factorization


class _Factor:
    """Sparse SPD factorization of ``A`` for ``nrhs`` right-hand sides (a hint).

    Two backends, measured on this project's systems: libigl's ``min_quad_with_fixed`` (Eigen
    simplicial LLT) factors 2.6-4x faster than CHOLMOD through ``cholespy`` (iron.ply,
    80k free vertices: 0.35 s vs 0.92 s; a 5k-vertex patch: 6-10 ms vs 25-30 ms) but solves
    3-5x slower per right-hand side (8 ms vs 1.7 ms; 0.4 ms vs 0.15 ms).  Below
    :data:`_CHOLESPY_MIN_RHS` right-hand sides libigl wins; cholespy (extra ``fast``) is
    used above it when installed.
    """

    def __init__(self, A: sp.spmatrix, nrhs: int = 1) -> None:
        self.n = A.shape[0]
        cholespy = None
        if nrhs >= _CHOLESPY_MIN_RHS:
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


# ------------------------------------------------------------------------------------------
# the solver


class _Refined(NamedTuple):
    """What :meth:`FastHeatSolver._refine` decided (see there)."""

    ok_v: np.ndarray
    lab_v: np.ndarray
    max_v: np.ndarray
    ok_f: np.ndarray
    lab_f: np.ndarray
    win_v: tuple
    win_f: tuple
    wide_v: np.ndarray
    wide_f: np.ndarray
    beat_v: np.ndarray
    beat_f: np.ndarray


class FastHeatSolver:
    """Argmax labels of the heat fields of many seed groups, by certified local solves.

    Same interface as :class:`~igl_heatseg.heat.exact.HeatSolver`; see the module docstring for
    the method.

    Parameters
    ----------
    V : (n, 3) float64
    F : (m, 3) int64
        Validated mesh.
    group : (n,) int64
        Seed group of each vertex, ``0..k-1``, or ``-1`` for a free vertex.  Every connected
        component must hold a seed.
    L : (n, n) sparse, optional
        Cotangent Laplacian as from ``igl.cotmatrix`` (negative semidefinite).
    halo : int, optional
        Hops by which patch domains are grown.  Default: from the free vertices per group
        ``r = n_free / k``, ``clip(4 sqrt(r), HALO_HOPS, HALO_HOPS_MAX)``.
    patch_size : int, optional
        Free vertices per patch.  Default ``clip(50 r, PATCH_VERTICES, PATCH_VERTICES_MAX)``.
    exact_work : float, optional
        Solve all groups exactly when ``k * n_free <= exact_work`` (default: the module's
        :data:`EXACT_WORK` at construction time) or when groups are sparse (more than
        :data:`LOCAL_MAX_FREE_PER_GROUP` free vertices per group: long-range fields);
        ``float("inf")`` forces exact solves, ``0`` local ones.
    refine_halo : int, optional
        Hops of the refinement domains (default: the larger of :data:`REFINE_HOPS` and the
        halo; ``0``: domains of the items and seeds alone, and no deeper passes); what they
        leave uncertified is solved exactly on the whole mesh.

    Attributes
    ----------
    k : int
        Number of groups.
    stats : dict
        Filled by :meth:`labels`: ``mode`` (``"exact"`` or ``"local"``), ``patches``,
        ``domain_vertices`` (sum of domain sizes), ``uncertified_vertices`` and
        ``uncertified_faces`` (after the patch solves), ``open_items`` (of those, where a
        group outside the top-K may win), ``refined_groups`` (groups of the first refinement
        pass's candidate pairs, open items' groups not counted), ``refine_pass2_items`` ...
        (items left to the deeper refinement passes), ``exact_vertices``, ``exact_faces``
        (left to the exact fallback), ``exact_wide`` (of those, where any nearby group may
        win), ``fallback_groups`` (groups solved exactly), and timings (``*_s``).

    Raises
    ------
    ValueError
        If some connected component holds no seed.

    Examples
    --------
    >>> import igl, numpy as np
    >>> V, F = igl.triangulated_grid(5, 5)
    >>> V = np.c_[V, np.zeros(len(V))]
    >>> group = -np.ones(len(V), dtype=np.int64); group[0] = 0; group[-1] = 1
    >>> hl = FastHeatSolver(V, F, group).labels()
    >>> int(hl.vertex_labels[0]), int(hl.vertex_labels[-1])
    (0, 1)
    """

    def __init__(
        self,
        V: np.ndarray,
        F: np.ndarray,
        group: np.ndarray,
        L: sp.spmatrix | None = None,
        *,
        halo: int | None = None,
        patch_size: int | None = None,
        exact_work: float | None = None,
        refine_halo: int | None = None,
    ) -> None:
        self.V, self.F = V, F
        self.n = V.shape[0]
        self.group = np.asarray(group, dtype=np.int64)
        self.known = np.flatnonzero(self.group >= 0)
        self.k = int(self.group.max()) + 1 if len(self.known) else 0
        require_seeded_components(self.n, F, self.known)
        r = (self.n - len(self.known)) / max(self.k, 1)
        ah, ap = _local_params(r)
        self.halo = ah if halo is None else int(halo)
        self.patch_size = ap if patch_size is None else int(patch_size)
        self.exact_work = float(EXACT_WORK if exact_work is None else exact_work)
        self.refine_halo = max(REFINE_HOPS, self.halo) if refine_halo is None else int(refine_halo)
        if L is None:
            L = igl.cotmatrix(V, F)
        self.L = sp.csr_matrix(L)
        self.free = np.flatnonzero(self.group < 0)
        self.nf = len(self.free)
        self._fidx = np.full(self.n, -1, dtype=np.int64)
        self._fidx[self.free] = np.arange(self.nf)
        Lf = self.L[self.free]
        self._A = sp.csr_matrix(-Lf[:, self.free])  # A_ff, (nf, nf), SPD
        # B[:, i] = L_fs 1_{S_i}: right-hand side of group i, (nf, k) sparse.
        G = sp.csr_matrix(
            (np.ones(len(self.known)), (np.arange(len(self.known)), self.group[self.known])),
            shape=(len(self.known), self.k),
        )
        self._B = sp.csc_matrix(Lf[:, self.known] @ G)
        self._factor: _Factor | None = None
        self._P: sp.csr_matrix | None = None  # adjacency pattern of A_ff (see _adjacency)
        self.stats: dict = {}

    # -- exact fields ----------------------------------------------------------------------

    def _global_factor(self, nrhs: int = 1) -> _Factor:
        if self._factor is None:
            t = time.perf_counter()
            try:
                self._factor = _Factor(self._A, nrhs)
            except RuntimeError as exc:
                raise ValueError(
                    f"factorization of the heat system failed ({len(self.known)} seeds, "
                    f"{self.nf} free vertices): {exc}"
                ) from exc
            self.stats["global_factor_s"] = time.perf_counter() - t
        return self._factor

    def _adjacency(self) -> sp.csr_matrix:
        """Adjacency pattern of the free vertices (:func:`_pattern` of ``A_ff``), built once."""
        if self._P is None:
            self._P = _pattern(self._A)
        return self._P

    def _free_fields(self, groups: np.ndarray, nrhs: int = 1) -> np.ndarray:
        """Exact fields of ``groups`` on the free vertices, shape (nf, len(groups)).

        ``nrhs``: how many fields will be asked for in all (chooses the factorization).
        """
        if self.nf == 0 or len(groups) == 0:
            return np.zeros((self.nf, len(groups)))
        return self._global_factor(max(nrhs, len(groups))).solve(self._B[:, groups].toarray())

    def temperatures(self, groups: Sequence[int], nrhs: int = 1) -> np.ndarray:
        """Exact temperature fields of the given groups (one global factorization).

        Parameters
        ----------
        groups : sequence of int
            Group ids in ``0..k-1``.
        nrhs : int
            Hint: how many fields will be requested from this solver in all.  Picks the
            factorization on first use (libigl's for few, CHOLMOD for many).

        Returns
        -------
        U : (n, len(groups)) float64
            ``U[:, j]`` is 1 on the seeds of ``groups[j]``, 0 on every other seed, harmonic
            (``L u = 0``) on free vertices.
        """
        groups = np.asarray(groups, dtype=np.int64).reshape(-1)
        U = np.zeros((self.n, len(groups)))
        U[self.known] = (self.group[self.known][:, None] == groups[None, :]).astype(np.float64)
        U[self.free] = self._free_fields(groups, nrhs)
        return U

    def temperature(self, i: int) -> np.ndarray:
        """One exact temperature field ``u_i``, shape (n,)."""
        return self.temperatures([i])[:, 0]

    # -- labels ----------------------------------------------------------------------------

    def labels(self, progress: Callable[[float], None] | None = None) -> HeatLabels:
        """Argmax labels over all groups.

        Parameters
        ----------
        progress : callable, optional
            Called with the fraction of work done, in ``(0, 1]``.

        Returns
        -------
        HeatLabels
            ``vertex_labels`` and ``face_labels`` as :meth:`HeatSolver.labels` (argmax of
            the vertex fields, and of their corner mean per face; ties to the lowest id).
            ``vertex_max`` is exact in the exact mode and where the fallback ran, else the
            certified lower bound ``w`` (exact up to the truncated heat ``d``).
            ``sum_error`` is ``max |sum_i u_i - 1|`` in the exact mode; in the local mode
            the largest relative residual ``|A_DD W - B| / |B|`` of the patch solves and the
            fallback's solves (the sum identity does not hold for truncated fields).
        """
        t0 = time.perf_counter()
        self.stats = {}
        sparse_groups = self.exact_work > 0 and self.nf > LOCAL_MAX_FREE_PER_GROUP * self.k
        if self.k * self.nf <= self.exact_work or self.nf == 0 or sparse_groups:
            hl = self._labels_exact(progress)
        else:
            hl = self._labels_local(progress)
        self.stats["labels_s"] = time.perf_counter() - t0
        if hl.sum_error > HEAT_SUM_TOL:
            log.warning(
                "heat solve check failed: error %.3g (tolerance %.1g)", hl.sum_error, HEAT_SUM_TOL
            )
        return hl

    def _labels_exact(self, progress) -> HeatLabels:
        """All fields solved exactly, in batches, folded into a running argmax.

        Seeds are labelled by their group (value exactly 1, all others 0).  A face is only
        re-evaluated for a batch if some corner's batch maximum beats the face's best mean
        so far (a mean never exceeds the largest corner value), so after the first batches
        each batch touches few faces: no ``m x batch`` work per batch.
        """
        self.stats["mode"] = "exact"
        n, F, nf, k = self.n, self.F, self.nf, self.k
        group, free, known, fidx = self.group, self.free, self.known, self._fidx
        m = F.shape[0]
        vval = np.full(nf, -np.inf)
        varg = np.zeros(nf, dtype=np.int64)
        usum = np.zeros(nf)
        fc = fidx[F]
        has_free = (fc >= 0).any(axis=1)
        farg = np.zeros(m, dtype=np.int64)
        allseed = np.flatnonzero(~has_free)
        if len(allseed):  # exact: corner counts / 3, ties to the lowest id
            farg[allseed] = _seed_face_labels(group[F[allseed]])
        Fh = F[has_free]
        hf = np.flatnonzero(has_free)
        fmax_h = np.full(len(hf), -np.inf)
        farg_h = np.zeros(len(hf), dtype=np.int64)
        vm = np.zeros(n)
        for g0 in range(0, k, _SOLVE_BATCH):
            g1 = min(k, g0 + _SOLVE_BATCH)
            gs = np.arange(g0, g1)
            X = self._free_fields(gs, k)  # (nf, b)
            usum += X.sum(axis=1)
            _argmax_update(X, g0, vval, varg)
            vm[free] = X.max(axis=1)
            vm[known] = ((group[known] >= g0) & (group[known] < g1)).astype(np.float64)
            cmax = np.maximum(np.maximum(vm[Fh[:, 0]], vm[Fh[:, 1]]), vm[Fh[:, 2]])
            sel = np.flatnonzero(cmax > fmax_h)
            if len(sel):
                Fs = Fh[sel]
                U = np.empty((n, g1 - g0))
                U[free] = X
                U[known] = (group[known][:, None] == gs[None, :]).astype(np.float64)
                Uf = corner_means(U, Fs)
                best = fmax_h[sel]
                arg = farg_h[sel]
                _argmax_update(Uf, g0, best, arg)
                fmax_h[sel] = best
                farg_h[sel] = arg
            if progress is not None:
                progress(g1 / k)
        farg[hf] = farg_h
        vertex_labels = group.copy()
        vertex_labels[free] = varg
        vertex_max = np.ones(n)
        vertex_max[free] = vval
        err = float(np.abs(usum - 1.0).max()) if nf else 0.0
        self.stats["fallback_groups"] = k
        return HeatLabels(
            vertex_labels=vertex_labels, face_labels=farg, vertex_max=vertex_max, sum_error=err
        )

    def _labels_local(self, progress) -> HeatLabels:
        st = self.stats
        st["mode"] = "local"
        V, F, n, nf, k = self.V, self.F, self.n, self.nf, self.k
        m = F.shape[0]
        group, free, fidx = self.group, self.free, self._fidx
        A, B = self._A, self._B
        K = max(int(TOPK), 2)  # the certificate compares the best with the second

        t = time.perf_counter()
        # 1. Patches: runs of patch_size free vertices in Morton order.
        order = np.argsort(_morton(V[free]), kind="stable")
        npatch = max(1, -(-nf // self.patch_size))
        patch = np.empty(nf, dtype=np.int64)
        patch[order] = np.arange(nf) * npatch // nf
        # Owner of each group: the patch holding most free neighbours of its seeds.
        Bc = B.tocoo()
        pair = sp.coo_matrix((np.ones(Bc.nnz), (Bc.col, patch[Bc.row])), shape=(k, npatch)).tocsr()
        owner = np.asarray(pair.argmax(axis=1)).ravel()
        owner[np.diff(pair.indptr) == 0] = -1  # group with no free neighbour
        # 2. Domains: (nf, npatch) pattern grown by `halo` hops through free vertices.
        X = _grow(
            self._adjacency(),
            np.r_[np.arange(nf), Bc.row],
            np.r_[patch, owner[Bc.col]],
            (nf, npatch),
            self.halo,
        )
        st["patches"] = npatch
        st["domain_vertices"] = int(X.nnz)
        st["setup_s"] = time.perf_counter() - t

        # Incidence free vertex -> faces, for the faces each domain touches.
        fc = fidx[F]  # (m, 3) free index of each corner or -1
        rows = fc.ravel()
        sel = rows >= 0
        VFf = sp.csr_matrix(
            (np.ones(int(sel.sum()), dtype=np.int8), (rows[sel], np.repeat(np.arange(m), 3)[sel])),
            shape=(nf, m),
        )
        VF = sp.csr_matrix(
            (np.ones(3 * m, dtype=np.int8), (F.T.ravel(), np.tile(np.arange(m), 3))), shape=(n, m)
        )
        vcold = np.zeros(nf)  # largest value of a group at a vertex where it was cold
        # Running top-K lower bounds per free vertex and per face.
        vval = np.full((nf, K), -np.inf)
        vid = np.full((nf, K), -1, dtype=np.int64)
        vexc = np.zeros(nf)  # bound on every group not kept (absent groups: w = 0)
        wsum = np.zeros(nf)
        fval = np.full((m, K), -np.inf)
        fid = np.full((m, K), -1, dtype=np.int64)
        fexc = np.zeros(m)
        resid = 0.0

        t = time.perf_counter()
        owned = np.argsort(owner, kind="stable")
        bounds = np.searchsorted(owner[owned], np.arange(npatch + 1) - 0.5)
        ownerless = owned[: bounds[0]]
        tsub = [0.0] * 5
        for c in range(npatch):
            gids = owned[bounds[c] : bounds[c + 1]]  # sorted by group id (stable sort)
            if len(gids) == 0:
                continue
            D = X.indices[X.indptr[c] : X.indptr[c + 1]]
            t1 = time.perf_counter()
            ADD = A[D][:, D]
            BD = B[D][:, gids].toarray()
            t2 = time.perf_counter()
            fac = _Factor(ADD, len(gids))
            t3 = time.perf_counter()
            W = fac.solve(BD)
            t4 = time.perf_counter()
            tsub[0] += t2 - t1
            tsub[1] += t3 - t2
            tsub[2] += t4 - t3
            if W.ndim == 1:
                W = W[:, None]
            bn = np.abs(BD).max()
            if bn > 0:
                resid = max(resid, float(np.abs(ADD @ W - BD).max() / bn))
            wsum[D] += W.sum(axis=1)
            # Rows where this patch's groups are all below SKIP_BELOW ("cold": far in the
            # halo) only raise the bound on non-kept groups; no candidates from them.
            nD, kc = W.shape
            rmax = W.max(axis=1)
            hot = rmax >= SKIP_BELOW
            cold = np.flatnonzero(~hot)
            vcold[D[cold]] = np.maximum(vcold[D[cold]], rmax[cold])
            hot = np.flatnonzero(hot)
            tv, ti_h, tx_h = _topk_rows(W[hot], K)  # patch-local top-K per hot vertex
            _merge_topk(vval, vid, vexc, D[hot], tv, gids[ti_h], tx_h)
            vexc[D[cold]] = np.maximum(vexc[D[cold]], rmax[cold])
            ti = np.zeros((nD, K), dtype=np.int64)
            ti[hot] = ti_h
            tx = rmax.copy()
            tx[hot] = tx_h
            t5 = time.perf_counter()
            tsub[3] += t5 - t4
            # Faces with a hot free corner or a seed corner of an owned group.  Candidates:
            # the groups in the local top-K of their hot corners and the groups of their seed
            # corners; every other group of this patch is below the corner mean of the local
            # (K+1)-th values (cold corners: their maximum).  Faces with only cold corners
            # are bounded at the end through `vcold`.
            gpos = np.full(k, -1, dtype=np.int64)
            gpos[gids] = np.arange(kc)
            own = self.known[gpos[group[self.known]] >= 0]
            faces = np.unique(np.r_[VFf[D[hot]].indices, VF[own].indices])
            loc = np.full(nf, nD, dtype=np.int64)
            loc[D] = np.arange(nD)
            Wz = np.vstack([W, np.zeros((1, kc))])
            cf = fc[faces]  # free index of corners, -1 at seeds
            lc = np.where(cf >= 0, loc[np.maximum(cf, 0)], nD)  # row in Wz (nD: value 0)
            sg = np.where(cf < 0, gpos[np.maximum(group[F[faces]], 0)], -1)  # own seed groups
            tiz = np.vstack([ti, np.zeros((1, K), dtype=np.int64)])
            txz = np.r_[tx, 0.0]
            cand = np.concatenate([tiz[lc[:, 0]], tiz[lc[:, 1]], tiz[lc[:, 2]], sg], axis=1)
            cand = np.sort(cand, axis=1)
            dup = np.zeros(cand.shape, dtype=bool)
            dup[:, 1:] = cand[:, 1:] == cand[:, :-1]
            dup |= cand < 0
            cz = np.maximum(cand, 0)
            isseed = (sg[:, :, None] == cz[:, None, :]) & (sg[:, :, None] >= 0)  # (r,3,c)
            val = (
                Wz[lc[:, 0:1], cz] + Wz[lc[:, 1:2], cz] + Wz[lc[:, 2:3], cz] + isseed.sum(axis=1)
            ) / 3.0
            val[dup] = -np.inf
            rest = (txz[lc[:, 0]] + txz[lc[:, 1]] + txz[lc[:, 2]]) / 3.0
            fv, fi, fx = _topk_rows(val, K)
            _merge_topk(
                fval,
                fid,
                fexc,
                faces,
                fv,
                gids[np.take_along_axis(cz, fi, 1)],
                np.maximum(fx, rest),
            )
            tsub[4] += time.perf_counter() - t5
            if progress is not None:
                progress(0.9 * (c + 1) / npatch)
        st["patch_solves_s"] = time.perf_counter() - t
        for name, val in zip(("slice", "factor", "solve", "vertices", "faces"), tsub, strict=True):
            st[f"patch_{name}_s"] = val
        if len(ownerless):
            log.debug("%d groups touch no free vertex", len(ownerless))

        t = time.perf_counter()
        # 3. Certificates.
        d = 1.0 - wsum  # truncated heat per free vertex
        slack_v = CERT_FACTOR * np.abs(d) + CERT_ABS
        rival_v = np.maximum(vval[:, 1], vexc)
        unc_v = ~(vval[:, 0] - rival_v > slack_v)
        # Faces: corner mean of |d| (0 at seeds); all-seed faces are exact.
        dab = np.zeros(n)
        dab[free] = np.abs(d)
        slack_f = CERT_FACTOR * (dab[F[:, 0]] + dab[F[:, 1]] + dab[F[:, 2]]) / 3.0 + CERT_ABS
        has_free = (fc >= 0).any(axis=1)
        vc = np.zeros(n)
        vc[free] = vcold
        fexc = np.maximum(fexc, np.maximum(np.maximum(vc[F[:, 0]], vc[F[:, 1]]), vc[F[:, 2]]))
        rival_f = np.maximum(fval[:, 1], fexc)
        unc_f = has_free & ~(fval[:, 0] - rival_f > slack_f)

        vertex_labels = group.copy()
        vertex_max = np.ones(n)
        vertex_labels[free] = vid[:, 0]
        vertex_max[free] = vval[:, 0]
        face_labels = fid[:, 0].copy()
        # Faces whose corners are all seeds: exact corner counts, ties to the lowest id.
        allseed = np.flatnonzero(~has_free)
        if len(allseed):
            face_labels[allseed] = _seed_face_labels(group[F[allseed]])

        # Uncertified items, their candidates, and the open ones.
        uv = np.flatnonzero(unc_v)
        uf = np.flatnonzero(unc_f)
        st["uncertified_vertices"] = len(uv)
        st["uncertified_faces"] = len(uf)
        cand_v = (vval[uv] + slack_v[uv, None] >= vval[uv, :1]) & (vid[uv] >= 0)
        cand_f = (fval[uf] + slack_f[uf, None] >= fval[uf, :1]) & (fid[uf] >= 0)
        # If a rival outside the kept candidates may win, every group is a candidate there.
        open_v = vexc[uv] + slack_v[uv] >= vval[uv, 0]
        open_f = fexc[uf] + slack_f[uf] >= fval[uf, 0]
        st["open_items"] = int(open_v.sum() + open_f.sum())
        st["certify_s"] = time.perf_counter() - t
        # 4. Refinement: the candidates of the uncertified items are re-solved on domains grown
        #    refine_halo hops around them; bounds from the boundary's harmonic measure.  Where
        #    a group outside the kept candidates may win ("open" items), every group with a
        #    seed next to the refinement domain is tried (see _refine).
        t = time.perf_counter()
        pv_i, pv_j = np.nonzero(cand_v & ~open_v[:, None])
        pf_i, pf_j = np.nonzero(cand_f & ~open_f[:, None])
        r = self._refine(
            uv,
            vid[uv][pv_i, pv_j],
            pv_i,
            open_v,
            uf,
            fid[uf][pf_i, pf_j],
            pf_i,
            open_f,
            fc,
            patch // _REFINE_SPLIT,
            np.maximum(np.where(cand_v, -np.inf, vval[uv]).max(axis=1), vexc[uv]) + slack_v[uv],
            np.maximum(np.where(cand_f, -np.inf, fval[uf]).max(axis=1), fexc[uf]) + slack_f[uf],
            progress=None if progress is None else (lambda f: progress(0.9 + 0.06 * f)),
        )
        st["refined_groups"] = len(np.union1d(vid[uv][pv_i, pv_j], fid[uf][pf_i, pf_j]))
        ok_v, lab_v, max_v, ok_f, lab_f = r.ok_v, r.lab_v, r.max_v, r.ok_f, r.lab_f
        win_v, win_f, wide_v, wide_f = r.win_v, r.win_f, r.wide_v, r.wide_f
        beat_v, beat_f = r.beat_v, r.beat_f
        # Deeper passes (2x, 3x the halo) for what is left.  Where a few possible winners
        # are too close to call, only they are re-solved (every other group stays below
        # `beat`); where a group not tried may win ("wide"), every group seeded next to the
        # larger domain is tried.
        for depth in range(2, 2 + REFINE_PASSES):
            lv = np.flatnonzero(~ok_v)
            lf = np.flatnonzero(~ok_f)
            if self.refine_halo == 0 or not (len(lv) or len(lf)):
                break
            mv = np.full(len(uv), -1, dtype=np.int64)
            mv[lv] = np.arange(len(lv))
            mf = np.full(len(uf), -1, dtype=np.int64)
            mf[lf] = np.arange(len(lf))
            kv = (mv[win_v[0]] >= 0) & ~wide_v[win_v[0]]
            kf = (mf[win_f[0]] >= 0) & ~wide_f[win_f[0]]
            r = self._refine(
                uv[lv],
                win_v[1][kv],
                mv[win_v[0][kv]],
                wide_v[lv],
                uf[lf],
                win_f[1][kf],
                mf[win_f[0][kf]],
                wide_f[lf],
                fc,
                patch // _REFINE_SPLIT,
                beat_v[lv],
                beat_f[lf],
                halo=depth * self.refine_halo,
                progress=None
                if progress is None
                else (lambda f, d=depth: progress(0.96 + 0.01 * (d - 2 + f))),
            )
            ok_v[lv], lab_v[lv], max_v[lv], wide_v[lv], beat_v[lv] = (
                r.ok_v,
                r.lab_v,
                r.max_v,
                r.wide_v,
                r.beat_v,
            )
            ok_f[lf], lab_f[lf], wide_f[lf], beat_f[lf] = r.ok_f, r.lab_f, r.wide_f, r.beat_f
            # the items of this pass get its pairs; the others keep theirs
            ov = mv[win_v[0]] < 0
            of = mf[win_f[0]] < 0
            win_v = (np.r_[win_v[0][ov], lv[r.win_v[0]]], np.r_[win_v[1][ov], r.win_v[1]])
            win_f = (np.r_[win_f[0][of], lf[r.win_f[0]]], np.r_[win_f[1][of], r.win_f[1]])
            st[f"refine_pass{depth}_items"] = len(lv) + len(lf)
        vertex_labels[free[uv[ok_v]]] = lab_v[ok_v]
        vertex_max[free[uv[ok_v]]] = max_v[ok_v]
        face_labels[uf[ok_f]] = lab_f[ok_f]
        st["refine_s"] = time.perf_counter() - t
        # The exact fallback solves the groups that may still win where refinement did not
        # decide (by its bounds); where a group that no pass tried may still win, all groups.
        cands = np.union1d(win_v[1][~ok_v[win_v[0]]], win_f[1][~ok_f[win_f[0]]])
        wv, wf = ~ok_v & wide_v, ~ok_f & wide_f
        st["exact_wide"] = int(wv.sum() + wf.sum())
        if wv.any() or wf.any():
            log.warning(
                "%d vertices/faces may be won by a group that no refinement pass tried: "
                "solving all %d groups exactly",
                int(wv.sum() + wf.sum()),
                k,
            )
            cands = np.arange(k)
        uv, uf = uv[~ok_v], uf[~ok_f]
        st["exact_vertices"] = len(uv)
        st["exact_faces"] = len(uf)
        st["fallback_groups"] = len(cands)
        t = time.perf_counter()
        if len(cands):
            rv_free = uv
            fcorn = F[uf]
            need = np.unique(np.r_[free[rv_free], fcorn.ravel()])
            best_v = np.full(len(uv), -np.inf)
            arg_v = np.zeros(len(uv), dtype=np.int64)
            best_f = np.full(len(uf), -np.inf)
            arg_f = np.zeros(len(uf), dtype=np.int64)
            pos = np.full(n, -1, dtype=np.int64)
            pos[need] = np.arange(len(need))
            for j0 in range(0, len(cands), _SOLVE_BATCH):
                gs = cands[j0 : j0 + _SOLVE_BATCH]
                Uf = self._free_fields(gs, len(cands))
                Bg = B[:, gs].toarray()
                bn = np.abs(Bg).max()
                if bn > 0:
                    resid = max(resid, float(np.abs(A @ Uf - Bg).max() / bn))
                U = np.zeros((len(need), len(gs)))
                isf = fidx[need] >= 0
                U[isf] = Uf[fidx[need[isf]]]
                U[~isf] = (group[need[~isf]][:, None] == gs[None, :]).astype(np.float64)
                _argmax_update_ids(U[pos[free[uv]]], gs, best_v, arg_v)
                Pf = pos[fcorn]
                Wf = corner_means(U, Pf)
                _argmax_update_ids(Wf, gs, best_f, arg_f)
            vertex_labels[free[uv]] = arg_v
            vertex_max[free[uv]] = best_v
            face_labels[uf] = arg_f
        st["fallback_s"] = time.perf_counter() - t
        if progress is not None:
            progress(1.0)
        log.info(
            "local heat labels: %d patches, %d domain vertices, %d/%d vertices and %d/%d faces "
            "left to the exact fallback, %d groups solved exactly",
            npatch,
            X.nnz,
            len(uv),
            nf,
            len(uf),
            m,
            len(cands),
        )
        return HeatLabels(
            vertex_labels=vertex_labels,
            face_labels=face_labels,
            vertex_max=vertex_max,
            sum_error=resid,
        )

    def _refine(
        self,
        uv,
        gv,
        iv,
        open_v,
        uf,
        gf,
        jf,
        open_f,
        fc,
        split,
        rival_v,
        rival_f,
        halo=None,
        progress=None,
    ):
        """Re-solve candidate groups on large domains around uncertified vertices and faces.

        Parameters
        ----------
        uv : (a,) int64
            Uncertified free vertices (free indices).
        gv, iv : (p,) int64
            Candidate pairs: group, index into ``uv``.
        open_v : (a,) bool
            Items where a group outside the candidates may win: every group with a seed on
            or next to the refinement domain is tried there, and the rest is bounded by the
            domain boundary's harmonic measure.
        uf, gf, jf, open_f
            The same for uncertified faces.
        fc : (m, 3) int64
            Free index of each face corner, -1 at seeds.
        split : (nf,) int64
            Part of each free vertex; clusters never span two parts.
        rival_v, rival_f : (a,), (b,) float64
            Bound on every non-candidate (used for items that are not open).
        halo : int, optional
            Hops of the domains (default ``refine_halo``).
        progress : callable, optional
            Called with the fraction of clusters done.

        Notes
        -----
        Items of one part within ``2 halo / 3`` hops of each other form a cluster
        (:func:`_clusters`).  A cluster's domain ``D`` grows ``halo`` hops around its
        items and its candidate groups' seeds and is factored once.  With ``h`` the harmonic
        measure of ``D``'s outer boundary (``A_DD h = L_D,out 1``), ``w <= u <= w + h``
        when the weights are non-negative (``u <= 1`` outside), and the groups without a
        seed next to ``D`` sum to at most ``h`` inside it.  As in the patch solves the
        margins are ``CERT_FACTOR`` times these bounds.

        Returns
        -------
        ok_v (a,) bool, lab_v (a,) int64, max_v (a,) float64, ok_f (b,) bool, lab_f (b,) int64
            Certified items, their labels (and the vertices' lower bound).
        win_v, win_f : tuple of two (q,) int64
            (item, group) pairs that may still win at an item (upper bound reaching the
            best lower bound).
        wide_v (a,) bool, wide_f (b,) bool
            Items where a group that was not tried may still win.
        beat_v (a,) float64, beat_f (b,) float64
            Bound on every group not in ``win_v`` / ``win_f`` at each item.

        All returned as a :class:`_Refined`.
        """
        A, B, F, group, nf = self._A, self._B, self.F, self.group, self.nf
        halo = self.refine_halo if halo is None else int(halo)
        a, b = len(uv), len(uf)
        lo_v = np.full(len(gv), -np.inf)
        hi_v = np.full(len(gv), np.inf)
        lo_f = np.full(len(gf), -np.inf)
        hi_f = np.full(len(gf), np.inf)
        ok_v = np.zeros(a, dtype=bool)
        lab_v = np.full(a, -1, dtype=np.int64)
        max_v = np.full(a, -np.inf)
        ok_f = np.zeros(b, dtype=bool)
        lab_f = np.full(b, -1, dtype=np.int64)
        wide_v = np.ones(a, dtype=bool)
        wide_f = np.ones(b, dtype=bool)
        beat_v = np.full(a, np.inf)
        beat_f = np.full(b, np.inf)
        win_v, win_f = [], []  # (item, group) pairs that may still win
        fcor = fc[uf]  # (b, 3) free corners of the face items, -1 at seeds
        # Items to refine, one vertex each (a face: a free corner, the largest free index).
        act_v = open_v.copy()
        act_v[iv] = True
        act_f = open_f.copy()
        act_f[jf] = True
        av, af = np.flatnonzero(act_v), np.flatnonzero(act_f)
        P = self._adjacency()
        ncl, cl = _clusters(P, np.r_[uv[av], fcor[af].max(axis=1)], max(halo // 3, 1), split)
        cl_v = np.full(a, -1, dtype=np.int64)
        cl_v[av] = cl[: len(av)]
        cl_f = np.full(b, -1, dtype=np.int64)
        cl_f[af] = cl[len(av) :]
        if ncl:
            # growth sources: item vertices and the free neighbours of the groups' seeds
            Bc = B[:, np.r_[gv, gf]].tocoo()
            src_r = np.r_[uv[av], fcor[af].ravel(), Bc.row]
            src_c = np.r_[cl_v[av], np.repeat(cl_f[af], 3), np.r_[cl_v[iv], cl_f[jf]][Bc.col]]
            keep = src_r >= 0
            X = _grow(P, src_r[keep], src_c[keep], (nf, ncl), halo)
            Arow = A @ np.ones(nf)
            Br = B.tocsr()
            pair_cl_v, pair_cl_f = cl_v[iv], cl_f[jf]
            loc = np.full(nf, -1, dtype=np.int64)
            for ci in range(ncl):
                if progress is not None:
                    progress(ci / ncl)
                D = X.indices[X.indptr[ci] : X.indptr[ci + 1]]
                sv = np.flatnonzero(pair_cl_v == ci)
                sf = np.flatnonzero(pair_cl_f == ci)
                ov = np.flatnonzero(open_v & (cl_v == ci))
                of = np.flatnonzero(open_f & (cl_f == ci))
                gids = np.unique(np.r_[gv[sv], gf[sf]])
                BDr = Br[D]
                if len(ov) or len(of):  # every group with a seed next to D
                    gids = np.union1d(gids, np.unique(BDr.indices))
                    # and the groups of the open faces' seed corners (their weight to D
                    # may be exactly zero, so B need not list them)
                    sg = group[F[uf[of]]].ravel()
                    gids = np.union1d(gids, sg[sg >= 0])
                ADD = A[D][:, D]
                bh = -(Arow[D] - ADD @ np.ones(len(D)))  # L_D,out 1 (>= 0 for cot weights)
                rhs = np.c_[BDr[:, gids].toarray(), bh]
                W = _Factor(ADD, rhs.shape[1]).solve(rhs)
                if W.ndim == 1:
                    W = W[:, None]
                h = np.maximum(W[:, -1], 0.0)
                W = W[:, :-1]
                loc[D] = np.arange(len(D))
                # candidate pairs
                col_v = np.searchsorted(gids, gv[sv])
                rv = loc[uv[iv[sv]]]
                lo_v[sv] = W[rv, col_v]
                hi_v[sv] = W[rv, col_v] + CERT_FACTOR * h[rv]
                col_f = np.searchsorted(gids, gf[sf])
                lo, hgap = _face_rows(W, h, loc, fcor[jf[sf]], group[F[uf[jf[sf]]]], gf[sf], col_f)
                lo_f[sf] = lo
                hi_f[sf] = lo + CERT_FACTOR * hgap
                # open items: all groups at once; the rest sum to at most h
                if len(ov):
                    rv = loc[uv[ov]]
                    Wv = W[rv]  # (len(ov), len(gids))
                    win_v.append(
                        _decide_all(
                            Wv, CERT_FACTOR * h[rv], gids, ov, ok_v, lab_v, max_v, wide_v, beat_v
                        )
                    )
                if len(of):
                    cr = fcor[of]
                    rl = np.where(cr >= 0, loc[np.maximum(cr, 0)], -1)
                    Wz = np.vstack([W, np.zeros((1, len(gids)))])
                    rz = np.where(rl >= 0, rl, len(D))
                    own = (group[F[uf[of]]][:, :, None] == gids[None, None, :]).sum(axis=1)
                    Wf = (Wz[rz[:, 0]] + Wz[rz[:, 1]] + Wz[rz[:, 2]] + own) / 3.0
                    hz = np.r_[h, 0.0]
                    gap = CERT_FACTOR * (hz[rz[:, 0]] + hz[rz[:, 1]] + hz[rz[:, 2]]) / 3.0
                    win_f.append(_decide_all(Wf, gap, gids, of, ok_f, lab_f, None, wide_f, beat_f))
                loc[D] = -1
        # candidate pairs of the items that are not open
        pv = ~open_v[iv]
        pf = ~open_f[jf]
        okp, labp, maxp, wp, widep, beatp = _decide(a, iv[pv], gv[pv], lo_v[pv], hi_v[pv], rival_v)
        sel = ~open_v
        ok_v[sel], lab_v[sel], max_v[sel] = okp[sel], labp[sel], maxp[sel]
        wide_v[sel], beat_v[sel] = widep[sel], beatp[sel]
        win_v.append(wp)
        okp, labp, _, wp, widep, beatp = _decide(b, jf[pf], gf[pf], lo_f[pf], hi_f[pf], rival_f)
        sel = ~open_f
        ok_f[sel], lab_f[sel], wide_f[sel], beat_f[sel] = (
            okp[sel],
            labp[sel],
            widep[sel],
            beatp[sel],
        )
        win_f.append(wp)
        win_v = tuple(np.concatenate(x) for x in zip(*win_v, strict=True))
        win_f = tuple(np.concatenate(x) for x in zip(*win_f, strict=True))
        return _Refined(
            ok_v, lab_v, max_v, ok_f, lab_f, win_v, win_f, wide_v, wide_f, beat_v, beat_f
        )


# ------------------------------------------------------------------------------------------
# helpers


def _local_params(r: float) -> tuple[int, int]:
    """Halo (hops) and patch size (free vertices) for ``r`` free vertices per group.

    Sparser groups have longer-range fields: the halo grows like the typical distance
    between seeds (``sqrt(r)``) and the patch so that it owns about 50 groups or more.
    Measured (first rounds, default patches): iron.ply (``r`` = 9.9) halo 10 / 12 / 14
    left 106 / 15 / 2 vertices uncertified at about the same total time; the 200k-face
    mesh with 5 % seeds (``r`` = 29) took 14.1 s with halo 14 (7,492 uncertified), 12.4 s
    with 20 and 8.7 s with 25 (277 uncertified).
    """
    halo = int(np.clip(round(4.0 * np.sqrt(max(r, 0.0))), HALO_HOPS, HALO_HOPS_MAX))
    patch = int(np.clip(50 * r, PATCH_VERTICES, PATCH_VERTICES_MAX))
    return halo, patch


def _pattern(A: sp.spmatrix) -> sp.csr_matrix:
    """Adjacency pattern of ``A`` (diagonal included) as int32 ones.

    int32, not int8: a hop sums a row's neighbours, and a vertex of valence 127 or more
    would overflow int8, wrap to zero and drop out of the grown set.
    """
    P = sp.csr_matrix(A, dtype=np.int32, copy=True)
    P.data[:] = 1
    return P


def _grow(
    P: sp.csr_matrix, rows: np.ndarray, cols: np.ndarray, shape: tuple, hops: int
) -> sp.csc_matrix:
    """Column sets grown ``hops`` edge hops: ``(rows, cols)`` marks vertex ``rows[i]`` in set
    ``cols[i]``; returns the (N, sets) 0/1 pattern, CSC with sorted indices."""
    X = sp.csr_matrix((np.ones(len(rows), dtype=np.int32), (rows, cols)), shape=shape)
    X.sum_duplicates()
    X.data[:] = 1
    for _ in range(hops):
        X = X + P @ X
        X.data[:] = 1
    X = X.tocsc()
    X.sort_indices()
    return X


def _clusters(
    P: sp.csr_matrix, item: np.ndarray, hops: int, split: np.ndarray
) -> tuple[int, np.ndarray]:
    """Cluster items of one part that lie within ``2 hops`` edge hops of each other.

    Parameters
    ----------
    P : (N, N) sparse
        Adjacency pattern (any non-zero is an edge).
    item : (p,) int64
        Vertex of each item (repeats allowed).
    hops : int
    split : (N,) int64
        Part of each vertex: items in different parts are never clustered together (this
        bounds a cluster's domain, and so its solves, on meshes with uncertified items
        everywhere).

    Returns
    -------
    count : int
    cluster : (p,) int64
        Cluster of each item, ``0..count-1``.
    """
    if len(item) == 0:
        return 0, np.zeros(0, dtype=np.int64)
    mark = np.zeros(P.shape[0], dtype=np.int32)
    mark[item] = 1
    for _ in range(hops):
        mark = np.minimum(mark + P @ mark, 1)
    sub = np.flatnonzero(mark)
    _, comp = connected_components(P[sub][:, sub], directed=False)
    pos = np.full(P.shape[0], -1, dtype=np.int64)
    pos[sub] = np.arange(len(sub))
    key = comp[pos[item]].astype(np.int64) * (int(split.max()) + 1) + split[item]
    used, cluster = np.unique(key, return_inverse=True)
    return len(used), cluster.astype(np.int64)


def _face_rows(W, h, loc, cr, cg, gid, col):
    """Lower bound and ``h`` gap of the face mean of one group per face item.

    ``W`` (|D|, c) fields on a domain, ``h`` (|D|,) its boundary's harmonic measure, ``loc``
    (nf,) row of each free vertex in ``D`` (-1 outside), ``cr`` (r, 3) free corners (-1 at
    seeds), ``cg`` (r, 3) seed group of each corner, ``gid`` (r,) the group and ``col`` (r,)
    its column in ``W``.

    Returns
    -------
    lo (r,) float64, gap (r,) float64 (corner mean of ``h``)
    """
    rl = np.where(cr >= 0, loc[np.maximum(cr, 0)], -1)
    isown = (cg == gid[:, None]).sum(axis=1)
    wv = np.where(rl >= 0, W[np.maximum(rl, 0), col[:, None]], 0.0)
    hv = np.where(rl >= 0, h[np.maximum(rl, 0)], 0.0)
    return (wv.sum(axis=1) + isown) / 3.0, hv.sum(axis=1) / 3.0


def _decide_all(Wv, gap, gids, items, ok, lab, best, wide, beat):
    """Certified argmax per item from all candidate values at once.

    ``Wv`` (r, c) lower bounds of the candidates ``gids`` (c,) (increasing), ``gap`` (r,)
    the upper bound's excess (also the bound on every non-candidate).  Writes ``ok``,
    ``lab``, ``best`` (if given), ``wide`` (a non-candidate may win) and ``beat`` (bound on
    every group not returned) at ``items`` (r,).

    Returns
    -------
    (item, group) pairs, each (q,) int64: the candidates that may still win.
    """
    if Wv.shape[1] == 0:
        return np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64)
    j = Wv.argmax(axis=1)  # first maximum: the lowest group id on ties
    r = np.arange(len(items))
    top = Wv[r, j]
    rest = Wv.copy()
    rest[r, j] = -np.inf
    rival = np.maximum(rest.max(axis=1) + gap, gap)
    ok[items] = top > rival + CERT_ABS
    lab[items] = gids[j]
    wide[items] = gap + CERT_ABS >= top
    if best is not None:
        best[items] = top
    may = Wv + (gap + CERT_ABS)[:, None] >= top[:, None]
    beat[items] = np.maximum(np.where(may, -np.inf, Wv).max(axis=1) + gap, gap)
    pi, pj = np.nonzero(may)
    return items[pi], gids[pj]


def _decide(a, item, gid, lo, hi, rival):
    """Certified argmax per item from candidate (item, group, lower, upper) bounds.

    An item is certified when its best lower bound exceeds the upper bound of every other
    candidate and ``rival`` (bound on non-candidates) by :data:`CERT_ABS`.

    Returns
    -------
    ok (a,) bool, label (a,) int64, best (a,) float64
    win : tuple of two (q,) int64
        (item, group) pairs whose upper bound reaches the item's best lower bound.
    wide : (a,) bool
        ``rival`` reaches the best lower bound (or the item has no candidate).
    beat : (a,) float64
        Bound on every group not in ``win``.
    """
    ok = np.zeros(a, dtype=bool)
    lab = np.full(a, -1, dtype=np.int64)
    best = np.full(a, -np.inf)
    if len(item) == 0:
        e = np.zeros(0, dtype=np.int64)
        return ok, lab, best, (e, e), np.ones(a, dtype=bool), np.full(a, np.inf)
    o = np.lexsort((gid, -lo, item))  # per item: largest lower bound first, then lowest id
    it, g, l_, h_ = item[o], gid[o], lo[o], hi[o]
    first = np.r_[True, it[1:] != it[:-1]]
    fi = np.flatnonzero(first)
    lab[it[fi]] = g[fi]
    best[it[fi]] = l_[fi]
    # largest upper bound among the other candidates of each item
    h2 = h_.copy()
    h2[fi] = -np.inf
    other = np.full(a, -np.inf)
    np.maximum.at(other, it, h2)
    ok[it[fi]] = True
    ok &= best > np.maximum(other, rival) + CERT_ABS
    may = h_ + CERT_ABS >= best[it]
    wide = rival + CERT_ABS >= best
    beat = np.asarray(rival, dtype=np.float64).copy()  # bound on every group not in `win`
    np.maximum.at(beat, it[~may], h_[~may])
    return ok, lab, best, (it[may], g[may]), wide, beat


def _morton(P: np.ndarray, bits: int = 21) -> np.ndarray:
    """Morton (Z-order) codes of points, shape (len(P),) uint64."""
    if len(P) == 0:
        return np.zeros(0, dtype=np.uint64)
    lo, hi = P.min(axis=0), P.max(axis=0)
    q = ((P - lo) / np.maximum(hi - lo, 1e-300).max() * ((1 << bits) - 1)).astype(np.uint64)
    code = np.zeros(len(P), dtype=np.uint64)
    for b in range(bits):
        for a in range(3):
            code |= ((q[:, a] >> np.uint64(b)) & np.uint64(1)) << np.uint64(3 * b + a)
    return code


def _topk_rows(M: np.ndarray, K: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Largest ``K`` entries of each row and a bound on the rest.

    Parameters
    ----------
    M : (r, c) float64

    Returns
    -------
    val : (r, K) float64
        Decreasing; ``-inf`` where the row has fewer than ``K`` entries.
    idx : (r, K) int64
        Their columns (0 where ``val`` is ``-inf``).
    rest : (r,) float64
        Largest entry not returned (``-inf`` if none).
    """
    r, c = M.shape
    val = np.full((r, K), -np.inf)
    idx = np.zeros((r, K), dtype=np.int64)
    ar = np.arange(r)
    if c <= K:
        o = np.argsort(-M, axis=1, kind="stable")
        val[:, :c] = np.take_along_axis(M, o, axis=1)
        idx[:, :c] = o
        return val, idx, np.full(r, -np.inf)
    M = M.copy()
    for j in range(K):  # K argmax passes: much faster than argpartition for small K
        a = M.argmax(axis=1)
        idx[:, j] = a
        val[:, j] = M[ar, a]
        M[ar, a] = -np.inf
    return val, idx, M.max(axis=1)


def _merge_topk(
    val: np.ndarray,
    ids: np.ndarray,
    exc: np.ndarray,
    rows: np.ndarray,
    bv: np.ndarray,
    bi: np.ndarray,
    bx: np.ndarray,
) -> None:
    """Fold a block's top-K lower bounds into running top-K lists.

    ``val, ids`` (N, K) hold the K largest values seen per row (decreasing) and their group
    ids; ``exc`` (N,) bounds every value seen but not kept.  ``bv, bi`` (len(rows), K) are a
    block's top-K values and group ids on ``rows``, ``bx`` (len(rows),) a bound on the rest
    of the block.
    """
    K = val.shape[1]
    cv = np.concatenate([val[rows], bv], axis=1)
    ci = np.concatenate([ids[rows], bi], axis=1)
    o = np.argsort(-cv, axis=1, kind="stable")
    cv = np.take_along_axis(cv, o, axis=1)
    val[rows] = cv[:, :K]
    ids[rows] = np.take_along_axis(ci, o[:, :K], axis=1)
    exc[rows] = np.maximum(np.maximum(exc[rows], cv[:, K]), bx)


def _seed_face_labels(Gc: np.ndarray) -> np.ndarray:
    """Face label of faces whose three corners are seeds: the group with most corners.

    ``Gc`` (r, 3) corner groups.  Ties (three different groups) go to the lowest id, as the
    exact argmax of the corner means (1/3 each) does.
    """
    a, b, c = Gc[:, 0], Gc[:, 1], Gc[:, 2]
    lab = np.minimum(np.minimum(a, b), c)
    lab = np.where(b == c, b, lab)
    lab = np.where(a == c, a, lab)
    lab = np.where(a == b, a, lab)
    return lab


def _argmax_update_ids(U: np.ndarray, gids: np.ndarray, best: np.ndarray, arg: np.ndarray) -> None:
    """Running argmax over columns with increasing group ids ``gids``; lower ids win ties
    (within :data:`~igl_heatseg.constants.TIE_RTOL`, as :func:`heat._argmax_update`)."""
    if U.shape[0] == 0:
        return
    pos = np.full(len(best), -1, dtype=np.int64)  # column that improved each row, or -1
    _argmax_update(U, 0, best, pos)
    upd = pos >= 0
    arg[upd] = gids[pos[upd]]
