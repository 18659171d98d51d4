"""Input checks shared by the surface fits, the kind selection, the samples and the tolerances.

Each returns its arrays validated and converted (``float64`` points, ``int64`` triangles and
face indices, weights normalised to sum 1) or raises :class:`~igl_heatseg.errors.MeshError`
naming the array and its shape.
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import MeshError

__all__ = ["check_inputs", "check_mesh", "check_faces", "weights_area"]


# ----------------------------------------------------------------------------- input checks


def _as_points(P, name: str = "P") -> np.ndarray:
    A = np.asarray(P, dtype=np.float64)
    if A.ndim != 2 or A.shape[1] != 3:
        raise MeshError(f"{name} must have shape (p, 3), got {A.shape}")
    if not np.all(np.isfinite(A)):
        raise MeshError(f"{name} (shape {A.shape}) has non-finite entries")
    return A


def check_inputs(P, N, w, need_normals: bool):
    """Validated ``P``, ``N`` (or None) and weights normalised to sum 1.

    Parameters
    ----------
    P : (p, 3) array_like of float
        Points.
    N : (p, 3) array_like of float or None
        Normals at the points.
    w : (p,) array_like of float or None
        Non-negative weights with a positive sum; uniform when None.
    need_normals : bool
        Whether ``N`` is required.

    Returns
    -------
    P : (p, 3) ndarray of float64
    N : (p, 3) ndarray of float64 or None
    w : (p,) ndarray of float64
        The weights divided by their sum (``1 / p`` each when ``w`` is None).

    Raises
    ------
    MeshError
        On arrays of the wrong shape, non-finite values, a missing required ``N`` or weights
        that are negative or without a positive sum.

    Examples
    --------
    >>> P, N, w = check_inputs([[0, 0, 0], [1, 0, 0]], None, [1, 3], need_normals=False)
    >>> P.dtype, N, w.tolist()
    (dtype('float64'), None, [0.25, 0.75])
    """
    P = _as_points(P)
    if N is None:
        if need_normals:
            raise MeshError(f"N is required for this fit (P has shape {P.shape})")
    else:
        N = _as_points(N, "N")
        if N.shape != P.shape:
            raise MeshError(f"N must have the shape of P {P.shape}, got {N.shape}")
    if w is None:
        w = np.full(len(P), 1.0 / max(len(P), 1))
    else:
        w = np.asarray(w, dtype=np.float64)
        if w.shape != (len(P),):
            raise MeshError(f"w must have shape ({len(P)},), got {w.shape}")
        if not np.all(np.isfinite(w)) or np.any(w < 0) or not w.sum() > 0:
            raise MeshError(f"w (shape {w.shape}) must be finite, >= 0, with a positive sum")
        w = w / w.sum()
    return P, N, w


def check_mesh(V, F):
    """Validated vertices and triangles.

    Parameters
    ----------
    V : (n, 3) array_like of float
        Vertices.
    F : (m, 3) array_like of int
        Triangles.

    Returns
    -------
    V : (n, 3) ndarray of float64
    F : (m, 3) ndarray of int64

    Raises
    ------
    MeshError
        On a wrong shape or dtype, non-finite vertices, no triangles or indices outside
        ``[0, n)``.
    """
    V = _as_points(V, "V")
    F = np.asarray(F)
    if F.ndim != 2 or F.shape[1] != 3 or not np.issubdtype(F.dtype, np.integer):
        raise MeshError(f"F must be an integer array of shape (m, 3), got {F.dtype} {F.shape}")
    if len(F) == 0 or F.min() < 0 or F.max() >= len(V):
        raise MeshError(f"F (shape {F.shape}) must be non-empty with indices in [0, {len(V)})")
    return V, F.astype(np.int64)


def check_faces(faces, m: int) -> np.ndarray:
    """Face indices from indices or a mask over a mesh's ``m`` faces.

    Parameters
    ----------
    faces : (k,) array_like of int, or (m,) array_like of bool
        Face indices, or a mask over all faces.
    m : int
        Number of faces of the mesh.

    Returns
    -------
    (k,) ndarray of int64
        The indices (those of the mask's True entries, ascending).

    Raises
    ------
    MeshError
        On a mask not of shape ``(m,)``, a non-integer or non-1-D array, or indices outside
        ``[0, m)``.

    Examples
    --------
    >>> import numpy as np
    >>> check_faces(np.array([False, True, True]), 3).tolist()
    [1, 2]
    """
    faces = np.asarray(faces)
    if faces.dtype == bool:
        if faces.shape != (m,):
            raise MeshError(f"faces as a mask must have shape ({m},), got {faces.shape}")
        return np.flatnonzero(faces)
    if faces.ndim != 1 or not np.issubdtype(faces.dtype, np.integer):
        raise MeshError(f"faces must be a 1-D integer array, got {faces.dtype} {faces.shape}")
    if len(faces) and (faces.min() < 0 or faces.max() >= m):
        raise MeshError(f"faces (shape {faces.shape}) must index [0, {m})")
    return faces.astype(np.int64)


def weights_area(w_raw) -> float:
    """Area a fit reports: the sum of the caller's weights (face areas), nan without weights.

    Parameters
    ----------
    w_raw : (p,) array_like of float or None
        The weights as given, before :func:`check_inputs` normalises them.

    Returns
    -------
    float

    Examples
    --------
    >>> weights_area([0.5, 1.5]), weights_area(None)
    (2.0, nan)
    """
    return math.nan if w_raw is None else float(np.sum(w_raw))
