"""Cut a chart open into a topological disk (paper §3.5 and its future work 1).

A chart can be mapped bijectively to the plane only if it is a topological disk: one
connected component, Euler characteristic ``V - E + F = 1`` and exactly one boundary loop.
This module

* measures a chart's topology (:func:`chart_topology`);
* cuts a chart open along the Dijkstra path between two vertices the user picked, the ends of
  a cylinder generatrix (the paper's mode, :func:`cut_along_path`, :func:`cut_along_paths`);
* cuts any chart to a disk automatically (:func:`cut_to_disk`): a *cut graph* of short paths
  is built with a greedy tree-cotree construction (Erickson & Whittlesey 2005, "Greedy optimal
  homotopy and homology generators", extended to boundaries by contracting all boundary
  vertices into the root).  On an annulus it is the shortest edge path between the two
  boundary loops (a generatrix on a cylinder); on a plate with ``h`` holes, ``h`` short paths
  joining the loops; on a torus, two short non-contractible loops through one vertex (the
  best of a few root vertices; ``igl.cut_to_disk``'s cut graph is used instead when it is
  shorter).  A closed genus-0 chart is opened along the shortest path between two far-apart
  vertices.

Opening a mesh along cut edges (:func:`cut_mesh_along_edges`) duplicates vertices: the corners
around a vertex are grouped into *wedges*, joined across every interior edge that is not cut;
each wedge becomes one output vertex.  Every output vertex is therefore a single fan of faces
(vertex-manifold by construction), also where a cut passes through a boundary vertex or where
the chart touched itself at a single vertex (a *pinch*, which is split even without cuts).

Conventions: ``F`` keeps its face order through every cut; ``vertex_map[i]`` is the vertex of
the input ``V`` that output vertex ``i`` is a copy of.  Edge lengths are Euclidean.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field

import igl
import numpy as np
import scipy.sparse as sp
from numpy.typing import ArrayLike
from scipy.sparse.csgraph import connected_components, minimum_spanning_tree
from scipy.sparse.csgraph import dijkstra as sp_dijkstra

from ..errors import CutError, MeshError
from ..mesh.checks import as_mesh_arrays
from ..mesh.topology import EdgeTopology, corner_edges, edge_topology, face_components
from .wedges import open_wedges, split_topology

__all__ = [
    "ChartTopology",
    "CutResult",
    "CutError",
    "chart_topology",
    "cut_to_disk",
    "cut_along_path",
    "cut_along_paths",
    "open_wedges",
    "split_topology",
    "cut_mesh_along_edges",
]

log = logging.getLogger(__name__)

#: Edges shorter than this (absolute) get this weight in shortest-path searches, because
#: scipy's sparse graphs treat an explicit 0 as a missing edge.
MIN_EDGE_WEIGHT: float = 1e-300

#: Root vertices tried for the greedy loop system of a closed chart of genus > 0.
CLOSED_ROOT_CANDIDATES: int = 4

#: How many offenders a message lists.
_SHOW = 5


@dataclass(frozen=True)
class ChartTopology:
    """Topology of a chart (a triangle mesh, usually a face subset of a bigger mesh).

    Attributes
    ----------
    components : int
        Edge-connected components of faces.
    euler : int
        ``V - E + F`` over the vertices the faces reference (a pinched vertex counts once).
    boundary_loops : int
        Boundary loops of the chart *as a surface*: a vertex where the chart touches itself
        (a pinch) is split first, so every loop is a simple cycle.
    genus : int
        Total genus of the surface, ``sum over components (2 - chi_c - b_c) / 2`` computed
        after splitting pinches.
    is_disk : bool
        ``components == 1 and euler == 1 and boundary_loops == 1 and pinched_vertices == 0``.
    pinched_vertices : int
        Extra vertex copies needed to split the vertices where the chart touches itself at a
        single vertex (0 for a manifold chart).
    """

    components: int
    euler: int
    boundary_loops: int
    genus: int
    is_disk: bool
    pinched_vertices: int = 0

    def as_dict(self) -> dict:
        """Plain dict for JSON reports."""
        return {
            "components": self.components,
            "euler": self.euler,
            "boundary_loops": self.boundary_loops,
            "genus": self.genus,
            "is_disk": self.is_disk,
            "pinched_vertices": self.pinched_vertices,
        }


@dataclass(frozen=True)
class CutResult:
    """A chart cut open.

    Attributes
    ----------
    V : (n', 3) float64
        Vertices of the cut chart (copies of input vertices; cut vertices appear several times).
    F : (m, 3) int64
        Faces in the *same order* as the input faces, indexing ``V``.
    vertex_map : (n',) int64
        Output vertex -> input vertex (index into the ``V`` that was passed in).
    cut_edges : (k, 2) int64
        The interior edges that were cut, as pairs of input vertex ids (smaller first).
    cut_length : float
        Total Euclidean length of ``cut_edges``.
    topology_before, topology_after : ChartTopology
    method : str
        ``"none"`` (already a disk), ``"unpinch"`` (only pinched vertices split),
        ``"annulus"``, ``"boundary-tree"`` (genus 0, several loops), ``"sphere-path"``,
        ``"tree-cotree"`` or ``"igl-cut-to-disk"`` (genus > 0), ``"paths"`` (user-given
        paths) or ``"edges"``.
    paths : list of (k_i,) int64
        For path-based cuts, the vertex sequences (input ids) of each path.
    """

    V: np.ndarray
    F: np.ndarray
    vertex_map: np.ndarray
    cut_edges: np.ndarray
    cut_length: float
    topology_before: ChartTopology
    topology_after: ChartTopology
    method: str = "none"
    paths: list = field(default_factory=list)


# --------------------------------------------------------------------------------------------
# input checks


def _check_chart(
    V: ArrayLike, F: ArrayLike, name: str
) -> tuple[np.ndarray, np.ndarray, EdgeTopology]:
    """Shape, range, edge-manifoldness and orientation checks (pinched vertices are allowed)."""
    V, F = as_mesh_arrays(V, F, name)
    n, m = V.shape[0], F.shape[0]
    if m == 0 or n == 0:
        raise MeshError(f"{name}: empty chart ({n} vertices, {m} faces)")
    bad = np.flatnonzero((F < 0).any(axis=1) | (F >= n).any(axis=1))
    if len(bad):
        items = ", ".join(f"face {f} = {F[f].tolist()}" for f in bad[:_SHOW])
        raise MeshError(
            f"{name}: {len(bad)} face(s) have vertex indices outside 0..{n - 1}: {items}"
        )
    rep = np.flatnonzero((F[:, 0] == F[:, 1]) | (F[:, 1] == F[:, 2]) | (F[:, 2] == F[:, 0]))
    if len(rep):
        items = ", ".join(f"face {f} = {F[f].tolist()}" for f in rep[:_SHOW])
        raise MeshError(f"{name}: {len(rep)} face(s) use the same vertex twice: {items}")
    topo = edge_topology(F)
    nm = np.flatnonzero(topo.edge_face_count > 2)
    if len(nm):
        items = ", ".join(f"edge {topo.E[e].tolist()}" for e in nm[:_SHOW])
        raise MeshError(
            f"{name}: {len(nm)} non-manifold edge(s) (shared by more than two faces): {items}"
        )
    D = corner_edges(F)
    inner = topo.interior[topo.EMAP]
    forward = D[:, 0] < D[:, 1]
    fwd = np.bincount(topo.EMAP[inner], weights=forward[inner], minlength=len(topo.E))
    flipped = np.flatnonzero(topo.interior & (fwd != 1))
    if len(flipped):
        items = ", ".join(f"edge {topo.E[e].tolist()}" for e in flipped[:_SHOW])
        raise MeshError(f"{name}: inconsistent face orientation on {len(flipped)} edge(s): {items}")
    return V, F, topo


# --------------------------------------------------------------------------------------------
# opening a mesh along edges


def _edge_ids(topo: EdgeTopology, n: int, pairs: np.ndarray) -> np.ndarray:
    """Unique-edge ids of vertex pairs; ``-1`` for pairs that are not edges."""
    pairs = np.sort(np.asarray(pairs, dtype=np.int64).reshape(-1, 2), axis=1)
    keys = topo.E[:, 0] * n + topo.E[:, 1]
    order = np.argsort(keys, kind="stable")  # E need not be sorted (see _relabel_topology)
    sk = keys[order]
    q = pairs[:, 0] * n + pairs[:, 1]
    pos = np.minimum(np.searchsorted(sk, q), len(sk) - 1)
    return np.where(sk[pos] == q, order[pos], -1)


def _relabel_topology(topo: EdgeTopology, Fu: np.ndarray) -> EdgeTopology:
    """Edge topology of ``Fu = open_wedges(F, topo, no cuts)`` from that of ``F``, without a sort.

    Splitting pinched vertices splits no edge: the two faces of an interior edge share their
    wedges at both ends.  So edge ids, ``EMAP``, counts and ``EF`` carry over and only the
    vertex ids of ``E`` change (``E`` rows stay ``min, max`` but need not be sorted by row).
    """
    ncorner = len(topo.EMAP)
    first = np.empty(len(topo.E), dtype=np.int64)
    first[topo.EMAP[::-1]] = np.arange(ncorner)[::-1]
    E = np.sort(corner_edges(Fu)[first], axis=1)
    return EdgeTopology(E=E, EMAP=topo.EMAP, edge_face_count=topo.edge_face_count, EF=topo.EF)


def _path_edges(path: np.ndarray) -> np.ndarray:
    return np.stack([path[:-1], path[1:]], axis=1)


def _path_mask(topo: EdgeTopology, n: int, paths: list) -> np.ndarray:
    """(ne,) bool: edges used by the vertex paths (steps that are not edges are ignored)."""
    cut = np.zeros(len(topo.E), dtype=bool)
    steps = [_path_edges(np.asarray(p, dtype=np.int64)) for p in paths if len(p) > 1]
    if steps:
        ids = _edge_ids(topo, n, np.concatenate(steps))
        cut[ids[ids >= 0]] = True
    return cut


# --------------------------------------------------------------------------------------------
# topology


def _topology(
    F: np.ndarray, topo: EdgeTopology, unpinched: tuple[np.ndarray, np.ndarray] | None = None
) -> ChartTopology:
    """Topology of ``F``; ``unpinched`` = ``open_wedges(F, topo, no cuts)`` if already known."""
    ncomp, _ = face_components(F, topo)
    nv = len(np.unique(F))
    chi = int(nv - len(topo.E) + F.shape[0])
    if unpinched is None:
        unpinched = open_wedges(F, topo, np.zeros(len(topo.E), dtype=bool))
    Fu, vmap = unpinched
    pinched = int(len(vmap) - nv)
    # Boundary loops after unpinching: components of the boundary-edge graph.  Edges keep
    # their ids (unpinching does not split edges), so map boundary edges through Fu.
    D = corner_edges(Fu)
    bmask = topo.boundary[topo.EMAP]
    bd = D[bmask]
    if len(bd):
        nu = len(vmap)
        B = sp.csr_matrix((np.ones(len(bd), dtype=np.int8), (bd[:, 0], bd[:, 1])), shape=(nu, nu))
        _, vc = connected_components(B, directed=False)
        loops = len(np.unique(vc[np.unique(bd)]))
    else:
        loops = 0
    chi_u = chi + pinched
    genus2 = 2 * ncomp - loops - chi_u
    genus = genus2 // 2
    is_disk = ncomp == 1 and chi == 1 and loops == 1 and pinched == 0
    return ChartTopology(
        components=ncomp,
        euler=chi,
        boundary_loops=int(loops),
        genus=int(genus),
        is_disk=bool(is_disk),
        pinched_vertices=pinched,
    )


def chart_topology(F: ArrayLike, name: str = "chart") -> ChartTopology:
    """Components, Euler characteristic, boundary loops and genus of a chart.

    Parameters
    ----------
    F : (m, 3) array_like of int
        Triangles of the chart (indices may skip unused vertices), consistently oriented and
        edge-manifold.
    name : str
        What to call the chart in error messages.

    Returns
    -------
    ChartTopology
        ``is_disk`` is True iff one component, ``euler == 1``, one boundary loop and no pinched
        vertex.

    Raises
    ------
    MeshError
        Wrong shape, negative indices, repeated corners, non-manifold edges, inconsistent
        orientation.

    Examples
    --------
    >>> chart_topology([[0, 1, 2], [0, 2, 3]]).is_disk
    True
    >>> t = chart_topology([[0, 1, 2], [0, 2, 3], [0, 3, 1], [1, 3, 2]])  # tetrahedron
    >>> (t.euler, t.boundary_loops, t.genus, t.is_disk)
    (2, 0, 0, False)
    """
    F = np.asarray(F)
    if F.ndim != 2 or F.shape[1] != 3:
        raise MeshError(f"{name}: `F` should have shape (m,3), shape is {F.shape}")
    if F.size and F.min() < 0:
        raise MeshError(f"{name}: `F` has negative vertex indices")
    n = int(F.max()) + 1 if F.size else 0
    _, F, topo = _check_chart(np.zeros((max(n, 1), 3)), F, name)
    return _topology(F, topo)


# --------------------------------------------------------------------------------------------
# cutting


def _finish(
    V: np.ndarray,
    F: np.ndarray,
    topo: EdgeTopology,
    cut: np.ndarray,
    before: ChartTopology,
    method: str,
    base_map: np.ndarray | None = None,
    paths: list | None = None,
) -> CutResult:
    """Open ``(V, F)`` along ``cut`` and package the result (ids mapped through ``base_map``)."""
    cut = cut & topo.interior
    Fn, vmap = open_wedges(F, topo, cut)
    Vn = np.ascontiguousarray(V[vmap])
    E = topo.E[cut]
    length = float(np.linalg.norm(V[E[:, 0]] - V[E[:, 1]], axis=1).sum()) if len(E) else 0.0
    if base_map is not None:
        vmap = base_map[vmap]
        E = np.sort(base_map[E], axis=1)
        paths = [base_map[p] for p in (paths or [])]
    # Fn is made of wedges: already unpinched, all of its vertices used.
    after = _topology(Fn, split_topology(topo, Fn), (Fn, np.arange(len(vmap))))
    return CutResult(
        V=Vn,
        F=Fn,
        vertex_map=vmap,
        cut_edges=E.reshape(-1, 2),
        cut_length=length,
        topology_before=before,
        topology_after=after,
        method=method,
        paths=list(paths or []),
    )


def cut_mesh_along_edges(
    V: ArrayLike, F: ArrayLike, cut_edges: ArrayLike, name: str = "chart"
) -> CutResult:
    """Open a chart along given edges (duplicating vertices), like ``igl.cut_mesh``.

    Each output vertex is one fan of faces joined across uncut interior edges, so the result
    is vertex-manifold for any cut set (also where a cut passes through a boundary vertex or
    the chart was pinched).  On a manifold chart it equals ``igl.cut_mesh`` (tested), without
    its unreferenced leftover vertices.  Note: ``igl.cut_mesh``'s mask entry ``(f, j)`` is the
    edge ``(F[f, j], F[f, (j+1) % 3])``, not the opposite-corner convention of
    :mod:`igl_heatseg.mesh.topology`.  A cut edge whose ends both stay joined around the other side
    (an isolated edge in the middle of the chart) has no effect.

    Parameters
    ----------
    V : (n, 3) array_like of float
    F : (m, 3) array_like of int
    cut_edges : (k, 2) array_like of int
        Vertex pairs; each must be an edge of ``F``.  Boundary edges are accepted and ignored.
    name : str

    Returns
    -------
    CutResult
        ``method == "edges"``; ``cut_edges`` lists the interior edges of the cut set
        (boundary pairs dropped).

    Raises
    ------
    MeshError
        Bad mesh, or a pair that is not an edge of ``F``.

    Examples
    --------
    >>> import numpy as np
    >>> F = np.array([[0, 1, 2], [0, 2, 3]]); V = np.eye(4, 3)
    >>> res = cut_mesh_along_edges(V, F, [[0, 2]])
    >>> len(res.V), res.cut_edges.tolist()
    (6, [[0, 2]])
    """
    V, F, topo = _check_chart(V, F, name)
    pairs = np.asarray(cut_edges, dtype=np.int64).reshape(-1, 2)
    ids = _edge_ids(topo, V.shape[0], pairs) if len(pairs) else np.zeros(0, dtype=np.int64)
    if (ids < 0).any():
        bad = pairs[ids < 0][:_SHOW].tolist()
        raise MeshError(f"{name}: {int((ids < 0).sum())} cut pair(s) are not edges of F: {bad}")
    cut = np.zeros(len(topo.E), dtype=bool)
    cut[ids] = True
    return _finish(V, F, topo, cut, _topology(F, topo), "edges")


def _lengths(V: np.ndarray, E: np.ndarray) -> np.ndarray:
    return np.maximum(np.linalg.norm(V[E[:, 0]] - V[E[:, 1]], axis=1), MIN_EDGE_WEIGHT)


def _graph(V: np.ndarray, topo: EdgeTopology) -> sp.csr_matrix:
    n = V.shape[0]
    E = topo.E
    w = _lengths(V, E)
    return sp.csr_matrix((w, (E[:, 0], E[:, 1])), shape=(n, n))


def _walk(pred: np.ndarray, v: int) -> list[int]:
    """Vertices from ``v`` back to the root of a predecessor tree (scipy's -9999 = none)."""
    out = [int(v)]
    while pred[out[-1]] >= 0:
        out.append(int(pred[out[-1]]))
    return out


def _sphere_cut(V: np.ndarray, topo: EdgeTopology) -> list[np.ndarray]:
    """Shortest path between two far-apart vertices (double Dijkstra sweep)."""
    G = _graph(V, topo)
    d0 = sp_dijkstra(G, directed=False, indices=int(topo.E[0, 0]))
    a = int(np.argmax(np.where(np.isfinite(d0), d0, -1)))
    da, pred = sp_dijkstra(G, directed=False, indices=a, return_predecessors=True)
    b = int(np.argmax(np.where(np.isfinite(da), da, -1)))
    path = _walk(pred, b)[::-1]
    if len(path) == 2:
        # A one-edge cut opens nothing (both ends stay single wedges): go one edge further.
        nbrs = np.union1d(G[b].indices, G[:, b].nonzero()[0])
        path.append(int(nbrs[nbrs != a][0]))
    return [np.asarray(path, dtype=np.int64)]


def _tree_cotree_cut(
    V: np.ndarray, F: np.ndarray, topo: EdgeTopology, boundary: np.ndarray
) -> list[np.ndarray]:
    """Greedy tree-cotree cut graph; returns its paths (boundary/root to boundary/root).

    With boundary, all boundary vertices form the root.  A closed surface needs one root
    vertex; the loops through it depend on it, so :data:`CLOSED_ROOT_CANDIDATES` roots (the
    most saddle-like vertex, then farthest-point samples) are tried and the shortest total
    loop length is kept.
    """
    n = V.shape[0]
    G = _graph(V, topo)
    if len(boundary):
        return _greedy_system(V, F, topo, G, boundary)
    # First root: the most saddle-like vertex (most negative angle defect); short
    # non-contractible loops run around waists, where the surface is saddle-shaped.
    defect = igl.gaussian_curvature(V, F)
    roots = [int(np.argmin(np.where(np.isin(np.arange(n), F), defect, np.inf)))]
    dmin = sp_dijkstra(G, directed=False, indices=roots[0])
    for _ in range(CLOSED_ROOT_CANDIDATES - 1):
        roots.append(int(np.argmax(np.where(np.isfinite(dmin), dmin, -1))))
        dmin = np.minimum(dmin, sp_dijkstra(G, directed=False, indices=roots[-1]))
    best, best_len = [], np.inf
    for r in roots:
        paths = _greedy_system(V, F, topo, G, np.array([r]))
        length = sum(np.linalg.norm(np.diff(V[p], axis=0), axis=1).sum() for p in paths)
        if length < best_len:
            best, best_len = paths, length
    return best


def _greedy_system(
    V: np.ndarray, F: np.ndarray, topo: EdgeTopology, G: sp.csr_matrix, sources: np.ndarray
) -> list[np.ndarray]:
    """One greedy tree-cotree system from a root set (Erickson & Whittlesey 2005)."""
    n, m = V.shape[0], F.shape[0]
    E = topo.E
    dist, pred, _ = sp_dijkstra(
        G, directed=False, indices=sources, return_predecessors=True, min_only=True
    )
    tv = np.flatnonzero(pred >= 0)
    in_tree = np.zeros(len(E), dtype=bool)
    in_tree[_edge_ids(topo, n, np.stack([tv, pred[tv]], axis=1))] = True

    cand = np.flatnonzero(topo.interior & ~in_tree)
    L = _lengths(V, E[cand])
    sigma = dist[E[cand, 0]] + dist[E[cand, 1]] + L
    fa = np.minimum(topo.EF[cand, 0], topo.EF[cand, 1])
    fb = np.maximum(topo.EF[cand, 0], topo.EF[cand, 1])
    key = fa * m + fb
    ukey, first = np.unique(key, return_index=True)  # a face pair shared twice: keep one
    sel = cand[first]
    w = (sigma[first].max() + 1.0) - sigma[first] if len(sel) else np.zeros(0)
    D = sp.csr_matrix((w, (fa[first], fb[first])), shape=(m, m))
    T = minimum_spanning_tree(D).tocoo()  # max spanning tree on sigma
    tkey = np.minimum(T.row, T.col).astype(np.int64) * m + np.maximum(T.row, T.col)
    in_cotree = np.zeros(len(E), dtype=bool)
    in_cotree[sel[np.searchsorted(ukey, tkey)]] = True
    left = cand[~in_cotree[cand]]
    log.debug("tree-cotree: %d generator edge(s), %d root vertices", len(left), len(sources))
    paths = []
    for e in left[np.argsort(dist[E[left, 0]] + dist[E[left, 1]])]:
        u, v = int(E[e, 0]), int(E[e, 1])
        paths.append(np.asarray(_walk(pred, u)[::-1] + _walk(pred, v), dtype=np.int64))
    return paths


def cut_to_disk(V: ArrayLike, F: ArrayLike, name: str = "chart") -> CutResult:
    """Cut a connected chart into a topological disk along short paths (automatic mode).

    * already a disk: returned unchanged (``cut_length == 0``, ``method == "none"``);
    * genus 0 with ``b >= 2`` boundary loops (annulus, plate with ``b - 1`` holes): ``b - 1``
      shortest paths that join all loops into one (for an annulus, the shortest edge path
      between its two loops: a generatrix on a cylinder);
    * closed genus 0: the shortest path between two far-apart vertices;
    * genus ``g > 0``: a greedy tree-cotree system of ``2g`` short loops (plus paths to the
      boundary loops, if any), or ``igl.cut_to_disk``'s cut graph when that is shorter
      (``method == "igl-cut-to-disk"``);
    * pinched vertices (the chart touches itself at one vertex) are split in every case.

    The result is verified with :func:`chart_topology`.

    Parameters
    ----------
    V : (n, 3) array_like of float
        Vertex positions; may contain vertices the chart does not use (they are dropped).
    F : (m, 3) array_like of int
        The chart's faces, edge-manifold and consistently oriented, one edge-connected
        component.
    name : str
        What to call the chart in messages.

    Returns
    -------
    CutResult
        ``F`` in the input face order; ``vertex_map`` maps to indices of the given ``V``.

    Raises
    ------
    MeshError
        Bad input, or a chart with several edge-connected components (cut each separately).
    CutError
        The construction did not yield a disk (internal error).

    Examples
    --------
    >>> import numpy as np
    >>> t = np.linspace(0, 2 * np.pi, 9)[:-1]
    >>> V = np.r_[np.c_[np.cos(t), np.sin(t), 0 * t], np.c_[np.cos(t), np.sin(t), 1 + 0 * t]]
    >>> i = np.arange(8); j = (i + 1) % 8
    >>> F = np.r_[np.c_[i, j, j + 8], np.c_[i, j + 8, i + 8]]
    >>> res = cut_to_disk(V, F)
    >>> res.topology_before.boundary_loops, res.topology_after.is_disk, round(res.cut_length, 6)
    (2, True, 1.0)
    """
    V, F, topo = _check_chart(V, F, name)
    none = np.zeros(len(topo.E), dtype=bool)
    Fu, umap = open_wedges(F, topo, none)  # pinched vertices split
    before = _topology(F, topo, (Fu, umap))
    if before.components != 1:
        raise MeshError(
            f"{name}: the chart has {before.components} edge-connected components; "
            "cut_to_disk handles one component at a time (split it with "
            "igl_heatseg.mesh.topology.face_components first)"
        )
    if before.is_disk:
        return _finish(V, F, topo, none, before, "none")
    # The rest works on the surface with pinched vertices split.
    Vu = V[umap]
    topo_u = _relabel_topology(topo, Fu)
    g, b = before.genus, before.boundary_loops
    if g == 0 and b == 1:
        method, paths = "unpinch", []
    elif g == 0 and b == 0:
        method, paths = "sphere-path", _sphere_cut(Vu, topo_u)
    else:
        method = "tree-cotree" if g > 0 else ("annulus" if b == 2 else "boundary-tree")
        paths = _tree_cotree_cut(Vu, Fu, topo_u, np.unique(topo_u.E[topo_u.boundary]))
    cut = _path_mask(topo_u, Vu.shape[0], paths)
    res = _finish(Vu, Fu, topo_u, cut, before, method, base_map=umap, paths=paths)
    if g > 0:
        # libigl's triangle-deletion cut graph (Gu et al. 2002) is sometimes shorter on
        # thin, many-handled parts: keep whichever valid disk cut is shorter.
        alt = [np.asarray(c, dtype=np.int64) for c in igl.cut_to_disk(Fu) if len(c) > 1]
        cut2 = _path_mask(topo_u, Vu.shape[0], alt) & topo_u.interior
        length2 = _lengths(Vu, topo_u.E[cut2]).sum()
        if length2 < res.cut_length * (1 - 1e-12):
            res2 = _finish(Vu, Fu, topo_u, cut2, before, "igl-cut-to-disk", umap, alt)
            if res2.topology_after.is_disk:
                res = res2
    if not res.topology_after.is_disk:
        raise CutError(
            f"{name}: internal error: {method} cut of a chart with genus {g} and {b} boundary "
            f"loop(s) gave {res.topology_after} instead of a disk"
        )
    log.info(
        "%s: %s cut, %d edge(s), length %.4g (genus %d, %d loop(s))",
        name,
        method,
        len(res.cut_edges),
        res.cut_length,
        g,
        b,
    )
    return res


def _vertex_ids(F: np.ndarray, n: int, ids: list, name: str) -> None:
    used = np.zeros(n, dtype=bool)
    used[F.ravel()] = True
    bad = []
    for v in ids:
        if isinstance(v, (bool, np.bool_)) or not isinstance(v, (int, np.integer)):
            bad.append(f"{v!r} (not an integer)")
        elif not 0 <= int(v) < n:
            bad.append(f"{int(v)} (outside 0..{n - 1})")
        elif not used[int(v)]:
            bad.append(f"{int(v)} (no face of the chart uses it)")
    if bad:
        raise MeshError(f"{name}: bad cut-path vertex id(s): " + ", ".join(bad))


def cut_along_paths(
    V: ArrayLike, F: ArrayLike, pairs: list[tuple[int, int]], name: str = "chart"
) -> CutResult:
    """Cut a chart open along Dijkstra paths between user-picked vertex pairs (paper mode).

    Each pair ``(v0, v1)`` is joined by the shortest edge path (``igl.dijkstra``, Euclidean
    weights).  The path avoids boundary vertices other than its own ends when it can, so the
    cut never runs along or touches a boundary in its middle (which would split off a piece).
    All paths are computed on the uncut chart and cut at once.

    Parameters
    ----------
    V : (n, 3) array_like of float
    F : (m, 3) array_like of int
    pairs : list of (int, int)
        Vertex ids of the chart (indices into ``V``), e.g. the two ends of a cylinder
        generatrix, one on each boundary loop.
    name : str

    Returns
    -------
    CutResult
        ``method == "paths"``; ``paths`` holds each path's vertex ids (in ``V``).  The result
        is *not* required to be a disk: check ``topology_after``.

    Raises
    ------
    MeshError
        Bad mesh, vertex ids out of range / unused by ``F`` / equal, or ends not connected.
    """
    V, F, topo = _check_chart(V, F, name)
    n = V.shape[0]
    pairs = [tuple(p) for p in pairs]
    for p in pairs:
        if len(p) != 2:
            raise MeshError(f"{name}: a cut path needs two vertex ids, got {p!r}")
    _vertex_ids(F, n, [v for p in pairs for v in p], name)
    for v0, v1 in pairs:
        if int(v0) == int(v1):
            raise MeshError(f"{name}: cut path ({v0}, {v1}) starts and ends at the same vertex")
    Fu, umap = open_wedges(F, topo, np.zeros(len(topo.E), dtype=bool))
    before = _topology(F, topo, (Fu, umap))
    Vu = np.ascontiguousarray(V[umap])
    topo_u = _relabel_topology(topo, Fu)
    # input vertex -> its first wedge (pinched vertices: the path starts in one of its fans)
    prim = np.full(n, -1, dtype=np.int64)
    prim[umap[::-1]] = np.arange(len(umap))[::-1]
    onb = np.zeros(len(umap), dtype=bool)
    onb[topo_u.E[topo_u.boundary].ravel()] = True
    VV = igl.adjacency_list(Fu)
    paths = []
    for v0, v1 in pairs:
        a, b = int(prim[int(v0)]), int(prim[int(v1)])
        keep = ~onb
        keep[[a, b]] = True
        VVr = [[w for w in nb if keep[w]] if keep[i] else [] for i, nb in enumerate(VV)]
        dist, prev = igl.dijkstra(Vu, VVr, a, {b})
        if not np.isfinite(dist[b]) or (b != a and prev[b] < 0):
            log.warning("%s: no path %d-%d avoiding the boundary; using any path", name, v0, v1)
            dist, prev = igl.dijkstra(Vu, VV, a, {b})
        if not np.isfinite(dist[b]) or prev[b] < 0:
            raise MeshError(f"{name}: vertices {v0} and {v1} are not connected in the chart")
        path = [b]
        while path[-1] != a and len(path) <= len(umap):
            path.append(int(prev[path[-1]]))
        if path[-1] != a:  # pragma: no cover - igl.dijkstra returned a broken tree
            raise RuntimeError(f"{name}: igl.dijkstra gave no path {v0}-{v1}")
        paths.append(np.asarray(path[::-1], dtype=np.int64))
    cut = _path_mask(topo_u, len(umap), paths)
    res = _finish(Vu, Fu, topo_u, cut, before, "paths", base_map=umap, paths=paths)
    if not res.topology_after.is_disk:
        log.warning(
            "%s: after cutting along %d path(s) the chart is not a disk: %s",
            name,
            len(pairs),
            res.topology_after,
        )
    return res


def cut_along_path(V: ArrayLike, F: ArrayLike, v0: int, v1: int, name: str = "chart") -> CutResult:
    """Cut a chart open along the Dijkstra path from ``v0`` to ``v1`` (paper §3.5).

    Shorthand for ``cut_along_paths(V, F, [(v0, v1)])``; see :func:`cut_along_paths`.

    Parameters
    ----------
    V : (n, 3) array_like of float
    F : (m, 3) array_like of int
    v0, v1 : int
        Start and end vertex (indices into ``V``) of a cylinder generatrix, usually one on
        each boundary loop of an annulus.
    name : str

    Returns
    -------
    CutResult

    Raises
    ------
    MeshError
    """
    return cut_along_paths(V, F, [(v0, v1)], name)
