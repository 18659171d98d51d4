"""Refinement of uncertified labels: re-solves on larger domains around them.

Step 4 of the fast heat solver (module docstring of :mod:`igl_heatseg.heat.fast`): the groups
that could still win at an uncertified vertex or face are re-solved on a domain grown
``halo`` hops around it; the harmonic measure ``h`` of the domain's outer boundary bounds the
truncation (``w <= u <= w + h`` for non-negative weights).  :func:`refine_passes` runs the
first pass and deeper ones (2x, 3x the halo) on what is left.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np
import scipy.sparse as sp

from .certify import CERT_FACTOR, Decision, Items, decide, decide_all
from .exact import HeatSystem
from .factor import SparseCholesky
from .patches import clusters, grow

__all__ = ["refine", "refine_passes", "face_rows"]


def refine_passes(
    system: HeatSystem,
    P: sp.csr_matrix,
    pending: Sequence[Items],
    split: np.ndarray,
    halo: int,
    passes: int,
    progress: Callable[[float], None] | None = None,
) -> tuple[list[Decision], dict]:
    """The first refinement pass, then up to ``passes`` deeper ones on what is left.

    Deeper passes (2x, 3x the halo): where a few possible winners are too close to call,
    only they are re-solved (every other group stays below ``beat``); where a group not
    tried may win ("wide"), every group seeded next to the larger domain is tried.
    ``halo == 0`` runs the first pass only.

    Returns
    -------
    decisions : list of Decision
        One per ``pending`` (each over all of its items).
    stats : dict
        ``refine_pass<depth>_items``: items left to each deeper pass.
    """
    stats = {}
    p0 = None if progress is None else (lambda f: progress(f * 0.6))
    decs = refine(system, P, pending, split, halo, p0)
    for depth in range(2, 2 + passes):
        left = [np.flatnonzero(~d.ok) for d in decs]
        if halo == 0 or not any(len(x) for x in left):
            break
        nxt = [it.next_pass(d, x) for it, d, x in zip(pending, decs, left, strict=True)]
        pd = None if progress is None else (lambda f, d=depth: progress(0.6 + 0.1 * (d - 2 + f)))
        deeper = refine(system, P, nxt, split, depth * halo, pd)
        for d, x, r in zip(decs, left, deeper, strict=True):
            d.update(x, r)
        stats[f"refine_pass{depth}_items"] = sum(len(x) for x in left)
    return decs, stats


def refine(
    system: HeatSystem,
    P: sp.csr_matrix,
    pending: Sequence[Items],
    split: np.ndarray,
    halo: int,
    progress: Callable[[float], None] | None = None,
) -> list[Decision]:
    """Re-solve candidate groups on large domains around uncertified items.

    Parameters
    ----------
    system : HeatSystem
    P : (nf, nf) csr_matrix
        Adjacency pattern of the free vertices.
    pending : sequence of Items
        Uncertified items (vertices, faces).
    split : (nf,) int64
        Part of each free vertex; clusters never span two parts.
    halo : int
        Hops of the domains.
    progress : callable, optional
        Called with the fraction of clusters done.

    Returns
    -------
    list of Decision
        One per ``pending``.

    Notes
    -----
    Items of one part within ``2 halo / 3`` hops of each other form a cluster
    (:func:`~igl_heatseg.heat.patches.clusters`).  A cluster's domain ``D`` grows ``halo``
    hops around its items and its candidate groups' seeds and is factored once.  With ``h``
    the harmonic measure of ``D``'s outer boundary (``A_DD h = L_D,out 1``),
    ``w <= u <= w + h`` when the weights are non-negative (``u <= 1`` outside), and the
    groups without a seed next to ``D`` sum to at most ``h`` inside it.  As in the patch
    solves the margins are ``CERT_FACTOR`` times these bounds.  Items that are not open are
    decided from their candidate pairs' bounds (:func:`~igl_heatseg.heat.certify.decide`),
    open ones from all the groups tried (:func:`~igl_heatseg.heat.certify.decide_all`).
    """
    A, B, nf = system.A, system.B, system.nf
    lo = [np.full(len(it.pair_item), -np.inf) for it in pending]
    hi = [np.full(len(it.pair_item), np.inf) for it in pending]
    decs = [Decision.undecided(len(it)) for it in pending]
    wins: list[list] = [[] for _ in pending]
    ncl, cls, X = _cluster_domains(system, P, pending, split, halo)
    pair_cl = [c[it.pair_item] for it, c in zip(pending, cls, strict=True)]
    if ncl:
        Arow = A @ np.ones(nf)
        Br = B.tocsr()
        loc = np.full(nf, -1, dtype=np.int64)
    for ci in range(ncl):
        if progress is not None:
            progress(ci / ncl)
        D = X.indices[X.indptr[ci] : X.indptr[ci + 1]]
        sel = [np.flatnonzero(pc == ci) for pc in pair_cl]  # pairs in the cluster
        opn = [np.flatnonzero(it.open & (c == ci)) for it, c in zip(pending, cls, strict=True)]
        BDr = Br[D]
        gids = _cluster_groups(pending, sel, opn, BDr)
        ADD = A[D][:, D]
        bh = -(Arow[D] - ADD @ np.ones(len(D)))  # L_D,out 1 (>= 0 for cot weights)
        rhs = np.c_[BDr[:, gids].toarray(), bh]
        W = SparseCholesky(ADD, rhs.shape[1]).solve(rhs)
        if W.ndim == 1:
            W = W[:, None]
        h = np.maximum(W[:, -1], 0.0)
        W = W[:, :-1]
        loc[D] = np.arange(len(D))
        for t, it in enumerate(pending):
            s = sel[t]
            lo[t][s], hi[t][s] = _pair_bounds(it, W, h, loc, gids, s)
            if len(opn[t]):  # open items: all groups at once; the rest sum to at most h
                Wv, gap = _all_bounds(it, W, h, loc, gids, opn[t])
                wins[t].append(decide_all(Wv, gap, gids, opn[t], decs[t]))
        loc[D] = -1
    # candidate pairs of the items that are not open
    for t, it in enumerate(pending):
        pp = ~it.open[it.pair_item]
        dp = decide(len(it), it.pair_item[pp], it.pair_group[pp], lo[t][pp], hi[t][pp], it.rival)
        decs[t].assign(~it.open, dp)
        wins[t].append(dp.win)
        decs[t].win = tuple(np.concatenate(x) for x in zip(*wins[t], strict=True))
    return decs


def _cluster_domains(
    system: HeatSystem, P: sp.csr_matrix, pending: Sequence[Items], split: np.ndarray, halo: int
) -> tuple[int, list[np.ndarray], sp.csc_matrix | None]:
    """Clusters of the items to refine and their domains.

    Returns the cluster count, the cluster of each item of each ``pending`` (``-1``: not
    refined) and the (nf, count) domain pattern: items and the free neighbours of their
    candidate groups' seeds, grown ``halo`` hops.
    """
    # Items to refine, one vertex each (a face: a free corner, the largest free index).
    act = []
    for it in pending:
        a = it.open.copy()
        a[it.pair_item] = True
        act.append(np.flatnonzero(a))
    anchors = np.concatenate(
        [np.zeros(0, dtype=np.int64)]
        + [it.corners[a].max(axis=1) for it, a in zip(pending, act, strict=True)]
    )
    ncl, cl = clusters(P, anchors, max(halo // 3, 1), split)
    cls, off = [], 0
    for it, a in zip(pending, act, strict=True):
        c = np.full(len(it), -1, dtype=np.int64)
        c[a] = cl[off : off + len(a)]
        off += len(a)
        cls.append(c)
    if not ncl:
        return 0, cls, None
    # growth sources: item vertices and the free neighbours of the groups' seeds
    pair_cl = np.concatenate([c[it.pair_item] for it, c in zip(pending, cls, strict=True)])
    Bc = system.B[:, np.concatenate([it.pair_group for it in pending])].tocoo()
    src_r = np.concatenate(
        [it.corners[a].ravel() for it, a in zip(pending, act, strict=True)] + [Bc.row]
    )
    src_c = np.concatenate(
        [np.repeat(c[a], it.corners.shape[1]) for it, a, c in zip(pending, act, cls, strict=True)]
        + [pair_cl[Bc.col]]
    )
    keep = src_r >= 0
    return ncl, cls, grow(P, src_r[keep], src_c[keep], (system.nf, ncl), halo)


def _cluster_groups(pending, sel, opn, BDr) -> np.ndarray:
    """Groups to solve on one cluster's domain (increasing): those of its candidate pairs
    ``sel``; if it has open items ``opn``, also every group with a seed next to the domain
    (``BDr``: rows of ``B`` on it)."""
    gids = np.unique(np.concatenate([it.pair_group[s] for it, s in zip(pending, sel, strict=True)]))
    if any(len(o) for o in opn):  # every group with a seed next to D
        gids = np.union1d(gids, np.unique(BDr.indices))
        # and the groups of the open faces' seed corners (their weight to D
        # may be exactly zero, so B need not list them)
        for it, o in zip(pending, opn, strict=True):
            if it.face and len(o):
                sg = it.seed_groups[o].ravel()
                gids = np.union1d(gids, sg[sg >= 0])
    return gids


def _pair_bounds(it: Items, W, h, loc, gids, s):
    """Lower and upper bounds of the candidate pairs ``s`` of ``it`` on one domain."""
    col = np.searchsorted(gids, it.pair_group[s])
    items = it.pair_item[s]
    if not it.face:
        rv = loc[it.corners[items, 0]]
        return W[rv, col], W[rv, col] + CERT_FACTOR * h[rv]
    lo, hgap = face_rows(W, h, loc, it.corners[items], it.seed_groups[items], it.pair_group[s], col)
    return lo, lo + CERT_FACTOR * hgap


def _all_bounds(it: Items, W, h, loc, gids, o):
    """Lower bounds of every group ``gids`` at the open items ``o`` of ``it``, and the gap."""
    if not it.face:
        rv = loc[it.corners[o, 0]]
        return W[rv], CERT_FACTOR * h[rv]
    cr = it.corners[o]
    rl = np.where(cr >= 0, loc[np.maximum(cr, 0)], -1)
    Wz = np.vstack([W, np.zeros((1, len(gids)))])
    rz = np.where(rl >= 0, rl, W.shape[0])
    own = (it.seed_groups[o][:, :, None] == gids[None, None, :]).sum(axis=1)
    Wf = (Wz[rz[:, 0]] + Wz[rz[:, 1]] + Wz[rz[:, 2]] + own) / 3.0
    hz = np.r_[h, 0.0]
    gap = CERT_FACTOR * (hz[rz[:, 0]] + hz[rz[:, 1]] + hz[rz[:, 2]]) / 3.0
    return Wf, gap


def face_rows(W, h, loc, cr, cg, gid, col):
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
