"""Patches, group ownership and domain growth for the fast heat solver's local solves.

Free vertices are cut into *patches* (consecutive runs in Morton order of their positions);
each seed group is *owned* by the patch holding most free neighbours of its seeds; a patch's
*domain* is the patch plus its groups' seed neighbours, grown by edge hops through free
vertices (:func:`grow`).  Refinement domains are grown the same way around clusters of
uncertified items (:func:`clusters`).  See :mod:`igl_heatseg.heat.fast` for the method.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

__all__ = [
    "HALO_HOPS",
    "HALO_HOPS_MAX",
    "PATCH_VERTICES",
    "PATCH_VERTICES_MAX",
    "Patches",
    "make_patches",
    "local_params",
    "pattern",
    "grow",
    "clusters",
    "morton",
]

#: Edge hops by which a patch's domain extends past its vertices and its groups' seeds.
#: Fields of one-vertex groups on iron.ply fall by about 2x per hop (measured), so 10 hops
#: leave about 1e-3 of the heat at the domain boundary.  This is the minimum; sparser
#: groups get more (:func:`local_params`).
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


class Patches(NamedTuple):
    """Patches of the free vertices and the domains of their local solves.

    Attributes
    ----------
    count : int
    patch : (nf,) int64
        Patch of each free vertex.
    owner : (k,) int64
        Patch owning each group (``-1``: the group has no free neighbour).
    domains : (nf, count) csc_matrix
        0/1 pattern: column ``c`` marks the free vertices of patch ``c``'s domain (sorted).
    """

    count: int
    patch: np.ndarray
    owner: np.ndarray
    domains: sp.csc_matrix

    def domain(self, c: int) -> np.ndarray:
        """Free vertices (increasing) of patch ``c``'s domain."""
        X = self.domains
        return X.indices[X.indptr[c] : X.indptr[c + 1]]

    def owned(self) -> tuple[list[np.ndarray], np.ndarray]:
        """Groups owned by each patch (increasing ids), and the groups owned by none."""
        owned = np.argsort(self.owner, kind="stable")
        bounds = np.searchsorted(self.owner[owned], np.arange(self.count + 1) - 0.5)
        per = [owned[bounds[c] : bounds[c + 1]] for c in range(self.count)]
        return per, owned[: bounds[0]]


def make_patches(
    Vfree: np.ndarray, B: sp.spmatrix, P: sp.csr_matrix, size: int, halo: int
) -> Patches:
    """Cut the free vertices into patches of about ``size``, assign groups, grow domains.

    Parameters
    ----------
    Vfree : (nf, 3) float64
        Positions of the free vertices.
    B : (nf, k) sparse
        Right-hand sides (non-zero where a free vertex neighbours a group's seed).
    P : (nf, nf) csr_matrix
        Adjacency pattern of the free vertices (:func:`pattern`).
    size : int
        Free vertices per patch.
    halo : int
        Hops by which domains grow past the patch and its groups' seed neighbours.
    """
    nf, k = B.shape
    order = np.argsort(morton(Vfree), kind="stable")
    npatch = max(1, -(-nf // size))
    patch = np.empty(nf, dtype=np.int64)
    patch[order] = np.arange(nf) * npatch // nf
    # Owner of each group: the patch holding most free neighbours of its seeds.
    Bc = B.tocoo()
    pair = sp.coo_matrix((np.ones(Bc.nnz), (Bc.col, patch[Bc.row])), shape=(k, npatch)).tocsr()
    owner = np.asarray(pair.argmax(axis=1)).ravel()
    owner[np.diff(pair.indptr) == 0] = -1  # group with no free neighbour
    # Domains: (nf, npatch) pattern grown by `halo` hops through free vertices.
    X = grow(P, np.r_[np.arange(nf), Bc.row], np.r_[patch, owner[Bc.col]], (nf, npatch), halo)
    return Patches(npatch, patch, owner, X)


def local_params(r: float) -> tuple[int, int]:
    """Halo (hops) and patch size (free vertices) for ``r`` free vertices per group.

    Sparser groups have longer-range fields: the halo grows like the typical distance
    between seeds (``sqrt(r)``) and the patch so that it owns about 50 groups or more.
    Measured (first rounds, default patches): iron.ply (``r`` = 9.9) halo 10 / 12 / 14
    left 106 / 15 / 2 vertices uncertified at about the same total time; the 200k-face
    mesh with 5 % seeds (``r`` = 29) took 14.1 s with halo 14 (7,492 uncertified), 12.4 s
    with 20 and 8.7 s with 25 (277 uncertified).

    Examples
    --------
    >>> local_params(9.9), local_params(1000.0)
    ((13, 600), (30, 16000))
    """
    halo = int(np.clip(round(4.0 * np.sqrt(max(r, 0.0))), HALO_HOPS, HALO_HOPS_MAX))
    patch = int(np.clip(50 * r, PATCH_VERTICES, PATCH_VERTICES_MAX))
    return halo, patch


def pattern(A: sp.spmatrix) -> sp.csr_matrix:
    """Adjacency pattern of ``A`` (diagonal included) as int32 ones.

    int32, not int8: a hop sums a row's neighbours, and a vertex of valence 127 or more
    would overflow int8, wrap to zero and drop out of the grown set.
    """
    P = sp.csr_matrix(A, dtype=np.int32, copy=True)
    P.data[:] = 1
    return P


def grow(
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


def clusters(
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


def morton(P: np.ndarray, bits: int = 21) -> np.ndarray:
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
