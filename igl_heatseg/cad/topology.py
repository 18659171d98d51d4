"""B-Rep topology from a labelled triangle mesh (numpy only, no OpenCASCADE).

The boundary between segments is cut into *chains*: mesh polylines along which exactly two
segments meet (or one segment and the mesh boundary, side ``-1``), running between *corners*
(mesh vertices where three or more sides meet, or where the boundary polyline kinks).  A chain
without corners is a closed loop (a circle between a cylinder and its cap) and starts at its
smallest vertex id, so both sides agree on it.  Every chain is stored once, oriented like the
boundary of its ``left`` segment (counter-clockwise around ``left`` seen from its mesh
normals); each segment's loops list ``(chain id, forward)`` pairs, ``forward=False`` meaning
the chain is walked backwards (it belongs to the other side).
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field

import numpy as np

from igl_heatseg.mesh.geometry import face_areas
from igl_heatseg.surfaces.samples import segment_adjacency

logger = logging.getLogger(__name__)

__all__ = ["Chain", "BoundaryGraph", "boundary_graph", "segment_neighbours", "segment_areas"]

#: Turning angle (radians) at which a boundary polyline vertex becomes a B-Rep vertex even
#: when only two sides meet there: the corners of an open square patch, the kinks of a mesh
#: boundary.  Well above the turning of a tessellated circle with >= 8 segments (45 deg).
KINK_ANGLE = np.deg2rad(50.0)


@dataclass
class Chain:
    """One B-Rep edge candidate: a mesh polyline between two sides.

    Attributes
    ----------
    verts : (q,) int64
        Mesh vertex ids along the chain, in the direction of ``left``'s boundary; for a closed
        chain ``verts[0] == verts[-1]``.
    left, right : int
        The segment the chain runs counter-clockwise around, and the other side (``-1``: the
        mesh boundary).
    """

    verts: np.ndarray
    left: int
    right: int

    @property
    def closed(self) -> bool:
        return bool(self.verts[0] == self.verts[-1])


@dataclass
class BoundaryGraph:
    """Chains, per-segment loops and B-Rep vertices of a labelled mesh.

    Attributes
    ----------
    chains : list of Chain
    loops : list (k) of list of list of (int, bool)
        ``loops[a]`` are the boundary loops of segment ``a``, each a cyclic list of
        ``(chain id, forward)``.
    corners : (c,) int64
        Mesh vertex ids that are B-Rep vertices (chain ends).
    vertex_sides : dict
        Corner vertex id -> sorted tuple of the sides (segments, ``-1`` for the mesh boundary)
        around it.
    """

    chains: list = field(default_factory=list)
    loops: list = field(default_factory=list)
    corners: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))
    vertex_sides: dict = field(default_factory=dict)


def _half_edges(F: np.ndarray, n: int):
    """Directed half-edges ``3f+k`` (F[f,k] -> F[f,k+1]) and the opposite of each (-1: none)."""
    src = F.ravel()
    dst = F[:, [1, 2, 0]].ravel()
    key = src * n + dst
    order = np.argsort(key, kind="stable")
    skey = key[order]
    want = dst * n + src
    pos = np.clip(np.searchsorted(skey, want), 0, len(skey) - 1)
    opp = np.where(skey[pos] == want, order[pos], -1)
    return src, dst, opp


def _vertex_sides(F, labels, src, opp, n) -> list:
    """For every vertex, the set of sides around it (labels plus -1 on the mesh boundary)."""
    sides = [set() for _ in range(n)]
    for f, lab in zip(F.ravel(), np.repeat(labels, 3), strict=True):
        sides[f].add(int(lab))
    for v in src[opp < 0]:
        sides[v].add(-1)
    return sides


def _trace_cycles(F, labels, src, dst, opp) -> list:
    """Boundary cycles of every segment as (segment, list of half-edges), each walked once."""
    face_lab = np.repeat(labels, 3)
    opp_lab = np.where(opp >= 0, face_lab[np.maximum(opp, 0)], -1)
    is_bnd = opp_lab != face_lab
    seen = np.zeros(len(src), bool)
    cycles = []
    for h0 in np.flatnonzero(is_bnd):
        if seen[h0]:
            continue
        cyc, h = [], int(h0)
        while not seen[h]:
            seen[h] = True
            cyc.append(h)
            g = 3 * (h // 3) + (h % 3 + 1) % 3  # v -> x in the same face
            for _ in range(len(src)):  # rotate around v inside the segment
                if is_bnd[g]:
                    break
                o = int(opp[g])
                g = 3 * (o // 3) + (o % 3 + 1) % 3
            h = g
        cycles.append((int(face_lab[h0]), cyc, opp_lab))
    return cycles


def _kinks(V, cycles, src, dst) -> set:
    """Vertices where a boundary cycle turns by more than KINK_ANGLE."""
    out = set()
    for _, cyc, _ in cycles:
        a, b = src[cyc], dst[cyc]
        d = V[b] - V[a]
        d /= np.maximum(np.linalg.norm(d, axis=1), 1e-300)[:, None]
        cosang = np.einsum("ij,ij->i", d, np.roll(d, -1, axis=0))
        out.update(int(v) for v in b[cosang < np.cos(KINK_ANGLE)])
    return out


def _pieces(cyc, opp_lab, src, dst, is_corner):
    """Split one cycle at corners into (right side, vertex list, half-edge list) pieces."""
    starts = [i for i, h in enumerate(cyc) if is_corner(int(src[h]))]
    if not starts:
        i0 = int(np.argmin(src[cyc]))
        hs = cyc[i0:] + cyc[:i0]
        return [(int(opp_lab[hs[0]]), [int(src[h]) for h in hs] + [int(src[hs[0]])], hs)]
    out = []
    for s, e in zip(starts, starts[1:] + [starts[0] + len(cyc)], strict=True):
        hs = [cyc[i % len(cyc)] for i in range(s, e)]
        out.append((int(opp_lab[hs[0]]), [int(src[h]) for h in hs] + [int(dst[hs[-1]])], hs))
    return out


def boundary_graph(V: np.ndarray, F: np.ndarray, labels: np.ndarray, k: int) -> BoundaryGraph:
    """Chains, loops and corners of a labelled, consistently oriented manifold mesh.

    Parameters
    ----------
    V : (n, 3) float64
    F : (m, 3) int64
    labels : (m,) int64
        Segment of every face, ``0..k-1``.
    k : int
        Number of segments.

    Returns
    -------
    BoundaryGraph

    Examples
    --------
    >>> import numpy as np
    >>> V = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0.]])
    >>> F = np.array([[0, 1, 2], [0, 2, 3]])
    >>> g = boundary_graph(V, F, np.array([0, 1]), 2)
    >>> sorted(g.corners.tolist()), len(g.chains), [len(lp) for lp in g.loops]
    ([0, 1, 2, 3], 5, [1, 1])
    """
    n = len(V)
    src, dst, opp = _half_edges(F, n)
    sides = _vertex_sides(F, labels, src, opp, n)
    cycles = _trace_cycles(F, labels, src, dst, opp)
    corner = {v for v in range(n) if len(sides[v]) >= 3}
    corner |= _kinks(V, cycles, src, dst)
    outgoing = np.zeros(n, np.int64)
    for _, cyc, _ in cycles:
        np.add.at(outgoing, src[cyc], 1)
    corner |= {v for v in np.flatnonzero(outgoing > 2).tolist()}  # pinched boundaries
    g = BoundaryGraph(loops=[[] for _ in range(k)])
    pieces = [(a, _pieces(cyc, opp_lab, src, dst, corner.__contains__))
              for a, cyc, opp_lab in cycles]
    edge_chain = {}
    for a, ps in pieces:  # register every chain from its left side
        for b, verts, hs in ps:
            if b == -1 or a < b:
                cid = len(g.chains)
                g.chains.append(Chain(np.asarray(verts, np.int64), a, b))
                for h in hs:
                    edge_chain[(int(src[h]), int(dst[h]))] = cid
    starts = set()
    for a, ps in pieces:
        loop = []
        for b, _, hs in ps:
            h = hs[0]
            if b == -1 or a < b:
                loop.append((edge_chain[(int(src[h]), int(dst[h]))], True))
            else:
                loop.append((edge_chain[(int(dst[h]), int(src[h]))], False))
        g.loops[a].append(loop)
    for c in g.chains:
        starts.add(int(c.verts[0]))
        starts.add(int(c.verts[-1]))
    g.corners = np.array(sorted(starts), np.int64)
    g.vertex_sides = {v: tuple(sorted(sides[v])) for v in starts}
    logger.debug("boundary graph: %d chains, %d corners", len(g.chains), len(starts))
    return g


def segment_neighbours(F: np.ndarray, labels: np.ndarray, k: int) -> dict:
    """Segment -> set of the segments sharing an edge with it.

    Parameters
    ----------
    F : (m, 3) int64
    labels : (m,) int64
        ``0..k-1``.
    k : int

    Returns
    -------
    dict of int -> set of int
        Every segment ``0..k-1`` is a key.

    Examples
    --------
    >>> import numpy as np
    >>> segment_neighbours(np.array([[0, 1, 2], [2, 1, 3], [4, 5, 6]]), np.array([0, 1, 2]), 3)
    {0: {1}, 1: {0}, 2: set()}
    """
    fa, fb = segment_adjacency(F, labels)
    out: dict = {a: set() for a in range(k)}
    for a, b in zip(labels[fa].tolist(), labels[fb].tolist(), strict=True):
        out[a].add(b)
        out[b].add(a)
    return out


def segment_areas(V: np.ndarray, F: np.ndarray, labels: np.ndarray, k: int) -> np.ndarray:
    """Area of every segment.

    Parameters
    ----------
    V : (n, 3) float64
    F : (m, 3) int64
    labels : (m,) int64
        ``0..k-1``.
    k : int

    Returns
    -------
    (k,) float64

    Examples
    --------
    >>> import numpy as np
    >>> V = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]])
    >>> segment_areas(V, np.array([[0, 1, 2], [2, 1, 3]]), np.array([0, 0]), 2).tolist()
    [1.0, 0.0]
    """
    return np.bincount(labels, weights=face_areas(V, F), minlength=k)
