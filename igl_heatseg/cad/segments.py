"""What :func:`~igl_heatseg.cad.build.build_brep` needs from a segmentation that did not fit
surfaces (the paper's mode) or that has charts (the pipeline): one surface per segment, fitted
without relabelling, and the certified chart UVs of the segments.

No OpenCASCADE here: these functions run before the build.
"""

from __future__ import annotations

import numpy as np

from igl_heatseg.surfaces.model import Surface
from igl_heatseg.surfaces.segment_fit import MIN_FIT_FACES, vertex_samples
from igl_heatseg.surfaces.select import fit_surface
from igl_heatseg.surfaces.tolerance import vertex_tolerance

__all__ = ["fit_segment_surfaces", "chart_uvs"]


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


def chart_uvs(labels: np.ndarray, surfaces, charts) -> list:
    """The ``uv`` argument of :func:`~igl_heatseg.cad.build.build_brep` from pipeline charts.

    A segment gets its chart's UV when it is freeform, is exactly one chart, that chart was
    not cut (one UV per mesh vertex) and its map is certified bijective; else ``None`` (the
    build then makes its own harmonic chart for a disk).

    Parameters
    ----------
    labels : (m,) int64
    surfaces : list of Surface
    charts : iterable
        :class:`igl_heatseg.pipeline.Chart` objects (``segment``, ``cut.F``,
        ``cut.vertex_map``, ``param.UV``, ``param.bijective``).

    Returns
    -------
    list of (ids (p,) int64, UV (p, 2) float64) or None, length k
    """
    k = len(surfaces)
    charts = list(charts or [])
    per_segment = np.bincount([c.segment for c in charts], minlength=k) if charts else \
        np.zeros(k, np.int64)
    uv: list = [None] * k
    for c in charts:
        a = int(c.segment)
        if a >= k or surfaces[a].is_analytic or per_segment[a] != 1:
            continue
        if c.cut is None or c.param is None or not bool(c.param.bijective):
            continue
        used = np.unique(np.asarray(c.cut.F))
        ids = np.asarray(c.cut.vertex_map, dtype=np.int64)[used]
        if len(np.unique(ids)) != len(ids):  # cut open: a mesh vertex has several UVs
            continue
        UV = np.asarray(c.param.UV, dtype=np.float64)[used]
        if np.all(np.isfinite(UV)):
            uv[a] = (ids, UV)
    return uv if any(x is not None for x in uv) else None
