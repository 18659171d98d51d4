"""Seeds (paper §3.1): vertices none of whose incident edges is sharp, grouped by edges.

Conventions
-----------
The dihedral *deviation* ``phi`` of an interior edge is the angle between the unit normals of
its two faces: 0 on a flat region, pi/2 on a cube edge, up to pi on a fold.  (The paper writes it
as ``pi - theta_j`` with ``theta_j`` the interior dihedral angle.)  Boundary edges have no
dihedral angle (``phi = nan``) and never make a vertex a non-seed.  ``igl.dihedral_angles`` is
for tetrahedra and crashes on triangles; we compute ``phi`` from face normals.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

from ..constants import THETA_DEFAULT
from ..mesh.geometry import face_normals
from ..mesh.topology import EdgeTopology, edge_topology

__all__ = ["dihedral_deviation", "sharp_edges", "seed_mask", "seed_groups"]


def dihedral_deviation(
    V: np.ndarray, F: np.ndarray, topo: EdgeTopology | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """Dihedral deviation of every unique edge.

    Parameters
    ----------
    V : (n, 3) float64
    F : (m, 3) int64
    topo : EdgeTopology, optional
        Precomputed ``edge_topology(F)``.

    Returns
    -------
    E : (ne, 2) int64
        Unique edges (``E[:, 0] < E[:, 1]``).
    phi : (ne,) float64
        Angle in ``[0, pi]`` between the normals of the two faces of each interior edge;
        ``nan`` on boundary edges.

    Examples
    --------
    >>> import numpy as np
    >>> V = np.array([[0., 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]])
    >>> F = np.array([[0, 2, 1], [0, 1, 3]])  # two faces folded at a right angle
    >>> E, phi = dihedral_deviation(V, F)
    >>> float(np.degrees(phi[np.isfinite(phi)][0]))
    90.0
    """
    topo = edge_topology(F) if topo is None else topo
    N = face_normals(V, F)
    phi = np.full(len(topo.E), np.nan)
    inner = topo.interior
    n0 = N[topo.EF[inner, 0]]
    n1 = N[topo.EF[inner, 1]]
    # atan2(|n0 x n1|, n0 . n1) is accurate near 0 and pi, unlike arccos.
    phi[inner] = np.arctan2(np.linalg.norm(np.cross(n0, n1), axis=1), (n0 * n1).sum(axis=1))
    return topo.E, phi


def sharp_edges(phi: np.ndarray, theta: float = THETA_DEFAULT) -> np.ndarray:
    """Interior edges whose dihedral deviation exceeds ``theta``.

    Parameters
    ----------
    phi : (ne,) float64
        From :func:`dihedral_deviation` (``nan`` on boundary edges).
    theta : float
        Threshold in radians (paper default pi/20).

    Returns
    -------
    sharp : (ne,) bool
        ``phi > theta``; boundary edges are never sharp.
    """
    with np.errstate(invalid="ignore"):
        return np.nan_to_num(phi, nan=-1.0) > theta


def seed_mask(
    V: np.ndarray, F: np.ndarray, theta: float = THETA_DEFAULT, topo: EdgeTopology | None = None
) -> np.ndarray:
    """Seed vertices: referenced vertices none of whose incident edges is sharp.

    Parameters
    ----------
    V : (n, 3) float64
    F : (m, 3) int64
    theta : float
        Sharpness threshold in radians.
    topo : EdgeTopology, optional

    Returns
    -------
    mask : (n,) bool
    """
    topo = edge_topology(F) if topo is None else topo
    E, phi = dihedral_deviation(V, F, topo)
    sharp = sharp_edges(phi, theta)
    mask = np.zeros(V.shape[0], dtype=bool)
    mask[F.ravel()] = True
    mask[E[sharp].ravel()] = False
    return mask


def seed_groups(
    F: np.ndarray, mask: np.ndarray, E: np.ndarray | None = None
) -> tuple[int, np.ndarray]:
    """Connected components of the seed vertices through edges with both ends seeds.

    Parameters
    ----------
    F : (m, 3) int64
    mask : (n,) bool
        Seed vertices.
    E : (ne, 2) int64, optional
        Unique edges of ``F`` (computed if not given).

    Returns
    -------
    k : int
        Number of groups.
    group : (n,) int64
        Group id ``0..k-1`` of each seed vertex, ``-1`` for non-seeds.  Groups are numbered by
        their smallest vertex id, so the numbering is deterministic.
    """
    n = mask.shape[0]
    if E is None:
        E = edge_topology(F).E
    keep = mask[E[:, 0]] & mask[E[:, 1]]
    Es = E[keep]
    A = sp.csr_matrix((np.ones(len(Es), dtype=np.int8), (Es[:, 0], Es[:, 1])), shape=(n, n))
    _, comp = connected_components(A, directed=False)
    group = np.full(n, -1, dtype=np.int64)
    seeds = np.flatnonzero(mask)
    # Renumber the components that contain seeds 0..k-1 by their smallest vertex id.
    _, first, inv = np.unique(comp[seeds], return_index=True, return_inverse=True)
    order = np.argsort(seeds[first], kind="stable")
    rank = np.empty_like(order)
    rank[order] = np.arange(len(order))
    group[seeds] = rank[inv.reshape(-1)]
    return int(len(first)), group
