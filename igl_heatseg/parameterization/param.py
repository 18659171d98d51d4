"""Parameterize disk charts: Hessian eigenmaps, certified bijectivity, fallbacks, baselines.

Pipeline of :func:`parameterize_chart` (ALGORITHM.md sections 6-7):

1. The chart must be a topological disk (one face component, one boundary loop, chi = 1);
   cut it first otherwise.  It is translated and scaled to unit area for the numerics; the
   map is scaled back at the end.
2. Hessian energy ``K`` (:mod:`igl_heatseg.parameterization.hessian`, ``"hlle"`` or ``"curved"``) and the Voronoi
   mass matrix ``M``; lowest eigenpairs of ``K y = lambda M y`` (shift-invert Lanczos with a
   slightly negative shift, dense ``eigh`` on small charts).  The constant is removed by
   M-centring the eigenvectors and dropping the direction it occupied.
3. Gram (affine) correction.  The eigenvectors ``Y`` are an affine image of an isometric
   layout, so ``l_e^2 ~ d_e^T G d_e`` for every edge ``e`` (``d_e`` the edge in eigen
   coordinates, ``G`` symmetric).  ``G`` is fitted by least squares with relative weights
   (equations divided by ``l_e^2``) and the map is ``Y G^(1/2)``.  When the numerical null
   space has dimension ``d > 2`` (relative eigenvalues below :data:`NULLSPACE_TOL`, e.g. tiny
   charts) the same fit is done for a ``d x d`` ``G`` over all ``d`` null vectors and its best
   rank-2 part is used, which reduces to the 2 x 2 correction when ``d = 2``.
4. The bijectivity certificate (:func:`igl_heatseg.parameterization.bijectivity.certify_map`).  A mirror image
   is turned over (``u -> -u``), not counted as flipped.
5. If not bijective and the Hessian map only has local defects (flips, no boundary overlap):
   :func:`repair_map` re-solves a small region around them harmonically (uniform weights),
   growing it ring by ring; a certified result that raises the symmetric Dirichlet energy by
   at most :data:`REPAIR_MAX_SD_RATIO` is ``"hessian-<energy>+repair"``.
6. Otherwise: a convex-combination map (Floater's mean value weights, boundary on a circle
   by arc length) is bijective by construction (Tutte, Floater); it is improved by SLIM
   (symmetric Dirichlet, free boundary), one iteration at a time with the certificate after
   each, keeping the last bijective iterate (``"tutte+slim"``); only if no iterate is
   bijective, SLIM with the boundary held on the circle (``"tutte+slim-fixed"``).

Under ``energy="auto"``, step 2 starts with a free test: charts whose total absolute Gaussian
curvature exceeds :data:`HLLE_SKIP_CURVATURE` (noisy scans, strongly doubly curved charts)
skip HLLE and go to the curved Hessian; the skip is recorded in ``attempts``.

Distortion measures (:func:`distortion`), all after a global scale normalisation that makes the
total image area equal the total 3D area; per-triangle Jacobian ``J`` (3D triangle in its own
isometric 2D frame -> image) with singular values ``s1 >= s2``, averages weighted by 3D area:

- ``conformal_mean`` / ``conformal_max``: ``s1 / s2`` (1 = conformal).
- ``area_mean`` / ``area_max``: ``max(s1 s2, 1 / (s1 s2))`` (1 = area preserving).
- ``sym_dirichlet``: ``s1^2 + s1^-2 + s2^2 + s2^-2`` (4 = isometry).
- ``stretch_max``: ``max(s1, 1 / s2)`` over triangles (1 = isometry).

Degenerate image triangles give ``inf``.  Flipped triangles use ``|det J|`` (flips are counted
by the certificate, not here).
"""

from __future__ import annotations

import contextlib
import dataclasses
import logging
import time
from dataclasses import dataclass, field
from typing import Iterable, Literal, Sequence

import igl
import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from numpy.typing import ArrayLike

from .bijectivity import Certificate, certify_map
from ..mesh.checks import as_mesh_arrays
from ..errors import MeshError
from .hessian import curved_hessian_energy, hlle_energy
from ..mesh.topology import boundary_loops, face_components

__all__ = [
    "ChartParam",
    "parameterize_chart",
    "map_chart",
    "hessian_map",
    "gram_correction",
    "tutte_map",
    "repair_map",
    "distortion",
    "total_abs_curvature",
    "limit_blas_threads",
    "compare_methods",
    "METHODS",
    "PIPELINE_METHODS",
    "NULLSPACE_TOL",
    "EIGEN_SHIFT",
    "DENSE_EIGEN_MAX",
    "HLLE_SKIP_CURVATURE",
    "BLAS_THREADS",
]

log = logging.getLogger(__name__)

#: Generalized eigenvalues at or below ``NULLSPACE_TOL * max(|computed eigenvalues|)`` are
#: "null": beyond the constant and two coordinates, such eigenvectors join the Gram fit (null
#: space of dimension > 3, e.g. on tiny charts).
NULLSPACE_TOL: float = 1e-8

#: Shift of the shift-invert Lanczos solve, ``sigma = -EIGEN_SHIFT`` (unit-area chart): just
#: below the zero eigenvalues so that ``K - sigma M`` is positive definite.
EIGEN_SHIFT: float = 1e-4

#: Charts with at most this many vertices use a dense generalized eigen-solve.
DENSE_EIGEN_MAX: int = 600

#: Eigenpairs computed beyond the constant and the two coordinates (to detect a larger null
#: space).
EXTRA_EIGENPAIRS: int = 3

#: Largest null-space dimension used in the generalized Gram fit.
MAX_NULL_DIM: int = 6

#: SLIM iterations of the Tutte fallback's improvement.
SLIM_ITERATIONS: int = 30

#: Local repair of a Hessian map with a few flips: rounds of growing the free region by one
#: ring around the offending vertices (uniform-weight harmonic re-solve of the free region).
REPAIR_ROUNDS: int = 4

#: The repair gives up when its free region would exceed this fraction of the vertices (or
#: :data:`REPAIR_MIN_FREE` vertices, whichever is larger).
REPAIR_MAX_FRACTION: float = 0.2
REPAIR_MIN_FREE: int = 64

#: A repaired Hessian map is kept only if its symmetric Dirichlet energy is at most this
#: factor above the (flipped) Hessian map's: a repair must not damage the map.
REPAIR_MAX_SD_RATIO: float = 1.05

#: Guarded SLIM stops after this many consecutive non-bijective iterates that follow a
#: bijective one (see :func:`_slim_guarded`).
SLIM_STOP_AFTER_BAD: int = 3

#: Soft-constraint weight holding the boundary in the fixed-boundary SLIM variant.
SLIM_SOFT_P: float = 1e5

#: ``energy="auto"`` skips the HLLE map of a chart whose total absolute Gaussian curvature
#: (:func:`total_abs_curvature`, the sum of the absolute angle defects of its interior
#: vertices; scale-invariant) exceeds this: ``8 pi``, a Gauss image covering the sphere twice.
#: Measured on the 219 charts of 18 meshes (fandisk, block, the shared data set's mechanical,
#: organic and scan meshes): no HLLE map above 13.3 was bijective (the largest among the 123
#: bijective ones: block chart 0, 13.2; then psb_352_bearing chart 0, 9.1); all 31 charts
#: above 8 pi failed HLLE (flips or a collapsed map), among them 17 of iron.ply's 41 scan
#: charts (noise makes every angle defect count: 131k of its 160k faces; 6.2 of 7.6 s of
#: failed HLLE attempts).  The skip is recorded in ``attempts``.
HLLE_SKIP_CURVATURE: float = 8.0 * np.pi

#: Full :func:`parameterize_chart` runs (with repair and fallbacks) known to
#: :func:`compare_methods`.
PIPELINE_METHODS: tuple[str, ...] = ("param-hlle", "param-curved", "param-auto")

#: Methods known to :func:`map_chart`.
METHODS: tuple[str, ...] = (
    "hessian-hlle",
    "hessian-curved",
    "tutte",
    "tutte+slim",
    "tutte+slim-fixed",
    "harmonic",
    "lscm",
    "arap",
)


@dataclass
class ChartParam:
    """A chart's map to the plane and how good it is.

    Attributes
    ----------
    UV : (n, 2) float64
        Image of every vertex of the input ``V`` (``NaN`` rows for vertices ``F`` does not use).
        Counter-clockwise image orientation when the map is bijective (mirror undone).
    method : str
        What produced ``UV``: ``"hessian-hlle"``, ``"hessian-curved"`` (bijective Hessian map),
        ``"hessian-hlle+repair"``, ``"hessian-curved+repair"`` (locally repaired),
        ``"tutte"``, ``"tutte+slim"``, ``"tutte+slim-fixed"`` (fallbacks), or a baseline of
        :func:`map_chart`: ``"harmonic"``, ``"lscm"``, ``"arap"``.
    bijective : bool
        Certificate verdict for ``UV``.
    flips, overlaps : int
        Flipped triangles and intersecting boundary-edge pairs of ``UV``.
    distortion : dict
        See :func:`distortion`.
    seconds : float
        Wall time of the whole call (all attempts).
    eigenvalues : (k,) float64 or None
        Lowest generalized eigenvalues of the Hessian attempt (unit-area chart), constant
        included; ``None`` when no Hessian map was tried.
    certificate : Certificate
        Full certificate of ``UV``.
    attempts : list of dict
        Every map tried, in order: method, bijective, flips, overlaps, seconds.
    fallback_used : bool
        True when the requested Hessian map failed the certificate (the chart's map is then a
        repaired Hessian map or a Tutte-based fallback).
    """

    UV: np.ndarray
    method: str
    bijective: bool
    flips: int
    overlaps: int
    distortion: dict
    seconds: float
    eigenvalues: np.ndarray | None = None
    certificate: Certificate | None = field(default=None, repr=False)
    attempts: list = field(default_factory=list)
    fallback_used: bool = False

    def summary(self) -> dict:
        """JSON-ready summary (no arrays except short eigenvalue lists)."""
        return {
            "method": self.method,
            "bijective": bool(self.bijective),
            "flips": int(self.flips),
            "overlaps": int(self.overlaps),
            "degenerate": int(self.certificate.degenerate) if self.certificate else None,
            "fallback_used": bool(self.fallback_used),
            "distortion": {k: float(v) for k, v in self.distortion.items()},
            "seconds": float(self.seconds),
            "eigenvalues": None if self.eigenvalues is None else self.eigenvalues.tolist(),
            "attempts": self.attempts,
        }


#: OpenBLAS threads while :func:`parameterize_chart` runs (``None``: leave as is).  Its
#: work is many small BLAS calls (Lanczos vectors, dense eigen-solves of small charts,
#: batched 3 x k pseudo-inverses) that gain nothing from a second thread, and when the other
#: core is busy every threaded call waits for a time slice.  Measured on the 2-core machine
#: with one busy process on the other core (all charts of a run, best of 1): iron.ply
#: 40.5 s with OpenBLAS's default 2 threads, 14.1 s with 1; fandisk 24.0 s vs 1.7 s (a
#: 492-vertex dense eigen-solve: 0.04 s vs up to 3.4 s); with the other core idle 1 thread
#: was as fast (11.0 vs 11.8 s on iron).
BLAS_THREADS: int | None = 1


def limit_blas_threads(threads: int | None = BLAS_THREADS):
    """Context manager: at most ``threads`` BLAS threads inside, restored on exit.

    Parameters
    ----------
    threads : int or None
        Thread count for every BLAS library loaded in the process (numpy's and scipy's
        OpenBLAS, MKL, BLIS; through ``threadpoolctl``), process-wide.  ``None`` leaves them
        as they are.

    Examples
    --------
    >>> with limit_blas_threads(1):
    ...     pass
    """
    if threads is None:
        return contextlib.nullcontext()
    from threadpoolctl import threadpool_limits

    return threadpool_limits(limits=int(threads), user_api="blas")


# --------------------------------------------------------------------------- input


def _prepare_chart(V: ArrayLike, F: ArrayLike, name: str):
    """Check a disk chart; return compacted, unit-area normalised arrays and the maps back."""
    V, F = as_mesh_arrays(V, F, name)
    n = V.shape[0]
    if F.shape[0] == 0:
        raise MeshError(f"{name}: empty chart (0 faces)")
    if F.min() < 0 or F.max() >= n:
        raise MeshError(f"{name}: `F` indexes vertices outside 0..{n - 1}")
    used = np.unique(F)
    if not np.all(np.isfinite(V[used])):
        raise MeshError(f"{name}: NaN or infinite vertex coordinates")
    remap = np.full(n, -1, dtype=np.int64)
    remap[used] = np.arange(len(used))
    Fc = remap[F]
    Vc = V[used]
    ncomp, _ = face_components(Fc)
    loops = boundary_loops(Fc)
    chi = len(used) - len(_edges(Fc)) + Fc.shape[0]
    if ncomp != 1 or len(loops) != 1 or chi != 1:
        raise MeshError(
            f"{name}: not a topological disk ({ncomp} face component(s), {len(loops)} boundary "
            f"loop(s), Euler characteristic {chi}; a disk has 1, 1, 1): cut it to a disk first"
        )
    dblA = np.linalg.norm(
        np.cross(Vc[Fc[:, 1]] - Vc[Fc[:, 0]], Vc[Fc[:, 2]] - Vc[Fc[:, 0]]), axis=1
    )
    area = 0.5 * dblA.sum()
    if not area > 0:
        raise MeshError(f"{name}: chart has zero area")
    scale = 1.0 / np.sqrt(area)
    Vn = (Vc - Vc.mean(axis=0)) * scale
    return Vn, Fc, used, scale, loops[0]


def _expand(UVc: np.ndarray, used: np.ndarray, n: int) -> np.ndarray:
    UV = np.full((n, 2), np.nan)
    UV[used] = UVc
    return UV


def _edges(F: np.ndarray) -> np.ndarray:
    """(ne, 2) unique undirected edges, smaller id first (1D-key ``np.unique``: fast)."""
    E = np.sort(np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]]), axis=1)
    n = int(F.max()) + 1
    key = np.unique(E[:, 0] * n + E[:, 1])
    return np.stack([key // n, key % n], axis=1)


def total_abs_curvature(V: ArrayLike, F: ArrayLike, bnd: np.ndarray | None = None) -> float:
    """Total absolute Gaussian curvature of a chart: ``sum |2 pi - angle sum|`` over interior
    vertices.

    Zero on a developable (intrinsically flat) chart, about ``integral |K| dA`` on a smooth
    one, and large on noisy scans (every vertex's angle defect counts).  Scale-invariant.
    :func:`parameterize_chart` uses it to skip HLLE under ``energy="auto"`` (see
    :data:`HLLE_SKIP_CURVATURE`).

    Parameters
    ----------
    V : (n, 3) array_like of float
        Vertices.
    F : (m, 3) array_like of int
        Triangles (every vertex used).
    bnd : (b,) int64, optional
        Boundary vertices (every boundary loop's); computed when omitted.

    Returns
    -------
    float
        In radians.
    """
    V, F = as_mesh_arrays(V, F, "total_abs_curvature")
    if bnd is None:
        loops = boundary_loops(F)
        bnd = np.concatenate(loops) if loops else np.zeros(0, dtype=np.int64)
    k = np.asarray(igl.gaussian_curvature(V, F), dtype=np.float64).ravel()
    inner = np.ones(V.shape[0], dtype=bool)
    inner[bnd] = False
    return float(np.abs(k[inner]).sum())


# --------------------------------------------------------------------------- Hessian map


def _mass_diagonal(V: np.ndarray, F: np.ndarray) -> np.ndarray:
    m = np.asarray(igl.massmatrix(V, F, igl.MASSMATRIX_TYPE_VORONOI).diagonal()).ravel()
    if not np.all(m > 0):
        m = np.asarray(igl.massmatrix(V, F, igl.MASSMATRIX_TYPE_BARYCENTRIC).diagonal()).ravel()
    return m


def _lowest_eigenpairs(
    K: sp.spmatrix, m: np.ndarray, k: int, psd: bool = True
) -> tuple[np.ndarray, np.ndarray]:
    """Lowest ``k`` eigenpairs of ``K y = lambda diag(m) y`` (eigenvectors M-orthonormal).

    Dense ``eigh`` for small charts; otherwise shift-invert Lanczos (``eigsh``) around
    ``-EIGEN_SHIFT`` with one sparse LU of ``K + EIGEN_SHIFT M`` in symmetric mode (minimum
    degree ordering on ``A + A^T``: 3x less fill than the default column ordering on HLLE's
    4-ring sparsity), LOBPCG if ARPACK fails.  ``psd=False`` (a matrix that may be
    indefinite, as libigl's curved Hessian on doubly curved charts) allows threshold pivoting
    (0.1, still preferring the diagonal; without symmetric mode SuperLU's minimum degree
    ordering was 40x slower on a 25k-vertex chart).
    """
    n = K.shape[0]
    k = min(k, n)
    if n <= DENSE_EIGEN_MAX:
        # Only the k wanted pairs (LAPACK sygvx): 2x faster than all of them on a 492-vertex
        # chart (0.017 vs 0.036 s).  The standard form D^-1/2 K D^-1/2 was faster still
        # (0.010 s) but, on the 119 charts of <= 600 vertices of 18 meshes, turned one
        # cut flat annulus (psb_352_bearing chart 3, seams touching at rounding level) from
        # a bijective Hessian map into a fallback; this solve matches the full one there.
        return sla.eigh(K.toarray(), np.diag(m), subset_by_index=[0, k - 1])
    M = sp.diags(m).tocsc()
    A = (K + EIGEN_SHIFT * M).tocsc()
    lu = spla.splu(
        A,
        permc_spec="MMD_AT_PLUS_A",
        diag_pivot_thresh=0.0 if psd else 0.1,
        options={"SymmetricMode": True},
    )
    OP = spla.LinearOperator((n, n), matvec=lu.solve, dtype=np.float64)
    try:
        # Fixed start vector: ARPACK's default one comes from a generator whose state depends
        # on earlier calls in the process, so the eigenvectors' signs (and the maps' rigid
        # motions) changed from run to run.
        v0 = np.random.default_rng(0).standard_normal(n)
        lam, Y = spla.eigsh(
            K.tocsc(), k=k, M=M, sigma=-EIGEN_SHIFT, which="LM", OPinv=OP, tol=0.0, v0=v0
        )
    except (RuntimeError, spla.ArpackNoConvergence) as exc:
        log.warning("eigsh failed (%s); retrying with LOBPCG", exc)
        X0 = np.random.default_rng(0).standard_normal((n, k))
        lam, Y = spla.lobpcg(K, X0, B=M, M=OP, largest=False, tol=1e-10, maxiter=500)
    order = np.argsort(lam)
    return lam[order], Y[:, order]


def gram_correction(Y: np.ndarray, V: np.ndarray, F: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Affine (Gram) correction of eigen-coordinates to an isometric-as-possible layout.

    Fits a symmetric ``G`` (d x d) with ``l_e^2 ~ d_e^T G d_e`` over the edges (least squares,
    each equation divided by ``l_e^2``) and returns ``Y C`` with ``C C^T`` the best rank-2
    positive part of ``G`` (``C = G^(1/2)`` for ``d = 2``, up to a rotation).

    Parameters
    ----------
    Y : (n, d) float64
        Eigen-coordinates, ``d >= 2``.
    V : (n, 3) float64
        Vertex positions (edge lengths ``l_e``).
    F : (m, 3) int64
        Triangles.

    Returns
    -------
    UV : (n, 2) float64
        Corrected coordinates (unit: those of ``V``).
    G : (d, d) float64
        The fitted Gram matrix.
    """
    E = _edges(F)
    D = Y[E[:, 1]] - Y[E[:, 0]]  # (ne, d)
    l2 = ((V[E[:, 1]] - V[E[:, 0]]) ** 2).sum(axis=1)
    d = Y.shape[1]
    iu, ju = np.triu_indices(d)
    coef = D[:, iu] * D[:, ju] * np.where(iu == ju, 1.0, 2.0)[None, :]
    w = 1.0 / l2
    sol, *_ = np.linalg.lstsq(coef * w[:, None], l2 * w, rcond=None)
    G = np.zeros((d, d))
    G[iu, ju] = sol
    G[ju, iu] = sol
    gl, gv = np.linalg.eigh(G)
    top = np.argsort(gl)[::-1][:2]
    gl2 = np.maximum(gl[top], 0.0)
    C = gv[:, top] * np.sqrt(gl2)[None, :]
    return Y @ C, G


def hessian_map(
    V: np.ndarray,
    F: np.ndarray,
    energy: Literal["hlle", "curved"] = "hlle",
    **energy_kwargs,
) -> tuple[np.ndarray, np.ndarray, int]:
    """Hessian eigenmap of a (unit-area, disk) chart, Gram-corrected.

    Parameters
    ----------
    V : (n, 3) float64
        Compact chart vertices (every vertex used by ``F``).
    F : (m, 3) int64
        Triangles.
    energy : {"hlle", "curved"}
        :func:`~igl_heatseg.parameterization.hessian.hlle_energy` or
        :func:`~igl_heatseg.parameterization.hessian.curved_hessian_energy`.

    Returns
    -------
    UV : (n, 2) float64
        Layout, not yet certified, orientation arbitrary.
    eigenvalues : (k,) float64
        Lowest generalized eigenvalues (the constant's included).
    null_dim : int
        Number of non-constant eigenvectors used in the Gram fit (2, or more when the
        numerical null space is larger).
    """
    n = V.shape[0]
    if energy == "hlle":
        K = hlle_energy(V, F, **energy_kwargs)
    elif energy == "curved":
        K = curved_hessian_energy(V, F)
    else:
        raise MeshError(f"hessian_map: `energy` must be 'hlle' or 'curved', got {energy!r}")
    m = _mass_diagonal(V, F)
    lam, Y = _lowest_eigenpairs(K, m, 3 + EXTRA_EIGENPAIRS, psd=energy == "hlle")
    null = int(np.count_nonzero(lam <= NULLSPACE_TOL * max(np.abs(lam).max(), 1e-300)))
    keep = min(max(3, null), MAX_NULL_DIM + 1, n)
    Yk = Y[:, :keep]
    # Remove the constant: M-centre, then keep the keep-1 dominant directions (M-weighted).
    Yk = Yk - (m @ Yk)[None, :] / m.sum()
    sq = np.sqrt(m)[:, None]
    U, s, Wt = np.linalg.svd(sq * Yk, full_matrices=False)
    basis = U[:, : keep - 1] / sq
    if keep - 1 < 2:
        basis = np.column_stack([basis, np.zeros(n)])
    UV, _ = gram_correction(basis, V, F)
    return UV, lam, keep - 1


# --------------------------------------------------------------------------- fallbacks


def _circle_boundary(V: np.ndarray, bnd: np.ndarray) -> np.ndarray:
    """Boundary vertices on the unit circle, spacing by arc length, counter-clockwise."""
    seg = np.linalg.norm(V[np.roll(bnd, -1)] - V[bnd], axis=1)
    t = np.concatenate([[0.0], np.cumsum(seg)[:-1]]) / seg.sum()
    ang = 2.0 * np.pi * t
    return np.stack([np.cos(ang), np.sin(ang)], axis=1)


def tutte_map(
    V: np.ndarray,
    F: np.ndarray,
    bnd: np.ndarray | None = None,
    weights: Literal["mean_value", "uniform"] = "mean_value",
) -> np.ndarray:
    """Convex-combination (Tutte/Floater) map with the boundary on a circle.

    Every interior vertex is a positive-weight average of its neighbours; the boundary goes to
    the unit circle, spaced by arc length.  With positive weights and a strictly convex
    boundary the map of a triangulated disk is bijective (Tutte 1963, Floater 2003), up to
    floating-point rounding of the linear solve (the certificate checks it).  Floater's mean
    value weights (default) follow the 3D geometry: on sliver-rich CAD tessellations they gave
    a symmetric Dirichlet energy of 5.6e3 where uniform weights gave 5e22 (abc_stl2_00000008).

    Parameters
    ----------
    V : (n, 3) float64
        Vertices.
    F : (m, 3) int64
        Disk triangulation using every vertex.
    bnd : (b,) int64, optional
        Ordered boundary loop (surface on the left); computed when omitted.
    weights : {"mean_value", "uniform"}
        Floater's mean value weights or Tutte's uniform weights.

    Returns
    -------
    UV : (n, 2) float64
        Counter-clockwise image in the unit disk.
    """
    n = V.shape[0]
    if bnd is None:
        bnd = boundary_loops(F)[0]
    if weights == "mean_value":
        L = _mean_value_laplacian(V, F)
    else:
        E = _edges(F)
        A = sp.csr_matrix(
            (np.ones(2 * len(E)), (np.r_[E[:, 0], E[:, 1]], np.r_[E[:, 1], E[:, 0]])),
            shape=(n, n),
        )
        L = (sp.diags(np.asarray(A.sum(axis=1)).ravel()) - A).tocsr()
    UV = np.zeros((n, 2))
    UV[bnd] = _circle_boundary(V, bnd)
    inner = np.setdiff1d(np.arange(n), bnd)
    if len(inner):
        LII = L[inner][:, inner].tocsc()
        rhs = -(L[inner][:, bnd] @ UV[bnd])
        solve = spla.factorized(LII)
        UV[inner, 0] = solve(rhs[:, 0])
        UV[inner, 1] = solve(rhs[:, 1])
        if weights == "mean_value" and not np.all(np.isfinite(UV)):
            return tutte_map(V, F, bnd, "uniform")
    return UV


def _mean_value_laplacian(V: np.ndarray, F: np.ndarray) -> sp.csr_matrix:
    """(n, n) ``diag(rowsum W) - W`` with Floater's mean value weights (positive, asymmetric)
    ``W[i, j] = (tan(a/2) + tan(b/2)) / |x_i - x_j|``, ``a, b`` the angles at ``i`` next to
    the edge ``(i, j)``."""
    n = V.shape[0]
    rows, cols, vals = [], [], []
    for c in range(3):
        i, j, k = F[:, c], F[:, (c + 1) % 3], F[:, (c + 2) % 3]
        eij = V[j] - V[i]
        eik = V[k] - V[i]
        lij = np.linalg.norm(eij, axis=1)
        lik = np.linalg.norm(eik, axis=1)
        cosa = np.clip((eij * eik).sum(1) / np.maximum(lij * lik, 1e-300), -1.0, 1.0)
        t = np.tan(0.5 * np.arccos(cosa))
        rows += [i, i]
        cols += [j, k]
        vals += [t / np.maximum(lij, 1e-300), t / np.maximum(lik, 1e-300)]
    W = sp.csr_matrix(
        (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(n, n)
    )
    return (sp.diags(np.asarray(W.sum(axis=1)).ravel()) - W).tocsr()


def repair_map(
    UV: np.ndarray,
    V: np.ndarray,
    F: np.ndarray,
    cert: Certificate,
    name: str = "chart",
    rounds: int = REPAIR_ROUNDS,
    max_fraction: float = REPAIR_MAX_FRACTION,
) -> tuple[np.ndarray, Certificate, int]:
    """Untangle a map with a few local flips by re-solving a small region harmonically.

    The free region starts as the vertices of the flipped and degenerate triangles (and wound
    vertices) and grows by one ring per round; its vertices are re-solved as the mean value
    (Floater) weighted average of their neighbours, weights from the 3D triangles, with every
    other vertex fixed.  Stops at the first
    round whose certificate is bijective.  Boundary overlaps are not repaired (returned as is).

    Parameters
    ----------
    UV : (n, 2) float64
        Map with the dominant orientation counter-clockwise.
    V : (n, 3) float64
        Chart vertices (for the weights).
    F : (m, 3) int64
        Triangles.
    cert : Certificate
        Certificate of ``UV``.

    Returns
    -------
    UV : (n, 2) float64
        Repaired map (the input where nothing was changed).
    cert : Certificate
        Its certificate.
    rounds : int
        Rounds used (0: nothing to do or overlaps).
    """
    n = UV.shape[0]
    if cert.bijective or cert.overlaps > 0:
        return UV, cert, 0
    E = _edges(F)
    A = sp.csr_matrix(
        (np.ones(2 * len(E)), (np.r_[E[:, 0], E[:, 1]], np.r_[E[:, 1], E[:, 0]])), shape=(n, n)
    )
    L = _mean_value_laplacian(V, F)
    free = np.zeros(n, dtype=bool)
    free[F[np.r_[cert.flipped_faces, cert.degenerate_faces]].ravel()] = True
    free[cert.wound_vertices] = True
    best_UV, best_cert = UV, cert
    for r in range(1, rounds + 1):
        free = free | (A @ free.astype(np.float64) > 0)
        if free.sum() > max(max_fraction * n, REPAIR_MIN_FREE) or (~free).sum() < 3:
            break
        fi = np.flatnonzero(free)
        fx = np.flatnonzero(~free)
        rhs = -(L[fi][:, fx] @ UV[fx])
        solve = spla.factorized(L[fi][:, fi].tocsc())
        UVr = UV.copy()
        UVr[fi, 0] = solve(rhs[:, 0])
        UVr[fi, 1] = solve(rhs[:, 1])
        c = certify_map(UVr, F, name=name)
        if c.mirrored:  # the repair never mirrors a map; treat as failure
            continue
        if c.bijective:
            return UVr, c, r
        if c.flips + c.degenerate + c.wound < (
            best_cert.flips + best_cert.degenerate + best_cert.wound
        ):
            best_UV, best_cert = UVr, c
    return best_UV, best_cert, rounds


def _slim_data(V: np.ndarray, F: np.ndarray, UV0: np.ndarray, b=None, bc=None, energy=None):
    if energy is None:
        energy = igl.MappingEnergyType.SYMMETRIC_DIRICHLET
    fixed = b is not None and len(b) > 0
    return igl.slim_precompute(
        np.asfortranarray(V),
        np.asfortranarray(F.astype(np.int32)),
        np.asfortranarray(UV0),
        energy,
        np.asarray(b if fixed else np.zeros(0), dtype=np.int32),
        np.asfortranarray(bc if fixed else np.zeros((0, 2))),
        SLIM_SOFT_P if fixed else 0.0,
    )


def _slim(
    V: np.ndarray, F: np.ndarray, UV0: np.ndarray, iterations: int, energy=None
) -> np.ndarray:
    """SLIM (libigl) from a flip-free start, free boundary, no certificate."""
    data = _slim_data(V, F, UV0, energy=energy)
    return np.ascontiguousarray(igl.slim_solve(data, iterations)[:, :2])


def _slim_guarded(
    V: np.ndarray,
    F: np.ndarray,
    UV0: np.ndarray,
    iterations: int,
    name: str,
    bnd: np.ndarray | None = None,
    loops: list[np.ndarray] | None = None,
) -> tuple[np.ndarray, Certificate | None, int, int]:
    """SLIM one iteration at a time from a bijective start; keep the last bijective iterate.

    SLIM's line search prevents flips but not boundary overlaps (free boundary), and an
    overlap can be transient: every iterate is certified and the result is the *last*
    bijective one, the one with the lowest energy (SLIM's energy decreases monotonically).
    Measured on the 20 charts of the shared data set that fall back to Tutte + SLIM, 30
    iterations: 7 have non-bijective iterates; on 5 of them a later iterate is bijective again
    (iron.ply chart 1: iterate 3 overlaps, 4-22 are bijective; stopping at the first
    non-bijective iterate kept iterate 2, symmetric Dirichlet 13.7 instead of 4.01; on
    abc_00007974_5's two charts no iterate before the first overlap was bijective and the
    fixed-boundary variant's 33.4 and 15.7 were kept instead of 4.05 and 4.09).  Certifying
    every iterate costs about a third of an iteration (boundary loops passed in); the
    previous scheme (all iterations, then again one at a time when the result failed) cost
    two SLIM runs whenever an overlap occurred.  With ``bnd`` the boundary is held (soft
    constraint, :data:`SLIM_SOFT_P`) at its start positions.

    Early stop: after :data:`SLIM_STOP_AFTER_BAD` consecutive non-bijective iterates that
    follow a bijective one.  On the 20 fallback charts, once an iterate had been bijective,
    a non-bijective run either lasted one iterate (iron.ply chart 1) or lasted to the last
    iteration (13 iterates on iron chart 7, 20 on block_noisy chart 0), so the stop kept the
    same iterate on all 20 and saved 3-21 of the 30 iterations on 7 of them.

    Returns
    -------
    UV : (n, 2) float64
        Last bijective iterate (``UV0`` when none was).
    cert : Certificate or None
        Its certificate (``None`` when no iterate was bijective).
    accepted : int
        Index (1-based) of the kept iterate, 0 when none.
    bijective_iterates : int
        Number of bijective iterates.
    """
    bc = UV0[bnd] if bnd is not None else None
    try:
        data = _slim_data(V, F, UV0, bnd, bc)
    except RuntimeError as exc:  # pragma: no cover - libigl failure
        log.warning("%s: SLIM failed: %s", name, exc)
        return UV0, None, 0, 0
    best, best_cert, accepted, good, bad_run = UV0, None, 0, 0, 0
    for it in range(1, iterations + 1):
        try:
            UV = np.ascontiguousarray(igl.slim_solve(data, 1)[:, :2])
        except RuntimeError as exc:  # pragma: no cover - libigl failure
            log.warning("%s: SLIM iteration failed: %s", name, exc)
            break
        if not np.all(np.isfinite(UV)):
            break
        UV, cert = _finish(UV, V, F, name, loops)
        if cert.bijective:
            best, best_cert, accepted, good, bad_run = UV, cert, it, good + 1, 0
        else:
            bad_run += 1
            if accepted > 0 and bad_run >= SLIM_STOP_AFTER_BAD:
                break
    return best, best_cert, accepted, good


def _harmonic(V, F, bnd):
    return igl.harmonic(V, F, bnd, _circle_boundary(V, bnd), 1)


def _lscm(V, F, bnd):
    # Two boundary vertices far apart, fixed at (0,0) and (|p-q|, 0).
    P = V[bnd]
    i = int(np.argmax(((P - P[0]) ** 2).sum(1)))
    j = int(np.argmax(((P - P[i]) ** 2).sum(1)))
    b = np.array([bnd[i], bnd[j]], dtype=np.int64)
    bc = np.array([[0.0, 0.0], [np.linalg.norm(P[i] - P[j]), 0.0]])
    UV, _ = igl.lscm(V, F, b, bc)
    return UV


def _arap(V, F, bnd, iterations=20):
    UV0 = _harmonic(V, F, bnd)
    data = igl.ARAPData()
    data.with_dynamics = True
    data.max_iter = iterations
    igl.arap_precomputation(V, F, 2, np.zeros(0, dtype=np.int32), data)
    return igl.arap_solve(np.zeros((0, 2)), data, UV0)


# --------------------------------------------------------------------------- distortion


def distortion(V: np.ndarray, F: np.ndarray, UV: np.ndarray) -> dict:
    """Angle, area and isometric distortion of a map (definitions in the module docstring).

    Parameters
    ----------
    V : (n, 3) float64
        3D vertices.
    F : (m, 3) int64
        Triangles.
    UV : (n, 2) float64
        Map; its global scale is normalised away (total image area := total 3D area).

    Returns
    -------
    dict
        ``conformal_mean``, ``conformal_max``, ``area_mean``, ``area_max``, ``sym_dirichlet``,
        ``stretch_max`` (floats, ``inf`` when a triangle's image is degenerate).
    """
    P0, P1, P2 = V[F[:, 0]], V[F[:, 1]], V[F[:, 2]]
    e1 = P1 - P0
    e2 = P2 - P0
    l1 = np.linalg.norm(e1, axis=1)
    x = e1 / l1[:, None]
    e2x = (e2 * x).sum(axis=1)
    e2y = np.linalg.norm(e2 - e2x[:, None] * x, axis=1)
    a3 = 0.5 * l1 * e2y
    W1 = UV[F[:, 1]] - UV[F[:, 0]]
    W2 = UV[F[:, 2]] - UV[F[:, 0]]
    auv = 0.5 * np.abs(W1[:, 0] * W2[:, 1] - W1[:, 1] * W2[:, 0])
    s = np.sqrt(a3.sum() / auv.sum()) if auv.sum() > 0 else 1.0
    W1 = W1 * s
    W2 = W2 * s
    # J [l1 e2x; 0 e2y] = [W1 W2]  =>  J = [W1 W2] inv(Q)
    if np.all(l1 != 0) and np.all(e2y != 0):
        # Closed forms for the triangular inverse and the 2 x 2 singular values
        # (s1, s2 = (p +- q) / 2 with p = |(a + d, c - b)|, q = |(a - d, c + b)|): 6x faster
        # than batched inv + svd, same values to rounding.
        a = W1[:, 0] / l1
        c = W1[:, 1] / l1
        b = (W2[:, 0] - a * e2x) / e2y
        d = (W2[:, 1] - c * e2x) / e2y
        p = np.hypot(a + d, c - b)
        q = np.hypot(a - d, c + b)
        s1, s2 = 0.5 * (p + q), 0.5 * np.abs(p - q)
    else:  # degenerate 3D triangle: numpy raises as before
        Q = np.zeros((len(F), 2, 2))
        Q[:, 0, 0] = l1
        Q[:, 0, 1] = e2x
        Q[:, 1, 1] = e2y
        Wm = np.stack([W1, W2], axis=2)  # columns W1, W2
        J = Wm @ np.linalg.inv(Q)
        sig = np.linalg.svd(J, compute_uv=False)
        s1, s2 = sig[:, 0], sig[:, 1]
    w = a3 / a3.sum()
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        conf = np.where(s2 > 0, s1 / s2, np.inf)
        det = s1 * s2
        area = np.where(det > 0, np.maximum(det, 1.0 / det), np.inf)
        sd = np.where(s2 > 0, s1**2 + s1**-2.0 + s2**2 + s2**-2.0, np.inf)
        stretch = np.where(s2 > 0, np.maximum(s1, 1.0 / s2), np.inf)
        return {
            "conformal_mean": float((w * conf).sum()),
            "conformal_max": float(conf.max()),
            "area_mean": float((w * area).sum()),
            "area_max": float(area.max()),
            "sym_dirichlet": float((w * sd).sum()),
            "stretch_max": float(stretch.max()),
        }


# --------------------------------------------------------------------------- entry points


def _finish(UVc, Vn, Fc, name, loops=None):
    """Certify; undo a mirror image (``u -> -u``) and return its certificate.

    The mirror's certificate is the same one with ``mirrored=False``: negating ``u`` negates
    every orientation determinant exactly (IEEE negation and products), so flips, degenerate
    triangles, boundary intersections and windings are unchanged (checked by
    ``tests/test_param.py``); it is not recomputed.
    """
    cert = certify_map(UVc, Fc, name=name, loops=loops)
    if cert.mirrored:
        UVc = UVc * np.array([-1.0, 1.0])
        cert = dataclasses.replace(cert, mirrored=False, orientation=1)
    return UVc, cert


def _run(method: str, Vn, Fc, bnd, name, energy_kwargs) -> tuple[np.ndarray, np.ndarray | None]:
    lam = None
    if method == "hessian-hlle":
        UVc, lam, _ = hessian_map(Vn, Fc, "hlle", **energy_kwargs)
    elif method == "hessian-curved":
        UVc, lam, _ = hessian_map(Vn, Fc, "curved")
    elif method == "tutte":
        UVc = tutte_map(Vn, Fc, bnd)
    elif method == "tutte+slim":
        UVc = _slim(Vn, Fc, tutte_map(Vn, Fc, bnd), SLIM_ITERATIONS)
    elif method == "tutte+slim-fixed":
        UVt = tutte_map(Vn, Fc, bnd)
        data = _slim_data(Vn, Fc, UVt, bnd, UVt[bnd])
        UVc = np.ascontiguousarray(igl.slim_solve(data, SLIM_ITERATIONS)[:, :2])
    elif method == "harmonic":
        UVc = _harmonic(Vn, Fc, bnd)
    elif method == "lscm":
        UVc = _lscm(Vn, Fc, bnd)
    elif method == "arap":
        UVc = _arap(Vn, Fc, bnd)
    else:
        raise MeshError(f"{name}: unknown method {method!r}; known: {', '.join(METHODS)}")
    return np.asarray(UVc, dtype=np.float64), lam


def map_chart(
    V: ArrayLike,
    F: ArrayLike,
    method: str = "hessian-hlle",
    *,
    name: str = "chart",
    **energy_kwargs,
) -> ChartParam:
    """Map a disk chart with one method, no fallback; certify it and measure distortion.

    Parameters
    ----------
    V : (n, 3) array_like of float
        Vertex positions (vertices not used by ``F`` are allowed and get ``NaN`` UVs).
    F : (m, 3) array_like of int
        Triangles of a topological disk, consistently oriented.
    method : str
        One of :data:`METHODS`.  ``"tutte+slim"`` keeps SLIM's result even if not bijective
        (use :func:`parameterize_chart` for the guarded version).
    name : str
        Chart name for messages.
    **energy_kwargs
        Passed to :func:`~igl_heatseg.parameterization.hessian.hlle_energy` for ``"hessian-hlle"``.

    Returns
    -------
    ChartParam

    Raises
    ------
    MeshError
        Bad arrays, or the chart is not a disk.
    """
    t0 = time.perf_counter()
    V_in = np.asarray(V)
    Vn, Fc, used, scale, bnd = _prepare_chart(V, F, name)
    try:
        with limit_blas_threads(BLAS_THREADS):
            UVc, lam = _run(method, Vn, Fc, bnd, name, energy_kwargs)
    except RuntimeError as exc:
        raise MeshError(f"{name}: {method} failed in libigl/scipy: {exc}") from None
    if not np.all(np.isfinite(UVc)):
        UVc = np.nan_to_num(UVc, nan=0.0, posinf=0.0, neginf=0.0)
    UVc, cert = _finish(UVc, Vn, Fc, name)
    dist = distortion(Vn, Fc, UVc)
    secs = time.perf_counter() - t0
    return ChartParam(
        UV=_expand(UVc / scale, used, V_in.shape[0]),
        method=method,
        bijective=cert.bijective,
        flips=cert.flips,
        overlaps=cert.overlaps,
        distortion=dist,
        seconds=secs,
        eigenvalues=lam,
        certificate=cert,
        attempts=[{"method": method, **cert.summary(), "seconds": secs}],
    )


def parameterize_chart(
    V: ArrayLike,
    F: ArrayLike,
    energy: Literal["hlle", "curved"] = "hlle",
    *,
    fallback: Literal["tutte+slim", "tutte", "none"] = "tutte+slim",
    slim_iterations: int = SLIM_ITERATIONS,
    repair: bool = True,
    hlle_skip_curvature: float | None = HLLE_SKIP_CURVATURE,
    name: str = "chart",
    **energy_kwargs,
) -> ChartParam:
    """Hessian eigenmap of a disk chart with certified bijectivity and a bijective fallback.

    Parameters
    ----------
    V : (n, 3) array_like of float
        Vertex positions (vertices not used by ``F`` get ``NaN`` UVs).
    F : (m, 3) array_like of int
        Triangles of a topological disk (1 component, 1 boundary loop, chi = 1), consistently
        oriented.  Any size from one triangle up.
    energy : {"hlle", "curved", "auto"}
        Hessian energy: the paper's HLLE (:func:`~igl_heatseg.parameterization.hessian.hlle_energy`), libigl's
        curved Hessian (:func:`~igl_heatseg.parameterization.hessian.curved_hessian_energy`), or ``"auto"``:
        HLLE, and the curved Hessian when the HLLE map is not bijective (HLLE is the more
        accurate on creased CAD charts, the curved Hessian the more robust on scans).  Under
        ``"auto"``, HLLE is skipped (straight to the curved Hessian) on charts whose
        :func:`total_abs_curvature` exceeds ``hlle_skip_curvature``.
    fallback : {"tutte+slim", "tutte", "none"}
        What to do when the Hessian map is not bijective: a Tutte map (bijective by
        construction), optionally improved by SLIM keeping the last certified-bijective
        iterate (free boundary; with the boundary held on the circle only when no
        free-boundary iterate is bijective); or nothing (return the non-bijective Hessian
        map, flagged).
    slim_iterations : int
        SLIM iterations for ``"tutte+slim"``.
    repair : bool
        Before falling back, try :func:`repair_map` on a Hessian map with local flips (no
        boundary overlaps); if that is bijective the method is ``"hessian-<energy>+repair"``.
    hlle_skip_curvature : float or None
        ``energy="auto"`` only: skip HLLE when the chart's total absolute Gaussian curvature
        is above this (default :data:`HLLE_SKIP_CURVATURE`, ``8 pi``; measured: HLLE was never
        bijective above 13.3).  The skipped attempt is listed in ``attempts`` with
        ``"skipped": True`` and the ``reason``.  ``None`` never skips.
    name : str
        Chart name for messages.
    **energy_kwargs
        Passed to :func:`~igl_heatseg.parameterization.hessian.hlle_energy`.

    Returns
    -------
    ChartParam
        ``method`` is ``"hessian-hlle"``/``"hessian-curved"`` when the Hessian map is bijective,
        else ``"tutte"``, ``"tutte+slim"`` or ``"tutte+slim-fixed"`` (``fallback_used=True``);
        ``attempts`` lists every
        map tried with its certificate.  ``UV`` is in the units of ``V`` (Hessian maps are
        isometric-as-possible; the Tutte fallback is scaled to the chart's area).

    Raises
    ------
    MeshError
        Bad arrays, the chart is not a disk, or an unknown ``energy``/``fallback``.

    Examples
    --------
    >>> import numpy as np
    >>> x, y = np.meshgrid(np.arange(5.0), np.arange(4.0))
    >>> V = np.stack([x.ravel(), y.ravel(), 0 * x.ravel()], 1)
    >>> i = np.arange(20).reshape(4, 5)[:-1, :-1].ravel()
    >>> F = np.concatenate([np.stack([i, i + 1, i + 6], 1), np.stack([i, i + 6, i + 5], 1)])
    >>> res = parameterize_chart(V, F)
    >>> res.method, res.bijective, round(res.distortion["sym_dirichlet"], 6)
    ('hessian-hlle', True, 4.0)
    """
    with limit_blas_threads(BLAS_THREADS):
        return _parameterize_chart(
            V,
            F,
            energy,
            fallback=fallback,
            slim_iterations=slim_iterations,
            repair=repair,
            hlle_skip_curvature=hlle_skip_curvature,
            name=name,
            energy_kwargs=energy_kwargs,
        )


def _parameterize_chart(
    V, F, energy, *, fallback, slim_iterations, repair, hlle_skip_curvature, name, energy_kwargs
) -> ChartParam:
    if energy not in ("hlle", "curved", "auto"):
        raise MeshError(f"{name}: `energy` must be 'hlle', 'curved' or 'auto', got {energy!r}")
    if fallback not in ("tutte+slim", "tutte", "none"):
        raise MeshError(
            f"{name}: `fallback` must be 'tutte+slim', 'tutte' or 'none', got {fallback!r}"
        )
    t0 = time.perf_counter()
    n_in = np.asarray(V).shape[0] if np.ndim(V) == 2 else 0
    Vn, Fc, used, scale, bnd = _prepare_chart(V, F, name)
    attempts = []
    tries = []  # (UV, cert, method, eigenvalues) of every Hessian map computed
    energies: tuple[str, ...] = ("hlle", "curved") if energy == "auto" else (energy,)
    tac = None
    if energy == "auto" and hlle_skip_curvature is not None:
        t = time.perf_counter()
        tac = total_abs_curvature(Vn, Fc, bnd)
        if tac > hlle_skip_curvature:
            energies = ("curved",)
            attempts.append(
                {
                    "method": "hessian-hlle",
                    "skipped": True,
                    "bijective": False,
                    "reason": f"total absolute curvature {tac:.3g} > {hlle_skip_curvature:.3g}: "
                    "HLLE predicted to flip (HLLE_SKIP_CURVATURE)",
                    "total_abs_curvature": tac,
                    "seconds": time.perf_counter() - t,
                }
            )
    for en in energies:
        meth = f"hessian-{en}"
        t = time.perf_counter()
        try:
            kw = energy_kwargs if en == "hlle" else {}
            UVh, lam_h, null_dim = hessian_map(Vn, Fc, en, **kw)
            ok = bool(np.all(np.isfinite(UVh)))
        except (RuntimeError, np.linalg.LinAlgError, ValueError) as exc:
            if isinstance(exc, MeshError):
                raise
            log.warning("%s: %s eigen-solve failed: %s", name, meth, exc)
            ok = False
        if ok:
            UVh, cert_h = _finish(UVh, Vn, Fc, name, [bnd])
            attempts.append(
                {
                    "method": meth,
                    **cert_h.summary(),
                    "null_dim": null_dim,
                    **({"total_abs_curvature": tac} if tac is not None and en == "hlle" else {}),
                    "seconds": time.perf_counter() - t,
                }
            )
            tries.append((UVh, cert_h, meth, lam_h))
            if cert_h.bijective:
                break
        else:
            attempts.append(
                {
                    "method": meth,
                    "bijective": False,
                    "error": "eigen-solve failed",
                    "seconds": time.perf_counter() - t,
                }
            )
    if tries:
        # The bijective one, else the one that is easiest to repair (no overlaps, fewest
        # local defects).
        def badness(tr):
            c = tr[1]
            return (not c.bijective, c.overlaps > 0, c.flips + c.degenerate + c.wound)

        UVc, cert, method, lam = min(tries, key=badness)
    else:
        UVc, cert, method, lam = np.zeros((Vn.shape[0], 2)), None, f"hessian-{energy}", None
    used_fallback = False
    if (cert is None or not cert.bijective) and fallback != "none":
        used_fallback = True
        if cert is not None:
            log.info(
                "%s: %s not bijective (flips %d, overlaps %d, degenerate %d, wound %d); "
                "falling back to %s",
                name,
                method,
                cert.flips,
                cert.overlaps,
                cert.degenerate,
                cert.wound,
                fallback,
            )
        repaired = False
        if repair and cert is not None and cert.overlaps == 0:
            t = time.perf_counter()
            UVr, cert_r, rounds = repair_map(UVc, Vn, Fc, cert, name)
            sd0 = distortion(Vn, Fc, UVc)["sym_dirichlet"]
            sd1 = distortion(Vn, Fc, UVr)["sym_dirichlet"]
            keep = cert_r.bijective and sd1 <= REPAIR_MAX_SD_RATIO * sd0
            attempts.append(
                {
                    "method": f"{method}+repair",
                    "rounds": rounds,
                    **cert_r.summary(),
                    "sym_dirichlet_ratio": float(sd1 / sd0) if sd0 > 0 else None,
                    "kept": bool(keep),
                    "seconds": time.perf_counter() - t,
                }
            )
            if keep:
                UVc, cert, method, repaired = UVr, cert_r, f"{method}+repair", True
    if used_fallback and not repaired:
        t = time.perf_counter()
        UVt = tutte_map(Vn, Fc, bnd)
        UVt, cert_t = _finish(UVt, Vn, Fc, name, [bnd])
        attempts.append({"method": "tutte", **cert_t.summary(), "seconds": time.perf_counter() - t})
        UVc, cert, method = UVt, cert_t, "tutte"
        if fallback == "tutte+slim" and cert_t.bijective and slim_iterations > 0:
            # Free boundary first, keeping its last bijective iterate; only if none of its
            # iterates is bijective, SLIM with the boundary held on the circle.
            t = time.perf_counter()
            UVs, cert_s, acc, good = _slim_guarded(Vn, Fc, UVt, slim_iterations, name, loops=[bnd])
            attempts.append(
                {
                    "method": "tutte+slim",
                    "accepted_iterations": acc,
                    "bijective_iterations": good,
                    **(cert_s.summary() if cert_s else cert_t.summary()),
                    "seconds": time.perf_counter() - t,
                }
            )
            if acc > 0:
                UVc, cert, method = UVs, cert_s, "tutte+slim"
            else:
                t = time.perf_counter()
                UVf, cert_f, acc_f, good_f = _slim_guarded(
                    Vn, Fc, UVt, slim_iterations, name, bnd, loops=[bnd]
                )
                attempts.append(
                    {
                        "method": "tutte+slim-fixed",
                        "accepted_iterations": acc_f,
                        "bijective_iterations": good_f,
                        **(cert_f.summary() if cert_f else cert_t.summary()),
                        "seconds": time.perf_counter() - t,
                    }
                )
                if acc_f > 0:
                    UVc, cert, method = UVf, cert_f, "tutte+slim-fixed"
        if not cert.bijective:
            log.warning("%s: fallback map is not bijective either (%s)", name, cert.summary())
        if method == "tutte":  # arbitrary scale: match the chart's area
            a = (
                0.5
                * np.abs(
                    np.cross(UVc[Fc[:, 1]] - UVc[Fc[:, 0]], UVc[Fc[:, 2]] - UVc[Fc[:, 0]])
                ).sum()
            )
            UVc = UVc / np.sqrt(a)
    elif cert is None:
        UVc, cert = _finish(UVc, Vn, Fc, name)
    dist = distortion(Vn, Fc, UVc)
    return ChartParam(
        UV=_expand(UVc / scale, used, n_in),
        method=method,
        bijective=cert.bijective,
        flips=cert.flips,
        overlaps=cert.overlaps,
        distortion=dist,
        seconds=time.perf_counter() - t0,
        eigenvalues=lam,
        certificate=cert,
        attempts=attempts,
        fallback_used=method not in ("hessian-hlle", "hessian-curved"),
    )


def compare_methods(
    charts: Iterable[tuple[str, np.ndarray, np.ndarray]],
    methods: Sequence[str] = ("hessian-hlle", "hessian-curved", "harmonic", "lscm"),
) -> list[dict]:
    """Run several parameterization methods on disk charts; one table row per (chart, method).

    Every method goes through the same certificate and distortion code.  Names from
    :data:`METHODS` run :func:`map_chart` (one method, no fallback); ``"param-hlle"``,
    ``"param-curved"``, ``"param-auto"`` run the full :func:`parameterize_chart` (Hessian map,
    repair, certified fallbacks) and report which map it produced.

    Parameters
    ----------
    charts : iterable of (name, V, F)
        Disk charts.
    methods : sequence of str
        Names from :data:`METHODS` or :data:`PIPELINE_METHODS`.

    Returns
    -------
    rows : list of dict
        Keys ``chart, faces, method, bijective, flips, overlaps, degenerate, conformal_mean,
        conformal_max, area_mean, area_max, sym_dirichlet, stretch_max, seconds``; for the
        ``param-*`` names also ``result`` (the method recorded for the chart) and
        ``fallback_used``; ``error`` when a method raised.
    """
    rows = []
    for cname, V, F in charts:
        for method in methods:
            row = {"chart": cname, "faces": int(np.shape(F)[0]), "method": method}
            try:
                if method in PIPELINE_METHODS:
                    res = parameterize_chart(V, F, method[len("param-") :], name=str(cname))
                    row.update({"result": res.method, "fallback_used": res.fallback_used})
                else:
                    res = map_chart(V, F, method, name=str(cname))
            except (MeshError, RuntimeError, np.linalg.LinAlgError) as exc:
                row.update({"bijective": False, "error": str(exc)})
                rows.append(row)
                continue
            row.update(
                {
                    "bijective": res.bijective,
                    "flips": res.flips,
                    "overlaps": res.overlaps,
                    "degenerate": res.certificate.degenerate,
                    **res.distortion,
                    "seconds": res.seconds,
                }
            )
            rows.append(row)
    return rows
