"""Baseline segmentations to compare the paper's method with.

* :func:`dihedral_region_growing` -- the purely geometric method the paper criticises: faces
  are joined across every interior edge that is not sharp (dihedral deviation <= theta); the
  segments are the face-connected components.  No seeds, no heat, no area threshold.
* :func:`random_walks` -- Random Walks segmentation (Lai, Hu, Martin, Rosin, "Fast mesh
  segmentation using random walks", SPM 2008) on the face dual graph with the paper's seeds:
  edge weights ``w = exp(-d / mean(d))`` with ``d = eta * (1 - cos phi)`` (``phi`` the dihedral
  deviation, ``eta = 1`` on concave and ``convex_eta`` (0.2) on convex edges, Lai et al.'s
  minima rule), graph Laplacian ``L = D - W`` (positive semidefinite), one harmonic problem per
  seed group, argmax.  Seeds and the eps round are the paper's (so the comparison isolates
  the operator): a face is a seed of group ``g`` iff its three corners are seed vertices of
  group ``g``; groups whose segment is smaller than ``eps`` times the largest of their component
  lose their seeds and the harmonic solve is repeated once.
* :func:`xatlas_charts` -- the charts of xatlas (PyPI ``xatlas``), a texture-atlas chart
  builder (normal deviation, roundness, straightness costs): face -> chart id.

All return final face labels ``0..k-1`` numbered by decreasing segment area.
"""

from __future__ import annotations

import logging

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from numpy.typing import ArrayLike
from scipy.sparse.csgraph import connected_components

from ..constants import EPS_DEFAULT, THETA_DEFAULT
from ..errors import MeshError
from ..mesh.checks import as_mesh_arrays
from ..mesh.geometry import face_areas, face_normals
from ..mesh.topology import edge_topology
from .paper import make_face_connected
from .params import check_segment_params, eps_keep
from .seeds import dihedral_deviation, seed_groups, sharp_edges

__all__ = [
    "dihedral_region_growing",
    "random_walks",
    "random_walk_weights",
    "xatlas_charts",
    "relabel_by_area",
    "CONVEX_ETA",
    "WEIGHT_FLOOR",
]

log = logging.getLogger(__name__)

#: Lai et al.'s factor on the dihedral distance of convex edges (concave edges use 1).
CONVEX_ETA: float = 0.2

#: Smallest dual-graph edge weight, so that a crease never disconnects the graph numerically.
WEIGHT_FLOOR: float = 1e-8

#: Right-hand sides solved together in the harmonic solves (memory: m x this doubles).
_RHS_BLOCK = 64


def relabel_by_area(labels: ArrayLike, area: ArrayLike) -> np.ndarray:
    """Renumber labels ``0..k-1`` by decreasing total area (ties: smaller old id first).

    Parameters
    ----------
    labels : (m,) int
        Any integer ids.
    area : (m,) float
        Face areas.

    Returns
    -------
    (m,) int64
    """
    ids, inv = np.unique(np.asarray(labels), return_inverse=True)
    inv = inv.reshape(-1)
    a = np.bincount(inv, weights=np.asarray(area, dtype=np.float64), minlength=len(ids))
    order = np.lexsort((np.arange(len(ids)), -a))
    rank = np.empty(len(ids), dtype=np.int64)
    rank[order] = np.arange(len(ids))
    return rank[inv]


def dihedral_region_growing(V: ArrayLike, F: ArrayLike, theta: float = THETA_DEFAULT) -> np.ndarray:
    """Face-connected regions bounded by sharp edges (pure dihedral region growing).

    Parameters
    ----------
    V : (n, 3) array_like of float
    F : (m, 3) array_like of int
        A validated (manifold, oriented) mesh.
    theta : float
        Sharpness threshold in radians (an interior edge with dihedral deviation ``> theta``
        separates regions); default pi/20 as the paper.

    Returns
    -------
    labels : (m,) int64
        ``0..k-1``, largest region first.

    Raises
    ------
    MeshError
        Bad arrays or ``theta`` out of range.

    Examples
    --------
    >>> import numpy as np
    >>> V = np.array([[x, y, z] for x in (0., 1) for y in (0., 1) for z in (0., 1)])
    >>> F = np.array([[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1],
    ...               [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]])
    >>> len(np.unique(dihedral_region_growing(V, F)))  # the six sides of a cube
    6
    """
    V, F = as_mesh_arrays(V, F, "mesh")
    check_segment_params(theta, EPS_DEFAULT)
    m = F.shape[0]
    topo = edge_topology(F)
    _, phi = dihedral_deviation(V, F, topo)
    join = topo.interior & ~sharp_edges(phi, theta)
    ef = topo.EF[join]
    A = sp.csr_matrix((np.ones(len(ef), dtype=np.int8), (ef[:, 0], ef[:, 1])), shape=(m, m))
    _, comp = connected_components(A, directed=False)
    return relabel_by_area(comp, face_areas(V, F))


def random_walk_weights(
    V: np.ndarray, F: np.ndarray, topo=None, convex_eta: float = CONVEX_ETA
) -> tuple[np.ndarray, np.ndarray]:
    """Lai et al.'s dual-graph edge weights.

    Parameters
    ----------
    V : (n, 3) float64
    F : (m, 3) int64
    topo : EdgeTopology, optional
    convex_eta : float
        Factor on convex edges (concave edges: 1).

    Returns
    -------
    pairs : (ne_int, 2) int64
        Face pairs of the interior edges.
    w : (ne_int,) float64
        ``max(exp(-d / mean(d)), WEIGHT_FLOOR)`` with ``d = eta (1 - cos phi)``; all ones on a
        flat mesh.
    """
    topo = edge_topology(F) if topo is None else topo
    inner = np.flatnonzero(topo.interior)
    pairs = topo.EF[inner]
    N = face_normals(V, F)
    cos = np.clip((N[pairs[:, 0]] * N[pairs[:, 1]]).sum(axis=1), -1.0, 1.0)
    # concave iff the far corner of face 1 lies above the plane of face 0
    far = F[pairs[:, 1]]
    e = topo.E[inner]
    opp = far[(far != e[:, :1]) & (far != e[:, 1:])]
    concave = ((V[opp] - V[e[:, 0]]) * N[pairs[:, 0]]).sum(axis=1) > 0
    d = np.where(concave, 1.0, convex_eta) * (1.0 - cos)
    mean = d.mean() if len(d) else 0.0
    w = np.ones_like(d) if mean <= 0 else np.maximum(np.exp(-d / mean), WEIGHT_FLOOR)
    return pairs, w


def _harmonic_argmax(Lap: sp.csr_matrix, fgroup: np.ndarray, k: int) -> np.ndarray:
    """argmax_i of the harmonic functions u_i (u_i = 1 on group i's faces, 0 on other seeds)."""
    known = np.flatnonzero(fgroup >= 0)
    free = np.flatnonzero(fgroup < 0)
    labels = fgroup.copy()
    if len(free) == 0:
        return labels
    Lff = Lap[free][:, free].tocsc()
    Lfs = Lap[free][:, known]
    solve = spla.factorized(Lff)
    best = np.full(len(free), -np.inf)
    arg = np.zeros(len(free), dtype=np.int64)
    g = fgroup[known]
    for start in range(0, k, _RHS_BLOCK):
        ids = np.arange(start, min(k, start + _RHS_BLOCK))
        rows = np.flatnonzero((g >= ids[0]) & (g <= ids[-1]))
        B = sp.csr_matrix(
            (np.ones(len(rows)), (rows, g[rows] - start)), shape=(len(known), len(ids))
        )
        R = -(Lfs @ B).toarray()
        U = np.column_stack([solve(R[:, j]) for j in range(R.shape[1])])
        j = U.argmax(axis=1)
        val = U[np.arange(len(free)), j]
        better = val > best
        best[better] = val[better]
        arg[better] = ids[j[better]]
    labels[free] = arg
    return labels


def random_walks(
    V: ArrayLike,
    F: ArrayLike,
    theta: float = THETA_DEFAULT,
    eps: float = EPS_DEFAULT,
    *,
    convex_eta: float = CONVEX_ETA,
) -> np.ndarray:
    """Random Walks segmentation (Lai et al. 2008) seeded like the paper.

    Parameters
    ----------
    V : (n, 3) array_like of float
    F : (m, 3) array_like of int
        A validated (manifold, oriented) mesh.
    theta : float
        Dihedral threshold of the seed test (radians).
    eps : float
        Area fraction of the single discard round (as the paper's eps).
    convex_eta : float
        Lai et al.'s factor on convex edges.

    Returns
    -------
    labels : (m,) int64
        ``0..k-1``, largest segment first; every segment face-connected.

    Raises
    ------
    MeshError
        Bad arrays or parameters out of range.
    """
    V, F = as_mesh_arrays(V, F, "mesh")
    check_segment_params(theta, eps)
    n, m = V.shape[0], F.shape[0]
    topo = edge_topology(F)
    E, phi = dihedral_deviation(V, F, topo)
    mask = np.ones(n, dtype=bool)
    mask[E[sharp_edges(phi, theta)].ravel()] = False
    _, vgroup = seed_groups(F, mask, E)
    # face seeds: all three corners in one group
    g3 = vgroup[F]
    fgroup = np.where(
        (g3[:, 0] >= 0) & (g3[:, 0] == g3[:, 1]) & (g3[:, 0] == g3[:, 2]), g3[:, 0], -1
    )
    # face components without any seed face become one group each
    pairs, w = random_walk_weights(V, F, topo, convex_eta)
    ncomp, fcomp = connected_components(
        sp.csr_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(m, m)),
        directed=False,
    )
    fgroup = _compact_groups(np.where(_seedless(fcomp, fgroup, ncomp), -2, fgroup), fcomp)
    area = face_areas(V, F)
    rows, cols = np.r_[pairs[:, 0], pairs[:, 1]], np.r_[pairs[:, 1], pairs[:, 0]]
    W = sp.csr_matrix((np.r_[w, w], (rows, cols)), shape=(m, m))
    Lap = (sp.diags(np.asarray(W.sum(axis=1)).ravel()) - W).tocsr()

    k0 = int(fgroup.max()) + 1
    labels0 = _harmonic_argmax(Lap, fgroup, k0)
    areas0 = np.bincount(labels0, weights=area, minlength=k0)
    gcomp = np.zeros(k0, dtype=np.int64)
    gcomp[fgroup[fgroup >= 0]] = fcomp[fgroup >= 0]
    keep = eps_keep(areas0, gcomp, eps, "largest")
    if keep.all():
        labels1, group1 = labels0, fgroup
    else:
        remap = np.full(k0, -1, dtype=np.int64)
        remap[keep] = np.arange(int(keep.sum()))
        group1 = np.where(fgroup >= 0, remap[np.maximum(fgroup, 0)], -1)
        labels1 = _harmonic_argmax(Lap, group1, int(keep.sum()))
    vgroup1 = np.full(n, -1, dtype=np.int64)
    seeded = group1 >= 0
    vgroup1[F[seeded].ravel()] = np.repeat(group1[seeded], 3)
    labels1, merged = make_face_connected(V, F, labels1, vgroup1, area, topo)
    log.info("random walks: %d groups -> %d kept, %d islands merged", k0, keep.sum(), merged)
    return relabel_by_area(labels1, area)


def _seedless(fcomp: np.ndarray, fgroup: np.ndarray, ncomp: int) -> np.ndarray:
    """(m,) bool: faces of components holding no seed face."""
    has = np.zeros(ncomp, dtype=bool)
    has[fcomp[fgroup >= 0]] = True
    return ~has[fcomp]


def _compact_groups(fgroup: np.ndarray, fcomp: np.ndarray) -> np.ndarray:
    """Groups renumbered 0..k-1; faces marked -2 (seedless component) get one group each."""
    out = np.full(len(fgroup), -1, dtype=np.int64)
    seed = fgroup >= 0
    _, inv = np.unique(fgroup[seed], return_inverse=True)
    out[seed] = inv.reshape(-1)
    k = int(out.max()) + 1 if seed.any() else 0
    sl = fgroup == -2
    if sl.any():
        _, cinv = np.unique(fcomp[sl], return_inverse=True)
        out[sl] = k + cinv.reshape(-1)
    return out


def xatlas_charts(V: ArrayLike, F: ArrayLike, **chart_options) -> np.ndarray:
    """Charts of the xatlas texture-atlas generator as face labels.

    Parameters
    ----------
    V : (n, 3) array_like of float
    F : (m, 3) array_like of int
    **chart_options
        Attributes of ``xatlas.ChartOptions`` (e.g. ``max_cost``, ``normal_deviation_weight``).

    Returns
    -------
    labels : (m,) int64
        ``0..k-1`` by decreasing area.  Faces xatlas leaves out of every chart (degenerate)
        get one label per face-connected piece.

    Raises
    ------
    ImportError
        If ``xatlas`` is not installed (``pip install xatlas``).
    MeshError
        Bad arrays or an unknown chart option.
    """
    try:
        import xatlas
    except ImportError as exc:
        raise ImportError("xatlas_charts needs the xatlas package: pip install xatlas") from exc
    V, F = as_mesh_arrays(V, F, "mesh")
    m = F.shape[0]
    opts = xatlas.ChartOptions()
    for key, val in chart_options.items():
        if not hasattr(opts, key):
            raise MeshError(f"xatlas.ChartOptions has no option {key!r}")
        setattr(opts, key, val)
    atlas = xatlas.Atlas()
    atlas.add_mesh(V.astype(np.float32), F.astype(np.uint32))
    atlas.generate(chart_options=opts)
    labels = np.full(m, -1, dtype=np.int64)
    for c in range(atlas.get_mesh_chart_count(0)):
        labels[np.asarray(atlas.get_mesh_chart(0, c).faces, dtype=np.int64)] = c
    missing = labels < 0
    if missing.any():
        k = int(labels.max()) + 1
        topo = edge_topology(F)
        ef = topo.EF[topo.interior]
        both = missing[ef[:, 0]] & missing[ef[:, 1]]
        A = sp.csr_matrix((np.ones(int(both.sum())), (ef[both, 0], ef[both, 1])), shape=(m, m))
        _, comp = connected_components(A, directed=False)
        _, inv = np.unique(comp[missing], return_inverse=True)
        labels[missing] = k + inv.reshape(-1)
        log.info("xatlas left %d faces out of every chart", int(missing.sum()))
    return relabel_by_area(labels, face_areas(V, F))
