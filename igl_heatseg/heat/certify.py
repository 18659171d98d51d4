"""Candidate bounds and certified decisions for the fast heat solver.

The patch solves give lower bounds ``w_i <= u_i`` on a patch's groups and, through the
truncated heat ``d = 1 - sum_i w_i``, upper bounds ``u_i <= w_i + d`` (module docstring of
:mod:`igl_heatseg.heat.fast`, step 3).  :class:`Candidates` keeps the ``K`` largest lower
bounds per item (vertex or face) and a bound on all others; :class:`PatchBounds` folds each
patch's fields into the vertex and face candidates; :meth:`Candidates.uncertified` finds the
items whose winner is not certified, as :class:`Items` for refinement; :func:`decide` and
:func:`decide_all` take certified decisions from refined bounds (:class:`Decision`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from .exact import HeatSystem

__all__ = [
    "CERT_FACTOR",
    "CERT_ABS",
    "SKIP_BELOW",
    "Candidates",
    "PatchBounds",
    "Items",
    "Decision",
    "topk_rows",
    "merge_topk",
    "decide",
    "decide_all",
]

#: Rows (vertices) where all of a patch's fields are below this skip the top-K bookkeeping
#: for that patch (they only raise the bound on groups not kept).  A winner's value is at
#: least 1 / (number of groups near), far above this; a wrong skip could only leave a label
#: uncertified (then refined or solved exactly), never change it.
SKIP_BELOW: float = 0.02

#: A label is certified when its margin over every rival exceeds
#: ``CERT_FACTOR * |d| + CERT_ABS`` (``d``: truncated heat, see the module docstring).
#: ``CERT_FACTOR = 1`` is the bound for non-negative weights; 2 covers mild violations.
CERT_FACTOR: float = 2.0

#: Absolute margin covering round-off differences between two direct solves.
CERT_ABS: float = 1e-9


# ------------------------------------------------------------------------------------------
# top-K candidates


def topk_rows(M: np.ndarray, K: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
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


def merge_topk(
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


@dataclass
class Candidates:
    """Running top-K lower bounds per item (one class for vertices and faces).

    Attributes
    ----------
    val : (N, K) float64
        The ``K`` largest lower bounds seen per item, decreasing (``-inf``: none).
    ids : (N, K) int64
        Their groups (``-1``: none).
    exc : (N,) float64
        Bound on every group not kept (absent groups: ``w = 0``).
    """

    val: np.ndarray
    ids: np.ndarray
    exc: np.ndarray

    @classmethod
    def empty(cls, N: int, K: int) -> Candidates:
        return cls(np.full((N, K), -np.inf), np.full((N, K), -1, dtype=np.int64), np.zeros(N))

    def merge(self, rows: np.ndarray, bv: np.ndarray, bi: np.ndarray, bx: np.ndarray) -> None:
        """Fold a block's top-K (:func:`merge_topk`)."""
        merge_topk(self.val, self.ids, self.exc, rows, bv, bi, bx)

    def uncertified(self, slack: np.ndarray, mask: np.ndarray | None = None):
        """Items whose best lower bound does not beat every rival by ``slack``.

        Parameters
        ----------
        slack : (N,) float64
            Margin demanded of each item (``CERT_FACTOR * |d| + CERT_ABS``).
        mask : (N,) bool, optional
            Items that can be uncertified at all (faces: those with a free corner).

        Returns
        -------
        items : (a,) int64
            The uncertified items.
        pair_item, pair_group : (p,) int64
            Candidate pairs (index into ``items``, group) whose upper bound reaches the best
            lower bound, at items that are not open.
        open : (a,) bool
            Items where a group outside the kept candidates may win.
        rival : (a,) float64
            Bound on every group that is not a candidate.
        """
        val, ids, exc = self.val, self.ids, self.exc
        rival = np.maximum(val[:, 1], exc)
        unc = ~(val[:, 0] - rival > slack)
        if mask is not None:
            unc &= mask
        u = np.flatnonzero(unc)
        vu, su = val[u], slack[u]
        cand = (vu + su[:, None] >= vu[:, :1]) & (ids[u] >= 0)
        # If a rival outside the kept candidates may win, every group is a candidate there.
        is_open = exc[u] + su >= vu[:, 0]
        pi, pj = np.nonzero(cand & ~is_open[:, None])
        rest = np.maximum(np.where(cand, -np.inf, vu).max(axis=1), exc[u]) + su
        return u, pi, ids[u][pi, pj], is_open, rest


# ------------------------------------------------------------------------------------------
# patch solves -> candidates


class PatchBounds:
    """Lower bounds from the patch solves, for every free vertex and every face.

    Parameters
    ----------
    system : HeatSystem
    F : (m, 3) int64
    K : int
        Candidates kept per item.

    Attributes
    ----------
    v : Candidates
        Per free vertex.
    f : Candidates
        Per face (bounds on faces with only cold corners are added by :meth:`finish`).
    wsum : (nf,) float64
        ``sum_i w_i`` over every group solved at each free vertex.
    vcold : (nf,) float64
        Largest value of a group at a vertex where it was cold (below :data:`SKIP_BELOW`).
    fc : (m, 3) int64
        Free index of each face corner, ``-1`` at seeds.
    """

    def __init__(self, system: HeatSystem, F: np.ndarray, K: int) -> None:
        self.s, self.F, self.K = system, F, K
        nf, m, n = system.nf, F.shape[0], system.n
        self.v = Candidates.empty(nf, K)
        self.f = Candidates.empty(m, K)
        self.wsum = np.zeros(nf)
        self.vcold = np.zeros(nf)
        # Incidence free vertex -> faces, and vertex -> faces, for the faces a domain touches.
        self.fc = fc = system.fidx[F]
        rows = fc.ravel()
        sel = rows >= 0
        self._VFf = sp.csr_matrix(
            (np.ones(int(sel.sum()), dtype=np.int8), (rows[sel], np.repeat(np.arange(m), 3)[sel])),
            shape=(nf, m),
        )
        self._VF = sp.csr_matrix(
            (np.ones(3 * m, dtype=np.int8), (F.T.ravel(), np.tile(np.arange(m), 3))), shape=(n, m)
        )

    def add_vertices(self, D: np.ndarray, gids: np.ndarray, W: np.ndarray):
        """Fold one patch's fields ``W`` (|D|, len(gids)) on its domain ``D`` into ``v``.

        Returns ``hot`` (rows with a value of at least :data:`SKIP_BELOW`), and per row the
        local top-K columns ``ti`` (|D|, K) (zeros at cold rows) and the bound ``tx`` (|D|,)
        on the rest (cold rows: their maximum), for :meth:`add_faces`.
        """
        K = self.K
        self.wsum[D] += W.sum(axis=1)
        # Rows where this patch's groups are all below SKIP_BELOW ("cold": far in the
        # halo) only raise the bound on non-kept groups; no candidates from them.
        nD = W.shape[0]
        rmax = W.max(axis=1)
        hot = rmax >= SKIP_BELOW
        cold = np.flatnonzero(~hot)
        self.vcold[D[cold]] = np.maximum(self.vcold[D[cold]], rmax[cold])
        hot = np.flatnonzero(hot)
        tv, ti_h, tx_h = topk_rows(W[hot], K)  # patch-local top-K per hot vertex
        self.v.merge(D[hot], tv, gids[ti_h], tx_h)
        self.v.exc[D[cold]] = np.maximum(self.v.exc[D[cold]], rmax[cold])
        ti = np.zeros((nD, K), dtype=np.int64)
        ti[hot] = ti_h
        tx = rmax.copy()
        tx[hot] = tx_h
        return hot, ti, tx

    def add_faces(self, D, gids, W, hot, ti, tx) -> None:
        """Fold one patch's fields into the face candidates (after :meth:`add_vertices`).

        Faces with a hot free corner or a seed corner of an owned group.  Candidates: the
        groups in the local top-K of their hot corners and the groups of their seed corners;
        every other group of this patch is below the corner mean of the local (K+1)-th values
        (cold corners: their maximum).  Faces with only cold corners are bounded at the end
        through ``vcold`` (:meth:`finish`).
        """
        s, F, K, fc = self.s, self.F, self.K, self.fc
        group = s.group
        nD, kc = W.shape
        gpos = np.full(s.k, -1, dtype=np.int64)
        gpos[gids] = np.arange(kc)
        own = s.known[gpos[group[s.known]] >= 0]
        faces = np.unique(np.r_[self._VFf[D[hot]].indices, self._VF[own].indices])
        loc = np.full(s.nf, nD, dtype=np.int64)
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
        fv, fi, fx = topk_rows(val, K)
        self.f.merge(faces, fv, gids[np.take_along_axis(cz, fi, 1)], np.maximum(fx, rest))

    def finish(self, cert_factor: float = CERT_FACTOR, cert_abs: float = CERT_ABS):
        """Certification margins, once every patch is in.

        Adds the bound from cold corners to the face candidates and returns the slack
        ``cert_factor * |d| + cert_abs`` per free vertex and per face (corner mean of ``|d|``,
        0 at seeds), and the faces that have a free corner.
        """
        s, F = self.s, self.F
        d = 1.0 - self.wsum  # truncated heat per free vertex
        slack_v = cert_factor * np.abs(d) + cert_abs
        dab = np.zeros(s.n)
        dab[s.free] = np.abs(d)
        slack_f = cert_factor * (dab[F[:, 0]] + dab[F[:, 1]] + dab[F[:, 2]]) / 3.0 + cert_abs
        has_free = (self.fc >= 0).any(axis=1)
        vc = np.zeros(s.n)
        vc[s.free] = self.vcold
        vcmax = np.maximum(np.maximum(vc[F[:, 0]], vc[F[:, 1]]), vc[F[:, 2]])
        self.f.exc = np.maximum(self.f.exc, vcmax)
        return slack_v, slack_f, has_free


# ------------------------------------------------------------------------------------------
# items to refine, and decisions


@dataclass
class Items:
    """Uncertified items of one kind (vertices or faces), as refinement takes them.

    Attributes
    ----------
    idx : (a,) int64
        Free vertex index (vertices) or face id (faces).
    corners : (a, c) int64
        Free index of each corner, ``-1`` at seeds: ``c = 1`` for vertices, 3 for faces.
    seed_groups : (a, c) int64
        Seed group of each corner (``-1`` at free corners).
    pair_item, pair_group : (p,) int64
        Candidate pairs: index into ``idx``, group.
    open : (a,) bool
        Items where a group outside the candidates may win: every group with a seed on or
        next to the refinement domain is tried there.
    rival : (a,) float64
        Bound on every non-candidate (used for items that are not open).
    """

    idx: np.ndarray
    corners: np.ndarray
    seed_groups: np.ndarray
    pair_item: np.ndarray
    pair_group: np.ndarray
    open: np.ndarray
    rival: np.ndarray

    @property
    def face(self) -> bool:
        return self.corners.shape[1] == 3

    def __len__(self) -> int:
        return len(self.idx)

    def next_pass(self, dec: Decision, left: np.ndarray) -> Items:
        """The items ``left`` undecided by ``dec``, with its (item, group) pairs that may still
        win (where no untried group may: ``wide`` items are open)."""
        m = np.full(len(self), -1, dtype=np.int64)
        m[left] = np.arange(len(left))
        keep = (m[dec.win[0]] >= 0) & ~dec.wide[dec.win[0]]
        return Items(
            self.idx[left],
            self.corners[left],
            self.seed_groups[left],
            m[dec.win[0][keep]],
            dec.win[1][keep],
            dec.wide[left],
            dec.beat[left],
        )


@dataclass
class Decision:
    """Refinement's decision on each item of an :class:`Items`.

    Attributes
    ----------
    ok : (a,) bool
        Certified.
    label : (a,) int64
        Best group (certified where ``ok``).
    best : (a,) float64
        Its lower bound.
    win : tuple of two (q,) int64
        (item, group) pairs that may still win at an item (upper bound reaching the best
        lower bound).
    wide : (a,) bool
        Items where a group that was not tried may still win.
    beat : (a,) float64
        Bound on every group not in ``win`` at each item.
    """

    ok: np.ndarray
    label: np.ndarray
    best: np.ndarray
    win: tuple
    wide: np.ndarray
    beat: np.ndarray

    @classmethod
    def undecided(cls, a: int) -> Decision:
        e = np.zeros(0, dtype=np.int64)
        return cls(
            np.zeros(a, dtype=bool),
            np.full(a, -1, dtype=np.int64),
            np.full(a, -np.inf),
            (e, e),
            np.ones(a, dtype=bool),
            np.full(a, np.inf),
        )

    def assign(self, sel: np.ndarray, other: Decision) -> None:
        """Take ``other``'s per-item fields at ``sel`` (``win`` is left alone)."""
        for name in ("ok", "label", "best", "wide", "beat"):
            getattr(self, name)[sel] = getattr(other, name)[sel]

    def update(self, left: np.ndarray, deeper: Decision) -> None:
        """Replace the decisions on items ``left`` by those of a deeper pass on them."""
        for name in ("ok", "label", "best", "wide", "beat"):
            getattr(self, name)[left] = getattr(deeper, name)
        # the items of that pass get its pairs; the others keep theirs
        inleft = np.zeros(len(self.ok), dtype=bool)
        inleft[left] = True
        o = ~inleft[self.win[0]]
        self.win = (
            np.r_[self.win[0][o], left[deeper.win[0]]],
            np.r_[self.win[1][o], deeper.win[1]],
        )


def decide_all(Wv, gap, gids, items, dec: Decision) -> tuple[np.ndarray, np.ndarray]:
    """Certified argmax per item from all candidate values at once.

    ``Wv`` (r, c) lower bounds of the candidates ``gids`` (c,) (increasing), ``gap`` (r,)
    the upper bound's excess (also the bound on every non-candidate).  Writes ``ok``,
    ``label``, ``best``, ``wide`` (a non-candidate may win) and ``beat`` (bound on every
    group not returned) of ``dec`` at ``items`` (r,).

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
    dec.ok[items] = top > rival + CERT_ABS
    dec.label[items] = gids[j]
    dec.wide[items] = gap + CERT_ABS >= top
    dec.best[items] = top
    may = Wv + (gap + CERT_ABS)[:, None] >= top[:, None]
    dec.beat[items] = np.maximum(np.where(may, -np.inf, Wv).max(axis=1) + gap, gap)
    pi, pj = np.nonzero(may)
    return items[pi], gids[pj]


def decide(a, item, gid, lo, hi, rival) -> Decision:
    """Certified argmax per item from candidate (item, group, lower, upper) bounds.

    An item is certified when its best lower bound exceeds the upper bound of every other
    candidate and ``rival`` (bound on non-candidates) by :data:`CERT_ABS`.

    Returns
    -------
    Decision
        For ``a`` items; ``wide`` where ``rival`` reaches the best lower bound (or the item
        has no candidate).
    """
    if len(item) == 0:
        return Decision.undecided(a)
    ok = np.zeros(a, dtype=bool)
    lab = np.full(a, -1, dtype=np.int64)
    best = np.full(a, -np.inf)
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
    return Decision(ok, lab, best, (it[may], g[may]), wide, beat)
