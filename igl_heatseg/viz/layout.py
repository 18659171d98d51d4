"""Chart geometry for the pictures: which charts to draw, area-normalised UVs, the 2D layout.

Charts are :class:`igl_heatseg.pipeline.Chart` objects: ``faces`` (faces of the whole mesh),
``segment``, the cut chart ``cut.F`` / ``cut.vertex_map`` / ``cut.cut_edges`` and its map
``param.UV`` (with ``param.certificate``).  numpy only (areas from
:mod:`igl_heatseg.mesh.geometry`), no polyscope.

Examples
--------
>>> import igl
>>> from igl_heatseg import validate_mesh
>>> from igl_heatseg.pipeline import run_pipeline
>>> V, F = igl.loop(*igl.icosahedron(), 2)
>>> charts = drawable_charts(run_pipeline(validate_mesh(V, F)).charts)
>>> uv = corner_uv(V, F, charts).reshape(-1, 3, 2)
>>> uv.shape == (len(F), 3, 2)
True
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike

from ..mesh.geometry import face_areas, uv_areas

if TYPE_CHECKING:
    from ..pipeline import Chart

__all__ = [
    "CHART_GAP",
    "drawable_charts",
    "flipped_faces",
    "corner_uv",
    "chart_layout",
    "scene_points",
]

#: Gap between charts laid out side by side (fraction of the largest chart's size).
CHART_GAP: float = 0.15


def drawable_charts(charts: Iterable[Chart] | None) -> list[Chart]:
    """The charts that have a map to draw (cut and parameterized), in their order.

    Parameters
    ----------
    charts : iterable of igl_heatseg.pipeline.Chart, or None

    Returns
    -------
    list of Chart
        Those with ``cut`` and ``param`` set (a chart that is not a disk under
        ``cut="none"`` has neither and is skipped).

    Examples
    --------
    >>> from igl_heatseg.pipeline import Chart
    >>> drawable_charts([Chart(id=0, segment=0, faces=np.arange(3))])
    []
    """
    return [c for c in (charts or ()) if c.cut is not None and c.param is not None]


def flipped_faces(c: Chart) -> np.ndarray:
    """Rows of ``c.cut.F`` whose image is flipped (from the map's certificate), (f,) int64."""
    cert = c.param.certificate
    if cert is None:
        return np.zeros(0, dtype=np.int64)
    return np.asarray(cert.flipped_faces, dtype=np.int64)


def _uv(c: Chart) -> np.ndarray:
    return np.asarray(c.param.UV, dtype=np.float64)[:, :2]


def _normalised_uv(V: np.ndarray, c: Chart) -> np.ndarray:
    """The chart's UV centred at its centroid and scaled to the chart's 3D area, (nc, 2)."""
    F, UV = np.asarray(c.cut.F, dtype=np.int64), _uv(c)
    a3 = float(face_areas(V[c.cut.vertex_map], F).sum())
    a2 = float(np.abs(uv_areas(UV, F)).sum())
    s = math.sqrt(a3 / a2) if a2 > 0 and a3 > 0 else 1.0
    used = np.unique(F)
    uv = (UV - UV[used].mean(axis=0)) * s
    return np.nan_to_num(uv, nan=0.0)  # rows of vertices F does not use


def corner_uv(V: ArrayLike, F: ArrayLike, charts: Iterable[Chart]) -> np.ndarray:
    """Per-corner UV of the whole mesh, every chart rescaled to its 3D area.

    Parameters
    ----------
    V : (n, 3) array_like of float
    F : (m, 3) array_like of int
    charts : iterable of igl_heatseg.pipeline.Chart
        Charts without a map are skipped.

    Returns
    -------
    UVc : (3m, 2) float64
        Corner ``j`` of face ``f`` at row ``3 f + j`` (polyscope's corner order); corners of
        faces no chart covers are NaN-free zeros.
    """
    V = np.asarray(V, dtype=np.float64)
    UVc = np.zeros((np.shape(F)[0], 3, 2))
    for c in drawable_charts(charts):
        UVc[np.asarray(c.faces, dtype=np.int64)] = _normalised_uv(V, c)[c.cut.F]
    return UVc.reshape(-1, 2)


def chart_layout(V: ArrayLike, charts: Sequence[Chart]) -> list[np.ndarray]:
    """Place every chart's normalised UV side by side in rows (largest first).

    Parameters
    ----------
    V : (n, 3) array_like of float
        Vertices of the whole mesh (for the area normalisation).
    charts : sequence of igl_heatseg.pipeline.Chart
        With maps (see :func:`drawable_charts`).

    Returns
    -------
    list of (nc, 2) float64
        Translated UV per chart (same order as ``charts``), not overlapping each other.
    """
    V = np.asarray(V, dtype=np.float64)
    uvs = [_normalised_uv(V, c) for c in charts]
    if not uvs:
        return []
    ext = []
    for c, uv in zip(charts, uvs, strict=True):
        used = uv[np.unique(c.cut.F)]
        ext.append((used.min(axis=0), used.max(axis=0)))
    sizes = np.array([hi - lo for lo, hi in ext])
    gap = CHART_GAP * float(sizes.max())
    total = float(((sizes[:, 0] + gap) * (sizes[:, 1] + gap)).sum())
    row_w = max(math.sqrt(total) * 1.3, float(sizes[:, 0].max()))
    order = np.argsort(-sizes[:, 1], kind="stable")
    out: list[np.ndarray] = [None] * len(uvs)  # type: ignore[list-item]
    x = y = row_h = 0.0
    for i in order:
        w, h = sizes[i]
        if x > 0 and x + w > row_w:
            x, y, row_h = 0.0, y - row_h - gap, 0.0
        lo, hi = ext[i]
        out[i] = uvs[i] - [lo[0], hi[1]] + [x, y]
        x += w + gap
        row_h = max(row_h, h)
    return out


def scene_points(V: ArrayLike, charts: Iterable[Chart] | None, planar: bool) -> np.ndarray:
    """Points the camera must see: the mesh, or the laid-out charts in the plane z = 0."""
    if not planar:
        return np.asarray(V)
    ch = drawable_charts(charts)
    placed = chart_layout(V, ch)
    uv = np.concatenate([p[np.unique(c.cut.F)] for c, p in zip(ch, placed, strict=True)])
    return np.c_[uv, np.zeros(len(uv))]
