"""Segment adjacency and areas of a labelled mesh for the B-Rep (numpy only, no OpenCASCADE).

The boundary chains, loops and corners (:func:`boundary_graph`) live in
:mod:`igl_heatseg.mesh.topology`, beside the other combinatorics of a mesh (the surface stage
traces trimming curves along them too); they are re-exported here for the CAD stage.
"""

from __future__ import annotations

import igl
import numpy as np

from igl_heatseg.mesh.geometry import face_areas
from igl_heatseg.mesh.topology import KINK_ANGLE, BoundaryGraph, Chain, boundary_graph
from igl_heatseg.surfaces.samples import segment_adjacency

__all__ = ["Chain", "BoundaryGraph", "boundary_graph", "segment_neighbours", "segment_areas",
           "inner_vertices", "KINK_ANGLE"]


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


def inner_vertices(F: np.ndarray, labels: np.ndarray) -> np.ndarray:
    """Vertices inside their segment: all their faces have one label and none of their edges
    is on the mesh's border (a faceted triangle of three such vertices has no edge or vertex
    that sewing touches).

    Parameters
    ----------
    F : (m, 3) int64
    labels : (m,) int64

    Returns
    -------
    (F.max() + 1,) bool

    Examples
    --------
    >>> import numpy as np
    >>> F = np.array([[0, 1, 2], [0, 2, 3], [0, 3, 4], [0, 4, 1]])   # a fan around vertex 0
    >>> inner_vertices(F, np.zeros(4, np.int64)).tolist()           # 1..4 are on the border
    [True, False, False, False, False]
    >>> inner_vertices(F, np.array([0, 0, 1, 1])).tolist()          # 0 is on two segments
    [False, False, False, False, False]
    """
    n = int(F.max()) + 1
    lo = np.full(n, np.iinfo(np.int64).max)
    hi = np.full(n, -1)
    np.minimum.at(lo, F.ravel(), np.repeat(labels, 3))
    np.maximum.at(hi, F.ravel(), np.repeat(labels, 3))
    return (lo == hi) & ~np.asarray(igl.is_border_vertex(F), dtype=bool)
