"""What :func:`~igl_heatseg.cad.build.build_brep` needs from a segmentation that did not fit
surfaces (the paper's mode) or that has charts (the pipeline): one surface per segment, fitted
without relabelling, and the certified chart UVs of the segments; and the border faces a
segment's surface misses, given to the neighbour whose surface holds them
(:func:`settle_borders`).

No OpenCASCADE here: these functions run before the build.
"""

from __future__ import annotations

import igl
import numpy as np

from igl_heatseg.errors import MeshError
from igl_heatseg.mesh.topology import label_pieces
from igl_heatseg.parameterization.split import PACKING_METHODS
from igl_heatseg.surfaces.model import Surface
from igl_heatseg.surfaces.segment_fit import MIN_FIT_FACES, vertex_samples
from igl_heatseg.surfaces.select import fit_surface
from igl_heatseg.surfaces.tolerance import vertex_tolerance

from .topology import segment_areas

__all__ = ["fit_segment_surfaces", "chart_uvs", "typical_rms", "check_inputs", "settle_borders"]


def fit_segment_surfaces(V: np.ndarray, F: np.ndarray, labels: np.ndarray,
                         tol: float | None = None) -> list:
    """One fitted surface per segment, the segments left as they are (no split, merge or move).

    Parameters
    ----------
    V : (n, 3) float64
    F : (m, 3) int64
    labels : (m,) int64
        ``0..k-1``.
    tol : float, optional
        Fit tolerance (model units); default
        :func:`~igl_heatseg.surfaces.tolerance.vertex_tolerance`.

    Returns
    -------
    list of Surface, length k
        The simplest adequate kind of each segment (:func:`~igl_heatseg.surfaces.fit_surface`);
        ``freeform`` when none is within tolerance or the segment has too few faces.

    Examples
    --------
    >>> import igl, numpy as np
    >>> V, F = igl.loop(*igl.icosahedron(), 2)
    >>> V /= np.linalg.norm(V, axis=1, keepdims=True)
    >>> [s.kind for s in fit_segment_surfaces(V, F, np.zeros(len(F), np.int64))]
    ['sphere']
    """
    V = np.asarray(V, dtype=np.float64)
    F = np.asarray(F, dtype=np.int64)
    labels = np.asarray(labels, dtype=np.int64)
    tol = vertex_tolerance(V, F) if tol is None else float(tol)
    out = []
    for a in range(int(labels.max()) + 1):
        faces = np.flatnonzero(labels == a)
        if len(faces) < MIN_FIT_FACES:
            P = V[np.unique(F[faces])] if len(faces) else V[:1]
            out.append(Surface("freeform", {"centroid": P.mean(axis=0)}))
            continue
        P, N, w = vertex_samples(V, F, faces)
        out.append(fit_surface(P, N, w, tol=tol))
    return out


def typical_rms(V: np.ndarray, F: np.ndarray, labels: np.ndarray, surfaces) -> float:
    """The part's noise as its fits see it: the area-weighted median, over the analytic
    segments, of the RMS distance of a segment's vertices to its surface.

    Noise is about even over a scanned part, so a segment whose RMS is several times this one
    misses a shape that its surface does not have (``build_brep`` gives it a B-spline face).

    Parameters
    ----------
    V : (n, 3) float64
    F : (m, 3) int64
    labels : (m,) int64
        ``0..k-1``.
    surfaces : list of Surface, length k

    Returns
    -------
    float
        Model units; 0 without analytic segments.

    Examples
    --------
    >>> import numpy as np
    >>> from igl_heatseg.surfaces.model import Surface
    >>> V = np.array([[0., 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0.2]])
    >>> F = np.array([[0, 1, 2], [1, 3, 2]])
    >>> z = Surface("plane", {"point": np.zeros(3), "normal": np.array([0., 0, 1])})
    >>> round(typical_rms(V, F, np.array([0, 0]), [z]), 6)      # sqrt(0.2^2 / 4)
    0.1
    """
    areas = segment_areas(V, F, labels, len(surfaces))
    rms, w = [], []
    for a, s in enumerate(surfaces):
        if s.is_analytic:
            verts = np.unique(F[labels == a])
            rms.append(float(np.sqrt(np.mean(s.distance(V[verts]) ** 2))))
            w.append(areas[a])
    if not rms:
        return 0.0
    rms, w = np.asarray(rms), np.asarray(w)
    order = np.argsort(rms)
    c = np.cumsum(w[order])
    return float(rms[order][min(int(np.searchsorted(c, 0.5 * c[-1])), len(c) - 1)])


def settle_borders(V: np.ndarray, F: np.ndarray, labels: np.ndarray, surfaces, tol: float,
                   movable=None, receivers=None) -> tuple[np.ndarray, np.ndarray]:
    """Border faces that a segment's surface misses, given to the neighbour whose surface
    holds them.

    A segment's boundary runs along mesh edges and can wander a triangle onto the next face
    of the part; the vertices there lie off the segment's surface by up to an edge length,
    more than the modelling tolerance, and the whole segment would be faceted for them. For
    each analytic segment with vertices farther than ``tol`` from its surface, the faces using
    those vertices move to an edge-adjacent analytic segment whose surface holds all three of
    their vertices within ``tol`` (the closest such surface; a face reached through faces moved
    before it counts as adjacent). A segment moves all such faces or none: none when one of
    them finds no neighbour, when they are all its faces, or when it would fall into more
    edge-connected pieces than before. A face moved away always holds a vertex off its old
    surface, so it never moves back. (The segmentation's
    :func:`~igl_heatseg.surfaces.strays.shed_strays` moves the faces that stand across their
    surface, by their normals, at its own fit tolerance; this is the build's test, at the
    modelling tolerance, with the neighbour's surface as the judge.)

    Parameters
    ----------
    V : (n, 3) float64
    F : (m, 3) int64
    labels : (m,) int64
        ``0..k-1``.
    surfaces : list of Surface, length k
    tol : float
        Modelling tolerance (model units).
    movable, receivers : set of int, optional
        The segments that may give faces, and those that may take them (default: every
        analytic segment).

    Returns
    -------
    labels : (m,) int64
        A new array (the input is not changed).
    moved : (p, 3) int64
        One row per moved face: face, old segment, new segment.

    Examples
    --------
    Two unit squares meeting at a right angle along x = 1 (the floor z = 0 and the wall x = 1),
    with one triangle of the wall labelled as the floor:

    >>> import numpy as np
    >>> from igl_heatseg.surfaces.model import Surface
    >>> V = np.array([[0., 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [1, 0, 1], [1, 1, 1]])
    >>> F = np.array([[0, 1, 2], [0, 2, 3], [1, 4, 5], [1, 5, 2]])
    >>> floor = Surface("plane", {"point": np.zeros(3), "normal": np.array([0., 0, 1])})
    >>> wall = Surface("plane", {"point": np.array([1., 0, 0]), "normal": np.array([1., 0, 0])})
    >>> labels, moved = settle_borders(V, F, np.array([0, 0, 0, 1]), [floor, wall], 0.01)
    >>> labels.tolist(), moved.tolist()
    ([0, 0, 1, 1], [[2, 0, 1]])
    """
    F = np.asarray(F, dtype=np.int64)
    labels = np.array(labels, dtype=np.int64)
    moved = []
    TT = None
    for a, s in enumerate(surfaces):
        if not s.is_analytic or (movable is not None and a not in movable):
            continue
        faces = np.flatnonzero(labels == a)
        verts = np.unique(F[faces])
        off = verts[np.abs(s.distance(V[verts])) > tol]
        if len(off) == 0:
            continue
        give = faces[np.isin(F[faces], off).any(axis=1)]
        if len(give) == len(faces):
            continue
        if TT is None:
            TT = igl.triangle_triangle_adjacency(F)[0]
        new = _take(V, F, TT, labels, give, a, surfaces, tol, receivers)
        if new is None:
            continue
        if len(np.unique(label_pieces(F, new, TT)[new == a])) > \
                len(np.unique(label_pieces(F, labels, TT)[faces])):
            continue
        moved.extend((int(f), a, int(new[f])) for f in give)
        labels = new
    return labels, np.array(moved, dtype=np.int64).reshape(-1, 3)


def _take(V, F, TT, labels, give, a, surfaces, tol, receivers):
    """Labels with every face of ``give`` (segment ``a``'s) taken by the closest edge-adjacent
    receiving surface within ``tol`` of its vertices, faces taken first counting as adjacent;
    None when a face finds none."""
    new = labels.copy()
    pending = [int(f) for f in give]
    while pending:
        left = []
        for f in pending:
            best, gap = -1, np.inf
            for b in {int(new[g]) for g in TT[f] if g >= 0} - {a}:
                if not surfaces[b].is_analytic or (receivers is not None and b not in receivers):
                    continue
                d = float(np.abs(surfaces[b].distance(V[F[f]])).max())
                if d <= tol and d < gap:
                    best, gap = b, d
            if best < 0:
                left.append(f)
            else:
                new[f] = best
        if len(left) == len(pending):
            return None
        pending = left
    return new


def chart_uvs(labels: np.ndarray, surfaces, charts) -> list:
    """The ``uv`` argument of :func:`~igl_heatseg.cad.build.build_brep` from pipeline charts.

    A segment gets its chart's UV when it is freeform, its map is certified bijective and one
    UV per mesh vertex (the chart was not cut open).  Its chart is one chart, or the pieces of
    one chart cut for packing (:func:`igl_heatseg.parameterization.split.cut_for_packing`,
    :func:`~igl_heatseg.parameterization.split.peel_for_packing`): they keep their chart's
    map, which is put together again.  Else ``None`` (the build then makes its own harmonic
    chart for a disk).

    Parameters
    ----------
    labels : (m,) int64
    surfaces : list of Surface
    charts : iterable
        :class:`igl_heatseg.pipeline.Chart` objects (``segment``, ``split_from``, ``cut.F``,
        ``cut.vertex_map``, ``param.UV``, ``param.bijective``, ``param.attempts``).

    Returns
    -------
    list of (ids (p,) int64, UV (p, 2) float64) or None, length k

    Examples
    --------
    >>> from types import SimpleNamespace as NS
    >>> cut = NS(F=np.array([[0, 1, 2]]), vertex_map=np.array([4, 5, 6]))
    >>> ch = NS(segment=0, split_from=None, cut=cut,
    ...         param=NS(UV=np.eye(3)[:, :2], bijective=True, attempts=[]))
    >>> free = Surface("freeform", {"centroid": np.zeros(3)})
    >>> ids, UV = chart_uvs(np.zeros(1, np.int64), [free], [ch])[0]
    >>> ids.tolist(), UV.tolist()
    ([4, 5, 6], [[1.0, 0.0], [0.0, 1.0], [0.0, 0.0]])
    """
    k = len(surfaces)
    by_segment: dict = {}
    for c in charts or []:
        by_segment.setdefault(int(c.segment), []).append(c)
    uv: list = [None] * k
    for a, cs in by_segment.items():
        if a >= k or surfaces[a].is_analytic:
            continue
        if len(cs) > 1 and not _pieces_of_one_map(cs):
            continue
        if any(c.cut is None or c.param is None or not bool(c.param.bijective) for c in cs):
            continue
        ids, UV = [], []
        for c in cs:
            used = np.unique(np.asarray(c.cut.F))
            ids.append(np.asarray(c.cut.vertex_map, dtype=np.int64)[used])
            UV.append(np.asarray(c.param.UV, dtype=np.float64)[used])
        ids, UV = np.concatenate(ids), np.concatenate(UV)
        uniq, first, inverse = np.unique(ids, return_index=True, return_inverse=True)
        if not np.array_equal(UV, UV[first][inverse]):  # cut open: a vertex has several UVs
            continue
        if np.all(np.isfinite(UV)):
            uv[a] = (uniq, UV[first])
    return uv if any(x is not None for x in uv) else None


def _pieces_of_one_map(charts) -> bool:
    """Whether the charts are pieces of one chart cut for packing (its map restricted)."""
    return len({c.split_from for c in charts}) == 1 and charts[0].split_from is not None and all(
        c.param is not None and c.param.attempts
        and c.param.attempts[-1].get("method") in PACKING_METHODS for c in charts)


def check_inputs(V, F, labels, surfaces, uv=None):
    """The arrays of :func:`~igl_heatseg.cad.build.build_brep`, checked and converted.

    Parameters
    ----------
    V : (n, 3) array_like of float
    F : (m, 3) array_like of int
    labels : (m,) array_like of int
        In ``0..len(surfaces) - 1``.
    surfaces : list of Surface
    uv : list of (ids (p,), UV (p, 2)) or None, optional
        One entry (or None) per segment.

    Returns
    -------
    V : (n, 3) float64
    F : (m, 3) int64
    labels : (m,) int64

    Raises
    ------
    MeshError
        Naming the array at fault and its shape, dtype or range.

    Examples
    --------
    >>> import numpy as np
    >>> z = Surface("plane", {"point": np.zeros(3), "normal": np.array([0., 0, 1])})
    >>> V = np.array([[0., 0, 0], [1, 0, 0], [0, 1, 0]])
    >>> check_inputs(V, np.array([[0, 1, 3]]), np.array([0]), [z])
    Traceback (most recent call last):
    ...
    igl_heatseg.errors.MeshError: F indexes vertices outside 0..2 (V has shape (3, 3))
    """
    V = np.asarray(V, dtype=np.float64)
    F = np.asarray(F)
    labels = np.asarray(labels)
    if V.ndim != 2 or V.shape[1] != 3 or len(V) == 0:
        raise MeshError(f"V must be (n, 3) float64, got shape {V.shape}")
    if F.ndim != 2 or F.shape[1] != 3 or len(F) == 0 or not np.issubdtype(F.dtype, np.integer):
        raise MeshError(f"F must be (m, 3) int64, got shape {F.shape} dtype {F.dtype}")
    F = F.astype(np.int64)
    if F.min() < 0 or F.max() >= len(V):
        raise MeshError(f"F indexes vertices outside 0..{len(V) - 1} (V has shape {V.shape})")
    if labels.shape != (len(F),) or not np.issubdtype(labels.dtype, np.integer):
        raise MeshError(f"labels must be ({len(F)},) int64, got shape {labels.shape}")
    labels = labels.astype(np.int64)
    k = len(surfaces)
    if labels.min() < 0 or labels.max() >= k:
        raise MeshError(f"labels must lie in 0..{k - 1} (one per surface; {k} surfaces given), "
                        f"found {labels.min()}..{labels.max()}")
    if not all(isinstance(s, Surface) for s in surfaces):
        raise MeshError("surfaces must be igl_heatseg.surfaces.model.Surface objects")
    if uv is not None:
        _validate_uv(uv, k, len(V))
    if not np.all(np.isfinite(V)):
        raise MeshError(f"V (shape {V.shape}) has non-finite coordinates")
    return V, F, labels


def _validate_uv(uv, k: int, n: int) -> None:
    if len(uv) != k:
        raise MeshError(f"uv must have one entry (or None) per segment: {k}, got {len(uv)}")
    for a, entry in enumerate(uv):
        if entry is None:
            continue
        ids, UV = (np.asarray(x) for x in entry)
        if ids.ndim != 1 or not np.issubdtype(ids.dtype, np.integer) or \
                (len(ids) and (ids.min() < 0 or ids.max() >= n)):
            raise MeshError(f"uv[{a}] vertex ids must be (p,) int64 in 0..{n - 1}, "
                            f"got shape {ids.shape} dtype {ids.dtype}")
        if UV.shape != (len(ids), 2) or not np.all(np.isfinite(UV)):
            raise MeshError(f"uv[{a}] UV must be ({len(ids)}, 2) finite float64, "
                            f"got shape {UV.shape}")
