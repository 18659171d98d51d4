"""The surface a segment's B-Rep face is built on: its fitted analytic surface, or a B-spline
over its chart when the analytic one is too far or misfits, or none (the segment is faceted).

The ``surfaces`` stage of :func:`~igl_heatseg.cad.build.build_brep`, and its first step: the
border faces of a segment that would be faceted for them, given to their neighbours
(:func:`settle`).
"""

from __future__ import annotations

import math

import numpy as np

from ._ocp import require_ocp

require_ocp()

from . import freeform, geometry  # noqa: E402
from .segments import settle_borders  # noqa: E402

__all__ = ["surface_for", "settle"]


def _segment(V, F, faces):
    """Vertex ids ``(p,)`` of a segment's faces and the faces renumbered into them."""
    verts, Fl = np.unique(F[faces], return_inverse=True)
    return verts, Fl.reshape(-1, 3)


def surface_for(a, s, V, F, faces, uv, tol, bspline=True, misfit=math.inf, notes=None):
    """The OCC surface to build segment ``a``'s face on, or why there is none.

    An analytic surface farther than ``tol`` from the segment, or whose vertex RMS distance is
    above ``misfit``, is replaced, when ``bspline``, by a B-spline fitted over the segment's
    chart (:func:`~igl_heatseg.cad.freeform.segment_chart`); in the second case only when the
    B-spline is the closer of the two. ``notes[a]`` then says why (for the report). A
    freeform segment gets a B-spline over its chart in ``uv`` (else a disk chart, or a
    one-to-one projection onto a plane for a segment with holes).

    Parameters
    ----------
    a : int
        Segment index (into ``uv`` and ``notes``).
    s : Surface
        The segment's fitted surface.
    V : (n, 3) float64
        Vertex positions.
    F : (m, 3) int64
        Triangles.
    faces : (f,) int64
        The segment's faces (rows of ``F``).
    uv : list of (ids, UV) or None
        Per segment, None or a chart: vertex ids ``(p,)`` and ``UV (p, 2)``.
    tol : float
        Largest vertex distance (model units) a surface may have from the segment.
    bspline : bool, optional
        Whether an analytic segment may become a B-spline.
    misfit : float, optional
        Vertex RMS distance above which an analytic surface within ``tol`` is compared with a
        B-spline.
    notes : dict or None, optional
        Filled with ``notes[a]``: why a B-spline replaced the analytic surface.

    Returns
    -------
    geom : Geom_Surface or None
    projector : geometry.Projector or None
    dev : float
        Largest vertex distance to ``geom`` (the analytic surface's when no face is built;
        NaN when nothing was fitted).
    reason : str or None
        None when ``geom`` is usable, else why the segment is faceted.

    Examples
    --------
    >>> import numpy as np
    >>> from igl_heatseg.surfaces.model import Surface
    >>> V = np.array([[0., 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0.1]])
    >>> F = np.array([[0, 1, 2], [1, 3, 2]])
    >>> z = Surface("plane", {"point": np.zeros(3), "normal": np.array([0., 0, 1])})
    >>> geom, proj, dev, why = surface_for(0, z, V, F, np.arange(2), None, tol=0.5)
    >>> round(dev, 6), why is None
    (0.1, True)
    >>> surface_for(0, z, V, F, np.arange(2), None, tol=0.01, bspline=False)[3]
    'surface deviates 0.1 from its segment (tol 0.01)'
    """
    verts, Fl = _segment(V, F, faces)
    if s.is_analytic:
        d = np.abs(s.distance(V[verts]))
        dev, rms = float(d.max()), float(np.sqrt(np.mean(d**2)))
        within = dev <= tol
        try:
            UV = freeform.segment_chart(s, V[verts], Fl) if bspline and (
                not within or rms > misfit) else None
            geom, err = (None, math.nan) if UV is None else \
                freeform.freeform_surface(V[verts], Fl, UV, tol)
        except Exception:  # noqa: BLE001 (OCC, numpy): within the tolerance, keep the surface
            if not within:
                raise
            UV, geom, err = None, None, math.nan
        if geom is not None and err <= tol and not (within and err >= dev):
            if notes is not None:
                notes[a] = (f"{s.kind} within the tolerance but misfit: vertex RMS {rms:.3g} "
                            f"above {misfit:.3g}" if within else
                            f"{s.kind} deviates {dev:.3g} (tol {tol:.3g})") + \
                    f"; B-spline within {err:.3g}, the {s.kind} within {dev:.3g}"
            return geom, geometry.Projector(None, geom), err, None
        if within:  # the analytic surface: no B-spline needed, or none closer
            geom = geometry.occ_surface(s)
            return geom, geometry.Projector(s, geom), dev, None
        why = f"surface deviates {dev:.3g} from its segment (tol {tol:.3g})"
        return None, None, dev, why if UV is None else f"{why}; B-spline fit error {err:.3g}"
    UV = None
    if uv is not None and uv[a] is not None:
        ids, UVg = (np.asarray(x) for x in uv[a])
        if not np.array_equal(np.unique(ids), verts):
            return None, None, math.nan, "given chart does not cover the segment's vertices"
        UV = np.zeros((len(verts), 2))
        UV[np.searchsorted(verts, ids)] = np.asarray(UVg, dtype=np.float64)
        UV = freeform.orient_chart(UV, Fl)  # mirrored if clockwise: normals follow the mesh
        if UV is None:
            return None, None, math.nan, "given chart folds (triangles of both orientations)"
    else:
        UV = freeform.disk_chart(V[verts], Fl)
        if UV is None:
            UV = freeform.projection_chart(V[verts], Fl)
        if UV is None:
            return None, None, math.nan, ("freeform segment is not a disk and no projection "
                                          "onto a plane is one-to-one")
    geom, err = freeform.freeform_surface(V[verts], Fl, UV, tol)
    if geom is None or err > tol:
        return None, None, err, f"B-spline fit error {err:.3g} above tol {tol:.3g}"
    return geom, geometry.Projector(None, geom), err, None


def settle(V, F, labels, surfaces, uv, tol, misfit, cache, notes=None):
    """Labels with the border faces moved (:func:`~igl_heatseg.cad.segments.settle_borders`)
    of the analytic segments that would be faceted for their distance to their surface, to
    neighbours within ``tol`` of their analytic surface.

    A segment farther than ``tol`` from its surface first gets its B-spline stand-in, as the
    build would (:func:`surface_for`, kept in ``cache`` under ``(segment, True)``); only a
    segment that gets none gives faces away. A stand-in built over a ragged border sews
    where the analytic surface over the settled border need not (a first tuning run with every
    analytic segment giving faces: on 3 parts, stand-ins replaced by their planes then lost 4,
    3 and 3 faces to sewing). A neighbour taking faces is within ``tol`` of its analytic
    surface (the misfit test of :func:`surface_for` may still give it a B-spline face: once
    on the fresh parts of 2026-11-29).

    Parameters
    ----------
    V : (n, 3) float64
    F : (m, 3) int64
    labels : (m,) int64
    surfaces : list of Surface, length k
    uv : list or None
        As for :func:`surface_for`.
    tol, misfit : float
        As for :func:`surface_for`.
    cache : dict
        ``(segment, bspline allowed) -> surface_for(...)``; the entries of the segments that
        gave or took faces are dropped.
    notes : dict or None, optional
        As for :func:`surface_for`.

    Returns
    -------
    labels : (m,) int64
    moved : (p, 3) int64
        Face, old segment, new segment.
    touched : set of int
        The segments that gave or took faces.

    Examples
    --------
    The floor and wall of :func:`~igl_heatseg.cad.segments.settle_borders`: the floor is
    faceted for the wall's triangle unless that triangle moves.

    >>> import numpy as np
    >>> from igl_heatseg.surfaces.model import Surface
    >>> V = np.array([[0., 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [1, 0, 1], [1, 1, 1]])
    >>> F = np.array([[0, 1, 2], [0, 2, 3], [1, 4, 5], [1, 5, 2]])
    >>> floor = Surface("plane", {"point": np.zeros(3), "normal": np.array([0., 0, 1])})
    >>> wall = Surface("plane", {"point": np.array([1., 0, 0]), "normal": np.array([1., 0, 0])})
    >>> labels, moved, touched = settle(V, F, np.array([0, 0, 0, 1]), [floor, wall], None,
    ...                                 0.01, np.inf, {})
    >>> labels.tolist(), moved.tolist(), sorted(touched)
    ([0, 0, 1, 1], [[2, 0, 1]], [0, 1])
    """
    givers, takers = set(), set()
    for a, s in enumerate(surfaces):
        if not s.is_analytic:
            continue
        faces = np.flatnonzero(labels == a)
        if np.abs(s.distance(V[np.unique(F[faces])])).max(initial=0.0) <= tol:
            takers.add(a)
            continue
        if (a, True) not in cache:
            try:
                cache[(a, True)] = surface_for(a, s, V, F, faces, uv, tol, misfit=misfit,
                                               notes=notes)
            except Exception:  # noqa: BLE001 (OCC, numpy): the build says why, faceting it
                continue
        if cache[(a, True)][3] is not None:
            givers.add(a)
    labels, moved = settle_borders(V, F, labels, surfaces, tol, givers, takers)
    touched = set(moved[:, 1].tolist()) | set(moved[:, 2].tolist())
    for a in touched:
        cache.pop((a, True), None)
        cache.pop((a, False), None)
    return labels, moved, touched
