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
import scipy.sparse as sp
from numpy.typing import ArrayLike
from scipy.sparse.csgraph import connected_components

from ..mesh.geometry import face_areas, uv_areas
from ..parameterization.split import PACKING_METHODS

if TYPE_CHECKING:
    from ..pipeline import Chart

__all__ = [
    "CHART_GAP",
    "drawable_charts",
    "flipped_faces",
    "corner_uv",
    "chart_layout",
    "map_groups",
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


def _normalised_group(V: np.ndarray, cs: list) -> list[np.ndarray]:
    """The UVs of pieces of one map, centred and scaled together to their 3D area."""
    a3 = a2 = 0.0
    uvs, cents = [_uv(c) for c in cs], []
    for c, UV in zip(cs, uvs, strict=True):
        F = np.asarray(c.cut.F, dtype=np.int64)
        a3 += float(face_areas(V[c.cut.vertex_map], F).sum())
        a2 += float(np.abs(uv_areas(UV, F)).sum())
        cents.append(UV[np.unique(F)])
    s = math.sqrt(a3 / a2) if a2 > 0 and a3 > 0 else 1.0
    centre = np.concatenate(cents).mean(axis=0)
    # rows of vertices F does not use are NaN: zeros
    return [np.nan_to_num((UV - centre) * s, nan=0.0) for UV in uvs]


def _group_uvs(V: np.ndarray, charts: list, groups: list) -> list[np.ndarray]:
    """Every chart's normalised UV, the charts of a group (:func:`map_groups`) together."""
    uvs: list = [None] * len(charts)
    for g in groups:
        for i, uv in zip(g, _normalised_group(V, [charts[i] for i in g]), strict=True):
            uvs[i] = uv
    return uvs


def map_groups(charts: Sequence[Chart]) -> list[list[int]]:
    """Charts drawn as one map: the pieces of a chart cut for packing (they keep its map, see
    :data:`igl_heatseg.parameterization.split.PACKING_METHODS`) together, every other chart
    alone; in the order of their first chart.

    Pieces come from one map when they come from one chart and touch where their UVs are the
    same (pieces of a chart cut for distortion have maps of their own, which differ along the
    seam between them).

    Parameters
    ----------
    charts : sequence of igl_heatseg.pipeline.Chart
        With maps (see :func:`drawable_charts`).

    Returns
    -------
    list of list of int
        Indices into ``charts``.

    Examples
    --------
    Two pieces of one map (vertex 1 at the same UV in both) and a chart of its own:

    >>> from types import SimpleNamespace as NS
    >>> whole, F = object(), np.array([[0, 1, 2]])
    >>> def piece(ids, UV, method="cut for packing"):
    ...     return NS(param=NS(attempts=[{"method": method}], UV=np.array(UV, float)),
    ...               chart_cut=whole, cut=NS(F=F, vertex_map=np.array(ids)))
    >>> a = piece([0, 1, 2], [[0, 0], [1, 0], [0, 1]])
    >>> b = piece([1, 3, 2], [[1, 0], [1, 1], [0, 1]])
    >>> c = piece([1, 4, 5], [[1, 0], [2, 0], [2, 1]], method="hlle")
    >>> map_groups([a, c, b])
    [[0, 2], [1]]
    >>> b.param.UV[0] = [1.5, 0.0]; b.param.UV[2] = [0.0, 1.5]  # another map: apart
    >>> map_groups([a, c, b])
    [[0], [1], [2]]
    """
    candidates: dict = {}
    for i, c in enumerate(charts):
        attempts = c.param.attempts or [{}]
        one_map = attempts[-1].get("method") in PACKING_METHODS and c.chart_cut is not None
        candidates.setdefault(("map", id(c.chart_cut)) if one_map else ("chart", i), []).append(i)
    groups = []
    for key, members in candidates.items():
        if key[0] == "chart" or len(members) == 1:
            groups.append(members)
            continue
        corners = []  # (mesh vertex, u, v) of every piece: equal where they touch in one map
        for i in members:
            c = charts[i]
            used = np.unique(np.asarray(c.cut.F))
            ids = np.asarray(c.cut.vertex_map)[used]
            uv = _uv(c)[used]
            corners.append(set(zip(ids.tolist(), uv[:, 0].tolist(), uv[:, 1].tolist(),
                                   strict=True)))
        n = len(members)
        touch = np.array([[p, q] for p in range(n) for q in range(p + 1, n)
                          if not corners[p].isdisjoint(corners[q])], dtype=np.int64).reshape(-1, 2)
        A = sp.coo_matrix((np.ones(len(touch)), (touch[:, 0], touch[:, 1])), shape=(n, n))
        label = connected_components(A, directed=False)[1]
        groups.extend([members[p] for p in np.flatnonzero(label == k)] for k in np.unique(label))
    return sorted(groups, key=lambda g: g[0])


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
    charts = drawable_charts(charts)
    # pieces of one map: one scale, so one checker size
    for c, uv in zip(charts, _group_uvs(V, charts, map_groups(charts)), strict=True):
        UVc[np.asarray(c.faces, dtype=np.int64)] = uv[c.cut.F]
    return UVc.reshape(-1, 2)


def chart_layout(V: ArrayLike, charts: Sequence[Chart]) -> list[np.ndarray]:
    """Place every chart's normalised UV side by side in rows (largest first); the pieces of a
    chart cut for packing together, as the map they come from (:func:`map_groups`).

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
    if not charts:
        return []
    groups = map_groups(charts)  # pieces of one map are drawn together, as that map
    uvs = _group_uvs(V, charts, groups)
    ext = []
    for g in groups:
        used = np.concatenate([uvs[i][np.unique(charts[i].cut.F)] for i in g])
        ext.append((used.min(axis=0), used.max(axis=0)))
    sizes = np.array([hi - lo for lo, hi in ext])
    gap = CHART_GAP * float(sizes.max())
    total = float(((sizes[:, 0] + gap) * (sizes[:, 1] + gap)).sum())
    row_w = max(math.sqrt(total) * 1.3, float(sizes[:, 0].max()))
    order = np.argsort(-sizes[:, 1], kind="stable")
    out: list[np.ndarray] = [None] * len(uvs)  # type: ignore[list-item]
    x = y = row_h = 0.0
    for j in order:
        w, h = sizes[j]
        if x > 0 and x + w > row_w:
            x, y, row_h = 0.0, y - row_h - gap, 0.0
        lo, hi = ext[j]
        for i in groups[j]:
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
