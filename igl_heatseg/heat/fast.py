"""Fast heat-field labels for meshes with thousands of seed groups.

:class:`FastHeatSolver` has :class:`~igl_heatseg.heat.exact.HeatSolver`'s interface and returns
the same argmax labels, but never solves one global system per group.

The problem (Mejia et al. 2018, §3.2; :mod:`igl_heatseg.heat.exact`): with ``A = -L``
(``L = igl.cotmatrix``, negative semidefinite) and ``f`` the free vertices,
``A_ff u_i = L_fs 1_{S_i}`` for every group ``i``.

Two regimes
-----------
*Few or sparse groups* (``k * n_free <= exact_work``, or more than
``LOCAL_MAX_FREE_PER_GROUP`` free vertices per group): one sparse Cholesky factorization of
``A_ff`` (libigl's LLT for fewer than 80 groups, else CHOLMOD through ``cholespy`` when
installed) and all ``k`` fields solved exactly in batches of 32, folded on the fly into the
argmax: this mode *is* ``HeatSolver`` (on the same
:class:`~igl_heatseg.heat.exact.HeatSystem`).

*Many groups* (noisy scans: thousands of one-vertex groups): local solves with certificates.

1. Free vertices are cut into *patches* of about ``patch_size`` vertices (consecutive runs in
   Morton order of their positions).  Each group is *owned* by the patch that holds most of the
   free neighbours of its seeds.
2. The *domain* ``D_c`` of patch ``c`` is the patch, plus the free neighbours of its groups'
   seeds, grown by ``halo`` edge hops through free vertices (halo and patch size grow with
   the free vertices per group, :func:`~igl_heatseg.heat.patches.local_params`).  One
   factorization of ``A_DD`` per patch; one right-hand side per owned group.  The result
   ``w_i`` solves the problem with ``u = 0`` imposed on the free vertices outside ``D_c``
   (``w_i = 0`` there).
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
   factorization, and the argmax is taken from exact values
   (:meth:`~igl_heatseg.heat.exact.HeatSolver.argmax`).

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

Modules: :mod:`~igl_heatseg.heat.patches` (steps 1-2: patches, owners, domains),
:mod:`~igl_heatseg.heat.certify` (step 3: top-K candidates, certificates, decisions),
:mod:`~igl_heatseg.heat.refine` (step 4), :mod:`~igl_heatseg.heat.exact` (the exact mode and
step 5) and :mod:`~igl_heatseg.heat.factor` (the sparse Cholesky factorizations); this one
orchestrates them.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable, Sequence

import numpy as np
import scipy.sparse as sp

from ..constants import HEAT_SUM_TOL
from .certify import CERT_ABS, CERT_FACTOR, Decision, Items, PatchBounds
from .exact import HeatLabels, HeatSolver, HeatSystem, seed_face_labels
from .factor import SparseCholesky
from .patches import (
    HALO_HOPS,
    HALO_HOPS_MAX,
    PATCH_VERTICES,
    PATCH_VERTICES_MAX,
    local_params,
    make_patches,
    pattern,
)
from .refine import refine_passes

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

#: Candidates (lower bounds) kept per vertex and per face (at least 2).
TOPK: int = 4

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
    system : HeatSystem
        The Dirichlet problem (shared with the exact solves).
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
        self.system = s = HeatSystem(V, F, group, L)
        self.n, self.k, self.group, self.known, self.L = s.n, s.k, s.group, s.known, s.L
        self.free, self.nf = s.free, s.nf
        r = (self.n - len(self.known)) / max(self.k, 1)
        ah, ap = local_params(r)
        self.halo = ah if halo is None else int(halo)
        self.patch_size = ap if patch_size is None else int(patch_size)
        self.exact_work = float(EXACT_WORK if exact_work is None else exact_work)
        self.refine_halo = max(REFINE_HOPS, self.halo) if refine_halo is None else int(refine_halo)
        self._P: sp.csr_matrix | None = None  # adjacency pattern of A_ff (see _adjacency)
        self.stats: dict = {}

    def _adjacency(self) -> sp.csr_matrix:
        """Adjacency pattern of the free vertices (:func:`pattern` of ``A_ff``), built once."""
        if self._P is None:
            self._P = pattern(self.system.A)
        return self._P

    def _exact(self, nrhs: int) -> HeatSolver:
        """The exact solver on this problem (its factorization is built once, for ``nrhs``)."""
        return HeatSolver(self.V, self.F, self.group, system=self.system, nrhs=nrhs)

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
        return self.system.temperatures(groups, nrhs)

    def temperature(self, i: int) -> np.ndarray:
        """One exact temperature field ``u_i``, shape (n,)."""
        return self.temperatures([i])[:, 0]

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
        factored = self.system.factor_s is not None
        sparse_groups = self.exact_work > 0 and self.nf > LOCAL_MAX_FREE_PER_GROUP * self.k
        if self.k * self.nf <= self.exact_work or self.nf == 0 or sparse_groups:
            self.stats["mode"] = "exact"
            self.stats["fallback_groups"] = self.k
            hl = self._exact(self.k).labels(progress)  # warns on a failed sum check
        else:
            hl = self._labels_local(progress)
            if hl.sum_error > HEAT_SUM_TOL:
                log.warning(
                    "heat solve check failed: error %.3g (tolerance %.1g)",
                    hl.sum_error,
                    HEAT_SUM_TOL,
                )
        if not factored and self.system.factor_s is not None:
            self.stats["global_factor_s"] = self.system.factor_s
        self.stats["labels_s"] = time.perf_counter() - t0
        return hl

    def _labels_local(self, progress) -> HeatLabels:
        """Steps 1-5 of the module docstring: patch solves, certificates, refinement, and
        the exact fallback."""
        st = self.stats
        st["mode"] = "local"
        s, F = self.system, self.F
        m = F.shape[0]
        t = time.perf_counter()
        patches = make_patches(self.V[s.free], s.B, self._adjacency(), self.patch_size, self.halo)
        st["patches"] = patches.count
        st["domain_vertices"] = int(patches.domains.nnz)
        st["setup_s"] = time.perf_counter() - t

        t = time.perf_counter()
        bounds, resid = self._patch_solves(patches, progress)
        st["patch_solves_s"] = time.perf_counter() - t

        t = time.perf_counter()
        vertex_labels, vertex_max, face_labels, pending = self._certify(bounds)
        st["certify_s"] = time.perf_counter() - t

        # 4. Refinement of the uncertified items (refine.py).
        t = time.perf_counter()
        (dv, df), pass_stats = refine_passes(
            s,
            self._adjacency(),
            pending,
            patches.patch // _REFINE_SPLIT,
            self.refine_halo,
            REFINE_PASSES,
            None if progress is None else (lambda f: progress(0.9 + 0.1 * f)),
        )
        st.update(pass_stats)
        st["refined_groups"] = len(np.union1d(pending[0].pair_group, pending[1].pair_group))
        uv, uf = pending[0].idx, pending[1].idx
        vertex_labels[s.free[uv[dv.ok]]] = dv.label[dv.ok]
        vertex_max[s.free[uv[dv.ok]]] = dv.best[dv.ok]
        face_labels[uf[df.ok]] = df.label[df.ok]
        st["refine_s"] = time.perf_counter() - t

        # 5. The exact fallback, where refinement did not decide.
        cands = self._fallback_groups(dv, df)
        uv, uf = uv[~dv.ok], uf[~df.ok]
        st["exact_vertices"] = len(uv)
        st["exact_faces"] = len(uf)
        st["fallback_groups"] = len(cands)
        t = time.perf_counter()
        if len(cands):
            r = self._exact(len(cands)).argmax(cands, uv, uf)
            resid = max(resid, r.error)
            vertex_labels[s.free[uv]] = r.vertex_labels
            vertex_max[s.free[uv]] = r.vertex_max
            face_labels[uf] = r.face_labels
        st["fallback_s"] = time.perf_counter() - t
        if progress is not None:
            progress(1.0)
        log.info(
            "local heat labels: %d patches, %d domain vertices, %d/%d vertices and %d/%d faces "
            "left to the exact fallback, %d groups solved exactly",
            patches.count,
            patches.domains.nnz,
            len(uv),
            s.nf,
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

    def _certify(self, bounds: PatchBounds):
        """3. Labels from the best lower bounds; the items left uncertified, for refinement.

        Returns vertex labels and maxima (n,), face labels (m,) and the uncertified
        vertices and faces as :class:`~igl_heatseg.heat.certify.Items`.
        """
        s, F, st = self.system, self.F, self.stats
        slack_v, slack_f, has_free = bounds.finish(CERT_FACTOR, CERT_ABS)
        vertex_labels = s.group.copy()
        vertex_max = np.ones(s.n)
        vertex_labels[s.free] = bounds.v.ids[:, 0]
        vertex_max[s.free] = bounds.v.val[:, 0]
        face_labels = bounds.f.ids[:, 0].copy()
        # Faces whose corners are all seeds: exact corner counts, ties to the lowest id.
        allseed = np.flatnonzero(~has_free)
        if len(allseed):
            face_labels[allseed] = seed_face_labels(s.group[F[allseed]])
        uv, pv, gv, open_v, rival_v = bounds.v.uncertified(slack_v)
        uf, pf, gf, open_f, rival_f = bounds.f.uncertified(slack_f, has_free)
        st["uncertified_vertices"] = len(uv)
        st["uncertified_faces"] = len(uf)
        st["open_items"] = int(open_v.sum() + open_f.sum())
        pending = [
            Items(uv, uv[:, None], s.group[s.free[uv]][:, None], pv, gv, open_v, rival_v),
            Items(uf, bounds.fc[uf], s.group[F[uf]], pf, gf, open_f, rival_f),
        ]
        return vertex_labels, vertex_max, face_labels, pending

    def _fallback_groups(self, dv: Decision, df: Decision) -> np.ndarray:
        """Groups the exact fallback solves: those that may still win where refinement did
        not decide (by its bounds); where a group that no pass tried may still win, all."""
        cands = np.union1d(dv.win[1][~dv.ok[dv.win[0]]], df.win[1][~df.ok[df.win[0]]])
        wv, wf = ~dv.ok & dv.wide, ~df.ok & df.wide
        self.stats["exact_wide"] = int(wv.sum() + wf.sum())
        if wv.any() or wf.any():
            log.warning(
                "%d vertices/faces may be won by a group that no refinement pass tried: "
                "solving all %d groups exactly",
                int(wv.sum() + wf.sum()),
                self.k,
            )
            cands = np.arange(self.k)
        return cands

    def _patch_solves(self, patches, progress) -> tuple[PatchBounds, float]:
        """1-2. One factorization per patch domain, one right-hand side per owned group;
        the fields folded into top-K lower bounds per vertex and face.  Returns the bounds
        and the largest relative residual of the solves."""
        s, st = self.system, self.stats
        A, B = s.A, s.B
        bounds = PatchBounds(s, self.F, max(int(TOPK), 2))  # the certificate compares 2
        resid = 0.0
        per_patch, ownerless = patches.owned()
        tsub = [0.0] * 5
        for c, gids in enumerate(per_patch):  # gids sorted by group id (stable sort)
            if len(gids) == 0:
                continue
            D = patches.domain(c)
            t1 = time.perf_counter()
            ADD = A[D][:, D]
            BD = B[D][:, gids].toarray()
            t2 = time.perf_counter()
            fac = SparseCholesky(ADD, len(gids))
            t3 = time.perf_counter()
            W = fac.solve(BD)
            t4 = time.perf_counter()
            if W.ndim == 1:
                W = W[:, None]
            bn = np.abs(BD).max()
            if bn > 0:
                resid = max(resid, float(np.abs(ADD @ W - BD).max() / bn))
            hot, ti, tx = bounds.add_vertices(D, gids, W)
            t5 = time.perf_counter()
            bounds.add_faces(D, gids, W, hot, ti, tx)
            t6 = time.perf_counter()
            for j, dt in enumerate((t2 - t1, t3 - t2, t4 - t3, t5 - t4, t6 - t5)):
                tsub[j] += dt
            if progress is not None:
                progress(0.9 * (c + 1) / patches.count)
        for name, val in zip(("slice", "factor", "solve", "vertices", "faces"), tsub, strict=True):
            st[f"patch_{name}_s"] = val
        if len(ownerless):
            log.debug("%d groups touch no free vertex", len(ownerless))
        return bounds, resid
