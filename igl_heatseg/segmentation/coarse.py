"""Coarse CAD exports in robust mode: how many levels of midpoint subdivision a mesh needs to
have seeds at all, the children's majority that brings labels back, and the snap that keeps
every segment on its own side of the creases."""

from __future__ import annotations

import igl
import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

from ..mesh.geometry import face_areas
from ..mesh.topology import edge_topology
from .params import ROBUST_THETA
from .seeds import dihedral_deviation

__all__ = [
    "starved_share",
    "off_crease_vertices",
    "subdivision_levels",
    "children_majority",
    "snap_to_creases",
    "STARVED_SHARE",
    "MAX_SUBDIVIDE",
    "MAX_SUBDIVIDED_FACES",
]

#: A mesh is too coarse for vertex seeds when faces with no vertex off the creases hold more
#: than this share of the area (a CAD export that puts every vertex on a face's outline:
#: measured ~1 on coarse exports, below 0.2 on meshes of 2,000 faces and more).
STARVED_SHARE: float = 0.1

#: At most this many levels of midpoint subdivision ...
MAX_SUBDIVIDE: int = 2

#: ... and no more faces than this after it.
MAX_SUBDIVIDED_FACES: int = 400_000


def starved_share(F: np.ndarray, seed: np.ndarray, area: np.ndarray) -> float:
    """Area share of the faces none of whose vertices can be a seed.

    Parameters
    ----------
    F : (m, 3) int64
    seed : (n,) bool
        Vertices on no crease.
    area : (m,) float64
        Face areas.

    Returns
    -------
    float
        In ``[0, 1]``; 0 for an empty mesh.

    Examples
    --------
    >>> import numpy as np
    >>> F = np.array([[0, 1, 2], [1, 3, 2]])
    >>> starved_share(F, np.array([False, False, False, True]), np.array([1.0, 3.0]))
    0.25
    """
    starved = ~seed[F].any(axis=1)
    total = float(area.sum())
    return float(area[starved].sum() / total) if total > 0 else 0.0


def off_crease_vertices(W: np.ndarray, F: np.ndarray, theta: float = ROBUST_THETA) -> np.ndarray:
    """(n,) bool: the vertices no crease touches (interior edges whose dihedral deviation
    exceeds ``theta`` radians), the candidates for the paper's seeds.

    Examples
    --------
    >>> import igl, numpy as np
    >>> V, F = igl.upsample(*igl.icosahedron(), 1)
    >>> V /= np.linalg.norm(V, axis=1, keepdims=True)   # a coarse sphere: 18-22 deg per edge
    >>> int(off_crease_vertices(V, F, 0.3).sum()), int(off_crease_vertices(V, F, 0.5).sum())
    (0, 42)
    """
    topo = edge_topology(F)
    sharp = np.nan_to_num(dihedral_deviation(W, F, topo)[1], nan=0.0) > theta
    seed = np.zeros(W.shape[0], dtype=bool)
    seed[F.ravel()] = True
    seed[topo.E[sharp].ravel()] = False
    return seed


def subdivision_levels(
    W: np.ndarray,
    F: np.ndarray,
    theta: float = ROBUST_THETA,
    max_levels: int = MAX_SUBDIVIDE,
    max_faces: int = MAX_SUBDIVIDED_FACES,
    off_crease: np.ndarray | None = None,
) -> int:
    """Levels of midpoint subdivision a mesh needs to have seeds on most of its area.

    The paper's seeds are vertices no crease touches. A coarse CAD export puts every vertex on
    a face's outline (a plane fanned from its rim, a cylinder of long strips from cap to cap),
    so it has none and comes out as one segment. Midpoint subdivision adds vertices inside the
    faces' edges without moving the surface: the fewest levels after which the faces with no
    seed vertex hold at most :data:`STARVED_SHARE` of the area (:func:`starved_share`).

    Parameters
    ----------
    W : (n, 3) float64
        The (denoised) vertices.
    F : (m, 3) int64
    theta : float
        Crease threshold (radians), as in :func:`segment_robust`.
    max_levels : int
        At most this many levels.
    max_faces : int
        And no more faces than this after them.
    off_crease : (n,) bool, optional
        :func:`off_crease_vertices` of ``W`` at ``theta``, when the caller has it already.

    Returns
    -------
    int
        0 on a mesh with seeds enough.

    Examples
    --------
    >>> import igl, numpy as np
    >>> V = np.array([[x, y, z] for x in (0., 1) for y in (0., 1) for z in (0., 1)])
    >>> F = np.array([[0, 2, 3], [0, 3, 1], [4, 5, 7], [4, 7, 6], [0, 1, 5], [0, 5, 4],
    ...               [2, 6, 7], [2, 7, 3], [0, 4, 6], [0, 6, 2], [1, 3, 7], [1, 7, 5]])
    >>> subdivision_levels(V, F)  # one level leaves a quarter of every triangle seedless
    2
    >>> subdivision_levels(*igl.upsample(V, F, 3))
    0
    """
    area = face_areas(W, F)
    for levels in range(max_levels + 1):
        if levels and F.shape[0] * 4 ** levels > max_faces:
            return levels - 1
        Wl, Fl = (W, F) if levels == 0 else igl.upsample(W, F, levels)
        seeds = off_crease if levels == 0 and off_crease is not None else \
            off_crease_vertices(Wl, Fl, theta)
        share = starved_share(Fl, seeds, np.repeat(area, 4 ** levels))
        if share <= STARVED_SHARE:
            return levels
    return max_levels


def children_majority(labels_fine: np.ndarray, m: int, children: int) -> np.ndarray:
    """The label most of each face's children carry.

    Parameters
    ----------
    labels_fine : (m * children,) int64
        Labels of the subdivided faces; ``igl.upsample`` numbers the children of face ``f``
        ``f * children + 0 .. children - 1``.
    m : int
        Faces of the coarse mesh.
    children : int
        ``4 ** levels``.

    Returns
    -------
    (m,) int64
        The most frequent child label (the smallest on a tie).

    Examples
    --------
    >>> import numpy as np
    >>> children_majority(np.array([0, 1, 1, 2, 3, 3, 0, 0]), 2, 4)
    array([1, 0])
    """
    C = labels_fine.reshape(m, children)
    k = int(labels_fine.max()) + 1
    counts = np.zeros((m, k), dtype=np.int64)
    np.add.at(counts, (np.repeat(np.arange(m), children), C.ravel()), 1)
    return counts.argmax(axis=1).astype(np.int64)


def snap_to_creases(
    F: np.ndarray, labels: np.ndarray, vertex_segment: np.ndarray, sharp: np.ndarray, topo=None
) -> np.ndarray:
    """Keep every segment on its own side of the creases.

    The heat fields cross creases: where seeds lie far from a crease on one side (a coarse
    mesh's cylinder, whose only seeds are halfway between its rims) and close to it on the
    other (its caps), the hotter side wins faces across the crease. Here the *regions* are the
    pieces of the surface the creases cut out (faces joined through non-crease edges); a face
    whose segment has no seed in its region takes, ring by ring, the segment of a neighbour in
    its region that has. A region without any seed keeps its labels.

    Parameters
    ----------
    F : (m, 3) int64
    labels : (m,) int64
        Segments ``0..k-1``.
    vertex_segment : (n,) int64
        The segment whose seed each vertex is, ``-1`` for no seed.
    sharp : (ne,) bool
        Crease edges, indexed like ``edge_topology(F).E``.
    topo : EdgeTopology, optional

    Returns
    -------
    (m,) int64
        New labels (same ids; every face is reached, as its region is connected).

    Examples
    --------
    >>> import numpy as np
    >>> F = np.array([[0, 1, 2], [1, 3, 2], [2, 3, 4]])
    >>> topo = edge_topology(F)
    >>> sharp = np.zeros(len(topo.E), dtype=bool)
    >>> sharp[(topo.E == [1, 2]).all(axis=1)] = True   # a crease between faces 0 and 1
    >>> snap_to_creases(F, np.array([0, 0, 1]), np.array([0, -1, -1, 1, 1]), sharp, topo)
    array([0, 1, 1])
    """
    topo = edge_topology(F) if topo is None else topo
    m = F.shape[0]
    labels = labels.copy()
    smooth = topo.interior & ~sharp
    f0, f1 = topo.EF[smooth, 0], topo.EF[smooth, 1]
    A = sp.csr_matrix((np.ones(len(f0)), (f0, f1)), shape=(m, m))
    A = (A + A.T).tocsr()
    nreg, region = connected_components(A, directed=False)
    k = int(labels.max()) + 1 if m else 0
    seeded = np.zeros((nreg, max(k, 1)), dtype=bool)
    corner_seg = vertex_segment[F]  # (m, 3)
    has = corner_seg >= 0
    seeded[np.repeat(region, 3).reshape(m, 3)[has], corner_seg[has]] = True
    ok = seeded[region, labels] | ~seeded[region].any(axis=1)
    while not ok.all():
        # each wrong face takes the most common segment of its right neighbours in its region
        good = sp.csr_matrix((np.ones(int(ok.sum())), (np.flatnonzero(ok), labels[ok])),
                             shape=(m, max(k, 1)))
        votes = (A @ good).tocsr()[~ok]
        reached = np.asarray(votes.sum(axis=1)).ravel() > 0
        if not reached.any():
            break
        wrong = np.flatnonzero(~ok)[reached]
        labels[wrong] = np.asarray(votes[reached].argmax(axis=1)).ravel()
        ok[wrong] = True
    return labels
