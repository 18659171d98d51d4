"""Peel the spikes off a chart's map, so that its pieces pack tighter (issue 13: atlas fill).

A coarse CAD export's chart is often a body with long spikes: sliver triangles that fan out
from a hole to the outline of a plane, or a jagged strip along a crease.  In a packed atlas a
spike keeps every other chart out of the space around it; cut off, it is a thin strip that
fits into a gap.

The body of a chart is found by a morphological *opening* of its map: the union of the discs
of radius ``r`` that fit inside the chart's image (rasterised, :data:`SPIKE_RASTER` pixels
across the square root of its area, at most :data:`SPIKE_MAX_PIXELS` in all).  A face whose
centroid lies outside the body is a spike face.  Edge-connected spike faces form a spike; a
spike no longer than :data:`SPIKE_TOOTH` times ``r`` (a tooth of a jagged outline, one or two
triangles) stays with the body.  The radii tried are :data:`SPIKE_RADII` times the square root
of the chart's area; the pieces of each must all be disks.  The split kept is the one with the
least *packing cost*: the area of the pieces' convex hulls plus a band of half the gutter
around each hull (the area a piece keeps other charts out of, and its share of the gutters),
when it is at least :data:`SPIKE_MIN_GAIN` below the whole chart's.

Every piece keeps the chart's map (see :func:`~.split.peel_for_packing`), so it stays
bijective with the same distortion.
"""

from __future__ import annotations

import igl
import numpy as np
from scipy import ndimage
from scipy.spatial import ConvexHull, QhullError

from ..mesh.geometry import uv_areas
from ..mesh.topology import label_pieces
from .cut import chart_topology
from .outline_pack import rasterize_chart

__all__ = ["split_spikes", "packing_cost", "SPIKE_RADII", "SPIKE_TOOTH", "SPIKE_MIN_GAIN"]

#: Opening radii tried, as fractions of the square root of the chart's (UV) area.
SPIKE_RADII: tuple = (0.05, 0.1, 0.15, 0.2, 0.3)

#: A spike whose bounding-box diagonal is under this many opening radii stays with the body
#: (a jagged outline's teeth are not worth a chart each).
SPIKE_TOOTH: float = 2.0

#: The pieces' packing cost must be at least this fraction below the whole chart's.
SPIKE_MIN_GAIN: float = 0.05

#: Raster resolution of the opening: pixels across the square root of the chart's area.
SPIKE_RASTER: int = 96

#: ... and at most this many pixels in the raster of a chart's box.
SPIKE_MAX_PIXELS: int = 1_000_000


def packing_cost(UV: np.ndarray, F: np.ndarray, gap: float) -> float:
    """Area a chart takes in a packed atlas, estimated from its convex hull.

    Parameters
    ----------
    UV : (n, 2) float64
        The chart's map (rows ``F`` does not use are ignored; they may be ``NaN``).
    F : (m, 3) int64
        Its triangles.
    gap : float
        Gutter between charts, in the units of ``UV``.

    Returns
    -------
    float
        Hull area + hull perimeter * ``gap`` / 2 + the area of a disc of diameter ``gap``
        (the hull dilated by half the gap).

    Examples
    --------
    >>> import numpy as np
    >>> sq = np.array([[0.0, 0], [1, 0], [1, 1], [0, 1]]); F = np.array([[0, 1, 2], [0, 2, 3]])
    >>> round(packing_cost(sq, F, 0.0), 12), round(packing_cost(sq, F, 0.1), 6)
    (1.0, 1.207854)
    """
    P = UV[np.unique(F)]
    if len(P) == 0:
        return 0.0
    try:
        hull = ConvexHull(P)
    except QhullError:  # all points on a line (its length: the box's diagonal): no area
        return float(np.hypot(*np.ptp(P, axis=0)) * gap + np.pi * gap * gap / 4)
    # in 2-D, ConvexHull's ``volume`` is the area and ``area`` the perimeter
    return float(hull.volume + hull.area * gap / 2 + np.pi * gap * gap / 4)


def _open(
    P: np.ndarray, F: np.ndarray, D: np.ndarray, pix: np.ndarray, t: float, r: float,
    TT: np.ndarray,
) -> list | None:
    """Pieces of the chart (``P``: its map, minimum at the origin; ``D``: each pixel's
    distance to the outside of the chart's raster of pixel ``t``, in the units of ``P``;
    ``pix``: each face's centroid pixel) for the opening radius ``r``; ``None`` when nothing
    is peeled or a piece is not a disk."""
    core = D > r
    if not core.any():
        return None
    body = ndimage.distance_transform_edt(~core, sampling=t) <= r
    inside = body[pix[:, 1], pix[:, 0]]
    if inside.all():
        return None
    comp = label_pieces(F, inside, TT)
    for c in np.unique(comp[~inside]):  # a tooth stays with the body
        spike = np.flatnonzero(comp == c)
        if np.hypot(*np.ptp(P[np.unique(F[spike])], axis=0)) < SPIKE_TOOTH * r:
            inside[spike] = True
    if inside.all():
        return None
    comp = label_pieces(F, inside, TT)
    pieces = [np.flatnonzero(comp == c) for c in np.unique(comp)]
    if not all(chart_topology(F[p], name="piece").is_disk for p in pieces):
        return None
    return pieces


def split_spikes(UV: np.ndarray, F: np.ndarray, gap: float) -> list | None:
    """Split a chart into its body and its spikes when the pieces pack tighter (module doc).

    Parameters
    ----------
    UV : (n, 2) float64
        A bijective map of the chart at its true scale (``NaN`` allowed for rows ``F`` does
        not use).
    F : (m, 3) int64
        Disk triangulation.
    gap : float
        Gutter between charts in the atlas, in the units of ``UV``.

    Returns
    -------
    list of (m_i,) int64 or None
        Face indices of the pieces (each an edge-connected disk; together every face once),
        ``None`` when the chart is best left whole.

    Examples
    --------
    A 10 x 10 square with a 10 x 0.2 spike along one side's end:

    >>> import numpy as np
    >>> sq = [[0.0, 0], [10, 0], [10, 10], [0, 10]]
    >>> UV = np.array(sq + [[10, 9.8], [20, 9.9], [10, 10.0]])
    >>> F = np.array([[0, 1, 4], [0, 4, 3], [4, 2, 3], [4, 5, 2]])
    >>> [p.tolist() for p in split_spikes(UV, F, 0.1)]
    [[0, 1, 2], [3]]
    >>> split_spikes(UV[:4], np.array([[0, 1, 2], [0, 2, 3]]), 0.1) is None  # no spike
    True
    """
    F = np.asarray(F, dtype=np.int64).reshape(-1, 3)
    if len(F) < 2:
        return None
    used, G = np.unique(F, return_inverse=True)
    G = G.reshape(-1, 3)
    P = np.asarray(UV, dtype=np.float64)[used]
    P = P - P.min(axis=0)
    area = float(np.abs(uv_areas(P, G)).sum())
    if not area > 0 or len(G) < 2:
        return None
    TT = igl.triangle_triangle_adjacency(G)[0]
    # pixel: SPIKE_RASTER across the square root of the area, coarser when the box would
    # take more than SPIKE_MAX_PIXELS (a long strip lying diagonally in its map)
    t = max(np.sqrt(area) / SPIKE_RASTER, np.sqrt(np.prod(np.ptp(P, axis=0)) / SPIKE_MAX_PIXELS))
    pad = 2
    M = rasterize_chart(P, G, t, pad)
    D = ndimage.distance_transform_edt(M, sampling=t)
    pix = np.floor(P[G].mean(axis=1) / t + pad).astype(np.int64)
    pix = np.clip(pix, 0, [M.shape[1] - 1, M.shape[0] - 1])
    whole = packing_cost(P, G, gap)
    best, best_cost = None, whole * (1 - SPIKE_MIN_GAIN)
    for frac in SPIKE_RADII:
        pieces = _open(P, G, D, pix, t, frac * np.sqrt(area), TT)
        if pieces is None:
            continue
        cost = sum(packing_cost(P, G[p], gap) for p in pieces)
        if cost < best_cost:
            best, best_cost = pieces, cost
    return best
