"""A segment's samples for fitting (:func:`face_samples`) and the per-face residuals of its surface
(:func:`face_residuals`).
"""

from __future__ import annotations

import igl
import numpy as np

from ..mesh.geometry import face_areas, face_normals
from .checks import check_faces, check_mesh
from .model import Surface

__all__ = [
    "segment_adjacency", "normal_positions",
    "vertex_samples","face_samples", "face_residuals"]


# ----------------------------------------------------------------------------- mesh helpers


def face_samples(V, F, faces):
    """Samples to fit one segment: its vertices and its face centroids, with normals and weights.

    Vertex normals are computed from the segment's faces only (a crease with the neighbouring
    segment does not bend them). Weights sum to the segment's area: half on the face centroids
    (each face's area / 2), half on the vertices (a third of the incident faces' areas / 2).

    Parameters
    ----------
    V : (n, 3) array_like of float64
        Vertices.
    F : (m, 3) array_like of int
        Triangles.
    faces : (k,) array_like of int, or (m,) bool
        The segment's faces.

    Returns
    -------
    P : (q + k, 3) float64
        The q distinct vertices of the faces, then the k face centroids.
    N : (q + k, 3) float64
        Unit normals (area-weighted vertex normals, face normals); zero rows with zero weight
        where undefined (degenerate faces).
    w : (q + k,) float64
        Non-negative weights.

    Examples
    --------
    >>> import numpy as np
    >>> V = np.array([[0., 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]])
    >>> P, N, w = face_samples(V, np.array([[0, 1, 2], [1, 3, 2]]), [0, 1])
    >>> P.shape, (N[-1] + 0.0).tolist(), float(w.sum())
    ((6, 3), [0.0, 0.0, 1.0], 1.0)
    """
    V, F = check_mesh(V, F)
    Fs = F[check_faces(faces, len(F))]
    if len(Fs) == 0:
        return np.zeros((0, 3)), np.zeros((0, 3)), np.zeros(0)
    verts, inv = np.unique(Fs, return_inverse=True)  # the segment as a small mesh
    Vl, Fl = V[verts], inv.reshape(-1, 3).astype(np.int64)
    dbl = igl.doublearea(Vl, Fl)
    FN = igl.per_face_normals(Vl, Fl, np.zeros(3))
    VN = igl.per_vertex_normals(Vl, Fl, igl.PER_VERTEX_NORMALS_WEIGHTING_TYPE_AREA)
    wv = np.bincount(Fl.ravel(), weights=np.repeat(dbl / 12.0, 3), minlength=len(verts))
    P = np.r_[Vl, Vl[Fl].mean(axis=1)]
    N = np.r_[VN, FN]
    w = np.r_[wv, dbl / 4.0]
    bad = ~np.all(np.isfinite(N), axis=1) | (np.abs(np.linalg.norm(N, axis=1) - 1) > 1e-6)
    N[bad], w[bad] = 0.0, 0.0
    return P, N, w


def face_residuals(V, F, faces, surface: Surface) -> np.ndarray:
    """Largest absolute distance of each face's corners and centroid to a surface.

    Parameters
    ----------
    V : (n, 3) array_like of float64
        Vertices.
    F : (m, 3) array_like of int
        Triangles.
    faces : (k,) array_like of int, or (m,) bool
        Faces to evaluate.
    surface : Surface
        The segment's surface.

    Returns
    -------
    r : (k,) float64
        Per-face residual in model units (``nan`` for ``freeform``). Compare with
        ``MAX_DEV_FACTOR * tol``; the centroid sees the chord error of coarse facets.

    Examples
    --------
    >>> import numpy as np
    >>> V = np.array([[0., 0, 0], [1, 0, 0], [0, 1, 0.3]])
    >>> s = Surface("plane", {"point": np.zeros(3), "normal": np.array([0., 0, 1])})
    >>> face_residuals(V, np.array([[0, 1, 2]]), [0], s)
    array([0.3])
    """
    V, F = check_mesh(V, F)
    Fs = F[check_faces(faces, len(F))]
    corners = V[Fs]  # (k, 3, 3)
    pts = np.concatenate([corners, corners.mean(axis=1, keepdims=True)], axis=1)
    d = surface.distance(pts.reshape(-1, 3)).reshape(len(Fs), 4)
    return np.max(np.abs(d), axis=1)


def segment_adjacency(F: np.ndarray, labels: np.ndarray,
                      TT: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Faces on both sides of every interior edge whose two labels differ (each edge once).

    Parameters
    ----------
    F : (m, 3) int64
    labels : (m,) int64
    TT : (m, 3) int64, optional
        ``igl.triangle_triangle_adjacency(F)[0]`` when the caller has it (computed otherwise).

    Returns
    -------
    fa, fb : (e,) int64
        ``fa < fb``.

    Examples
    --------
    >>> import numpy as np
    >>> F = np.array([[0, 1, 2], [2, 1, 3]])
    >>> fa, fb = segment_adjacency(F, np.array([0, 1]))
    >>> fa.tolist(), fb.tolist()
    ([0], [1])
    """
    if TT is None:
        TT = igl.triangle_triangle_adjacency(np.ascontiguousarray(F, dtype=np.int64))[0]
    fa = np.repeat(np.arange(len(F)), 3)
    fb = TT.ravel()
    keep = (fb > fa) & (labels[np.maximum(fb, 0)] != labels[fa])
    return fa[keep], fb[keep]


def normal_positions(V: np.ndarray, normals_from) -> np.ndarray | None:
    """The positions face normals come from, as the fits take them (``W``): ``normals_from``
    as a float64 array, or None when it is absent or equal to ``V`` (robust mode passes an
    undenoised copy for a clean mesh; with None the fits do not compute its normals twice, as
    :func:`~igl_heatseg.surfaces.segment_fit.normals_agree`'s ``raw`` fallback would).

    Parameters
    ----------
    V : (n, 3) float64
    normals_from : (n, 3) array_like of float, or None

    Returns
    -------
    (n, 3) float64 or None

    Examples
    --------
    >>> import numpy as np
    >>> V = np.zeros((3, 3))
    >>> normal_positions(V, V.copy()) is None, normal_positions(V, V + 1).shape
    (True, (3, 3))
    """
    if normals_from is None:
        return None
    W = np.ascontiguousarray(normals_from, dtype=np.float64)
    return None if W.shape == V.shape and np.array_equal(W, V) else W


def vertex_samples(V: np.ndarray, F: np.ndarray, faces: np.ndarray, W: np.ndarray | None = None):
    """Samples to fit a face set: its vertices, with normals from those faces only.

    Parameters
    ----------
    V : (n, 3) float64
    F : (m, 3) int64
    faces : (k,) int64
        Face ids.
    W : (n, 3) float64, optional
        Positions the normals are computed from (e.g. a denoised copy of ``V``); default ``V``.

    Returns
    -------
    P : (p, 3) float64
        The faces' vertices.
    N : (p, 3) float64
        Area-weighted vertex normals of the face set (a crease with a neighbour does not bend
        them).
    w : (p,) float64
        A third of the incident faces' areas (sums to the set's area).

    Examples
    --------
    >>> import numpy as np
    >>> V = np.array([[0., 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]])
    >>> P, N, w = vertex_samples(V, np.array([[0, 1, 2], [1, 3, 2]]), np.array([0, 1]))
    >>> P.shape, round(float(w.sum()), 12), N[0].tolist()
    ((4, 3), 1.0, [0.0, 0.0, 1.0])
    """
    Fs = F[faces]
    verts, inv = np.unique(Fs, return_inverse=True)
    inv = inv.reshape(-1, 3)
    A = face_areas(V, Fs)
    FN = face_normals(V if W is None else W, Fs)
    AN = np.repeat(FN * A[:, None], 3, axis=0)  # one row per corner
    # (bincount of no faces is int64: float64 so that an empty set gives empty float arrays)
    N = np.stack([np.bincount(inv.ravel(), weights=AN[:, c], minlength=len(verts))
                  for c in range(3)], axis=1).astype(np.float64)
    N /= np.maximum(np.linalg.norm(N, axis=1, keepdims=True), 1e-300)
    w = np.bincount(inv.ravel(), weights=np.repeat(A / 3.0, 3), minlength=len(verts))
    return V[verts], N, w.astype(np.float64)
