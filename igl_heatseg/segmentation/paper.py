"""The paper's segmentation (§3.1–3.4): seeds, heat fields, argmax labels, the eps round.

Decisions (the paper, Mejia et al. 2018 §3.1-3.4, and what it leaves open):

* Each connected component is segmented on its own: the eps rule compares a group's area with
  the largest segment *of its component*, and a component with no seed vertex at all becomes a
  single segment (all its vertices form one group).
* A segment must be face-connected.  After the argmax, every face-connected piece of a label
  other than the label's main piece (the one holding most of the group's seed corners, then the
  largest) is merged into the neighbouring piece with which it shares the longest boundary,
  smallest pieces first.  The count is reported as ``merged_islands``.
* If the eps round drops no group, the second solve would repeat the first and is skipped.
"""

from __future__ import annotations

import heapq
import logging
import time
from collections.abc import Callable
from dataclasses import dataclass, field

import igl
import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

from ..constants import EPS_DEFAULT, THETA_DEFAULT
from ..heat.exact import HeatSolver
from ..heat.fast import FastHeatSolver
from ..mesh.checks import CleanMesh
from ..mesh.geometry import face_areas
from ..mesh.topology import EdgeTopology, edge_topology, vertex_components
from .params import check_segment_params, check_solver, eps_keep
from .seeds import dihedral_deviation, seed_groups, sharp_edges

__all__ = [
    "final_numbering",
    "group_seedless_components",
    "Segmentation",
    "segment_mesh",
    "make_face_connected",
    "SOLVERS",
    "heat_round",
    "group_components",
]

log = logging.getLogger(__name__)

Progress = Callable[[str, float], None]

#: Heat solvers by name: "fast" (default; certified local solves, same labels) and "exact"
#: (the reference: one global solve per group).  See :mod:`igl_heatseg.heat.fast`.
SOLVERS = {"fast": FastHeatSolver, "exact": HeatSolver}


@dataclass
class Segmentation:
    """Result of :func:`segment_mesh`, with the intermediate results the paper's figures use.

    Attributes
    ----------
    labels : (m,) int64
        Final face labels ``0..k-1``, largest segment (by area) first.
    vertex_labels : (n,) int64
        Final vertex labels (argmax of the final fields), same numbering as ``labels``.
    segment_areas : (k,) float64
        Area of each final segment, decreasing.
    seed_mask : (n,) bool
        Seed vertices (no incident sharp edge).
    sharp_edges : (s, 2) int64
        Sharp interior edges (vertex pairs).
    seed_group : (n,) int64
        Initial seed group of each vertex, ``-1`` for non-seeds (paper Fig. 6a).
    initial_labels : (m,) int64
        Face labels of the initial (over-)segmentation, as initial group ids (Fig. 11b).
    initial_areas : (k0,) float64
        Area of each initial group's segment, indexed by initial group id (Fig. 12).
    final_group : (n,) int64
        Seed group of each vertex in the final round (survivors renumbered), ``-1`` free.
    segment_group : (k,) int64
        Final-round group id of each final segment (``final_group`` numbering).
    kept_groups : (k1,) int64
        Initial group id of each surviving group.
    components : int
        Connected components of the mesh.
    seedless_components : int
        Components with no seed vertex (each became one segment).
    merged_islands : int
        Face-connected pieces merged into a neighbour (final round).
    merged_islands_initial : int
        The same, for the initial round.
    heat_sum_error : float
        ``max |sum_i u_i - 1|`` over both rounds.
    theta, eps : float
        Parameters used.
    timings : dict of str to float
        Seconds per stage.
    group_component : (k0,) int64
        Connected component of each initial group (what the eps rule is applied per).
    mode : str
        ``"paper"`` or ``"robust"``.
    """

    labels: np.ndarray
    vertex_labels: np.ndarray
    segment_areas: np.ndarray
    seed_mask: np.ndarray
    sharp_edges: np.ndarray
    seed_group: np.ndarray
    initial_labels: np.ndarray
    initial_areas: np.ndarray
    final_group: np.ndarray
    segment_group: np.ndarray
    kept_groups: np.ndarray
    components: int
    seedless_components: int
    merged_islands: int
    merged_islands_initial: int
    heat_sum_error: float
    theta: float
    eps: float
    timings: dict = field(default_factory=dict)
    group_component: np.ndarray | None = None
    mode: str = "paper"
    _solvers: tuple = field(default=(None, None), repr=False)

    @property
    def num_segments(self) -> int:
        """Number of final segments ``k``."""
        return int(self.segment_areas.shape[0])

    @property
    def initial_groups(self) -> int:
        """Number of initial seed groups ``k0`` (including seedless components)."""
        return int(self.initial_areas.shape[0])

    def temperature(self, segment: int, initial: bool = False) -> np.ndarray:
        """Temperature field of a final segment (or of an initial group), shape (n,).

        Parameters
        ----------
        segment : int
            Final segment id (``0..k-1``), or initial group id when ``initial=True``.
        initial : bool
            Use the initial round's fields.

        Raises
        ------
        RuntimeError
            If the solvers were not kept (``segment_mesh(..., keep_solvers=False)``).
        """
        solver = self._solvers[0 if initial else 1]
        if solver is None:
            raise RuntimeError("solvers not kept; call segment_mesh(..., keep_solvers=True)")
        gid = segment if initial else int(self.segment_group[segment])
        return solver.temperature(gid)


def group_seedless_components(
    F: np.ndarray, group: np.ndarray
) -> tuple[np.ndarray, int, int, int, np.ndarray]:
    """Make every connected component without a seed vertex one group of its own.

    Parameters
    ----------
    F : (m, 3) int64
    group : (n,) int64
        Seed group per vertex, ``-1`` for free vertices.

    Returns
    -------
    group : (n,) int64
        A copy; the vertices of the ``s`` seedless components get ids ``k..k+s-1``.
    k : int
        Number of groups afterwards.
    seedless : int
        Number of seedless components ``s``.
    ncomp : int
        Number of connected components.
    vcomp : (n,) int64
        Component id of each vertex.
    """
    ncomp, vcomp = vertex_components(group.shape[0], F)
    seeds = group >= 0
    seeded = np.zeros(ncomp, dtype=bool)
    seeded[vcomp[seeds]] = True
    seedless = np.flatnonzero(~seeded)
    k = int(group.max()) + 1 if seeds.any() else 0
    group = group.copy()
    for j, c in enumerate(seedless):
        group[vcomp == c] = k + j
    return group, k + len(seedless), len(seedless), ncomp, vcomp


def group_components(group: np.ndarray, vcomp: np.ndarray, k: int) -> np.ndarray:
    """Connected component of each seed group.

    Parameters
    ----------
    group : (n,) int64
        Seed group per vertex, ``-1`` for non-seeds.
    vcomp : (n,) int64
        Connected component per vertex.
    k : int
        Number of groups.

    Returns
    -------
    gcomp : (k,) int64
    """
    gcomp = np.zeros(k, dtype=np.int64)
    gcomp[group[group >= 0]] = vcomp[group >= 0]
    return gcomp


def segment_mesh(
    mesh: CleanMesh,
    theta: float = THETA_DEFAULT,
    eps: float = EPS_DEFAULT,
    *,
    progress: Progress | None = None,
    keep_solvers: bool = True,
    solver: str = "fast",
) -> Segmentation:
    """Segment a validated mesh as the paper does.

    Parameters
    ----------
    mesh : CleanMesh
        From :func:`igl_heatseg.io.load_mesh` or :func:`igl_heatseg.mesh.validate_mesh`.
    theta : float
        Dihedral threshold in radians, ``0 < theta <= pi`` (default pi/20, paper Table 1).
    eps : float
        Area fraction, ``0 <= eps <= 1`` (default 0.05): initial segments smaller than
        ``eps`` times the largest segment of their component lose their seeds.
    progress : callable(stage, fraction), optional
        Called during the heat solves (``stage`` is ``"heat initial"`` or ``"heat final"``).
    keep_solvers : bool
        Keep both factorizations so that :meth:`Segmentation.temperature` works.
    solver : {"fast", "exact"}
        Heat solver: ``"fast"`` (:class:`~igl_heatseg.heat.fast.FastHeatSolver`, default)
        or ``"exact"`` (:class:`~igl_heatseg.heat.exact.HeatSolver`, one global solve per group;
        the reference the fast one is tested against).

    Returns
    -------
    Segmentation

    Raises
    ------
    ValueError
        If ``theta`` or ``eps`` is out of range.

    Examples
    --------
    >>> import igl
    >>> from igl_heatseg import validate_mesh
    >>> V, F = igl.icosahedron()
    >>> V, F = igl.loop(V, F, 4)   # a fine sphere: no edge is sharp
    >>> seg = segment_mesh(validate_mesh(V, F))
    >>> seg.num_segments
    1
    """
    check_segment_params(theta, eps)
    check_solver(solver)
    solver_cls = SOLVERS[solver]
    V, F = mesh.V, mesh.F
    n = V.shape[0]
    timings: dict[str, float] = {}

    t = time.perf_counter()
    topo = edge_topology(F)
    E, phi = dihedral_deviation(V, F, topo)
    sharp = sharp_edges(phi, theta)
    mask = np.ones(n, dtype=bool)
    mask[E[sharp].ravel()] = False
    _, group0 = seed_groups(F, mask, E)
    group0, k0, n_seedless, ncomp, vcomp = group_seedless_components(F, group0)
    area = face_areas(V, F)
    timings["seeds"] = time.perf_counter() - t
    log.info("%d seed vertices in %d groups (%d seedless components)", mask.sum(), k0, n_seedless)

    t = time.perf_counter()
    L = igl.cotmatrix(V, F)
    timings["laplacian"] = time.perf_counter() - t

    labels0, solver0, merged0, hl0 = heat_round(
        V, F, group0, L, area, topo, timings, "initial", progress, solver_cls
    )
    areas0 = np.bincount(labels0, weights=area, minlength=k0)

    # eps round, per component.
    gcomp = group_components(group0, vcomp, k0)
    kept = np.flatnonzero(eps_keep(areas0, gcomp, eps, "largest"))
    if len(kept) == k0:
        labels1, solver1, merged1, hl1 = labels0, solver0, merged0, hl0
        group1 = group0
    else:
        remap = np.full(k0, -1, dtype=np.int64)
        remap[kept] = np.arange(len(kept))
        group1 = np.where(group0 >= 0, remap[np.maximum(group0, 0)], -1)
        labels1, solver1, merged1, hl1 = heat_round(
            V, F, group1, L, area, topo, timings, "final", progress, solver_cls
        )
    labels, vertex_labels, segment_areas, order = final_numbering(
        F, labels1, hl1.vertex_labels, area, len(kept)
    )

    return Segmentation(
        labels=labels,
        vertex_labels=vertex_labels,
        segment_areas=segment_areas,
        seed_mask=mask,
        sharp_edges=E[sharp],
        seed_group=group0,
        initial_labels=labels0,
        initial_areas=areas0,
        final_group=group1,
        segment_group=order,
        kept_groups=kept,
        components=ncomp,
        seedless_components=n_seedless,
        merged_islands=merged1,
        merged_islands_initial=merged0,
        heat_sum_error=max(hl0.sum_error, hl1.sum_error),
        theta=float(theta),
        eps=float(eps),
        timings=timings,
        group_component=gcomp,
        _solvers=(solver0, solver1) if keep_solvers else (None, None),
    )


def final_numbering(
    F: np.ndarray, labels: np.ndarray, vertex_labels: np.ndarray, area: np.ndarray, k: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Renumber group labels ``0..k-1`` as final segments: non-empty ones, largest area first.

    Parameters
    ----------
    F : (m, 3) int64
    labels : (m,) int64
        Face labels as group ids ``0..k-1``.
    vertex_labels : (n,) int64
        Vertex argmax labels as group ids.
    area : (m,) float64
        Face areas.
    k : int
        Number of groups.

    Returns
    -------
    labels : (m,) int64
        ``0..s-1``, segment 0 the largest; ties go to the lower group id.
    vertex_labels : (n,) int64
        Same numbering; a vertex whose group ended with no face takes an incident face's label.
    segment_areas : (s,) float64
        Decreasing.
    order : (s,) int64
        Group id of each segment.
    """
    areas = np.bincount(labels, weights=area, minlength=k)
    nonempty = np.flatnonzero(np.bincount(labels, minlength=k) > 0)
    order = nonempty[np.lexsort((nonempty, -areas[nonempty]))]
    final_of_group = np.full(k, -1, dtype=np.int64)
    final_of_group[order] = np.arange(len(order))
    out = final_of_group[labels]
    vout = final_of_group[vertex_labels]
    orphans = np.flatnonzero(vout < 0)
    if len(orphans):
        vf = np.full(len(vout), -1, dtype=np.int64)
        vf[F.ravel()] = np.repeat(out, 3)
        vout[orphans] = vf[orphans]
    return out, vout, areas[order], order


def heat_round(V, F, group, L, area, topo, timings, stage, progress, solver_cls=FastHeatSolver):
    """One heat round: factor, label every vertex/face by its hottest group, merge islands.

    Returns ``(face labels (m,), solver, islands merged, HeatLabels)``; adds
    ``factor_<stage>``, ``solve_<stage>`` and ``islands_<stage>`` to ``timings``.
    """
    t = time.perf_counter()
    solver = solver_cls(V, F, group, L)
    timings[f"factor_{stage}"] = time.perf_counter() - t
    t = time.perf_counter()
    cb = None if progress is None else (lambda f: progress(f"heat {stage}", f))
    hl = solver.labels(progress=cb)
    timings[f"solve_{stage}"] = time.perf_counter() - t
    t = time.perf_counter()
    labels, merged = make_face_connected(V, F, hl.face_labels, group, area, topo)
    timings[f"islands_{stage}"] = time.perf_counter() - t
    return labels, solver, merged, hl


def make_face_connected(
    V: np.ndarray,
    F: np.ndarray,
    labels: np.ndarray,
    group: np.ndarray,
    area: np.ndarray,
    topo: EdgeTopology | None = None,
) -> tuple[np.ndarray, int]:
    """Merge face-connected pieces so that every label is one edge-connected piece.

    The main piece of a label holds most corners that are seeds of that label's group (then:
    the largest area).  Every other piece is an island, merged into the neighbouring piece
    with which it shares the longest boundary (total edge length), smallest islands first.

    Parameters
    ----------
    V : (n, 3) float64
    F : (m, 3) int64
    labels : (m,) int64
        Face labels (group ids).
    group : (n,) int64
        Seed group of each vertex (``-1`` free).
    area : (m,) float64
        Face areas.
    topo : EdgeTopology, optional

    Returns
    -------
    labels : (m,) int64
        New face labels (same id space; islands take their neighbour's label).
    merged : int
        Number of islands merged.
    """
    topo = edge_topology(F) if topo is None else topo
    m = F.shape[0]
    inner = np.flatnonzero(topo.interior)
    f0, f1 = topo.EF[inner, 0], topo.EF[inner, 1]
    same = labels[f0] == labels[f1]
    A = sp.csr_matrix((np.ones(int(same.sum()), dtype=np.int8), (f0[same], f1[same])), shape=(m, m))
    npieces, piece = connected_components(A, directed=False)
    first = np.zeros(npieces, dtype=np.int64)
    first[piece[::-1]] = np.arange(m)[::-1]
    plabel = labels[first]
    if npieces == len(np.unique(labels)):
        return labels, 0
    parea = np.bincount(piece, weights=area, minlength=npieces)
    own = (group[F] == labels[:, None]).sum(axis=1)
    pseed = np.bincount(piece, weights=own, minlength=npieces)
    order = np.lexsort((-parea, -pseed, plabel))
    is_main_first = np.r_[True, plabel[order][1:] != plabel[order][:-1]]
    island = np.ones(npieces, dtype=bool)
    island[order[is_main_first]] = False

    # Boundary lengths between neighbouring pieces.
    diff = ~same
    elen = np.linalg.norm(V[topo.E[inner[diff], 0]] - V[topo.E[inner[diff], 1]], axis=1)
    pa, pb = piece[f0[diff]], piece[f1[diff]]
    nbrs: list[dict[int, float]] = [dict() for _ in range(npieces)]
    for a, b, ln in zip(pa.tolist(), pb.tolist(), elen.tolist(), strict=True):
        if a != b:
            nbrs[a][b] = nbrs[a].get(b, 0.0) + ln
            nbrs[b][a] = nbrs[b].get(a, 0.0) + ln

    parent = np.arange(npieces)
    heap = [(parea[p], p) for p in np.flatnonzero(island).tolist()]
    heapq.heapify(heap)
    plabel = plabel.copy()
    merged = 0
    while heap:
        a_area, a = heapq.heappop(heap)
        if parent[a] != a or not island[a] or a_area != parea[a]:
            continue  # stale entry
        if not nbrs[a]:
            island[a] = False  # nothing to merge into
            continue
        b = max(nbrs[a].items(), key=lambda kv: (kv[1], -kv[0]))[0]
        # merge a into b
        parent[a] = b
        merged += 1
        parea[b] += parea[a]
        for c, ln in nbrs[a].items():
            if c == b:
                continue
            nbrs[c].pop(a, None)
            nbrs[c][b] = nbrs[c].get(b, 0.0) + ln
            nbrs[b][c] = nbrs[b].get(c, 0.0) + ln
        nbrs[b].pop(a, None)
        nbrs[a] = {}
        if island[b]:
            heapq.heappush(heap, (parea[b], b))
    # resolve roots
    root = parent.copy()
    while True:
        nxt = root[root]
        if np.array_equal(nxt, root):
            break
        root = nxt
    return plabel[root][piece], merged
