"""Repair of the defects real exports have, on libigl's own routines (``repair=True``).

:func:`repair_mesh` takes a cleaned triangle mesh (exact duplicate vertices merged, no
unreferenced vertex: what :func:`~igl_heatseg.mesh.checks.validate_mesh` hands it) and, in
this order:

1. welds vertices closer than ``weld_tol`` x the bounding-box diagonal
   (``igl.remove_duplicate_vertices``; the kept vertices stay in the input's order);
2. drops faces of zero area: a repeated corner (after welding) or collinear corners (the
   criterion of the strict check, :data:`~igl_heatseg.constants.DEGENERATE_FACE_TOL`);
3. drops duplicate faces (same three vertices, either orientation; ``igl.unique_simplices``),
   keeping the first;
4. splits non-manifold vertices and edges into manifold sheets (``igl.split_nonmanifold``:
   a vertex or edge is copied once per sheet of faces around it);
5. orients every component consistently (``igl.bfs_orient``), outward when it is closed
   (``igl.orient_outward``); an open component keeps the orientation most of its input faces
   had.

Faces keep the input's order (dropped ones left out). A dropped face takes, for the outputs
that are per input face, the label of the face across its longest edge (a duplicate: the label
of its kept twin), or ``-1`` when no kept face is there (``face_source``). Every change is
counted in :attr:`RepairResult.counts`, which the commands write to ``report.json`` as
``repairs``.
"""

from __future__ import annotations

from dataclasses import dataclass

import igl
import numpy as np

from ..constants import DEGENERATE_FACE_TOL
from ..errors import MeshError
from .geometry import face_areas
from .topology import corner_fans, edge_topology, unique_rows

__all__ = ["WELD_TOL", "RepairResult", "repair_mesh", "nonmanifold_vertices"]

#: Vertices closer than this fraction of the bounding-box diagonal are welded by repair.
WELD_TOL: float = 1e-7


@dataclass(frozen=True)
class RepairResult:
    """What :func:`repair_mesh` made of a mesh.

    Attributes
    ----------
    V : (n', 3) float64
    F : (m', 3) int64
        The repaired mesh; ``F`` row ``r`` is input face ``keep[r]``.
    keep : (m',) int64
        Input faces kept, ascending.
    face_source : (m,) int64
        Input face -> repaired face whose label it takes (itself when kept; across the longest
        edge when dropped; the kept twin of a duplicate), ``-1`` when none.
    vertex_map : (n,) int64
        Input vertex -> one repaired vertex (the first copy of a split vertex), ``-1`` when no
        kept face uses it.
    vertex_origin : (n',) int64
        Repaired vertex -> the input vertex it comes from.
    counts : dict
        ``welded_vertices``, ``zero_area_faces``, ``duplicate_faces``,
        ``nonmanifold_edges``, ``nonmanifold_vertices``, ``split_vertices``,
        ``reoriented_faces``, ``dropped_faces_unlabelled``, and ``weld_tolerance``.
    """

    V: np.ndarray
    F: np.ndarray
    keep: np.ndarray
    face_source: np.ndarray
    vertex_map: np.ndarray
    vertex_origin: np.ndarray
    counts: dict

    @property
    def changed(self) -> bool:
        """True when the mesh differs from the input."""
        return any(v for k, v in self.counts.items() if k != "weld_tolerance")


def _degenerate(V: np.ndarray, F: np.ndarray) -> np.ndarray:
    with np.errstate(over="ignore", invalid="ignore"):
        rep = (F[:, 0] == F[:, 1]) | (F[:, 1] == F[:, 2]) | (F[:, 2] == F[:, 0])
        P0, P1, P2 = V[F[:, 0]], V[F[:, 1]], V[F[:, 2]]
        longest2 = np.max(
            [((P1 - P0) ** 2).sum(1), ((P2 - P1) ** 2).sum(1), ((P0 - P2) ** 2).sum(1)], axis=0
        )
        dblA = 2.0 * face_areas(V, F)
        return rep | ~(dblA > DEGENERATE_FACE_TOL * longest2)


def _longest_edge(V: np.ndarray, F: np.ndarray) -> np.ndarray:
    """(m, 2) sorted vertex pair of each face's longest edge."""
    E = np.stack([F[:, [1, 2]], F[:, [2, 0]], F[:, [0, 1]]], axis=1)  # (m, 3, 2)
    L = ((V[E[:, :, 0]] - V[E[:, :, 1]]) ** 2).sum(2)
    k = np.argmax(L, axis=1)
    return np.sort(E[np.arange(len(F)), k], axis=1)


def nonmanifold_vertices(F: np.ndarray, topo=None) -> np.ndarray:
    """Vertices whose incident faces form more than one edge-connected fan.

    Corners ``(f, v)`` are nodes; two corners of the same vertex are joined when their faces
    share an interior edge through that vertex.  A manifold vertex has one component of corners.
    """
    topo = edge_topology(F) if topo is None else topo
    n = int(F.max()) + 1
    _, comp = corner_fans(F, topo)
    corner_vertex = F.T.ravel()  # node j*m+f -> F[f, j]
    pairs = unique_rows(np.stack([corner_vertex, comp], axis=1))
    fans = np.bincount(pairs[:, 0], minlength=n)
    return np.flatnonzero(fans > 1)


def _nonmanifold_counts(F: np.ndarray) -> tuple[int, int]:
    topo = edge_topology(F)
    return int((topo.edge_face_count > 2).sum()), int(len(nonmanifold_vertices(F, topo)))


def _same_orientation(F0: np.ndarray, F1: np.ndarray) -> np.ndarray:
    """Rows of ``F1`` that are a rotation (not a reflection) of the same row of ``F0``."""
    same = np.zeros(len(F0), dtype=bool)
    for s in range(3):
        same |= (np.roll(F0, s, axis=1) == F1).all(axis=1)
    return same


def repair_mesh(
    V: np.ndarray, F: np.ndarray, name: str = "mesh", weld_tol: float | None = None
) -> RepairResult:
    """Repair a cleaned triangle mesh (see the module docstring for the steps).

    Parameters
    ----------
    V : (n, 3) float64
    F : (m, 3) int64
        Every vertex used, exact duplicates merged.
    name : str
    weld_tol : float, optional
        Weld distance relative to the bounding-box diagonal (default :data:`WELD_TOL`;
        ``0`` welds nothing).

    Returns
    -------
    RepairResult

    Raises
    ------
    MeshError
        Nothing is left after dropping the zero-area and duplicate faces.
    """
    V = np.ascontiguousarray(V, dtype=np.float64)
    F = np.ascontiguousarray(F, dtype=np.int64)
    n, m = V.shape[0], F.shape[0]
    tol_rel = WELD_TOL if weld_tol is None else float(weld_tol)
    if not tol_rel >= 0:
        raise MeshError(f"{name}: weld tolerance must be >= 0, got {weld_tol!r}")
    diag = float(np.linalg.norm(V.max(0) - V.min(0))) if n else 0.0
    tol = tol_rel * diag
    counts = {
        "weld_tolerance": tol,
        "welded_vertices": 0,
        "zero_area_faces": 0,
        "duplicate_faces": 0,
        "nonmanifold_edges": 0,
        "nonmanifold_vertices": 0,
        "split_vertices": 0,
        "reoriented_faces": 0,
        "dropped_faces_unlabelled": 0,
    }

    # 1. weld (libigl rounds to a grid of `tol`); keep the first vertex of each class, in order
    weld = np.arange(n)
    if tol > 0:
        _, _, SVJ, _ = igl.remove_duplicate_vertices(V, F, tol)
        SVJ = np.asarray(SVJ, dtype=np.int64)
        if len(np.unique(SVJ)) < n:
            first = np.full(SVJ.max() + 1, n, dtype=np.int64)
            np.minimum.at(first, SVJ, np.arange(n))
            weld = first[SVJ]  # vertex -> representative (lowest index of its class)
            counts["welded_vertices"] = int(n - len(np.unique(weld)))
    Fw = weld[F]

    # 2. zero-area faces, 3. duplicates (first kept)
    zero = _degenerate(V, Fw)
    counts["zero_area_faces"] = int(zero.sum())
    alive = np.flatnonzero(~zero)
    twin = np.arange(m)
    if len(alive):
        _, _, IC = igl.unique_simplices(Fw[alive])
        IC = np.asarray(IC, dtype=np.int64).reshape(-1)
        first = np.full(IC.max() + 1, m, dtype=np.int64)
        np.minimum.at(first, IC, alive)
        twin[alive] = first[IC]
    dup = twin != np.arange(m)
    counts["duplicate_faces"] = int(dup.sum())
    keep = np.flatnonzero(~zero & ~dup)
    if len(keep) == 0:
        raise MeshError(
            f"{name}: nothing is left after repair: all {m} faces have zero area or repeat "
            "another face"
        )
    rank = np.full(m, -1, dtype=np.int64)
    rank[keep] = np.arange(len(keep))

    # where dropped faces take their label: across the longest edge, or the kept twin
    face_source = rank.copy()
    face_source[dup] = rank[twin[dup]]
    if zero.any():
        Fk = Fw[keep]
        E = np.sort(np.concatenate([Fk[:, [1, 2]], Fk[:, [2, 0]], Fk[:, [0, 1]]]), axis=1)
        owner = np.tile(np.arange(len(keep)), 3)
        key = E[:, 0] * (n + 1) + E[:, 1]
        order = np.lexsort((owner, key))
        skey, sown = key[order], owner[order]
        zf = np.flatnonzero(zero)
        le = _longest_edge(V, Fw[zf])
        q = le[:, 0] * (n + 1) + le[:, 1]
        pos = np.searchsorted(skey, q)
        hit = (pos < len(skey)) & (skey[np.minimum(pos, len(skey) - 1)] == q)
        face_source[zf] = np.where(hit, sown[np.minimum(pos, len(skey) - 1)], -1)
    counts["dropped_faces_unlabelled"] = int((face_source < 0).sum())

    # compact the vertices still used (input order)
    Fk = Fw[keep]
    used = np.unique(Fk)
    vnew = np.full(n, -1, dtype=np.int64)
    vnew[used] = np.arange(len(used))
    Vk, Fk, origin = V[used], vnew[Fk], used

    # 4. non-manifold edges and vertices -> manifold sheets
    nme, nmv = _nonmanifold_counts(Fk)
    counts["nonmanifold_edges"], counts["nonmanifold_vertices"] = nme, nmv
    if nme or nmv:
        SV, SF, SVI = igl.split_nonmanifold(Vk, Fk)
        SF = np.asarray(SF, dtype=np.int64)
        SVI = np.asarray(SVI, dtype=np.int64)
        # keep the vertices in input order: sort copies by (origin, first use)
        o = np.lexsort((np.arange(len(SVI)), SVI))
        r = np.empty_like(o)
        r[o] = np.arange(len(o))
        Fk, origin = r[SF], origin[SVI[o]]
        Vk = V[origin]
        counts["split_vertices"] = int(len(SVI) - len(used))

    # 5. orientation: consistent per component (BFS), outward when closed
    FF, C = igl.bfs_orient(Fk)
    FF = np.asarray(FF, dtype=np.int64)
    C = np.asarray(C, dtype=np.int64).reshape(-1)
    topo = edge_topology(FF)
    boundary_faces = np.unique(topo.EF[topo.edge_face_count == 1].ravel())
    boundary_faces = boundary_faces[boundary_faces >= 0]
    open_comp = np.zeros(C.max() + 1, dtype=bool)
    open_comp[C[boundary_faces]] = True
    closed = ~open_comp[C]
    if closed.any():
        FO, _ = igl.orient_outward(Vk, FF, C.reshape(-1, 1))
        FF = np.where(closed[:, None], np.asarray(FO, dtype=np.int64), FF)
    same = _same_orientation(Fk, FF)
    # open components: keep the orientation most input faces had
    flip_comp = np.bincount(C, weights=~same, minlength=len(open_comp)) > np.bincount(
        C, weights=same, minlength=len(open_comp)
    )
    flip = open_comp[C] & flip_comp[C]
    FF[flip] = FF[flip][:, ::-1]
    counts["reoriented_faces"] = int((~_same_orientation(Fk, FF)).sum())

    vertex_map = np.full(n, -1, dtype=np.int64)
    vertex_map[origin[::-1]] = np.arange(len(origin))[::-1]  # first copy
    # welded vertices map to their representative's vertex
    vertex_map = vertex_map[weld]
    return RepairResult(
        V=np.ascontiguousarray(Vk),
        F=np.ascontiguousarray(FF),
        keep=keep,
        face_source=face_source,
        vertex_map=vertex_map,
        vertex_origin=origin,
        counts=counts,
    )
