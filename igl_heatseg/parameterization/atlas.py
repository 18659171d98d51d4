"""Pack chart UV maps into one texture atlas in the unit square, and write OBJ files with UVs.

Every chart map is assumed bijective already (see :mod:`~.bijectivity`); packing only moves
charts rigidly (rotation + translation) and scales all of them by one common factor, so
each chart keeps its orientation and its map stays bijective; charts do not overlap and stay
at least the gutter apart (their gutter-padded bounding boxes with the box packers, their
outlines with :func:`~.outline_pack.pack_outlines`).

Packing: optional per-chart rescale so that UV area equals 3D area (charts from different
methods may come in different units), rotation of each chart to its minimum-area bounding
rectangle (rotating calipers on the convex hull, then "landscape"), then shelf and skyline
packing of the boxes (several bin widths, the squarest layout kept) and, up to
:data:`~.outline_pack.OUTLINE_MAX_CHARTS` charts, packing of the charts' own outlines at any
of several rotations; the smaller square wins.  The result is normalised into ``[0, 1]^2``
with the common scale.

OBJ conventions: indices are 1-based; ``f v/vt v/vt v/vt``; coordinates written with 17
significant digits so that a re-read file gives back the same doubles.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike

from ..errors import MeshError
from ..mesh.geometry import uv_areas
from .outline_pack import OUTLINE_MAX_CHARTS, pack_outlines, rotate_points

__all__ = [
    "PackedAtlas",
    "pack_charts",
    "min_area_rotation",
    "rotate_points",
    "convex_hull",
    "boxes_overlap",
    "atlas_corner_uv",
    "GUTTER_DEFAULT",
    "GUTTER_MAX",
]

log = logging.getLogger(__name__)

#: Gap between charts, as a fraction of the atlas side (4 texels of a 1024 px texture, 2 of 512).
GUTTER_DEFAULT: float = 0.004

#: Largest gutter the pipeline and the CLI accept: the outline packer fails from about 0.2
#: (a chart fitting nowhere, or memory), measured on small meshes; 0.1 packs.
GUTTER_MAX: float = 0.1

#: Shelf widths tried, as multiples of ``sqrt(sum of box areas)``.
_SHELF_WIDTH_FACTORS = np.linspace(0.7, 2.5, 37)

#: Skyline packing (tries quarter turns; quadratic in the chart count) is tried up to this many
#: charts, shelf packing always.
SKYLINE_MAX_CHARTS: int = 400

#: Skyline bin widths tried, as multiples of ``sqrt(sum of box areas)``.
_SKYLINE_WIDTH_FACTORS = np.linspace(0.8, 1.6, 9)

#: UVs may exceed [0, 1] by this much from rounding before they are clipped.
UV_ROUND_TOL: float = 1e-9


@dataclass(frozen=True)
class PackedAtlas:
    """Charts packed into the unit square.

    Attributes
    ----------
    uvs : list of (n_i, 2) float64
        Packed UVs of each chart, all in ``[0, 1]^2``.
    boxes : (k, 4) float64
        Each chart's axis-aligned bounding box in the atlas, ``[u_min, v_min, u_max, v_max]``
        (without gutter); with the box packer, boxes of different charts are at least the gutter
        apart (the outline packer keeps the charts themselves apart).
    scale : float
        Common factor from (area-normalised, if ``areas`` was given) chart units to atlas units.
    chart_scales : (k,) float64
        Per-chart factor applied before ``scale`` (1 unless ``areas`` was given).
    rotations : (k,) float64
        Rotation applied to each chart (radians, counter-clockwise).
    gutter : float
        Smallest gap between two charts (box packers: between their boxes) in atlas units.
    fill : float
        Sum of chart UV areas in the atlas (how much of the unit square is used).
    """

    uvs: list
    boxes: np.ndarray
    scale: float
    chart_scales: np.ndarray
    rotations: np.ndarray
    gutter: float
    fill: float


#: Directions of the Akl-Toussaint filter in :func:`convex_hull` (points strictly inside the
#: polygon of the extreme points in these directions cannot be hull vertices).
_HULL_DIRECTIONS = 32


def _hull_candidates(P: np.ndarray) -> np.ndarray:
    """The points of ``P`` that can be convex-hull vertices (Akl-Toussaint filter).

    The extreme points in :data:`_HULL_DIRECTIONS` directions, in angular order, form a
    convex polygon inside the hull; a point strictly inside it (with a rounding margin) is
    interior to the hull.  Measured on iron.ply's 41 charts (85k UV points): the Python
    monotone chain took 0.70 s on all points and about a tenth of that on the survivors.
    """
    if len(P) < 4 * _HULL_DIRECTIONS:
        return P
    ang = np.linspace(0.0, 2.0 * np.pi, _HULL_DIRECTIONS, endpoint=False)
    idx = np.argmax(P @ np.stack([np.cos(ang), np.sin(ang)]), axis=0)
    idx = idx[np.r_[True, idx[1:] != idx[:-1]]]
    if len(idx) > 1 and idx[0] == idx[-1]:
        idx = idx[:-1]
    if len(np.unique(idx)) < 3:
        return P
    Q = P[idx]
    E = np.roll(Q, -1, axis=0) - Q
    ext = float(np.ptp(P, axis=0).max())
    margin = 1e-9 * ext * ext
    inside = np.ones(len(P), dtype=bool)
    for q, e in zip(Q, E, strict=True):
        inside &= e[0] * (P[:, 1] - q[1]) - e[1] * (P[:, 0] - q[0]) > margin
    return P[~inside]


def convex_hull(P: np.ndarray) -> np.ndarray:
    """Convex hull (Andrew's monotone chain), counter-clockwise, no repeated point.

    Examples
    --------
    >>> convex_hull([[0, 0], [2, 0], [1, 1], [2, 2], [0, 2], [1, 0]]).tolist()
    [[0.0, 0.0], [2.0, 0.0], [2.0, 2.0], [0.0, 2.0]]
    """
    P = np.unique(_hull_candidates(np.asarray(P, dtype=np.float64)), axis=0)
    if len(P) < 3:
        return P

    def half(points):
        out: list = []
        for p in points:
            while len(out) >= 2:
                o, a = out[-2], out[-1]
                if (a[0] - o[0]) * (p[1] - o[1]) - (a[1] - o[1]) * (p[0] - o[0]) > 0:
                    break
                out.pop()
            out.append(p)
        return out

    pts = [tuple(p) for p in P]  # sorted lexicographically by np.unique
    lower = half(pts)
    upper = half(pts[::-1])
    return np.array(lower[:-1] + upper[:-1])


def min_area_rotation(UV: ArrayLike) -> float:
    """Rotation angle that gives the minimum-area axis-aligned bounding box, width >= height.

    Rotating calipers: the optimal rectangle has a side on a convex-hull edge.

    Parameters
    ----------
    UV : (n, 2) array_like of float

    Returns
    -------
    angle : float
        Counter-clockwise angle (radians) to rotate the points by.

    Examples
    --------
    >>> import numpy as np
    >>> P = np.array([[0, 0], [1, 1], [0.5, 1.5], [-0.5, 0.5]])  # a 45-degree rectangle
    >>> round(float(abs(np.degrees(min_area_rotation(P))) % 90), 6)
    45.0
    """
    P = np.asarray(UV, dtype=np.float64)
    H = convex_hull(P)
    if len(H) < 3:
        angles = np.array([0.0])
    else:
        d = np.roll(H, -1, axis=0) - H
        angles = -np.arctan2(d[:, 1], d[:, 0])
    best, best_area = 0.0, np.inf
    for t in angles:
        c, s = np.cos(t), np.sin(t)
        R = H @ np.array([[c, s], [-s, c]])
        ext = R.max(axis=0) - R.min(axis=0)
        area = ext[0] * ext[1]
        if area < best_area * (1 - 1e-12):
            best, best_area = float(t), area
            best_ext = ext
    if len(H) >= 2 and best_ext[1] > best_ext[0]:
        best += np.pi / 2
    return float(np.arctan2(np.sin(best), np.cos(best)))


def _shelf(w: np.ndarray, h: np.ndarray, width: float) -> tuple[np.ndarray, float, float]:
    """Shelf packing in the given order; returns offsets (k,2), used width, total height."""
    xy = np.zeros((len(w), 2))
    x = y = shelf_h = used_w = 0.0
    for i in range(len(w)):
        if x > 0 and x + w[i] > width:
            y += shelf_h
            x = shelf_h = 0.0
        xy[i] = (x, y)
        x += w[i]
        shelf_h = max(shelf_h, h[i])
        used_w = max(used_w, x)
    return xy, used_w, y + shelf_h


def _skyline(
    w: np.ndarray, h: np.ndarray, width: float
) -> tuple[np.ndarray, np.ndarray, float, float]:
    """Bottom-left skyline packing in the given order, each box optionally turned 90 degrees.

    Returns offsets (k,2), turned flags (k,), used width, total height.
    """
    xs = [0.0]  # skyline segment starts (ascending); segment s spans xs[s]..xs[s+1] or width
    ys = [0.0]
    xy = np.zeros((len(w), 2))
    turned = np.zeros(len(w), dtype=bool)
    used_w = total_h = 0.0
    for i in range(len(w)):
        best = None
        for ww, hh, rot in ((w[i], h[i], False), (h[i], w[i], True)):
            if ww > width:
                continue
            ends = xs[1:] + [width]
            for s in range(len(xs)):
                x = xs[s]
                if x + ww > width * (1 + 1e-12):
                    break
                top, j = ys[s], s
                while ends[j] < x + ww * (1 - 1e-12):
                    j += 1
                    top = max(top, ys[j])
                key = (top + hh, x)
                if best is None or key < best[0]:
                    best = (key, x, top, ww, hh, rot)
        if best is None:  # wider than the bin both ways (width >= max side, cannot happen)
            raise RuntimeError("pack_charts: internal error, box wider than the atlas")
        _, x, top, ww, hh, rot = best
        xy[i] = (x, top)
        turned[i] = rot
        used_w, total_h = max(used_w, x + ww), max(total_h, top + hh)
        # new skyline: segments before x, the box top over [x, x+ww), the rest after
        x1 = x + ww
        nx, ny = [], []
        for s in range(len(xs)):
            a = xs[s]
            b = xs[s + 1] if s + 1 < len(xs) else width
            if b <= x or a >= x1:
                nx.append(a)
                ny.append(ys[s])
            else:
                if a < x:
                    nx.append(a)
                    ny.append(ys[s])
                if b > x1:
                    nx.append(x1)
                    ny.append(ys[s])
        k = int(np.searchsorted(nx, x))
        nx.insert(k, x)
        ny.insert(k, top + hh)
        order = np.argsort(nx, kind="stable")
        xs, ys = [nx[o] for o in order], [ny[o] for o in order]
        # merge neighbours of equal height
        mx, my = [xs[0]], [ys[0]]
        for a, y in zip(xs[1:], ys[1:], strict=True):
            if y != my[-1]:
                mx.append(a)
                my.append(y)
        xs, ys = mx, my
    return xy, turned, used_w, total_h


def pack_charts(
    uvs: list,
    faces: list,
    areas: ArrayLike | None = None,
    *,
    gutter: float = GUTTER_DEFAULT,
    rotate: bool = True,
    packer: Literal["auto", "boxes", "outlines"] = "auto",
) -> PackedAtlas:
    """Pack chart UV maps into ``[0, 1]^2`` without overlaps between charts.

    Parameters
    ----------
    uvs : list of (n_i, 2) array_like of float
        Each chart's UV coordinates (a bijective map; orientation is preserved).
    faces : list of (m_i, 3) array_like of int
        Each chart's triangles, indexing its ``uvs[i]``.
    areas : (k,) array_like of float, optional
        3D surface area of each chart.  When given, each chart is first scaled so its UV area
        equals its 3D area, so relative sizes in the atlas follow the surface.  Otherwise the
        charts' own UV units are kept (one common factor for all).
    gutter : float
        Gap between charts as a fraction of the side of a square as large as the charts'
        bounding boxes together (the atlas is larger: :attr:`PackedAtlas.gutter` is the gap in
        atlas units), ``0 <= gutter < 0.5``.
    rotate : bool
        Rotate each chart to its minimum-area bounding box.
    packer : {"auto", "boxes", "outlines"}
        ``"boxes"``: shelf and skyline packing of the bounding boxes (boxes at least the gutter
        apart, charts turned by quarter turns); ``"outlines"``: the charts' own outlines on a
        raster (:func:`~.outline_pack.pack_outlines`: charts at least the gutter apart, turned
        by any of 4 or 8 angles, their boxes may overlap); ``"auto"`` (default): the smaller
        of the two layouts (outlines only up to :data:`~.outline_pack.OUTLINE_MAX_CHARTS`
        charts).

    Returns
    -------
    PackedAtlas

    Raises
    ------
    MeshError
        Mismatched lists, bad shapes, non-finite UVs, face indices out of range, a chart with
        zero UV area, or bad ``areas``/``gutter``.

    Examples
    --------
    >>> import numpy as np
    >>> sq = np.array([[0., 0], [1, 0], [1, 1], [0, 1]]); F = np.array([[0, 1, 2], [0, 2, 3]])
    >>> atlas = pack_charts([sq, 2 * sq], [F, F])
    >>> len(boxes_overlap(atlas.boxes))
    0
    >>> round(float(np.ptp(atlas.uvs[1][:, 0]) / np.ptp(atlas.uvs[0][:, 0])), 9)
    2.0
    """
    # One long function on purpose: input checks, per-chart scaling and rotation, the two
    # packers and the normalisation share the box arrays; split, they would pass ~8 arrays.
    if len(uvs) != len(faces):
        raise MeshError(f"pack_charts: {len(uvs)} UV arrays but {len(faces)} face arrays")
    if len(uvs) == 0:
        raise MeshError("pack_charts: no charts to pack")
    if not (0 <= gutter < 0.5):
        raise MeshError(f"pack_charts: gutter must be in [0, 0.5), got {gutter}")
    if packer not in ("auto", "boxes", "outlines"):
        raise MeshError(
            f"pack_charts: packer must be 'auto', 'boxes' or 'outlines', got {packer!r}"
        )
    k = len(uvs)
    P_list, F_list = [], []
    for i, (UV, F) in enumerate(zip(uvs, faces, strict=True)):
        UV = np.asarray(UV, dtype=np.float64)
        F = np.asarray(F)
        if UV.ndim != 2 or UV.shape[1] != 2:
            raise MeshError(f"chart {i}: `uv` should have shape (n,2), shape is {UV.shape}")
        if F.ndim != 2 or F.shape[1] != 3 or F.dtype.kind not in "iu":
            raise MeshError(f"chart {i}: `F` should be (m,3) integers, got {F.shape} {F.dtype}")
        if len(F) == 0:
            raise MeshError(f"chart {i}: no faces")
        if F.min() < 0 or F.max() >= len(UV):
            raise MeshError(f"chart {i}: face indices outside 0..{len(UV) - 1}")
        if not np.isfinite(UV).all():
            raise MeshError(f"chart {i}: UVs contain NaN or infinite values")
        P_list.append(UV)
        F_list.append(F.astype(np.int64))
    uv_area = np.array([np.abs(uv_areas(P, F)).sum() for P, F in zip(P_list, F_list, strict=True)])
    zero = np.flatnonzero(uv_area <= 0)
    if len(zero):
        raise MeshError(f"pack_charts: chart(s) {zero[:5].tolist()} have zero UV area")
    if areas is None:
        chart_scales = np.ones(k)
    else:
        areas = np.asarray(areas, dtype=np.float64).reshape(-1)
        if areas.shape != (k,) or not (np.isfinite(areas).all() and (areas > 0).all()):
            raise MeshError(f"pack_charts: `areas` must be {k} positive numbers")
        chart_scales = np.sqrt(areas / uv_area)

    rotations = np.zeros(k)
    local = []
    for i in range(k):
        P = P_list[i] * chart_scales[i]
        if rotate:
            rotations[i] = min_area_rotation(P)
            P = rotate_points(P, rotations[i])
        local.append(P - P.min(axis=0))
    ext = np.array([P.max(axis=0) for P in local])  # (k, 2) box sizes
    ext = np.maximum(ext, 1e-300)
    # Gutter in chart units: a fraction of the (estimated) atlas side.
    side0 = np.sqrt((ext[:, 0] * ext[:, 1]).sum())
    g = gutter * side0 / max(1.0 - 2 * gutter, 1e-9)
    w, h = ext[:, 0] + g, ext[:, 1] + g
    order = np.lexsort((-w, -h))  # tallest first
    best = None
    root = np.sqrt((w * h).sum())
    for fac in _SHELF_WIDTH_FACTORS:
        width = max(fac * root, w.max())
        xy, used_w, total_h = _shelf(w[order], h[order], width)
        side = max(used_w, total_h)
        if best is None or side < best[0] * (1 - 1e-12):
            best = (side, xy, np.zeros(k, dtype=bool))
    if k <= SKYLINE_MAX_CHARTS:
        big = np.argsort(-np.maximum(w, h), kind="stable")  # longest side first
        for fac in _SKYLINE_WIDTH_FACTORS:
            width = max(fac * root, np.minimum(w, h).max())
            xy, turned, used_w, total_h = _skyline(w[big], h[big], width)
            side = max(used_w, total_h)
            if side < best[0] * (1 - 1e-12):
                xy_o = np.empty_like(xy)
                t_o = np.empty_like(turned)
                xy_o[big], t_o[big] = xy, turned
                best = (side, xy_o[order], t_o)  # offsets in `order` space, flags not
    side, xy_sorted, turned = best
    method = "boxes"
    xy = np.empty_like(xy_sorted)
    xy[order] = xy_sorted
    turn = turned * (np.pi / 2)  # extra rotation of every chart, radians
    if packer == "outlines" or (packer == "auto" and k <= OUTLINE_MAX_CHARTS):
        offsets, angles = pack_outlines(local, F_list, g)
        placed = [rotate_points(local[i], angles[i]) for i in range(k)]
        placed = [P - P.min(axis=0) + offsets[i] for i, P in enumerate(placed)]
        lo = np.min([P.min(axis=0) for P in placed], axis=0)
        side_o = float((np.max([P.max(axis=0) for P in placed], axis=0) - lo).max()) + g
        if packer == "outlines" or side_o < side:
            side, turn = side_o, angles
            xy = np.array([P.min(axis=0) - lo for P in placed])
            method = "outlines"
    for i in np.flatnonzero(turn):
        # a rotation (orientation kept), back into the box's corner
        local[i] = rotate_points(local[i], turn[i])
        local[i] -= local[i].min(axis=0)
        t = rotations[i] + turn[i]
        rotations[i] = np.arctan2(np.sin(t), np.cos(t))
    # The whole layout (with a half gutter around every chart) maps to [0, 1]^2.
    scale = 1.0 / side
    out, boxes = [], np.zeros((k, 4))
    for i in range(k):
        Q = (local[i] + xy[i] + g / 2) * scale
        if Q.min() < -UV_ROUND_TOL or Q.max() > 1 + UV_ROUND_TOL:
            raise RuntimeError(f"pack_charts: internal error, chart {i} left the unit square")
        Q = np.clip(Q, 0.0, 1.0)
        out.append(Q)
        boxes[i] = [*Q.min(axis=0), *Q.max(axis=0)]
    fill = float((uv_area * chart_scales**2).sum() * scale**2)
    log.info(
        "packed %d chart(s) by %s: fill %.1f %%, gutter %.3g", k, method, 100 * fill, g * scale
    )
    return PackedAtlas(
        uvs=out,
        boxes=boxes,
        scale=float(scale),
        chart_scales=chart_scales,
        rotations=rotations,
        gutter=float(g * scale),
        fill=fill,
    )


def boxes_overlap(boxes: ArrayLike, gap: float = 0.0) -> np.ndarray:
    """Pairs of axis-aligned boxes that overlap or are closer than ``gap``.

    Parameters
    ----------
    boxes : (k, 4) array_like of float
        ``[x_min, y_min, x_max, y_max]`` per box.
    gap : float
        Boxes closer than this (in both axes) count as overlapping; touching boxes with
        ``gap == 0`` do not.

    Returns
    -------
    pairs : (p, 2) int64
        ``i < j`` for each overlapping pair.

    Examples
    --------
    >>> boxes_overlap([[0, 0, 1, 1], [0.5, 0.5, 2, 2], [3, 3, 4, 4]]).tolist()
    [[0, 1]]
    """
    B = np.asarray(boxes, dtype=np.float64).reshape(-1, 4)
    sep_x = (B[:, None, 0] >= B[None, :, 2] + gap) | (B[None, :, 0] >= B[:, None, 2] + gap)
    sep_y = (B[:, None, 1] >= B[None, :, 3] + gap) | (B[None, :, 1] >= B[:, None, 3] + gap)
    hit = ~(sep_x | sep_y)
    i, j = np.nonzero(np.triu(hit, 1))
    return np.stack([i, j], axis=1).astype(np.int64)


def atlas_corner_uv(m: int, chart_faces: list, chart_F: list, uvs: list) -> np.ndarray:
    """Per-corner UVs of the whole mesh from per-chart UVs.

    Parameters
    ----------
    m : int
        Face count of the whole mesh.
    chart_faces : list of (m_i,) array_like of int
        Which faces of the whole mesh chart ``i`` holds (its faces in order).
    chart_F : list of (m_i, 3) array_like of int
        Chart ``i``'s triangles on its own (cut) vertices, row ``r`` = whole-mesh face
        ``chart_faces[i][r]`` with the same corner order.
    uvs : list of (n_i, 2) array_like of float
        Chart ``i``'s UV per (cut) vertex.

    Returns
    -------
    corner_uv : (m, 3, 2) float64
        ``corner_uv[f, j]`` = UV of corner ``j`` of face ``f``.

    Raises
    ------
    MeshError
        A face not covered by any chart, or covered twice.

    Examples
    --------
    >>> import numpy as np
    >>> tri = np.array([[0, 1, 2]])
    >>> uv = atlas_corner_uv(2, [[1], [0]], [tri, tri], [np.eye(3)[:, :2], np.zeros((3, 2))])
    >>> uv[1].tolist()
    [[1.0, 0.0], [0.0, 1.0], [0.0, 0.0]]
    """
    out = np.full((m, 3, 2), np.nan)
    count = np.zeros(m, dtype=np.int64)
    for faces, F, UV in zip(chart_faces, chart_F, uvs, strict=True):
        faces = np.asarray(faces, dtype=np.int64)
        out[faces] = np.asarray(UV, dtype=np.float64)[np.asarray(F, dtype=np.int64)]
        np.add.at(count, faces, 1)
    bad = np.flatnonzero(count != 1)
    if len(bad):
        raise MeshError(
            f"atlas: {len(bad)} face(s) are in {sorted(set(count[bad].tolist()))} charts "
            f"instead of exactly one, e.g. faces {bad[:5].tolist()}"
        )
    return out
