"""Mesh geometry primitives, the package's one home for them, on libigl's own routines.

Face areas (``igl.doublearea``) and unit face normals (``igl.per_face_normals``, right-hand
rule on ``F``'s corner order: counter-clockwise corners seen from the side the normal points
to). Every stage computes areas and normals through here.
"""

from __future__ import annotations

import igl
import numpy as np

__all__ = ["face_areas", "face_normals", "uv_areas"]

#: Normal given to a degenerate (zero-area) face: none (validated meshes have no such face,
#: and a zero vector keeps a degenerate face from voting in any normal average).
_ZERO = np.zeros(3)


def face_areas(V: np.ndarray, F: np.ndarray) -> np.ndarray:
    """Triangle areas.

    Parameters
    ----------
    V : (n, 3) float64
    F : (m, 3) int64

    Returns
    -------
    A : (m,) float64
        Areas (non-negative).

    Examples
    --------
    >>> import numpy as np
    >>> face_areas(np.array([[0., 0, 0], [2, 0, 0], [0, 1, 0]]), np.array([[0, 1, 2]]))
    array([1.])
    """
    V = np.ascontiguousarray(V, dtype=np.float64)
    F = np.ascontiguousarray(F, dtype=np.int64)
    if len(F) == 0:
        return np.zeros(0)
    return 0.5 * igl.doublearea(V, F).ravel()


def face_normals(V: np.ndarray, F: np.ndarray) -> np.ndarray:
    """Unit face normals (right-hand rule on ``F``'s corner order).

    Parameters
    ----------
    V : (n, 3) float64
    F : (m, 3) int64

    Returns
    -------
    N : (m, 3) float64
        Unit normals; ``(0, 0, 0)`` for a degenerate face.

    Examples
    --------
    >>> import numpy as np
    >>> face_normals(np.array([[0., 0, 0], [1, 0, 0], [0, 1, 0]]), np.array([[0, 1, 2]]))
    array([[0., 0., 1.]])
    """
    V = np.ascontiguousarray(V, dtype=np.float64)
    F = np.ascontiguousarray(F, dtype=np.int64)
    if len(F) == 0:
        return np.zeros((0, 3))
    return igl.per_face_normals(V, F, _ZERO)


def uv_areas(UV: np.ndarray, F: np.ndarray) -> np.ndarray:
    """Signed areas of triangles in the plane (positive for counter-clockwise corners).

    Parameters
    ----------
    UV : (n, 2) float64
    F : (m, 3) int64

    Returns
    -------
    A : (m,) float64

    Examples
    --------
    >>> import numpy as np
    >>> uv_areas(np.array([[0., 0], [1, 0], [0, 1]]), np.array([[0, 1, 2], [0, 2, 1]]))
    array([ 0.5, -0.5])
    """
    a = UV[F[:, 1]] - UV[F[:, 0]]
    b = UV[F[:, 2]] - UV[F[:, 0]]
    return 0.5 * (a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0])
