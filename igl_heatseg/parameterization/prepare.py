"""Chart preparation shared by every map: checks, unit-area normalisation, edges, the
oriented certificate, BLAS thread limiting and the total absolute curvature.

A chart must be a topological disk (one face component, one boundary loop, chi = 1); cut it
first otherwise.  :func:`prepare_chart` translates it and scales it to unit area for the
numerics; maps are scaled back by the caller.
"""

from __future__ import annotations

import contextlib
import dataclasses

import igl
import numpy as np
from numpy.typing import ArrayLike

from ..errors import MeshError
from ..mesh.checks import as_mesh_arrays
from ..mesh.topology import boundary_loops, face_components
from .bijectivity import Certificate, certify_map

__all__ = [
    "PreparedChart",
    "prepare_chart",
    "expand_uv",
    "unique_edges",
    "certify_oriented",
    "total_abs_curvature",
    "limit_blas_threads",
    "BLAS_THREADS",
]

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


@dataclasses.dataclass(frozen=True)
class PreparedChart:
    """A disk chart ready for mapping (see :func:`prepare_chart`).

    Attributes
    ----------
    V : (n', 3) float64
        Used vertices, centred and scaled to unit total area.
    F : (m, 3) int64
        Triangles indexing ``V``.
    used : (n',) int64
        Input vertex id of every row of ``V``.
    scale : float
        ``1 / sqrt(area)``: a map of ``V`` divided by ``scale`` is in the input's units.
    boundary : (b,) int64
        The boundary loop (surface on its left).
    n_input : int
        Rows of the input ``V``.
    """

    V: np.ndarray
    F: np.ndarray
    used: np.ndarray
    scale: float
    boundary: np.ndarray
    n_input: int


def prepare_chart(V: ArrayLike, F: ArrayLike, name: str = "chart") -> PreparedChart:
    """Check a disk chart and return it compacted and normalised to unit area.

    Parameters
    ----------
    V : (n, 3) array_like of float
        Vertices (rows not used by ``F`` are dropped).
    F : (m, 3) array_like of int
        Triangles of a topological disk.
    name : str
        Chart name for messages.

    Returns
    -------
    PreparedChart

    Raises
    ------
    MeshError
        Bad arrays, an empty or zero-area chart, or a chart that is not a disk.

    Examples
    --------
    >>> import numpy as np
    >>> V = np.array([[0.0, 0, 0], [2, 0, 0], [0, 2, 0], [9, 9, 9]])
    >>> c = prepare_chart(V, np.array([[0, 1, 2]]))
    >>> c.used.tolist(), round(c.scale, 12), c.n_input
    ([0, 1, 2], 0.707106781187, 4)
    """
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
    chi = len(used) - len(unique_edges(Fc)) + Fc.shape[0]
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
    return PreparedChart(Vn, Fc, used, float(scale), loops[0], n)


def expand_uv(UVc: np.ndarray, used: np.ndarray, n: int) -> np.ndarray:
    """Scatter a compact map back to ``n`` rows (``NaN`` for rows not in ``used``).

    Examples
    --------
    >>> import numpy as np
    >>> expand_uv(np.ones((1, 2)), np.array([1]), 2).tolist()
    [[nan, nan], [1.0, 1.0]]
    """
    UV = np.full((n, 2), np.nan)
    UV[used] = UVc
    return UV


def unique_edges(F: np.ndarray) -> np.ndarray:
    """(ne, 2) unique undirected edges, smaller id first (1D-key ``np.unique``: fast).

    Examples
    --------
    >>> import numpy as np
    >>> unique_edges(np.array([[0, 1, 2], [2, 1, 3]])).tolist()
    [[0, 1], [0, 2], [1, 2], [1, 3], [2, 3]]
    """
    E = np.sort(np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]]), axis=1)
    n = int(F.max()) + 1
    key = np.unique(E[:, 0] * n + E[:, 1])
    return np.stack([key // n, key % n], axis=1)


def certify_oriented(
    UV: np.ndarray, V: np.ndarray, F: np.ndarray, name: str = "chart", loops=None
) -> tuple[np.ndarray, Certificate]:
    """Certify a map; undo a mirror image (``u -> -u``) and return its certificate.

    The mirror's certificate is the same one with ``mirrored=False``: negating ``u`` negates
    every orientation determinant exactly (IEEE negation and products), so flips, degenerate
    triangles, boundary intersections and windings are unchanged (checked by
    ``tests/test_param.py``); it is not recomputed.

    Parameters
    ----------
    UV : (n, 2) float64
        Map.
    V : (n, 3) float64
        Chart vertices (unused; kept for a uniform signature).
    F : (m, 3) int64
        Triangles.
    name : str
        Chart name for messages.
    loops : list of (b,) int64, optional
        Boundary loops, when known (saves finding them again).

    Returns
    -------
    UV : (n, 2) float64
        Counter-clockwise map.
    cert : Certificate

    Examples
    --------
    >>> import numpy as np
    >>> UV0 = np.array([[0.0, 0], [0, 1], [1, 0]])  # clockwise
    >>> UV, cert = certify_oriented(UV0, None, np.array([[0, 1, 2]]))
    >>> UV[2].tolist(), cert.bijective, cert.mirrored
    ([-1.0, 0.0], True, False)
    """
    cert = certify_map(UV, F, name=name, loops=loops)
    if cert.mirrored:
        UV = UV * np.array([-1.0, 1.0])
        cert = dataclasses.replace(cert, mirrored=False, orientation=1)
    return UV, cert


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

    Examples
    --------
    >>> import numpy as np
    >>> V = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [-1, 0, 0], [0, -1, 0]])
    >>> F = np.array([[0, 1, 2], [0, 2, 3], [0, 3, 4], [0, 4, 1]])
    >>> total_abs_curvature(V, F)
    0.0
    >>> V[0, 2] = 1.0  # a pyramid's apex: angle defect 2 pi - 4 * 60 degrees
    >>> round(total_abs_curvature(V, F) / np.pi, 9)
    0.666666667
    """
    V, F = as_mesh_arrays(V, F, "total_abs_curvature")
    if bnd is None:
        loops = boundary_loops(F)
        bnd = np.concatenate(loops) if loops else np.zeros(0, dtype=np.int64)
    k = np.asarray(igl.gaussian_curvature(V, F), dtype=np.float64).ravel()
    inner = np.ones(V.shape[0], dtype=bool)
    inner[bnd] = False
    return float(np.abs(k[inner]).sum())
