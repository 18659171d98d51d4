"""Robust mode: the paper's seeds + heat pipeline made to survive scan noise and smooth blends.

The paper's mode (:func:`igl_heatseg.segmentation.segment_mesh`) stays the default and faithful.
This mode changes what the seeds are, measured on generated machined parts with exact B-Rep
labels (``tools/make_parts.py``) and the two ABC parts; see ``benchmarks/segmentation_table.py``.

Pipeline of :func:`segment_robust`:

1. **Denoise**, when the median dihedral deviation says the mesh is noisy and no exactly
   coplanar faces say it is a clean CAD export.  Bilateral
   filtering of the face normals (Zheng et al. 2011: neighbours = faces sharing a vertex,
   spatial Gaussian of the centroid distance with sigma = mean neighbour distance, range
   Gaussian of ``|n_i - n_j|`` with ``sigma_r``), then the vertex update of Sun et al. 2007
   (``x_i += mean over faces f of v: n_f n_f . (c_f - x_i)``), so that the heat fields and
   curvatures are computed on a surface consistent with the filtered normals.
2. **Creases** are interior edges whose filtered dihedral deviation exceeds ``theta``
   (default :data:`ROBUST_THETA`, 0.7 rad = 40 deg, not the paper's 9 deg: on a mesh of edge
   length ``h`` a fillet or hole of radius ``r`` turns ``h / r`` per edge, which at CAD
   tessellation sizes is 15-35 deg; machined creases are 45 deg or more).  Vertices on a crease
   (and ``crease_dilation`` rings around it, default 0) are not seeds.
3. **Curvature classes** replace the dihedral test for tangent-continuous (G1) boundaries that no
   dihedral angle can see (a fillet meets its planes at 0 deg).  Principal curvatures of the
   denoised surface cut open along the creases (:func:`split_along_creases`: no quadric fit
   straddles a crease; without the cut, narrow planes next to creases had no flat seeds at
   all), ``igl.principal_curvature`` over a ``curvature_ring``-ring:
   a vertex is *flat* if ``max |k| * h < flat_curvature``, *umbilic* if
   ``min |k| >= anisotropy * max |k|`` (sphere-like), otherwise *cylindrical* with an axis (the
   direction of least curvature).  Seed groups are the connected components of seed vertices
   through edges whose two ends have the same class and, for cylindrical vertices, axes within
   ``axis_angle`` (so two fillets along different box edges, or a hub and its torus fillet,
   stay apart) and, for flat vertices, normals within ``flat_normal_angle`` (a large-radius
   fillet that turns too little per edge to count as curved is still cut from its plane).
4. **Heat** (the paper's fields, :class:`igl_heatseg.heat.fast.FastHeatSolver`) on the
   denoised surface, argmax labels, islands merged
   (:func:`igl_heatseg.segmentation.paper.make_face_connected`).
5. **Area threshold relative to the part**: groups whose segment is smaller than
   ``eps * (area of their component)`` lose their seeds (the largest group of a component is
   always kept), and step 4 runs again.  The paper compares with the largest segment, which on
   a fragmented noisy mesh is itself small.
6. **Primitive type** per segment: least-squares plane, sphere and cylinder fits of the segment's
   (denoised) vertices; the simplest type whose RMS distance is within
   ``PRIMITIVE_TOL * h`` of the best is reported (``"Plane"``, ``"Cylinder"``, ``"Sphere"``,
   else ``"Other"``: cones, tori and freeform).
7. **Surfaces**: adjacent segments that one quick primitive fits merge
   (:func:`~igl_heatseg.segmentation.primitive_merge.merge_by_primitives`), then the fits of
   :mod:`igl_heatseg.surfaces` refine the labels (:func:`~igl_heatseg.surfaces.refine_segmentation`:
   on an exact CAD tessellation split, merge and move boundaries; on a noisy mesh only move
   boundaries) and give every segment its surface.

A coarse CAD export, whose vertices all lie on creases (so that step 2 finds no seed), runs
steps 2-5 on a midpoint subdivision of itself (:mod:`igl_heatseg.segmentation.coarse`): the
labels come back to its faces by the children's majority, after every segment is kept on its
own side of the creases.
"""

from __future__ import annotations

import logging
import math
import time
from dataclasses import dataclass, field

import igl
import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

from ..errors import MeshError
from ..mesh.checks import CleanMesh
from ..mesh.geometry import face_areas, face_normals
from ..mesh.topology import edge_topology
from ..surfaces.boundaries import boundary_curves
from ..surfaces.refine import refine_segmentation
from ..surfaces.segment_fit import fit_segments
from ..surfaces.tolerance import exact_tessellation, vertex_tolerance
from .coarse import (
    MAX_SUBDIVIDE,
    STARVED_SHARE,
    children_majority,
    snap_to_creases,
    starved_share,
    subdivision_levels,
)
from .denoise import BILATERAL_SIGMA_R, bilateral_normals, denoise_vertices
from .paper import (
    SOLVERS,
    Segmentation,
    final_numbering,
    group_components,
    group_seedless_components,
    heat_round,
    make_face_connected,
)
from .params import ROBUST_EPS, ROBUST_THETA, check_segment_params, check_solver, eps_keep
from .primitive_merge import (
    PRIMITIVE_TOL,
    fit_cylinder,
    fit_plane,
    fit_sphere,
    merge_by_primitives,
    primitive_type,
)
from .seeds import dihedral_deviation

__all__ = [
    "RobustSegmentation",
    "segment_robust",
    "bilateral_normals",
    "denoise_vertices",
    "curvature_classes",
    "split_along_creases",
    "subdivision_levels",
    "starved_share",
    "snap_to_creases",
    "merge_by_primitives",
    "fit_plane",
    "fit_sphere",
    "fit_cylinder",
    "primitive_type",
    "ROBUST_THETA",
    "ROBUST_EPS",
    "NOISE_FREE_ANGLE",
    "FLAT_CURVATURE",
    "ANISOTROPY",
    "AXIS_ANGLE",
    "PRIMITIVE_TOL",
    "STARVED_SHARE",
]

log = logging.getLogger(__name__)


#: A vertex is flat when ``max |k| * mean_edge_length`` is below this (radians per edge).
FLAT_CURVATURE: float = 0.15

#: Two flat seed vertices join only if their normals differ by less than this (radians): a
#: large-radius fillet that turns less than FLAT_CURVATURE per edge is still cut from its plane.
FLAT_NORMAL_ANGLE: float = 0.07

#: A curved vertex is umbilic (sphere-like) when ``min |k| >= ANISOTROPY * max |k|``.
ANISOTROPY: float = 0.5

#: Two cylindrical seed vertices join only if their axes differ by less than this (radians).
AXIS_ANGLE: float = math.radians(25.0)

#: Denoise (step 1) only when the median dihedral deviation exceeds this (radians, 1 degree):
#: measured medians are ~0 on clean CAD tessellations, ~5 deg with normal noise of 0.05 and
#: ~10 deg with 0.1 times the mean edge length.
NOISE_FREE_ANGLE: float = math.radians(1.0)


#: Rings of the quadric fit of ``igl.principal_curvature``.
CURVATURE_RING: int = 2

#: Rings around creases that hold no seeds.
CREASE_DILATION: int = 0

#: Adjacent segments merge when one primitive fits their union within this many mean edge
#: lengths (RMS) ...
MERGE_TOL: float = 0.1

#: ... plus this many times the input's median dihedral deviation (radians; a noise estimate:
#: normal noise of sigma = 0.1 mean edge lengths gives a median of about 0.17) ...
MERGE_NOISE: float = 1.2


@dataclass
class RobustSegmentation(Segmentation):
    """:class:`~igl_heatseg.segmentation.paper.Segmentation` plus what robust mode adds.

    ``theta`` is the crease threshold used; ``eps`` the part-relative area fraction;
    ``seed_mask``/``seed_group`` are the robust seeds; ``sharp_edges`` the creases.

    Attributes
    ----------
    primitive_types : list of str, length k
        ``"Plane"``, ``"Cylinder"``, ``"Sphere"`` or ``"Other"`` per final segment.
    primitive_rms : (k,) float64
        RMS distance of the segment's vertices to the chosen primitive (model units).
    vertex_class : (n,) int64
        0 flat, 1 cylindrical, 2 umbilic (step 3 of the module docstring).
    denoised_V : (n, 3) float64
        The surface the heat fields were solved on (before any subdivision).
    subdivided : int
        Levels of midpoint subdivision the seeds and heat fields were computed on (0: the
        input's own faces; then ``seed_mask``, ``seed_group``, ``final_group`` and
        ``vertex_class`` are those of the input's vertices in the subdivided mesh).
    refinement : str
        What refined the labels by the fits: ``"full"`` (split, merge, move boundaries) or
        ``"off"``.
    surfaces : list of Surface, length k, or None
        The fitted surface of every segment (:mod:`igl_heatseg.surfaces`), when fitted.
    boundary_curves : list of BoundaryCurve, or None
        With the surfaces: the trimming curve of every boundary chain between two segments (or
        a segment and the mesh border), on the two surfaces' intersection where it is well
        conditioned, else the smoothed mesh chain
        (:func:`igl_heatseg.surfaces.boundaries.boundary_curves`; validated-mesh positions).
    """

    primitive_types: list = field(default_factory=list)
    surfaces: list | None = None
    boundary_curves: list | None = None
    primitive_rms: np.ndarray | None = None
    vertex_class: np.ndarray | None = None
    denoised_V: np.ndarray | None = None
    subdivided: int = 0
    refinement: str = "off"


# --------------------------------------------------------------------------------------------
# Curvature classes
# --------------------------------------------------------------------------------------------


def split_along_creases(
    F: np.ndarray, sharp: np.ndarray, topo=None
) -> tuple[np.ndarray, np.ndarray]:
    """Duplicate vertices so that the faces on the two sides of a crease share none.

    Corners of one vertex stay together when their faces share a non-sharp interior edge
    through it; each group of corners becomes one new vertex.  Curvature fits on the result
    never straddle a crease.

    Parameters
    ----------
    F : (m, 3) int64
    sharp : (ne,) bool
        Crease edges, indexed like ``edge_topology(F).E``.
    topo : EdgeTopology, optional

    Returns
    -------
    F2 : (m, 3) int64
        Faces indexing the new vertices.
    orig : (n2,) int64
        New vertex -> input vertex.
    """
    topo = edge_topology(F) if topo is None else topo
    m = F.shape[0]
    keep = np.flatnonzero(topo.interior & ~sharp)
    f0, f1 = topo.EF[keep, 0], topo.EF[keep, 1]
    rows, cols = [], []
    for k in range(2):
        v = topo.E[keep, k]
        j0 = np.argmax(F[f0] == v[:, None], axis=1)
        j1 = np.argmax(F[f1] == v[:, None], axis=1)
        rows.append(j0 * m + f0)
        cols.append(j1 * m + f1)
    rows, cols = np.concatenate(rows), np.concatenate(cols)
    # corners of the same vertex in the same face are distinct nodes; also tie each corner to
    # itself so that isolated corners form their own component
    A = sp.csr_matrix((np.ones(len(rows)), (rows, cols)), shape=(3 * m, 3 * m))
    _, comp = connected_components(A, directed=False)
    _, comp = np.unique(comp, return_inverse=True)
    comp = comp.reshape(-1)
    F2 = comp.reshape(3, m).T.copy()
    orig = np.empty(int(comp.max()) + 1, dtype=np.int64)
    orig[comp] = F.T.ravel()
    return F2.astype(np.int64), orig


def curvature_classes(
    V: np.ndarray,
    F: np.ndarray,
    h: float,
    flat_curvature: float = FLAT_CURVATURE,
    anisotropy: float = ANISOTROPY,
    ring: int = CURVATURE_RING,
) -> tuple[np.ndarray, np.ndarray]:
    """Flat / cylindrical / umbilic class and axis of every vertex.

    Parameters
    ----------
    V : (n, 3) float64
    F : (m, 3) int64
    h : float
        Mean edge length (curvatures are compared as ``|k| * h``, radians per edge).
    flat_curvature, anisotropy : float
        See :data:`FLAT_CURVATURE`, :data:`ANISOTROPY`.
    ring : int
        Rings of the quadric fit.

    Returns
    -------
    cls : (n,) int64
        0 flat, 1 cylindrical, 2 umbilic.
    axis : (n, 3) float64
        Unit direction of least absolute curvature (a cylinder's axis).
    """
    PD1, PD2, k1, k2, _ = igl.principal_curvature(V, F, int(ring), True)
    a1, a2 = np.abs(k1), np.abs(k2)
    big, small = np.maximum(a1, a2), np.minimum(a1, a2)
    axis = np.where((a1 < a2)[:, None], PD1, PD2)
    cls = np.where(big * h < flat_curvature, 0, np.where(small < anisotropy * big, 1, 2))
    bad = ~np.isfinite(big)
    cls[bad] = 0
    return cls.astype(np.int64), axis


# --------------------------------------------------------------------------------------------
# The robust segmentation
# --------------------------------------------------------------------------------------------


def _dihedral(V: np.ndarray, F: np.ndarray, topo) -> np.ndarray:
    """(ne,) angle between the normals of the two faces of each interior edge, 0 elsewhere."""
    return np.nan_to_num(dihedral_deviation(V, F, topo)[1], nan=0.0)


def _mean_edge_length(V: np.ndarray, E: np.ndarray) -> float:
    return float(np.linalg.norm(V[E[:, 0]] - V[E[:, 1]], axis=1).mean())


def _expand_into_band(group: np.ndarray, band: np.ndarray, E: np.ndarray, rings: int):
    """Give the near-crease band vertices the group of a neighbouring seed, ring by ring.

    The band holds no seeds while groups are formed (curvature fits there straddle the
    crease); for the heat solve it is filled from the seeds on its own side, so that, as in the
    paper, only the crease vertices themselves are free and boundaries stay on the creases.
    Edges are processed in order; a band vertex reached by two groups in the same ring takes
    the one of its last edge.
    """
    group = group.copy()
    for _ in range(rings):
        a, b = E[:, 0], E[:, 1]
        fwd = (group[a] >= 0) & (group[b] < 0) & band[b]
        bwd = (group[b] >= 0) & (group[a] < 0) & band[a]
        if not (fwd.any() or bwd.any()):
            break
        new = group.copy()
        new[b[fwd]] = group[a[fwd]]
        new[a[bwd]] = group[b[bwd]]
        group = new
    return group


def _robust_round(W, F, group, L, area, topo, timings, stage, progress, solver_cls):
    """One heat round on the denoised surface (the paper's round, see ``paper.heat_round``)."""
    labels, _, merged, hl = heat_round(
        W, F, group, L, area, topo, timings, stage, progress, solver_cls
    )
    return labels, merged, hl


def segment_robust(
    mesh: CleanMesh,
    theta: float = ROBUST_THETA,
    eps: float = ROBUST_EPS,
    *,
    denoise: bool | None = None,
    sigma_r: float = BILATERAL_SIGMA_R,
    flat_curvature: float = FLAT_CURVATURE,
    anisotropy: float = ANISOTROPY,
    axis_angle: float = AXIS_ANGLE,
    flat_normal_angle: float = FLAT_NORMAL_ANGLE,
    crease_dilation: int = CREASE_DILATION,
    curvature_ring: int = CURVATURE_RING,
    merge: bool = True,
    fit_surfaces: bool = True,
    refine: bool | None = None,
    subdivide: int | None = None,
    solver: str = "fast",
    progress=None,
) -> RobustSegmentation:
    """Segment a validated mesh in robust mode (see the module docstring).

    Parameters
    ----------
    mesh : CleanMesh
        From :func:`igl_heatseg.io.load_mesh` or :func:`igl_heatseg.mesh.validate_mesh`.
    theta : float
        Crease threshold on the filtered dihedral deviation, radians in ``(0, pi]``.
    eps : float
        Area fraction in ``[0, 1]`` of the part's component below which a segment loses its
        seeds.
    denoise : bool, optional
        Bilateral normal filtering and vertex update first (step 1).  Default: only when the
        median dihedral deviation of the input exceeds :data:`NOISE_FREE_ANGLE` and the mesh
        is not an exact tessellation
        (:func:`~igl_heatseg.surfaces.tolerance.exact_tessellation`: a coarse CAD export's
        facets turn by more than a degree, and filtering them only blurs its small chamfers).
    sigma_r : float
        Range sigma of the bilateral filter (on ``|n_i - n_j|``).
    flat_curvature, anisotropy, axis_angle, flat_normal_angle : float
        Curvature classes and joins (step 3).
    crease_dilation : int
        Rings around creases without seeds.
    curvature_ring : int
        Rings of the curvature fit.
    merge : bool
        Merge adjacent segments that one primitive fits (:func:`merge_by_primitives`).
    fit_surfaces : bool
        Fit one surface (plane, cylinder, cone, sphere, torus, else freeform) to every final
        segment (``surfaces``; the labels are not changed).
    refine : bool, optional
        Refine the segmentation by the fits instead
        (:func:`igl_heatseg.surfaces.refine_segmentation`: split what no surface explains, merge
        what one explains, move boundary faces to the surface they lie on). Default (``None``)
        and ``True``: all of it, on exact CAD tessellations and noisy meshes alike (on noise a
        merge must fit both parts about as well as their own fits do); ``False``: none.
    subdivide : int, optional
        Levels of midpoint subdivision (``igl.upsample``, each face into 4; the geometry does
        not change) the seeds and heat fields are computed on; the labels come back to the
        input's faces by majority of their children.  Default: as many as a coarse CAD export
        needs to have seeds at all (:func:`subdivision_levels`), 0 on a dense mesh.
    solver : {"fast", "exact"}
        Heat solver, as in :func:`igl_heatseg.segmentation.paper.segment_mesh`.
    progress : callable(stage, fraction), optional
        Progress of the heat rounds.

    Returns
    -------
    RobustSegmentation
        ``labels`` ``0..k-1``, largest segment first (areas of the input surface), every
        segment face-connected; ``primitive_types`` per segment.

    Raises
    ------
    MeshError
        If a parameter is out of range.
    """
    check_segment_params(theta, eps)
    check_solver(solver)
    if crease_dilation < 0 or curvature_ring < 1:
        raise MeshError("crease_dilation must be >= 0 and curvature_ring >= 1")
    if subdivide is not None and not 0 <= subdivide <= MAX_SUBDIVIDE:
        raise MeshError(f"subdivide must be in [0, {MAX_SUBDIVIDE}], got {subdivide!r}")
    V, F = mesh.V, mesh.F
    n = V.shape[0]
    timings: dict[str, float] = {}
    refine = "off" if refine is False else "full"
    topo = edge_topology(F)
    E = topo.E
    h = _mean_edge_length(V, E)

    t = time.perf_counter()
    raw_phi = _dihedral(V, F, topo)
    noise_angle = float(np.median(raw_phi[topo.interior])) if topo.interior.any() else 0.0
    exact = None  # exact_tessellation(V, F), once, where a stage needs it
    if denoise is None:
        if noise_angle > NOISE_FREE_ANGLE:
            exact = exact_tessellation(V, F)
        denoise = noise_angle > NOISE_FREE_ANGLE and not exact
        log.info("robust: median dihedral deviation %.2f deg", math.degrees(noise_angle))
    if denoise:
        W = denoise_vertices(V, F, bilateral_normals(V, F, sigma_r=sigma_r))
    else:
        W = V.copy()
    timings["denoise"] = time.perf_counter() - t

    t = time.perf_counter()
    N, areaW = (face_normals(W, F), face_areas(W, F))
    phi = _dihedral(W, F, topo)
    sharp = phi > theta
    seed = np.zeros(n, dtype=bool)
    seed[F.ravel()] = True
    seed[E[sharp].ravel()] = False
    off_crease = seed.copy()  # vertices on no crease
    if crease_dilation:
        adj = sp.csr_matrix((np.ones(len(E)), (E[:, 0], E[:, 1])), shape=(n, n))
        adj = adj + adj.T
        crease = ~seed
        for _ in range(crease_dilation):
            crease = crease | ((adj @ crease.astype(np.float64)) > 0)
        seed &= ~crease
    band = off_crease & ~seed  # near a crease: no seed of its own, but not on the crease
    if subdivide is None:
        subdivide = subdivision_levels(W, F, theta, off_crease=off_crease)
    if subdivide > 0:
        return _on_subdivision(
            mesh, W, int(subdivide), sharp, noise_angle, timings,
            dict(theta=theta, eps=eps, sigma_r=sigma_r, flat_curvature=flat_curvature,
                 anisotropy=anisotropy, axis_angle=axis_angle,
                 flat_normal_angle=flat_normal_angle, crease_dilation=crease_dilation,
                 curvature_ring=curvature_ring, solver=solver, progress=progress),
            merge, fit_surfaces, refine, exact,
        )
    F2, orig = split_along_creases(F, sharp, topo)
    cls2, axis2 = curvature_classes(W[orig], F2, h, flat_curvature, anisotropy, curvature_ring)
    # a seed vertex lies on no crease, so it has exactly one copy
    cls = np.zeros(n, dtype=np.int64)
    axis = np.zeros((n, 3))
    cls[orig] = cls2
    axis[orig] = axis2
    a, b = E[:, 0], E[:, 1]
    join = seed[a] & seed[b] & (cls[a] == cls[b])
    join &= (cls[a] != 1) | (np.abs((axis[a] * axis[b]).sum(axis=1)) > math.cos(axis_angle))
    VN = np.zeros_like(W)
    for k in range(3):
        for c in range(3):
            VN[:, c] += np.bincount(F[:, k], weights=N[:, c] * areaW, minlength=n)
    VN /= np.maximum(np.linalg.norm(VN, axis=1, keepdims=True), 1e-300)
    join &= (cls[a] != 0) | ((VN[a] * VN[b]).sum(axis=1) > math.cos(flat_normal_angle))
    A = sp.csr_matrix((np.ones(int(join.sum())), (a[join], b[join])), shape=(n, n))
    _, comp = connected_components(A, directed=False)
    group0 = np.full(n, -1, dtype=np.int64)
    _, inv = np.unique(comp[seed], return_inverse=True)
    group0[seed] = inv.reshape(-1)
    group0, k0, n_seedless, ncomp, vcomp = group_seedless_components(F, group0)
    timings["seeds"] = time.perf_counter() - t
    log.info("robust: %d seed vertices in %d groups", int((group0 >= 0).sum()), k0)

    t = time.perf_counter()
    L = igl.cotmatrix(W, F)
    labels0, merged0, hl0 = _robust_round(
        W, F, _expand_into_band(group0, band, E, crease_dilation), L, areaW, topo,
        timings, "initial", progress, SOLVERS[solver],
    )
    areas0 = np.bincount(labels0, weights=areaW, minlength=k0)
    timings["heat_initial"] = time.perf_counter() - t

    t = time.perf_counter()
    gcomp = group_components(group0, vcomp, k0)
    kept = np.flatnonzero(eps_keep(areas0, gcomp, eps, "component"))
    if len(kept) == k0:
        labels1, merged1, hl1, group1 = labels0, merged0, hl0, group0
    else:
        remap = np.full(k0, -1, dtype=np.int64)
        remap[kept] = np.arange(len(kept))
        group1 = np.where(group0 >= 0, remap[np.maximum(group0, 0)], -1)
        labels1, merged1, hl1 = _robust_round(
            W, F, _expand_into_band(group1, band, E, crease_dilation), L, areaW, topo,
            timings, "final", progress, SOLVERS[solver],
        )
    timings["heat_final"] = time.perf_counter() - t

    k1 = len(kept)
    vtol = _fit_tolerance(V, F, merge, refine, fit_surfaces)
    if merge:
        t = time.perf_counter()
        tol = (MERGE_TOL + MERGE_NOISE * noise_angle) * h
        # capped by the distance tolerance: the dihedral estimate explodes on slivers
        tol = min(tol, max(MERGE_TOL * h, vtol))
        labels1, _ = merge_by_primitives(W, F, labels1, tol, topo=topo)
        timings["merge"] = time.perf_counter() - t
    labels, vertex_labels, segment_areas, order, surfaces, curves, types, rms = _finish(
        V, F, W, N, h, labels1, hl1.vertex_labels, k1, refine, fit_surfaces, progress, timings,
        vtol, exact,
    )

    return RobustSegmentation(
        labels=labels,
        vertex_labels=vertex_labels,
        segment_areas=segment_areas,
        seed_mask=group0 >= 0,
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
        mode="robust",
        primitive_types=types,
        surfaces=surfaces,
        boundary_curves=curves,
        primitive_rms=np.asarray(rms, dtype=np.float64),
        vertex_class=cls,
        denoised_V=W,
        refinement=refine,
    )


def _fit_tolerance(V, F, merge, refine, fit_surfaces) -> float | None:
    """:func:`vertex_tolerance` of the input, once, when a merge, refinement or fit needs it."""
    return vertex_tolerance(V, F) if merge or refine != "off" or fit_surfaces else None


def _finish(V, F, W, N, h, labels1, vlab1, k1, refine, fit_surfaces, progress, timings, vtol,
            exact=None):
    """The common end of :func:`segment_robust`: refinement (``refine``: "full" or "off") or
    one fit per segment, the final numbering, the trimming curves between the fitted segments,
    the old primitive types."""
    n = V.shape[0]
    surfaces = None
    # one exactness test for the denoising choice, the refinement and the curves (0.17 s on a
    # 36k-face part); ``exact`` is the caller's when it made it
    if exact is None and (refine != "off" or fit_surfaces):
        exact = exact_tessellation(V, F)
    if refine != "off":  # split, merge and move
        t = time.perf_counter()
        ref = refine_segmentation(V, F, labels1, vtol, normals_from=W, progress=progress,
                                  exact=exact)
        labels1, k1 = ref.labels, len(ref.surfaces)
        vlab1 = np.zeros(n, dtype=np.int64)
        vlab1[F.ravel()] = np.repeat(labels1, 3)
        surfaces = ref.surfaces
        timings["surfaces"] = time.perf_counter() - t
    labels, vertex_labels, segment_areas, order = final_numbering(
        F, labels1, vlab1, face_areas(V, F), k1
    )
    if surfaces is not None:
        surfaces = [surfaces[g] for g in order]
    elif fit_surfaces:  # one surface per segment, the labels as they are
        t = time.perf_counter()
        surfaces = fit_segments(V, F, labels, vtol, normals_from=W)
        timings["surfaces"] = time.perf_counter() - t
    curves = None
    if surfaces is not None:
        t = time.perf_counter()
        curves = boundary_curves(V, F, labels, surfaces, h, vtol, exact=exact)
        timings["boundary_curves"] = time.perf_counter() - t

    t = time.perf_counter()
    diag = float(np.linalg.norm(W.max(axis=0) - W.min(axis=0)))
    types, rms = [], []
    for s in range(len(order)):
        fs = np.flatnonzero(labels == s)
        name, r = primitive_type(W[np.unique(F[fs])], N[fs], h, diag)
        types.append(name)
        rms.append(r)
    timings["primitives"] = time.perf_counter() - t
    return labels, vertex_labels, segment_areas, order, surfaces, curves, types, np.asarray(rms)


def _on_subdivision(mesh, W, levels, sharp, noise_angle, timings, kw, merge, fit_surfaces, refine,
                    exact=None):
    """:func:`segment_robust` on the midpoint subdivision of the denoised surface ``W``, the
    labels brought back to ``mesh``'s faces (majority of the children, then face-connected)."""
    V, F = mesh.V, mesh.F
    n, m = V.shape[0], F.shape[0]
    t = time.perf_counter()
    Wf, Ff = igl.upsample(W, F, levels)
    Wf = np.ascontiguousarray(Wf, dtype=np.float64)
    Ff = np.ascontiguousarray(Ff, dtype=np.int64)
    nf = Wf.shape[0]
    fine_mesh = CleanMesh(V=Wf, F=Ff, vertex_map=np.arange(nf), input_vertex=np.arange(nf),
                          name=f"{mesh.name} (subdivided x{levels})")
    timings["subdivide"] = time.perf_counter() - t
    log.info("robust: %d faces too coarse for seeds: %d levels of subdivision, %d faces", m,
             levels, Ff.shape[0])
    fine = segment_robust(fine_mesh, denoise=False, merge=False, fit_surfaces=False,
                          refine=False, subdivide=0, **kw)
    for key, value in fine.timings.items():
        timings[key] = timings.get(key, 0.0) + value
    children = 4 ** levels
    topo = edge_topology(F)
    h = _mean_edge_length(W, topo.E)
    fine_topo = edge_topology(Ff)
    fine_sharp = _dihedral(Wf, Ff, fine_topo) > kw["theta"]
    seg_of_group = np.full(len(fine.kept_groups) + 1, -1, dtype=np.int64)
    seg_of_group[fine.segment_group] = np.arange(len(fine.segment_group))
    vseg = np.where(fine.final_group >= 0, seg_of_group[fine.final_group], -1)
    fine_labels = snap_to_creases(Ff, fine.labels, vseg, fine_sharp, fine_topo)
    vtol = _fit_tolerance(V, F, merge, refine, fit_surfaces)
    if merge:
        # on the subdivided surface, whose points inside a fan cap are off the cylinder its rim
        # lies on; the tolerance is the fits' (the dihedral noise estimate of the dense path
        # explodes on slivers: a median of 60 deg at noise 0.1 h)
        t = time.perf_counter()
        tol = max(MERGE_TOL * h, vtol)
        fine_labels, _ = merge_by_primitives(Wf, Ff, fine_labels, tol, topo=fine_topo)
        timings["merge"] = time.perf_counter() - t
    labels1 = children_majority(fine_labels, m, children)
    labels1, _ = make_face_connected(V, F, labels1, np.full(n, -1, dtype=np.int64),
                                     face_areas(V, F), topo)
    k1 = fine.num_segments
    N = face_normals(W, F)
    labels, vertex_labels, segment_areas, order, surfaces, curves, types, rms = _finish(
        V, F, W, N, h, labels1, fine.vertex_labels[:n], k1, refine, fit_surfaces,
        kw["progress"], timings, vtol, exact,
    )
    return RobustSegmentation(
        labels=labels,
        vertex_labels=vertex_labels,
        segment_areas=segment_areas,
        seed_mask=fine.seed_mask[:n],
        sharp_edges=topo.E[sharp],
        seed_group=fine.seed_group[:n],
        initial_labels=children_majority(fine.initial_labels, m, children),
        initial_areas=fine.initial_areas,
        final_group=fine.final_group[:n],
        segment_group=order if refine != "off" else fine.segment_group[order],
        kept_groups=fine.kept_groups,
        components=fine.components,
        seedless_components=fine.seedless_components,
        merged_islands=fine.merged_islands,
        merged_islands_initial=fine.merged_islands_initial,
        heat_sum_error=fine.heat_sum_error,
        theta=fine.theta,
        eps=fine.eps,
        timings=timings,
        group_component=fine.group_component,
        mode="robust",
        primitive_types=types,
        surfaces=surfaces,
        boundary_curves=curves,
        primitive_rms=rms,
        vertex_class=fine.vertex_class[:n],
        denoised_V=W,
        subdivided=levels,
        refinement=refine,
    )
