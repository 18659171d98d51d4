"""Camera maths: a three-quarter view that frames a part, and a top-down view of the plane.

numpy only (face areas and normals from :mod:`igl_heatseg.mesh.geometry`, on libigl), no
polyscope: :func:`igl_heatseg.viz.render.set_camera` hands the result to polyscope.

Examples
--------
>>> import numpy as np
>>> P = np.array([[0.0, 0, 0], [2, 0, 0], [0, 1, 0], [0, 0, 0.5], [2, 1, 0.5]])
>>> eye, target, up = three_quarter_camera(P, aspect=4 / 3)
>>> bool(abs(up @ (target - eye)) < 1e-9)
True
>>> eye, target, up = top_down_camera(P[:, :2], aspect=4 / 3)
>>> eye[:2].tolist() == target[:2].tolist() == [1.0, 0.5], up.tolist()
(True, [0.0, 1.0, 0.0])
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike

from ..mesh.geometry import face_areas, face_normals

__all__ = [
    "DEFAULT_SIZE",
    "VIEW_DIRECTION",
    "CAMERA_MARGIN",
    "best_view_direction",
    "three_quarter_camera",
    "top_down_camera",
]

#: Default picture size in pixels (width, height).
DEFAULT_SIZE: tuple[int, int] = (1200, 900)

#: The view direction in the mesh's principal frame (largest, middle, smallest axis) for a
#: three-quarter view.
VIEW_DIRECTION: tuple[float, float, float] = (0.45, 0.50, 0.74)

#: The margin around the part, as a fraction of the frame.
CAMERA_MARGIN: float = 1.10

#: polyscope's default vertical field of view, degrees.
DEFAULT_FOV: float = 45.0

#: Largest number of vertices used to fit the camera (a random-free, strided subsample).
CAMERA_SAMPLES: int = 20000


def _principal_frame(P: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Bounding-box centre (3,) and principal axes (3, 3) (rows: largest spread first)."""
    c = 0.5 * (P.min(axis=0) + P.max(axis=0))
    Q = P - c
    axes = np.eye(3)
    if len(P) >= 3 and np.ptp(Q, axis=0).max() > 0:
        _, _, Vt = np.linalg.svd(Q - Q.mean(axis=0), full_matrices=False)
        if Vt.shape[0] == 3:
            axes = Vt
    # Deterministic signs: the largest component of each axis positive; right-handed frame.
    axes = axes * np.sign(axes[np.arange(3), np.abs(axes).argmax(axis=1)])[:, None]
    if np.linalg.det(axes) < 0:
        axes[2] *= -1
    return c, axes


def best_view_direction(
    V: ArrayLike,
    F: ArrayLike,
    labels: ArrayLike | None = None,
    direction: Sequence[float] = VIEW_DIRECTION,
) -> np.ndarray:
    """Choose among the 8 mirror images of a three-quarter direction the one showing most.

    A candidate ``d`` (``direction`` in the principal frame, with every sign combination)
    scores the effective number of visible labels ``exp(H)``, where ``H`` is the entropy of
    the labels' projected visible areas ``sum area_f * max(0, n_f . d)``; without labels, the
    projected visible area.  Ties keep the first candidate (all signs positive).

    Parameters
    ----------
    V : (n, 3) array_like of float
    F : (m, 3) array_like of int
        Outward-oriented triangles (for a closed part, front faces point to the camera).
    labels : (m,) array_like of int, optional
        Face labels (e.g. the final segmentation).
    direction : (3,) float
        In the principal frame (largest, middle, smallest spread).

    Returns
    -------
    d : (3,) float64
        Unit vector from the part towards the camera, in world coordinates.
    """
    V = np.asarray(V, dtype=np.float64)
    _, axes = _principal_frame(V)
    N = face_areas(V, F)[:, None] * face_normals(V, F)
    lab = None if labels is None else np.asarray(labels, dtype=np.int64)
    best, best_d = -np.inf, None
    for sx in (1, -1):
        for sy in (1, -1):
            for sz in (1, -1):
                d = (np.asarray(direction, dtype=np.float64) * [sx, sy, sz]) @ axes
                d /= np.linalg.norm(d)
                w = np.maximum(N @ d, 0.0)
                if lab is None:
                    score = float(w.sum())
                else:
                    a = np.bincount(lab, weights=w)
                    p = a[a > 0] / a.sum() if a.sum() > 0 else np.ones(1)
                    score = float(np.exp(-(p * np.log(p)).sum()))
                if score > best * (1 + 1e-9) + 1e-12:
                    best, best_d = score, d
    return best_d


def _centre_offset(x: np.ndarray, depth_of, lo: float, hi: float) -> float:
    """Lateral camera offset ``c`` with ``max((x - c)/depth) = -min((x - c)/depth)`` (bisection)."""
    for _ in range(60):
        c = 0.5 * (lo + hi)
        r = (x - c) / depth_of
        if r.max() + r.min() > 0:
            lo = c
        else:
            hi = c
    return 0.5 * (lo + hi)


def _fit_frustum(x, y, z, tx, ty, margin, iterations: int = 4):
    """Camera distance along +z and lateral offsets so that every point is in view, centred.

    ``x, y, z``: point coordinates in the camera frame (z towards the camera); ``tx, ty``: the
    tangents of the half fields of view.  Returns ``(dist, cx, cy)``.
    """
    cx, cy = 0.5 * (x.max() + x.min()), 0.5 * (y.max() + y.min())
    dist = 0.0
    for _ in range(iterations):
        dist = float(np.max(np.maximum(z + np.abs(x - cx) / tx, z + np.abs(y - cy) / ty)))
        dist *= margin
        depth = dist - z
        cx = _centre_offset(x, depth, float(x.min()), float(x.max()))
        cy = _centre_offset(y, depth, float(y.min()), float(y.max()))
    # final distance for the final offsets
    dist = margin * float(np.max(np.maximum(z + np.abs(x - cx) / tx, z + np.abs(y - cy) / ty)))
    return dist, cx, cy


def three_quarter_camera(
    P: ArrayLike,
    aspect: float = DEFAULT_SIZE[0] / DEFAULT_SIZE[1],
    fov_deg: float = DEFAULT_FOV,
    direction: Sequence[float] | None = None,
    margin: float = CAMERA_MARGIN,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A perspective camera that sees all of ``P`` from a three-quarter angle.

    The view direction defaults to :data:`VIEW_DIRECTION` expressed in the principal frame of
    the points (largest, middle, smallest spread), so a flat part is not seen edge-on; the up
    vector is the middle principal axis made orthogonal to the view (pointing so that the
    camera looks down on the part).  The distance is the smallest at which every point lies
    inside the frustum (times ``margin``), and the target is shifted so that the part's image
    is centred.

    Parameters
    ----------
    P : (n, 3) array_like of float
    aspect : float
        Image width / height.
    fov_deg : float
        Vertical field of view (polyscope's default is 45 degrees).
    direction : (3,) float, optional
        Unit vector from the part towards the camera, in *world* coordinates (e.g. from
        :func:`best_view_direction`).
    margin : float
        > 1 leaves a border.

    Returns
    -------
    eye : (3,) float64
        Camera position.
    target : (3,) float64
        Point looked at.
    up : (3,) float64
        Unit up vector.
    """
    P = np.asarray(P, dtype=np.float64)
    if len(P) > CAMERA_SAMPLES:
        P = P[:: int(math.ceil(len(P) / CAMERA_SAMPLES))]
    c, axes = _principal_frame(P)
    Q = P - c
    if direction is None:
        d = np.asarray(VIEW_DIRECTION, dtype=np.float64) @ axes
    else:
        d = np.asarray(direction, dtype=np.float64)
    d = d / np.linalg.norm(d)
    # Up: a world axis (parts are usually modelled axis-aligned), made orthogonal to the view
    # and pointing so that the camera looks down on the part; of the two axes least aligned
    # with the view, the one that lets the part fill the frame best (smallest distance).
    ty = math.tan(math.radians(fov_deg) / 2)
    tx = ty * aspect
    best = None
    for w in np.argsort(np.abs(d))[:2]:
        up = np.eye(3)[w] - d[w] * d
        up /= np.linalg.norm(up)
        if d[w] < 0:
            up = -up
        right = np.cross(up, d)  # the camera's right axis (not an area: one vector)
        x, y, z = Q @ right, Q @ up, Q @ d
        dist, cx, cy = _fit_frustum(x, y, z, tx, ty, margin)
        dist = max(dist, 1e-12 + float(np.abs(Q).max()))
        if best is None or dist < best[0] * (1 - 1e-6):
            best = (dist, up, cx * right + cy * up)
    dist, up, shift = best
    target = c + shift
    return target + dist * d, target, up


def top_down_camera(
    P: ArrayLike,
    aspect: float = DEFAULT_SIZE[0] / DEFAULT_SIZE[1],
    fov_deg: float = DEFAULT_FOV,
    margin: float = CAMERA_MARGIN,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A camera looking straight down the z axis at points of the plane z = 0 (chart layout).

    Parameters
    ----------
    P : (n, 2) or (n, 3) array_like of float
        Only x and y are used.
    aspect, fov_deg, margin
        As :func:`three_quarter_camera`.

    Returns
    -------
    eye, target, up : (3,) float64
        ``up`` is +y.
    """
    P = np.asarray(P, dtype=np.float64)
    c = 0.5 * (P.min(axis=0) + P.max(axis=0))
    ext = P.max(axis=0) - P.min(axis=0)
    t = math.tan(math.radians(fov_deg) / 2)
    dist = margin * max(ext[1] / 2 / t, ext[0] / 2 / (t * aspect), 1e-9)
    target = np.array([c[0], c[1], 0.0])
    return target + [0.0, 0.0, dist], target, np.array([0.0, 1.0, 0.0])
