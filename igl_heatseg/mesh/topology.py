"""Combinatorial helpers on triangle meshes (edges, adjacency, components, boundary loops).

All functions here take trusted, validated input (see :func:`igl_heatseg.mesh.checks.validate_mesh`).

Edge convention (libigl's): edge ``j`` of face ``f`` is the one *opposite* corner ``j``, i.e.
``(F[f, (j+1) % 3], F[f, (j+2) % 3])``; the corner-edge index is ``c = j * m + f``
(column-major, as ``igl.edge_topology``/``igl.unique_edge_map`` use it).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

__all__ = [
    "EdgeTopology",
    "unique_rows",
    "corner_edges",
    "edge_topology",
    "corner_fans",
    "face_adjacency",
    "face_components",
    "label_pieces",
    "vertex_components",
    "boundary_loops",
    "euler_characteristic",
]


@dataclass(frozen=True)
class EdgeTopology:
    """Unique undirected edges of a triangle mesh and their incidence.

    Attributes
    ----------
    E : (ne, 2) int64
        Unique undirected edges, ``E[e, 0] < E[e, 1]``.
    EMAP : (3*m,) int64
        Corner-edge ``c = j*m + f`` (edge opposite corner ``j`` of face ``f``) -> unique edge id.
    edge_face_count : (ne,) int64
        Number of faces incident to each edge (1 boundary, 2 interior, >2 non-manifold).
    EF : (ne, 2) int64
        For edges with at most two faces: the incident faces, ``-1`` where missing.  For a
        non-manifold edge only the first two faces are stored.
    """

    E: np.ndarray
    EMAP: np.ndarray
    edge_face_count: np.ndarray
    EF: np.ndarray

    @property
    def boundary(self) -> np.ndarray:
        """(ne,) bool: edges with exactly one incident face."""
        return self.edge_face_count == 1

    @property
    def interior(self) -> np.ndarray:
        """(ne,) bool: edges with exactly two incident faces."""
        return self.edge_face_count == 2


def unique_rows(A: np.ndarray, return_inverse: bool = False, return_counts: bool = False):
    """Unique rows of a 2-D array, sorted lexicographically: ``np.unique(A, axis=0, ...)``.

    ``np.unique(axis=0)`` sorts rows as opaque (void) elements with a generic comparison and is
    several times slower on meshes (iron.ply: ``validate_mesh`` 2.65 s -> 0.65 s,
    ``edge_topology`` 0.88 s -> 0.18 s).  Rows of two non-negative integers are packed into one
    int64 key and argsorted; other rows are ordered with ``np.lexsort``.  The output is
    identical to numpy's (``-0.0`` and ``0.0`` compare equal in both).

    Parameters
    ----------
    A : (r, c) int or float array
        No NaN (rows holding NaN never compare equal in ``np.unique`` either).
    return_inverse : bool
        Also return ``inverse`` (r,) int64 with ``U[inverse] == A``.
    return_counts : bool
        Also return ``counts`` (u,) int64.

    Returns
    -------
    U : (u, c) array of ``A.dtype``
    inverse : (r,) int64, optional
    counts : (u,) int64, optional
    """
    A = np.asarray(A)
    r = A.shape[0]
    if r == 0:
        out = [A[:0]]
        if return_inverse:
            out.append(np.zeros(0, dtype=np.int64))
        if return_counts:
            out.append(np.zeros(0, dtype=np.int64))
        return out[0] if len(out) == 1 else tuple(out)
    key = None
    if A.dtype.kind in "iu" and A.shape[1] == 2 and A.min() >= 0:
        b = np.int64(A[:, 1].max()) + 1
        if A[:, 0].max() < np.iinfo(np.int64).max // b:
            key = A[:, 0].astype(np.int64) * b + A[:, 1]
    new = np.empty(r, dtype=bool)
    new[0] = True
    if key is not None:
        order = np.argsort(key)  # int64 sort: vectorized, unlike void-row sorts
        ks = key[order]
        new[1:] = ks[1:] != ks[:-1]
        S = A[order]
    else:
        order = np.lexsort(A.T[::-1])
        S = A[order]
        new[1:] = (S[1:] != S[:-1]).any(axis=1)
    starts = np.flatnonzero(new)
    out = [S[starts]]
    if return_inverse:
        inv = np.empty(r, dtype=np.int64)
        inv[order] = np.cumsum(new) - 1
        out.append(inv)
    if return_counts:
        out.append(np.diff(np.r_[starts, r]).astype(np.int64))
    return out[0] if len(out) == 1 else tuple(out)


def corner_edges(F: np.ndarray) -> np.ndarray:
    """Directed corner-edges of ``F``.

    Parameters
    ----------
    F : (m, 3) int64

    Returns
    -------
    D : (3*m, 2) int64
        ``D[j*m + f] = (F[f, (j+1)%3], F[f, (j+2)%3])``, oriented as in the face.
    """
    return np.concatenate([F[:, [1, 2]], F[:, [2, 0]], F[:, [0, 1]]], axis=0)


def edge_topology(F: np.ndarray) -> EdgeTopology:
    """Unique edges, the corner-edge map, and edge-face incidence.

    Parameters
    ----------
    F : (m, 3) int64
        Triangles.

    Returns
    -------
    EdgeTopology
    """
    m = F.shape[0]
    D = corner_edges(F)
    S = np.sort(D, axis=1)
    E, EMAP, counts = unique_rows(S, return_inverse=True, return_counts=True)
    EMAP = EMAP.reshape(-1).astype(np.int64)
    faces = np.tile(np.arange(m, dtype=np.int64), 3)
    order = np.argsort(EMAP, kind="stable")
    starts = np.concatenate([[0], np.cumsum(counts)[:-1]])
    EF = np.full((E.shape[0], 2), -1, dtype=np.int64)
    EF[:, 0] = faces[order[starts]]
    has2 = counts >= 2
    EF[has2, 1] = faces[order[starts[has2] + 1]]
    return EdgeTopology(
        E=E.astype(np.int64), EMAP=EMAP, edge_face_count=counts.astype(np.int64), EF=EF
    )


def corner_fans(
    F: np.ndarray, topo: EdgeTopology | None = None, joined: np.ndarray | None = None
) -> tuple[int, np.ndarray]:
    """Fans of face corners around each vertex.

    Corners ``(f, j)`` (node ``j*m + f``, vertex ``F[f, j]``) are joined when their faces share
    an interior edge through that vertex.  Around a manifold vertex all corners form one fan;
    a vertex with several fans is non-manifold (or, with ``joined`` excluding cut edges, is
    split into one wedge per fan when the mesh is opened along the cut).

    Parameters
    ----------
    F : (m, 3) int64
    topo : EdgeTopology, optional
        Precomputed ``edge_topology(F)``.
    joined : (ne,) bool, optional
        Interior edges across which corners are joined (default: all interior edges).

    Returns
    -------
    count : int
        Number of fans.
    fan : (3*m,) int64
        Fan id of corner node ``j*m + f``.
    """
    topo = edge_topology(F) if topo is None else topo
    m = F.shape[0]
    keep = topo.interior if joined is None else (topo.interior & joined)
    inner = np.flatnonzero(keep)
    f0, f1 = topo.EF[inner, 0], topo.EF[inner, 1]
    rows, cols = [], []
    for k in range(2):
        v = topo.E[inner, k]
        j0 = np.argmax(F[f0] == v[:, None], axis=1)  # corner of v in f0
        j1 = np.argmax(F[f1] == v[:, None], axis=1)
        rows.append(j0 * m + f0)
        cols.append(j1 * m + f1)
    rows = np.concatenate(rows)
    cols = np.concatenate(cols)
    A = sp.csr_matrix((np.ones(len(rows), dtype=np.int8), (rows, cols)), shape=(3 * m, 3 * m))
    count, fan = connected_components(A, directed=False)
    return int(count), fan.astype(np.int64)


def face_adjacency(F: np.ndarray, topo: EdgeTopology | None = None) -> sp.csr_matrix:
    """Face-face adjacency through shared (manifold) edges.

    Parameters
    ----------
    F : (m, 3) int64
    topo : EdgeTopology, optional
        Precomputed :func:`edge_topology` of ``F``.

    Returns
    -------
    A : (m, m) scipy.sparse.csr_matrix of int8
        Symmetric, ``A[f, g] = 1`` iff faces ``f`` and ``g`` share an edge.
    """
    topo = edge_topology(F) if topo is None else topo
    inner = topo.EF[topo.interior]
    m = F.shape[0]
    data = np.ones(2 * len(inner), dtype=np.int8)
    rows = np.concatenate([inner[:, 0], inner[:, 1]])
    cols = np.concatenate([inner[:, 1], inner[:, 0]])
    return sp.csr_matrix((data, (rows, cols)), shape=(m, m))


def face_components(F: np.ndarray, topo: EdgeTopology | None = None) -> tuple[int, np.ndarray]:
    """Edge-connected components of faces.

    Returns
    -------
    count : int
    C : (m,) int64
        Component id of each face, ``0..count-1``.
    """
    count, C = connected_components(face_adjacency(F, topo), directed=False)
    return int(count), C.astype(np.int64)


def label_pieces(F: np.ndarray, labels: np.ndarray, TT: np.ndarray) -> np.ndarray:
    """Split every label into its edge-connected pieces of faces.

    Parameters
    ----------
    F : (m, 3) int64
    labels : (m,) int
        Any integer label per face.
    TT : (m, 3) int64
        Face-face adjacency, -1 on a border (``igl.triangle_triangle_adjacency(F)[0]``).

    Returns
    -------
    (m,) int64
        Piece of each face, ``0..p-1``: two faces share a piece when a chain of faces with
        their label joins them through shared edges.

    Examples
    --------
    >>> import igl, numpy as np
    >>> F = np.array([[0, 1, 2], [1, 3, 2], [2, 3, 4]])
    >>> TT = igl.triangle_triangle_adjacency(F)[0]
    >>> label_pieces(F, np.array([7, 8, 7]), TT).tolist()    # label 7 falls into two pieces
    [0, 1, 2]
    """
    fa = np.repeat(np.arange(len(F)), 3)
    fb = np.asarray(TT).ravel()
    keep = (fb >= 0) & (labels[np.maximum(fb, 0)] == labels[fa])
    A = sp.csr_matrix((np.ones(int(keep.sum())), (fa[keep], fb[keep])), shape=(len(F),) * 2)
    return connected_components(A, directed=False)[1].astype(np.int64)


def vertex_components(n: int, F: np.ndarray) -> tuple[int, np.ndarray]:
    """Connected components of the vertices ``0..n-1`` joined by the edges of ``F``.

    Returns
    -------
    count : int
    C : (n,) int64
    """
    D = corner_edges(F)
    A = sp.csr_matrix((np.ones(len(D), dtype=np.int8), (D[:, 0], D[:, 1])), shape=(n, n))
    count, C = connected_components(A, directed=False)
    return int(count), C.astype(np.int64)


def boundary_loops(F: np.ndarray) -> list[np.ndarray]:
    """Ordered boundary loops of an edge-manifold, consistently oriented mesh.

    Each loop follows the boundary half-edges in face orientation (the surface lies on the left).

    Returns
    -------
    loops : list of (k,) int64
        Vertex ids, first vertex not repeated at the end; longest loop first.
    """
    D = corner_edges(F)
    S = np.sort(D, axis=1)
    _, inv, counts = unique_rows(S, return_inverse=True, return_counts=True)
    bd = D[counts[inv.reshape(-1)] == 1]
    if len(bd) == 0:
        return []
    nxt = dict(zip(bd[:, 0].tolist(), bd[:, 1].tolist(), strict=True))
    # A vertex with two outgoing boundary half-edges (pinched boundary) cannot be in a
    # validated mesh; the dict keeps one of them and the walk still terminates.
    seen: set[int] = set()
    loops = []
    for start in bd[:, 0].tolist():
        if start in seen:
            continue
        loop = [start]
        seen.add(start)
        v = nxt[start]
        while v != start and v not in seen:
            loop.append(v)
            seen.add(v)
            v = nxt.get(v, start)
        loops.append(np.asarray(loop, dtype=np.int64))
    loops.sort(key=len, reverse=True)
    return loops


def euler_characteristic(F: np.ndarray) -> int:
    """V - E + F counted over the vertices referenced by ``F``.

    Returns
    -------
    chi : int
    """
    nv = len(np.unique(F))
    ne = len(unique_rows(np.sort(corner_edges(F), axis=1)))
    return int(nv - ne + F.shape[0])
