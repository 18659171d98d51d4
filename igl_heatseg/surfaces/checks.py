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
    """Validated ``P``, ``N`` (or None) and weights normalised to sum 1."""
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
    V = _as_points(V, "V")
    F = np.asarray(F)
    if F.ndim != 2 or F.shape[1] != 3 or not np.issubdtype(F.dtype, np.integer):
        raise MeshError(f"F must be an integer array of shape (m, 3), got {F.dtype} {F.shape}")
    if len(F) == 0 or F.min() < 0 or F.max() >= len(V):
        raise MeshError(f"F (shape {F.shape}) must be non-empty with indices in [0, {len(V)})")
    return V, F.astype(np.int64)


def check_faces(faces, m: int) -> np.ndarray:
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
    return math.nan if w_raw is None else float(np.sum(w_raw))
