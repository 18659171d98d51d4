"""The one validated boundary: every mesh is checked here before the pipeline sees it.

libigl accepts bad input silently (out-of-range indices, NaN coordinates, zero-area faces,
empty meshes).  :func:`validate_mesh` rejects all of these with :class:`~igl_heatseg.MeshError`
naming the problem and where, and cleans what can be cleaned without changing the surface
(unreferenced and exactly duplicated vertices), keeping the map back to the input's numbering.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import igl
import numpy as np
from numpy.typing import ArrayLike

from ..constants import DEGENERATE_FACE_TOL
from ..errors import MeshError
from .geometry import face_areas
from .repair import nonmanifold_vertices as _nonmanifold_vertices
from .repair import repair_mesh
from .topology import corner_edges, edge_topology, unique_rows

__all__ = ["CleanMesh", "validate_mesh", "as_mesh_arrays", "triangulate_polygons", "COORD_MAX"]

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
    face_map : (m,) int64 or None
        Face of ``F`` -> input face it comes from (a polygon's triangles share one; ``None``:
        the identity, every input face is one row of ``F``). Ascending: ``F`` keeps the
        input's face order.
    face_source : (m_in,) int64 or None
        Input face -> the face of ``F`` whose label it takes: one of its own triangles, or for
        a face that repair dropped, the face across its longest edge (a duplicate: its kept
        twin), ``-1`` when there is none. ``None``: the identity.
    split_faces : int
        Input polygon faces (more than 3 corners) triangulated.
    repairs : dict
        What ``repair=True`` changed, counted (empty without repair): see
        :func:`igl_heatseg.mesh.repair.repair_mesh`.
    """

    V: np.ndarray
    F: np.ndarray
    vertex_map: np.ndarray
    input_vertex: np.ndarray
    name: str = "mesh"
    merged_vertices: int = 0
    unreferenced_vertices: int = 0
    face_map: np.ndarray | None = None
    face_source: np.ndarray | None = None
    split_faces: int = 0
    repairs: dict = field(default_factory=dict)

    @property
    def n_input_vertices(self) -> int:
        """Vertex count of the input, before cleaning."""
        return int(self.vertex_map.shape[0])

    @property
    def n_input_faces(self) -> int:
        """Face count of the input (polygons counted once), before triangulation and repair."""
        if self.face_source is not None:
            return int(self.face_source.shape[0])
        if self.face_map is not None and len(self.face_map):
            return int(self.face_map[-1]) + 1
        return int(self.F.shape[0])

    @property
    def same_faces(self) -> bool:
        """True when ``F`` row ``i`` is input face ``i`` (no polygon split, no face dropped)."""
        return self.face_map is None and self.face_source is None

    def input_face_labels(self, labels: ArrayLike) -> np.ndarray:
        """Per-face labels of ``F`` -> one label per input face, in the input's face order.

        A polygon takes the label covering most of its area among its triangles (ties: the
        lowest label); a face dropped by repair takes the label of ``face_source`` (the face
        across its longest edge, or the kept twin of a duplicate), ``-1`` when it has none.
        """
        lab = np.asarray(labels, dtype=np.int64).reshape(-1)
        if lab.shape[0] != self.F.shape[0]:
            raise MeshError(f"{self.name}: {lab.shape[0]} labels for {self.F.shape[0]} faces")
        if self.same_faces:
            return lab.copy()
        m_in = self.n_input_faces
        fmap = np.arange(len(lab)) if self.face_map is None else self.face_map
        src = self.face_source
        if src is None:
            src = np.full(m_in, -1, dtype=np.int64)
            src[fmap[::-1]] = np.arange(len(lab))[::-1]
        out = np.where(src >= 0, lab[np.maximum(src, 0)], -1)
        count = np.bincount(fmap, minlength=m_in)
        multi = count[fmap] > 1
        if multi.any():
            from .geometry import face_areas

            t = np.flatnonzero(multi)
            area = face_areas(self.V, self.F[t])
            # area per (input face, label); the largest wins, the lowest label on ties
            keys, inv = np.unique(np.stack([fmap[t], lab[t]], axis=1), axis=0, return_inverse=True)
            tot = np.bincount(inv.reshape(-1), weights=area, minlength=len(keys))
            order = np.lexsort((keys[:, 1], -tot, keys[:, 0]))
            first = np.ones(len(order), dtype=bool)
            first[1:] = keys[order[1:], 0] != keys[order[:-1], 0]
            win = order[first]
            out[keys[win, 0]] = keys[win, 1]
        return out


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


#: Largest absolute coordinate accepted: squares and products of coordinates (areas, cotangent
#: weights) must not overflow float64.
COORD_MAX = 1e30

#: What the messages of fixable defects add: the option that fixes them.
_FIX = " (use --repair, or repair=True, to {})"


def triangulate_polygons(F, name: str = "mesh") -> tuple[np.ndarray, np.ndarray | None, int]:
    """Triangles of polygon faces, with ``igl.polygons_to_triangles`` (a fan per polygon).

    Parameters
    ----------
    F : (m, 3) or (m, k) array_like of int, or a sequence of index sequences
        Triangles, ``k``-gons, or polygons of any sizes (at least 3 corners each).
    name : str

    Returns
    -------
    T : (t, 3) int64
        Triangles, in the input's face order (a polygon's ``k - 2`` triangles in a row).
    face_map : (t,) int64 or None
        Triangle -> input face; ``None`` when every face was a triangle (``T`` is ``F``).
    split : int
        Number of input faces with more than three corners.

    Raises
    ------
    MeshError
        Faces with fewer than three corners, or non-integer indices.
    """
    if isinstance(F, np.ndarray) and F.ndim == 2 and F.shape[1] == 3:
        return F, None, 0
    try:
        if isinstance(F, np.ndarray) and F.ndim == 2:
            rows = F
            sizes = np.full(F.shape[0], F.shape[1], dtype=np.int64)
            flat = np.asarray(F).reshape(-1)
        else:
            rows = [np.asarray(f).reshape(-1) for f in F]
            sizes = np.array([len(r) for r in rows], dtype=np.int64)
            flat = np.concatenate(rows) if rows else np.zeros(0, dtype=np.int64)
    except (TypeError, ValueError) as exc:
        raise MeshError(f"{name}: `F` must be (m,3) triangles or a list of polygons: {exc}") from None
    if flat.dtype.kind == "f" and flat.size and not (
        np.isfinite(flat).all() and (flat == np.round(flat)).all()
    ):
        raise MeshError(f"{name}: `F` must hold integer vertex indices, found non-integers")
    if flat.size and flat.dtype.kind not in "iuf":
        raise MeshError(f"{name}: `F` must hold integer vertex indices, dtype is {flat.dtype}")
    if (sizes == 3).all():
        return flat.astype(np.int64).reshape(-1, 3), None, 0
    small = np.flatnonzero(sizes < 3)
    if len(small):
        raise MeshError(
            f"{name}: {len(small)} face(s) have fewer than 3 corners: face {int(small[0])} has "
            f"{int(sizes[small[0]])}"
        )
    C = np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64)
    T, J = igl.polygons_to_triangles(np.ascontiguousarray(flat, dtype=np.int64), C)
    return np.asarray(T, dtype=np.int64), np.asarray(J, dtype=np.int64), int((sizes > 3).sum())


def validate_mesh(
    V: ArrayLike,
    F,
    name: str = "mesh",
    *,
    check_orientation: bool = True,
    repair: bool = False,
    checks: str = "all",
    weld_tol: float | None = None,
) -> CleanMesh:
    """Check a mesh, triangulate its polygons and clean (or repair) what can be.

    Rejected (``MeshError``, message names the problem, counts it, lists the first few and,
    for the defects ``repair=True`` fixes, says so): wrong shapes or dtypes; an empty mesh;
    NaN/inf (or beyond :data:`COORD_MAX`) coordinates; negative or out-of-range indices; faces
    with a repeated corner or zero area; non-manifold edges (more than two faces) and
    vertices (more than one fan); inconsistent orientation.
    Cleaned (reported in the returned object): polygon faces are triangulated (a fan, see
    :func:`triangulate_polygons`), unreferenced vertices dropped and vertices with exactly
    equal coordinates merged.  Boundaries and several components are fine.

    Parameters
    ----------
    V : (n, 3) array_like of float
        Vertex positions.
    F : (m, 3) array_like of int, (m, k), or a sequence of polygons
        Faces, 0-based indices into ``V``.
    name : str
        What to call the mesh in messages (a file name, say).
    check_orientation : bool
        Reject meshes whose adjacent faces disagree on orientation.
    repair : bool
        Repair instead of refusing: weld near-duplicate vertices, drop zero-area and
        duplicate faces, split non-manifold vertices and edges, orient every component
        consistently (outward when closed); :func:`igl_heatseg.mesh.repair.repair_mesh`.
        Every change is counted in ``CleanMesh.repairs``.
    checks : {"all", "indices"}
        ``"indices"``: only what indexing needs (shapes, index ranges, finite coordinates),
        no geometric or topological check: for scoring per-face labels of any mesh.
    weld_tol : float, optional
        With ``repair``: weld distance relative to the bounding-box diagonal (default
        :data:`igl_heatseg.mesh.repair.WELD_TOL`).

    Returns
    -------
    CleanMesh
        ``F`` keeps the input's face order (a polygon's triangles in a row; faces dropped by
        repair left out); ``vertex_map`` maps input vertices to cleaned ones, ``face_map``
        triangles to input faces.

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
    >>> validate_mesh([[0., 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], [[0, 1, 2, 3]]).F.tolist()
    [[0, 1, 2], [0, 2, 3]]
    """
    if checks not in ("all", "indices"):
        raise MeshError(f"{name}: checks must be 'all' or 'indices', got {checks!r}")
    face_map, split = None, 0
    if not (isinstance(F, np.ndarray) and F.ndim == 2 and F.shape[1] == 3):
        try:
            Fa = np.asarray(F)
        except (TypeError, ValueError):  # ragged: polygons of several sizes
            Fa = None
        if Fa is None or Fa.dtype == object:
            F, face_map, split = triangulate_polygons(F, name)
        elif Fa.ndim == 2 and Fa.shape[1] > 3:
            F, face_map, split = triangulate_polygons(Fa, name)
    V, F = as_mesh_arrays(V, F, name)
    n_in, m = V.shape[0], F.shape[0]
    if m == 0 or n_in == 0:
        raise MeshError(f"{name}: empty mesh ({n_in} vertices, {m} faces)")

    def fin(f) -> int:  # face number in the input
        return int(f if face_map is None else face_map[f])

    bad = np.flatnonzero((F < 0).any(axis=1) | (F >= n_in).any(axis=1))
    if len(bad):
        items = [f"face {fin(f)} = {F[f].tolist()}" for f in bad[:_SHOW]]
        raise MeshError(
            f"{name}: {len(bad)} face(s) have vertex indices outside 0..{n_in - 1}: "
            + _listing(items, len(bad))
        )

    used = np.zeros(n_in, dtype=bool)
    used[F.ravel()] = True
    with np.errstate(invalid="ignore"):
        nonfinite = np.flatnonzero(~(np.abs(V) <= COORD_MAX).all(axis=1) & used)
    if len(nonfinite):
        items = [f"vertex {v} = {V[v].tolist()}" for v in nonfinite[:_SHOW]]
        what = (
            "NaN or infinite coordinates"
            if not np.isfinite(V[nonfinite]).all()
            else f"too large coordinates (at most {COORD_MAX:g} in absolute value)"
        )
        raise MeshError(
            f"{name}: {len(nonfinite)} vertex(es) have {what}: " + _listing(items, len(nonfinite))
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
    merged = int(len(ref) - len(uniq))
    face_source = None
    repairs: dict = {}

    if repair and checks == "all":
        rep = repair_mesh(Vc, Fc, name=name, weld_tol=weld_tol)
        repairs = rep.counts
        if rep.changed:
            # compose: input vertex -> cleaned -> repaired; repaired face -> input face
            vertex_map = np.where(vertex_map >= 0, rep.vertex_map[np.maximum(vertex_map, 0)], -1)
            input_vertex = input_vertex[rep.vertex_origin]
            m_in = m if face_map is None else int(face_map[-1]) + 1
            fm = np.arange(m) if face_map is None else face_map
            face_source = np.full(m_in, -1, dtype=np.int64)
            src = rep.face_source  # triangle (before repair) -> repaired face or -1
            has = src >= 0
            face_source[fm[has][::-1]] = src[has][::-1]  # first triangle with a source wins
            face_map = fm[rep.keep]
            if face_map.shape[0] == m_in and (face_map == np.arange(m_in)).all():
                face_map = None
            if face_map is None and (face_source == np.arange(m_in)).all():
                face_source = None
            Vc, Fc = rep.V, rep.F
            F = F[rep.keep]  # for messages

    mesh = CleanMesh(
        V=np.ascontiguousarray(Vc),
        F=np.ascontiguousarray(Fc),
        vertex_map=vertex_map,
        input_vertex=input_vertex,
        name=name,
        merged_vertices=merged,
        unreferenced_vertices=int(n_in - len(ref)),
        face_map=face_map,
        face_source=face_source,
        split_faces=int(split or 0),
        repairs=repairs,
    )
    if checks == "all":
        _check_surface(mesh, F, check_orientation, after_repair=repair)
    return mesh


def _check_surface(mesh: CleanMesh, F: np.ndarray, check_orientation: bool, after_repair: bool):
    """The geometric and topological checks on a cleaned mesh (``F``: its faces as input)."""
    Vc, Fc, name, input_vertex = mesh.V, mesh.F, mesh.name, mesh.input_vertex
    fmap = mesh.face_map
    pre = f"{name}: after repair, " if after_repair else f"{name}: "

    def fix(what: str) -> str:
        return "" if after_repair else _FIX.format(what)

    def fin(f) -> int:
        return int(f if fmap is None else fmap[f])

    def vin(v: np.ndarray) -> list[int]:
        return input_vertex[v].tolist()

    repeated = np.flatnonzero(
        (Fc[:, 0] == Fc[:, 1]) | (Fc[:, 1] == Fc[:, 2]) | (Fc[:, 2] == Fc[:, 0])
    )
    if len(repeated):
        items = [f"face {fin(f)} = {F[f].tolist()}" for f in repeated[:_SHOW]]
        raise MeshError(
            f"{pre}{len(repeated)} face(s) use the same vertex twice (after merging vertices "
            "with equal coordinates), so they have zero area: " + _listing(items, len(repeated))
            + fix("drop them")
        )

    with np.errstate(over="ignore", invalid="ignore"):
        P0, P1, P2 = Vc[Fc[:, 0]], Vc[Fc[:, 1]], Vc[Fc[:, 2]]
        dblA = 2.0 * face_areas(Vc, Fc)
        longest2 = np.max(
            [((P1 - P0) ** 2).sum(1), ((P2 - P1) ** 2).sum(1), ((P0 - P2) ** 2).sum(1)], axis=0
        )
        degenerate = np.flatnonzero(~(dblA > DEGENERATE_FACE_TOL * longest2))
    if len(degenerate):
        items = [f"face {fin(f)} (area {dblA[f] / 2:.3g})" for f in degenerate[:_SHOW]]
        raise MeshError(
            f"{pre}{len(degenerate)} face(s) have zero area (collinear corners; cotangent "
            "weights would be infinite): " + _listing(items, len(degenerate)) + fix("drop them")
        )

    topo = edge_topology(Fc)
    nm = np.flatnonzero(topo.edge_face_count > 2)
    if len(nm):
        items = [
            f"edge ({vin(topo.E[e])[0]}, {vin(topo.E[e])[1]}) in {topo.edge_face_count[e]} faces"
            for e in nm[:_SHOW]
        ]
        raise MeshError(
            f"{pre}{len(nm)} non-manifold edge(s) (shared by more than two faces): "
            + _listing(items, len(nm)) + fix("split them into manifold sheets")
        )

    nmv = _nonmanifold_vertices(Fc, topo)
    if len(nmv):
        items = [f"vertex {v}" for v in vin(nmv[:_SHOW])]
        raise MeshError(
            f"{pre}{len(nmv)} non-manifold vertex(es) (faces around them form more than one "
            "fan, e.g. two parts touching at a point): " + _listing(items, len(nmv))
            + fix("split them")
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
                f"{fin(topo.EF[e, 0])} and {fin(topo.EF[e, 1])}"
                for e in flipped[:_SHOW]
            ]
            raise MeshError(
                f"{pre}inconsistent orientation on {len(flipped)} edge(s) (both faces run "
                "the edge the same way"
                + ("; a non-orientable surface" if after_repair else "")
                + "): " + _listing(items, len(flipped))
                + fix("orient each component consistently")
            )
