"""The one validated boundary: every mesh is checked here before the pipeline sees it.

libigl accepts bad input silently (out-of-range indices, NaN coordinates, zero-area faces,
empty meshes).  :func:`validate_mesh` rejects all of these with :class:`~igl_heatseg.MeshError`
naming the problem and where, and cleans what can be cleaned without changing the surface
(unreferenced and exactly duplicated vertices), keeping the map back to the input's numbering.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from ..constants import DEGENERATE_FACE_TOL
from ..errors import MeshError
from .geometry import face_areas
from .topology import corner_edges, corner_fans, edge_topology, unique_rows

__all__ = ["CleanMesh", "validate_mesh", "as_mesh_arrays"]

#: How many offenders a message lists before "...".
_SHOW = 5


@dataclass(frozen=True)
class CleanMesh:
    """A validated triangle mesh and the map back to the input's numbering.

    Attributes
    ----------
    V : (n, 3) float64, C-contiguous
        Cleaned vertices: only referenced ones, exact duplicates merged.
    F : (m, 3) int64, C-contiguous
        Faces in the input's face order, indexing ``V``.
    vertex_map : (n_in,) int64
        Input vertex -> cleaned vertex, ``-1`` for unreferenced input vertices.
    input_vertex : (n,) int64
        Cleaned vertex -> one input vertex (the first) that maps to it.
    name : str
        Where the mesh came from (file name or argument name), used in messages.
    merged_vertices : int
        Number of input vertices merged into an exact duplicate.
    unreferenced_vertices : int
        Number of input vertices no face uses.
    """

    V: np.ndarray
    F: np.ndarray
    vertex_map: np.ndarray
    input_vertex: np.ndarray
    name: str = "mesh"
    merged_vertices: int = 0
    unreferenced_vertices: int = 0

    @property
    def n_input_vertices(self) -> int:
        """Vertex count of the input, before cleaning."""
        return int(self.vertex_map.shape[0])


def _listing(items: list[str], total: int) -> str:
    s = ", ".join(items[:_SHOW])
    return s + (f", ... ({total - _SHOW} more)" if total > _SHOW else "")


def as_mesh_arrays(V: ArrayLike, F: ArrayLike, name: str = "mesh") -> tuple[np.ndarray, np.ndarray]:
    """Convert ``V``, ``F`` to float64 (n,3) / int64 (m,3) arrays, checking shapes and dtypes.

    Only array-level checks (shape, dtype, integrality); no geometry or topology.

    Raises
    ------
    MeshError
    """
    try:
        V = np.asarray(V)
        F = np.asarray(F)
    except Exception as exc:  # ragged lists and the like
        raise MeshError(f"{name}: V and F must be arrays: {exc}") from None
    if V.ndim != 2 or V.shape[1] != 3:
        raise MeshError(f"{name}: `V` should have shape (n,3), shape is {V.shape}")
    if F.ndim != 2 or F.shape[1] != 3:
        raise MeshError(f"{name}: `F` should have shape (m,3) (triangles), shape is {F.shape}")
    if V.dtype.kind not in "fiu":
        raise MeshError(f"{name}: `V` must hold numbers, dtype is {V.dtype}")
    if F.dtype.kind == "f":
        if F.size and not (np.all(np.isfinite(F)) and np.all(F == np.round(F))):
            raise MeshError(f"{name}: `F` must hold integer vertex indices, found non-integers")
    elif F.dtype.kind not in "iu":
        raise MeshError(f"{name}: `F` must hold integer vertex indices, dtype is {F.dtype}")
    return (
        np.ascontiguousarray(V, dtype=np.float64),
        np.ascontiguousarray(F, dtype=np.int64),
    )


def validate_mesh(
    V: ArrayLike,
    F: ArrayLike,
    name: str = "mesh",
    *,
    check_orientation: bool = True,
) -> CleanMesh:
    """Check a triangle mesh and clean what can be cleaned.

    Rejected (``MeshError``, message names the problem, counts it and lists the first few):
    wrong shapes or dtypes; an empty mesh; NaN/inf coordinates; negative or out-of-range
    indices; faces with a repeated corner or zero area; non-manifold edges (more than two
    faces) and vertices (more than one fan); inconsistent orientation.
    Cleaned (reported in the returned object): unreferenced vertices are dropped and vertices
    with exactly equal coordinates are merged.  Boundaries and several components are fine.

    Parameters
    ----------
    V : (n, 3) array_like of float
        Vertex positions.
    F : (m, 3) array_like of int
        Triangles, 0-based indices into ``V``.
    name : str
        What to call the mesh in messages (a file name, say).
    check_orientation : bool
        Reject meshes whose adjacent faces disagree on orientation.

    Returns
    -------
    CleanMesh
        ``F`` keeps the input's face order; ``vertex_map`` maps input vertices to cleaned ones.

    Raises
    ------
    MeshError

    Examples
    --------
    >>> import numpy as np
    >>> V = np.array([[0., 0, 0], [1, 0, 0], [0, 1, 0], [5, 5, 5]])
    >>> mesh = validate_mesh(V, [[0, 1, 2]])
    >>> mesh.V.shape, mesh.unreferenced_vertices
    ((3, 3), 1)
    """
    V, F = as_mesh_arrays(V, F, name)
    n_in, m = V.shape[0], F.shape[0]
    if m == 0 or n_in == 0:
        raise MeshError(f"{name}: empty mesh ({n_in} vertices, {m} faces)")

    bad = np.flatnonzero((F < 0).any(axis=1) | (F >= n_in).any(axis=1))
    if len(bad):
        items = [f"face {f} = {F[f].tolist()}" for f in bad[:_SHOW]]
        raise MeshError(
            f"{name}: {len(bad)} face(s) have vertex indices outside 0..{n_in - 1}: "
            + _listing(items, len(bad))
        )

    used = np.zeros(n_in, dtype=bool)
    used[F.ravel()] = True
    nonfinite = np.flatnonzero(~np.isfinite(V).all(axis=1) & used)
    if len(nonfinite):
        items = [f"vertex {v} = {V[v].tolist()}" for v in nonfinite[:_SHOW]]
        raise MeshError(
            f"{name}: {len(nonfinite)} vertex(es) have NaN or infinite coordinates: "
            + _listing(items, len(nonfinite))
        )

    # Clean: drop unreferenced vertices, merge exact duplicates (STL stores 3 per face).
    ref = np.flatnonzero(used)
    uniq, inverse = unique_rows(V[ref], return_inverse=True)
    inverse = inverse.reshape(-1)
    vertex_map = np.full(n_in, -1, dtype=np.int64)
    vertex_map[ref] = inverse
    input_vertex = np.full(len(uniq), -1, dtype=np.int64)
    input_vertex[inverse[::-1]] = ref[::-1]  # first input vertex of each class wins
    Fc = vertex_map[F]
    Vc = np.ascontiguousarray(uniq, dtype=np.float64)
    # np.unique sorts vertices lexicographically; keep the input's order instead so that a
    # clean input comes out unchanged.
    order = np.argsort(input_vertex, kind="stable")
    rank = np.empty_like(order)
    rank[order] = np.arange(len(order))
    Vc, input_vertex, Fc = Vc[order], input_vertex[order], rank[Fc]
    vertex_map[ref] = rank[inverse]

    def vin(v: np.ndarray) -> list[int]:
        return input_vertex[v].tolist()

    repeated = np.flatnonzero(
        (Fc[:, 0] == Fc[:, 1]) | (Fc[:, 1] == Fc[:, 2]) | (Fc[:, 2] == Fc[:, 0])
    )
    if len(repeated):
        items = [f"face {f} = {F[f].tolist()}" for f in repeated[:_SHOW]]
        raise MeshError(
            f"{name}: {len(repeated)} face(s) use the same vertex twice (after merging vertices "
            "with equal coordinates), so they have zero area: " + _listing(items, len(repeated))
        )

    P0, P1, P2 = Vc[Fc[:, 0]], Vc[Fc[:, 1]], Vc[Fc[:, 2]]
    dblA = 2.0 * face_areas(Vc, Fc)
    longest2 = np.max(
        [((P1 - P0) ** 2).sum(1), ((P2 - P1) ** 2).sum(1), ((P0 - P2) ** 2).sum(1)], axis=0
    )
    degenerate = np.flatnonzero(dblA <= DEGENERATE_FACE_TOL * longest2)
    if len(degenerate):
        items = [f"face {f} (area {dblA[f] / 2:.3g})" for f in degenerate[:_SHOW]]
        raise MeshError(
            f"{name}: {len(degenerate)} face(s) have zero area (collinear corners; cotangent "
            "weights would be infinite): " + _listing(items, len(degenerate))
        )

    topo = edge_topology(Fc)
    nm = np.flatnonzero(topo.edge_face_count > 2)
    if len(nm):
        items = [
            f"edge ({vin(topo.E[e])[0]}, {vin(topo.E[e])[1]}) in {topo.edge_face_count[e]} faces"
            for e in nm[:_SHOW]
        ]
        raise MeshError(
            f"{name}: {len(nm)} non-manifold edge(s) (shared by more than two faces): "
            + _listing(items, len(nm))
        )

    nmv = _nonmanifold_vertices(Fc, topo)
    if len(nmv):
        items = [f"vertex {v}" for v in vin(nmv[:_SHOW])]
        raise MeshError(
            f"{name}: {len(nmv)} non-manifold vertex(es) (faces around them form more than one "
            "fan, e.g. two parts touching at a point): " + _listing(items, len(nmv))
        )

    if check_orientation:
        D = corner_edges(Fc)
        inner = topo.interior[topo.EMAP]
        # On an oriented interior edge the two faces traverse it in opposite directions.
        forward = D[:, 0] < D[:, 1]
        fwd_count = np.bincount(topo.EMAP[inner], weights=forward[inner], minlength=len(topo.E))
        flipped = np.flatnonzero(topo.interior & (fwd_count != 1))
        if len(flipped):
            items = [
                f"edge ({vin(topo.E[e])[0]}, {vin(topo.E[e])[1]}) between faces "
                f"{topo.EF[e, 0]} and {topo.EF[e, 1]}"
                for e in flipped[:_SHOW]
            ]
            raise MeshError(
                f"{name}: inconsistent orientation on {len(flipped)} edge(s) (both faces run "
                "the edge the same way; re-orient the faces): " + _listing(items, len(flipped))
            )

    return CleanMesh(
        V=np.ascontiguousarray(Vc),
        F=np.ascontiguousarray(Fc),
        vertex_map=vertex_map,
        input_vertex=input_vertex,
        name=name,
        merged_vertices=int(len(ref) - len(uniq)),
        unreferenced_vertices=int(n_in - len(ref)),
    )


def _nonmanifold_vertices(F: np.ndarray, topo) -> np.ndarray:
    """Vertices whose incident faces form more than one edge-connected fan.

    Corners ``(f, v)`` are nodes; two corners of the same vertex are joined when their faces
    share an interior edge through that vertex.  A manifold vertex has one component of corners.
    """
    n = int(F.max()) + 1
    _, comp = corner_fans(F, topo)
    corner_vertex = F.T.ravel()  # node j*m+f -> F[f, j]
    pairs = unique_rows(np.stack([corner_vertex, comp], axis=1))
    fans = np.bincount(pairs[:, 0], minlength=n)
    return np.flatnonzero(fans > 1)
