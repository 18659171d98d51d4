"""Open a mesh along cut edges by splitting its vertices into wedges.

The corners around a vertex are grouped into *wedges*, joined across every interior edge that
is not cut; each wedge becomes one output vertex (:func:`open_wedges`), so every output vertex
is a single fan of faces.  :func:`split_topology` updates the edge topology for the opened mesh
without sorting again.  Used by :mod:`igl_heatseg.parameterization.cut`.
"""

from __future__ import annotations

import numpy as np

from ..mesh.topology import EdgeTopology, corner_edges, corner_fans

__all__ = ["open_wedges", "split_topology"]


def open_wedges(
    F: np.ndarray, topo: EdgeTopology, cut: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Split vertices into wedges joined across interior edges that are not cut.

    Parameters
    ----------
    F : (m, 3) int64
    topo : EdgeTopology of F
    cut : (ne,) bool
        Edges to cut (boundary entries are ignored).

    Returns
    -------
    Fn : (m, 3) int64
        Faces on the wedge vertices.
    vertex_map : (n',) int64
        Wedge vertex -> vertex of ``F``.  The first wedge of each referenced vertex gets the
        rank of that vertex among the referenced ones (so an uncut, unpinched, compact mesh
        comes back unchanged); extra wedges are appended.

    Examples
    --------
    >>> import numpy as np
    >>> from igl_heatseg.mesh.topology import edge_topology
    >>> F = np.array([[0, 1, 2], [0, 2, 3]])
    >>> topo = edge_topology(F)
    >>> cut = (np.sort(topo.E, axis=1) == [0, 2]).all(axis=1)
    >>> Fn, vmap = open_wedges(F, topo, cut)
    >>> Fn.tolist(), vmap.tolist()
    ([[0, 1, 5], [4, 2, 3]], [0, 1, 2, 3, 0, 2])
    """
    m = F.shape[0]
    ncomp, comp = corner_fans(F, topo, joined=~cut)
    corner_vertex = F.T.ravel()  # node j*m + f -> F[f, j]
    comp_vertex = np.empty(ncomp, dtype=np.int64)
    comp_vertex[comp] = corner_vertex
    order = np.lexsort((np.arange(ncomp), comp_vertex))
    sv = comp_vertex[order]
    first = np.ones(ncomp, dtype=bool)
    first[1:] = sv[1:] != sv[:-1]
    nprim = int(first.sum())
    new_id = np.empty(ncomp, dtype=np.int64)
    new_id[order[first]] = np.arange(nprim)
    new_id[order[~first]] = nprim + np.arange(ncomp - nprim)
    vertex_map = np.empty(ncomp, dtype=np.int64)
    vertex_map[new_id] = comp_vertex
    Fn = new_id[comp].reshape(3, m).T
    return np.ascontiguousarray(Fn), vertex_map


def split_topology(topo: EdgeTopology, Fn: np.ndarray) -> EdgeTopology:
    """Edge topology of ``Fn = open_wedges(F, topo, cut)`` from that of ``F``, without a sort.

    An interior edge of ``F`` whose two faces reach it through different wedge pairs in
    ``Fn`` (it was opened) becomes two boundary edges: the first face keeps the edge id, the
    second face's copy gets a new id after the old ones.  Every other edge carries over.  Same
    edges as :func:`igl_heatseg.mesh.topology.edge_topology` of ``Fn`` up to edge numbering
    (``E`` is not sorted by row; :mod:`~.cut` does not need it).

    Examples
    --------
    >>> import numpy as np
    >>> from igl_heatseg.mesh.topology import edge_topology
    >>> F = np.array([[0, 1, 2], [0, 2, 3]])
    >>> topo = edge_topology(F)
    >>> Fn, _ = open_wedges(F, topo, (np.sort(topo.E, axis=1) == [0, 2]).all(axis=1))
    >>> split_topology(topo, Fn).edge_face_count.tolist()  # the cut edge: two boundary edges
    [1, 1, 1, 1, 1, 1]
    """
    m = Fn.shape[0]
    ne = len(topo.E)
    D = np.sort(corner_edges(Fn), axis=1)
    ncorner = len(topo.EMAP)
    first = np.empty(ne, dtype=np.int64)
    first[topo.EMAP[::-1]] = np.arange(ncorner)[::-1]
    last = np.empty(ne, dtype=np.int64)
    last[topo.EMAP] = np.arange(ncorner)
    inner = topo.edge_face_count == 2
    split = inner & (D[first] != D[last]).any(axis=1)
    s_ids = np.flatnonzero(split)
    new_ids = ne + np.arange(len(s_ids))
    EMAP = topo.EMAP.copy()
    EMAP[last[s_ids]] = new_ids
    E = np.concatenate([D[first], D[last[s_ids]]])
    counts = np.concatenate([topo.edge_face_count, np.ones(len(s_ids), dtype=np.int64)])
    counts[s_ids] = 1
    EF = np.concatenate([topo.EF, np.full((len(s_ids), 2), -1, dtype=np.int64)])
    EF[s_ids, 1] = -1
    EF[new_ids, 0] = last[s_ids] % m  # corner-edge c = j*m + f
    EF[s_ids, 0] = first[s_ids] % m
    return EdgeTopology(E=E, EMAP=EMAP, edge_face_count=counts, EF=EF)
