"""Freeform segments: a UV chart and a least-squares B-spline surface over it.

The chart (given, or LSCM / harmonic onto the unit disk when the segment is a disk) is sampled on a
regular (u, v) grid: grid points inside the chart take the barycentric interpolation of the
3D vertex positions of the chart triangle holding them, the others a thin-plate extension over
the grid (smooth, continuing the slopes at the chart border).  The grid is approximated by
``GeomAPI_PointsToBSplineSurface`` with iso-parametric parameters, so grid (u, v) maps
linearly to the surface parameters and the fit error is measured at every mesh vertex.
"""

from __future__ import annotations

import logging

import igl
import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from scipy.spatial import cKDTree

from ._ocp import require_ocp

require_ocp()

from OCP.Approx import Approx_ParametrizationType  # noqa: E402
from OCP.collections import Array2_gp_Pnt  # noqa: E402
from OCP.GeomAbs import GeomAbs_Shape  # noqa: E402
from OCP.GeomAPI import GeomAPI_PointsToBSplineSurface  # noqa: E402
from OCP.gp import gp_Pnt  # noqa: E402

from .geometry import DEG_MIN, any_perp  # noqa: E402

logger = logging.getLogger(__name__)

__all__ = ["disk_chart", "projection_chart", "segment_chart", "orient_chart", "freeform_surface"]

#: Highest degree of a freeform patch: cubic; higher degrees let the approximation meet its
#: tolerance at the grid points while oscillating between them (measured: errors of 3 units
#: at mesh vertices of a unit patch with degree up to 8).
SURF_DEG_MAX = 3

#: Fraction of the modelling tolerance a freeform patch aims at (the best grid is kept if no
#: grid meets it; the face is built when that one is within the tolerance): a patch at the
#: full tolerance trimmed a noisy 24 x 7 strip to three quarters of its area.
FREEFORM_TARGET = 0.2

#: Fewest samples along the shorter side of a chart's box.
GRID_MIN = 6

#: Sample counts along the longer side of a chart's box, tried in turn.
FREEFORM_GRIDS = (12, 20, 32, 48, 64)

#: Margin added around a chart's UV box (fraction of its size) so that trimming curves lie
#: strictly inside the patch.
UV_MARGIN = 0.03

#: Nearest triangle centroids searched when locating a grid point in the chart.
LOCATE_K = 12

#: Barycentric slack for "inside a chart triangle" (round-off on shared edges).
BARY_EPS = 1e-9


def disk_chart(V: np.ndarray, F: np.ndarray):
    """A bijective chart of a disk-like mesh (LSCM, else harmonic onto the unit disk).

    Parameters
    ----------
    V : (p, 3) float64
    F : (q, 3) int64
        A face-connected segment, compact vertex indices.

    Returns
    -------
    UV : (p, 2) float64 or None
        Counter-clockwise (positive triangle areas) when the mesh normals are seen from above.
    """
    nv = len(np.unique(F))
    edges, uses = np.unique(np.sort(np.r_[F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]], axis=1),
                            axis=0, return_counts=True)
    if nv - len(edges) + len(F) != 1 or nv != len(V):
        return None
    bnd = igl.boundary_loop(F)
    if len(bnd) < 3 or len(bnd) != np.count_nonzero(uses == 1):
        return None  # more than one boundary loop: two fans on one vertex, say
    far = bnd[int(np.argmax(np.linalg.norm(V[bnd] - V[bnd[0]], axis=1)))]
    scale = float(np.linalg.norm(V[far] - V[bnd[0]]))
    try:
        UV, _ = igl.lscm(V, F, np.array([bnd[0], far]), np.array([[0.0, 0.0], [scale, 0.0]]))
        UV = orient_chart(_align(UV), F)
    except RuntimeError:  # libigl's solve failed (e.g. a fan of a few triangles)
        UV = None
    if UV is None:  # LSCM folded or failed: a Tutte-like map onto the disk is bijective
        try:
            circle = igl.map_vertices_to_circle(V, bnd)
            UV = orient_chart(igl.harmonic(V, F, bnd, circle, 1), F)
        except RuntimeError:
            return None
    return UV


def projection_chart(V: np.ndarray, F: np.ndarray):
    """A chart of a segment that is a height field over a plane: its orthogonal projection.

    For segments :func:`disk_chart` cannot map (an annulus, a face with holes): a fillet ring
    around a hole, a nearly flat face with bosses cut out. The projection planes tried are
    normal to the segment's area-weighted mean face normal, then to its vertices' direction of
    least spread; the first whose projection is certified bijective
    (:func:`~igl_heatseg.parameterization.bijectivity.certify_map`: no flipped or degenerate
    triangle, no boundary overlap) is returned, rotated to its minimum-area rectangle.

    Parameters
    ----------
    V : (p, 3) float64
    F : (q, 3) int64
        The segment, compact vertex indices.

    Returns
    -------
    UV : (p, 2) float64 or None
        Counter-clockwise as in :func:`orient_chart`; None when no projection is one-to-one.

    Examples
    --------
    >>> import numpy as np
    >>> t = np.linspace(0, 2 * np.pi, 13)[:-1]
    >>> ring = np.r_[np.c_[np.cos(t), np.sin(t)], 2 * np.c_[np.cos(t), np.sin(t)]]
    >>> V = np.c_[ring, 0.1 * (ring ** 2).sum(axis=1)]          # a bowl with a hole
    >>> i = np.arange(12); j = (i + 1) % 12
    >>> F = np.r_[np.c_[i, j, j + 12], np.c_[i, j + 12, i + 12]]
    >>> disk_chart(V, F) is None, projection_chart(V, F).shape
    (True, (24, 2))
    """
    from ..parameterization.bijectivity import certify_map

    FN = np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]])  # area-weighted
    normals = [FN.sum(axis=0)]
    if len(V) >= 3:
        normals.append(np.linalg.svd(V - V.mean(axis=0), full_matrices=False)[2][-1])
    for n in normals:
        length = float(np.linalg.norm(n))
        if not length > 0:
            continue
        UV = orient_chart(_in_plane(V, V.mean(axis=0), n / length), F)
        if UV is not None and certify_map(UV, F).bijective:
            return orient_chart(_align(UV), F)
    return None


def segment_chart(s, V: np.ndarray, F: np.ndarray):
    """A chart of a segment whose analytic surface deviates from it, for a B-spline fit.

    Parameters
    ----------
    s : Surface
        The segment's fitted surface.
    V : (p, 3) float64
    F : (q, 3) int64
        The segment, compact vertex indices.

    Returns
    -------
    UV : (p, 2) float64 or None
        For a plane, the points in the plane's frame (a chart with any number of holes);
        otherwise :func:`disk_chart`, else (no disk) :func:`projection_chart`.
        Counter-clockwise as in :func:`orient_chart`; None when no chart is one-to-one.

    Examples
    --------
    >>> import numpy as np
    >>> from igl_heatseg.surfaces.model import Surface
    >>> s = Surface("plane", {"point": np.zeros(3), "normal": np.array([0.0, 0.0, 1.0])})
    >>> V = np.array([[0.0, 0.0, 0.1], [1.0, 0.0, -0.1], [0.0, 1.0, 0.0]])
    >>> UV = segment_chart(s, V, np.array([[0, 1, 2]]))
    >>> bool(_signed_areas(UV, np.array([[0, 1, 2]]))[0] > 0), np.ptp(UV, axis=0).tolist()
    (True, [1.0, 1.0])
    """
    if s.kind != "plane":
        UV = disk_chart(V, F)
        return projection_chart(V, F) if UV is None else UV
    return orient_chart(_in_plane(V, s.params["point"], s.params["normal"]), F)


def _in_plane(V: np.ndarray, point: np.ndarray, n: np.ndarray) -> np.ndarray:
    """Coordinates ``(p, 2)`` of the points in a frame of the plane through ``point`` with
    unit normal ``n`` (orthogonal projection)."""
    e1 = any_perp(n)
    Q = V - point
    return np.c_[Q @ e1, Q @ np.cross(n, e1)]


def _align(UV: np.ndarray) -> np.ndarray:
    """Rotate a chart to its minimum-area bounding rectangle (less extension outside it)."""
    from scipy.spatial import ConvexHull

    H = UV[ConvexHull(UV).vertices]
    E = np.roll(H, -1, axis=0) - H
    best, best_area = UV, np.inf
    for ang in np.arctan2(E[:, 1], E[:, 0]):
        c, s = np.cos(-ang), np.sin(-ang)
        R = UV @ np.array([[c, s], [-s, c]])
        area = np.prod(R.max(axis=0) - R.min(axis=0))
        if area < best_area:
            best, best_area = R, area
    return best


def orient_chart(UV: np.ndarray, F: np.ndarray):
    """A chart with positive triangle areas, so that ``Su x Sv`` follows the mesh normals.

    Parameters
    ----------
    UV : (p, 2) float64
    F : (q, 3) int64
        The segment's triangles in compact vertex indices.

    Returns
    -------
    (p, 2) float64 or None
        ``UV``, mirrored in u when every triangle is clockwise; None when the chart folds.

    Examples
    --------
    >>> import numpy as np
    >>> orient_chart(np.array([[0.0, 0.0], [0.0, 1.0], [1.0, 0.0]]), np.array([[0, 1, 2]]))
    array([[-0.,  0.],
           [-0.,  1.],
           [-1.,  0.]])
    """
    area = _signed_areas(UV, F)
    if np.all(area < 0):
        UV = UV * np.array([-1.0, 1.0])
        area = -area
    return UV if np.all(area > 0) else None


def _signed_areas(UV, F):
    a, b, c = UV[F[:, 0]], UV[F[:, 1]], UV[F[:, 2]]
    e1, e2 = b - a, c - a
    return 0.5 * (e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0])


def _locate(UV, F, Q):
    """Chart triangle and barycentric coordinates of query points (tri = -1 when outside)."""
    cent = UV[F].mean(axis=1)
    k = min(LOCATE_K, len(F))
    _, cand = cKDTree(cent).query(Q, k=k)
    cand = cand.reshape(len(Q), k)
    a, b, c = UV[F[cand, 0]], UV[F[cand, 1]], UV[F[cand, 2]]
    v0, v1, v2 = b - a, c - a, Q[:, None, :] - a
    den = v0[..., 0] * v1[..., 1] - v0[..., 1] * v1[..., 0]
    den = np.where(np.abs(den) > 0, den, 1e-300)
    l1 = (v2[..., 0] * v1[..., 1] - v2[..., 1] * v1[..., 0]) / den
    l2 = (v0[..., 0] * v2[..., 1] - v0[..., 1] * v2[..., 0]) / den
    bary = np.stack([1 - l1 - l2, l1, l2], axis=-1)
    best = np.argmax(bary.min(axis=-1), axis=1)
    rows = np.arange(len(Q))
    tri = cand[rows, best]
    w = bary[rows, best]
    tri = np.where(w.min(axis=1) >= -BARY_EPS, tri, -1)
    return tri, w


def _differences(g: int):
    d1 = sp.diags([-np.ones(g - 1), np.ones(g - 1)], [0, 1], shape=(g - 1, g))
    d2 = sp.diags([np.ones(g - 2), -2 * np.ones(g - 2), np.ones(g - 2)], [0, 1, 2],
                  shape=(g - 2, g))
    return d1, d2


def _thin_plate(gu: int, gv: int) -> sp.csr_matrix:
    """Thin-plate energy matrix of a gu x gv grid (second differences; linear functions are
    in its null space, so the extension continues the chart's slopes instead of flattening)."""
    (d1u, d2u), (d1v, d2v) = _differences(gu), _differences(gv)
    duu = sp.kron(d2u, sp.identity(gv))
    dvv = sp.kron(sp.identity(gu), d2v)
    duv = sp.kron(d1u, d1v)
    return (duu.T @ duu + dvv.T @ dvv + 2 * duv.T @ duv).tocsr()


def _grid_points(V, F, UV, shape, box):
    """3D samples on a (gu, gv) grid over the UV box (inside: interpolated; outside:
    thin-plate extension)."""
    gu, gv = shape
    u = np.linspace(box[0], box[1], gu)
    v = np.linspace(box[2], box[3], gv)
    Q = np.stack(np.meshgrid(u, v, indexing="ij"), axis=-1).reshape(-1, 2)
    tri, w = _locate(UV, F, Q)
    inside = tri >= 0
    X = np.zeros((len(Q), 3))
    X[inside] = np.einsum("pk,pkd->pd", w[inside], V[F[tri[inside]]])
    if not inside.all():
        Qm = _thin_plate(gu, gv)
        out = np.flatnonzero(~inside)
        kn = np.flatnonzero(inside)
        A = Qm[out][:, out].tocsc()
        X[out] = spla.spsolve(A, -(Qm[out][:, kn] @ X[kn])).reshape(len(out), 3)
    return X.reshape(gu, gv, 3)


def _approximate(grid: np.ndarray, tol: float):
    gu, gv = grid.shape[:2]
    arr = Array2_gp_Pnt(1, gu, 1, gv)
    for i in range(gu):
        for j in range(gv):
            x = grid[i, j]
            arr.SetValue(i + 1, j + 1, gp_Pnt(float(x[0]), float(x[1]), float(x[2])))
    fit = GeomAPI_PointsToBSplineSurface(arr, Approx_ParametrizationType.Approx_IsoParametric,
                                         DEG_MIN, SURF_DEG_MAX, GeomAbs_Shape.GeomAbs_C2,
                                         float(tol))
    if not fit.IsDone():
        return None
    return fit.Surface()


def _vertex_error(surf, V, UV, box):
    u0, u1, v0, v1 = surf.Bounds()
    su = u0 + (UV[:, 0] - box[0]) / (box[1] - box[0]) * (u1 - u0)
    sv = v0 + (UV[:, 1] - box[2]) / (box[3] - box[2]) * (v1 - v0)
    err = 0.0
    for p, a, b in zip(V, su, sv, strict=True):
        q = surf.Value(float(a), float(b))
        err = max(err, float(np.linalg.norm(p - (q.X(), q.Y(), q.Z()))))
    return err


def freeform_surface(V: np.ndarray, F: np.ndarray, UV: np.ndarray, tol: float):
    """Least-squares B-spline surface over a segment's chart.

    Parameters
    ----------
    V : (p, 3) float64
    F : (q, 3) int64
        The segment, compact vertex indices.
    UV : (p, 2) float64
        A bijective chart with positive triangle areas.
    tol : float
        Largest accepted distance between a mesh vertex and its image ``S(UV)``.

    Returns
    -------
    surface : Geom_BSplineSurface or None
        The first grid of :data:`FREEFORM_GRIDS` within ``FREEFORM_TARGET * tol`` (else the
        one with the smallest error).
    err : float
        Largest ``|S(UV_i) - V_i|`` over the segment's vertices.
    """
    lo, hi = UV.min(axis=0), UV.max(axis=0)
    pad = UV_MARGIN * (hi - lo).max()
    box = (lo[0] - pad, hi[0] + pad, lo[1] - pad, hi[1] + pad)
    aspect = (box[3] - box[2]) / (box[1] - box[0])
    target = FREEFORM_TARGET * tol
    best, best_err = None, np.inf
    for g in FREEFORM_GRIDS:  # samples along the longer side; the other side in proportion
        shape = (g, max(GRID_MIN, round(g * aspect))) if aspect <= 1 else \
            (max(GRID_MIN, round(g / aspect)), g)
        surf = _approximate(_grid_points(V, F, UV, shape, box), 0.5 * target)
        if surf is None:
            continue
        err = _vertex_error(surf, V, UV, box)
        logger.debug("freeform grid %s: error %.3g (target %.3g)", shape, err, target)
        if err < best_err:
            best, best_err = surf, err
        if err <= target:
            break
    return best, best_err
