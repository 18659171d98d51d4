"""Blends split down their middle: a narrow fillet dealt out half to each of the two faces it
joins, found along their seam and given a segment of its own (:func:`seam_blends`); and the
sphere where three or more fillets of one radius meet, dealt out between them
(:func:`corner_blends`).

On a noisy mesh a fillet one or two triangles wide has no seed of its own: the heat fields of
the two faces it joins meet along its middle, and each takes half. Each half lies close to its
neighbour's surface (a quarter fillet of radius ``r`` leaves a plane by at most
``r (1 - cos 45)``, 0.3 ``r``), so no face is far enough off it to be a stray for
:mod:`.refine`; yet one surface explains the seam far better than the two do. The case: f21
housing_s21002_frontal_n0.1, eight fillets of radius 2.9 at noise 0.31, each dealt out between
two planes; the planes deviated from their segments by 2.8-3.5 (the CAD tolerance was 1.16)
and the B-Rep stage faceted ten of them.
"""
from __future__ import annotations

import logging

import numpy as np
import scipy.sparse as sp

from ..mesh.geometry import face_areas
from .model import Surface
from .primitives import fitted_surface
from .samples import segment_adjacency, vertex_samples
from .segment_fit import corner_rms, explains, fit_faces, refit_segments
from .split import evidence

__all__ = ["seam_blends", "corner_blends", "corner_sphere", "SEAM_BEAT", "SEAM_OWN",
           "SEAM_MIN_FACES", "SEAM_MAX_SHARE", "CORNER_RADIUS_SPREAD", "CORNER_AXIS_GAP",
           "CORNER_BEAT", "CORNER_MIN_FACES"]

log = logging.getLogger(__name__)

#: The seam's own surface must fit its faces' corners this many times closer (RMS) than the two
#: segments' surfaces do (on the housing's fillets: 2.0-2.9; a noisy coarse plate's seam, which
#: no blend crosses, 1.7) ...
SEAM_BEAT = 2.0

#: ... and the two surfaces must fit the seam this many times worse than their whole segments
#: (a gear's tooth flank, an involute typed plane at 3 noise levels, fits every band of itself
#: as badly as the rest).
SEAM_OWN = 1.5

#: ... and the seam must have at least this many faces ...
SEAM_MIN_FACES = 20

#: ... and hold at most this share of either segment's faces (a blend runs along the border of
#: two larger faces; on a coarse export every face of a fan touches its border).
SEAM_MAX_SHARE = 0.5

#: A corner's cylinders agree on their radius within this share of their mean radius ...
CORNER_RADIUS_SPREAD = 0.25

#: ... their axes pass within this share of the radius (plus the tolerance) of the point
#: nearest to all of them, the sphere's centre ...
CORNER_AXIS_GAP = 0.1

#: ... the sphere fitted to the corner's faces fits them this many times closer (RMS) than the
#: cylinders that hold them (a rounded box's corner leaves its fillets by up to ``0.18 r``) ...
CORNER_BEAT = 1.5

#: ... and the corner has at least this many faces.
CORNER_MIN_FACES = 4


def _two_surface_rms(V, F, labels, fits, faces) -> float:
    """RMS distance of ``faces``' corners to their own segment's surface."""
    d2 = 0.0
    for k in np.unique(labels[faces]):
        own = faces[labels[faces] == k]
        d2 += float((fits[k].distance(V[F[own]].reshape(-1, 3)) ** 2).sum())
    return float(np.sqrt(d2 / (3 * len(faces))))


def seam_blends(V, F, labels, fits: dict, tol: float, TT, W=None, FN=None,
                nxt: int | None = None) -> int:
    """Give the faces along the seam of two analytic segments a segment of their own when one
    surface explains them clearly better than the two segments' surfaces (module docstring).

    The seam of segments ``a`` and ``b`` is their faces with a corner on the border between
    them. It becomes a segment when its own fit (:func:`~.segment_fit.fit_faces`) is analytic,
    within ``tol`` and evidence (:func:`~.split.evidence`), its RMS at least :data:`SEAM_BEAT`
    times below the two surfaces' RMS on the seam, which must itself be :data:`SEAM_OWN` times
    their RMS on their whole segments, and the seam has :data:`SEAM_MIN_FACES` faces or more
    and at most :data:`SEAM_MAX_SHARE` of either segment. A face goes to one seam at most. The
    refinement's boundary moves then settle the new segment's border.

    Parameters
    ----------
    V : (n, 3) float64
        Positions (distances are measured here).
    F : (m, 3) int64
        Triangles.
    labels : (m,) int64
        Segment of every face, changed in place.
    fits : dict
        Surface of every segment, changed in place (the new segments, and their neighbours
        refitted on what they keep).
    tol : float
        Fit tolerance (model units).
    TT : (m, 3) int64
        ``igl.triangle_triangle_adjacency(F)[0]``.
    W : (n, 3) float64, optional
        Positions the normals come from (a denoised copy of ``V``).
    FN : (m, 3) float64, optional
        Unit face normals.
    nxt : int, optional
        Label of the first new segment (default: one above the largest in ``fits``).

    Returns
    -------
    int
        Segments made.

    Examples
    --------
    A quarter fillet of radius 0.65, two facets wide, between two planes, with noise, and dealt
    out down its middle:

    >>> import igl, numpy as np
    >>> from igl_heatseg.surfaces.segment_fit import fit_faces
    >>> t = np.pi / 4 * np.arange(3)
    >>> x = np.r_[np.arange(-6.0, 0, 0.5), 0.65 * np.sin(t), np.full(13, 0.65)]
    >>> z = np.r_[np.zeros(12), 0.65 * (1 - np.cos(t)), 0.65 + 0.5 * np.arange(1, 14)]
    >>> y = np.arange(0.0, 8.01, 0.5)
    >>> V = np.c_[np.repeat(x, len(y)), np.tile(y, len(x)), np.repeat(z, len(y))]
    >>> V += np.random.default_rng(1).normal(scale=0.05, size=V.shape)
    >>> i = np.arange(len(V)).reshape(len(x), len(y))[:-1, :-1].ravel()
    >>> F = np.r_[np.c_[i, i + len(y), i + len(y) + 1], np.c_[i, i + len(y) + 1, i + 1]]
    >>> row = np.r_[i, i] // len(y)                 # profile row of every face
    >>> labels = (row >= 13).astype(np.int64)       # rows 12, 13: the fillet
    >>> fits = {k: fit_faces(V, F, np.flatnonzero(labels == k), 0.12) for k in (0, 1)}
    >>> TT = igl.triangle_triangle_adjacency(F)[0]
    >>> seam_blends(V, F, labels, fits, 0.12, TT), fits[2].kind
    (1, 'cylinder')
    >>> np.unique(row[labels == 2]).tolist()
    [12, 13]
    """
    nxt = max(fits) + 1 if nxt is None else nxt
    fa, fb = segment_adjacency(F, labels, TT)
    if len(fa) == 0:
        return 0
    m = len(F)
    # vertex -> faces incidence, to gather the faces around a seam's vertices
    VF = sp.csr_matrix((np.ones(3 * m), (F.ravel(), np.repeat(np.arange(m), 3))),
                       shape=(len(V), m))
    lo, hi = np.minimum(labels[fa], labels[fb]), np.maximum(labels[fa], labels[fb])
    counts = np.bincount(labels)
    taken = np.zeros(m, dtype=bool)
    made, touched = 0, set()
    for a, b in np.unique(np.c_[lo, hi], axis=0).tolist():
        if not (fits[a].is_analytic and fits[b].is_analytic):
            continue
        on = (lo == a) & (hi == b)
        verts = np.intersect1d(F[fa[on]], F[fb[on]])
        band = np.unique(VF[verts].indices)
        band = band[((labels[band] == a) | (labels[band] == b)) & ~taken[band]]
        share = max((labels[band] == a).sum() / counts[a], (labels[band] == b).sum() / counts[b])
        if len(band) < SEAM_MIN_FACES or share > SEAM_MAX_SHARE:
            continue
        u = fit_faces(V, F, band, tol, W=W, FN=FN)
        if not (explains(u, tol) and evidence(F, band, u)):
            continue
        two = _two_surface_rms(V, F, labels, fits, band)
        if u.rms * SEAM_BEAT > two or two < SEAM_OWN * max(fits[a].rms, fits[b].rms):
            continue
        log.debug("seam of segments %d and %d (%d faces): one %s within %.3g, the two within "
                  "%.3g", a, b, len(band), u.kind, u.rms, two)
        taken[band] = True
        touched.update((a, b))
        labels[band] = nxt
        fits[nxt] = u
        nxt += 1
        made += 1
    refit_segments(V, F, labels, fits, touched, tol, W, FN)
    return made


def _vertex_label_incidence(F, labels, n) -> sp.csr_matrix:
    """(n, k) sparse: the labels of the faces around every vertex (entries: face counts)."""
    M = sp.csr_matrix((np.ones(F.size), (F.ravel(), np.repeat(labels, 3))),
                      shape=(n, int(labels.max()) + 1))
    M.sum_duplicates()
    return M


def _axes_meet(cyls) -> tuple[np.ndarray, float, float]:
    """The point nearest to the axes of ``cyls`` (least squares), the largest axis distance to
    it, and the smallest eigenvalue of the normal matrix (0 when the axes are parallel)."""
    A, b = np.zeros((3, 3)), np.zeros(3)
    projs = []
    for s in cyls:
        d = s.params["axis"]
        P = np.eye(3) - np.outer(d, d)
        projs.append((P, s.params["point"]))
        A += P
        b += P @ s.params["point"]
    eig = float(np.linalg.eigvalsh(A)[0])
    if eig < 0.5:
        return np.zeros(3), np.inf, eig
    c = np.linalg.solve(A, b)
    gap = max(float(np.linalg.norm(P @ (c - p))) for P, p in projs)
    return c, gap, eig


def _fillets_meet(x, ks, fits, tol):
    """(centre, mean radius, labels) of the cylinders ``ks`` around a vertex at ``x`` when at
    least three of them meet in a corner (radii within CORNER_RADIUS_SPREAD, axes within
    CORNER_AXIS_GAP of one point, ``x`` about a radius from it), dropping the cylinder whose
    axis passes farthest while the rest do not (a corner's piece typed cylinder); else None."""
    ks = sorted(ks)
    while len(ks) >= 3:
        r = np.array([fits[k].params["radius"] for k in ks])
        c, gap, _ = _axes_meet([fits[k] for k in ks])
        rm = float(r.mean())
        if (np.ptp(r) <= CORNER_RADIUS_SPREAD * rm and gap <= CORNER_AXIS_GAP * rm + tol
                and abs(np.linalg.norm(x - c) - rm) <= CORNER_RADIUS_SPREAD * rm + tol):
            return c, rm, ks
        if not np.isfinite(gap):
            return None
        far = [np.linalg.norm((np.eye(3) - np.outer(a, a)) @ (c - fits[k].params["point"]))
               for k in ks for a in [fits[k].params["axis"]]]
        ks.pop(int(np.argmax(far)))
    return None


def corner_blends(V, F, labels, fits: dict, tol: float, W=None, FN=None,
                  nxt: int | None = None) -> list:
    """Give the sphere where three or more cylinders of one radius meet a segment of its own,
    out of the faces the cylinders' segments hold beyond it (module docstring).

    A rounded box's corner is a sphere of the fillets' radius, centred where their axes meet,
    and each fillet ends on the great circle of the sphere across its axis. Without a seed of
    its own (a noisy irregular mesh: 17 faces a corner) it is dealt out between the fillets.
    The corner here: a vertex where the segments of three or more cylinders meet, their radii
    within :data:`CORNER_RADIUS_SPREAD`, their axes within :data:`CORNER_AXIS_GAP` of one
    point ``c`` (a cylinder whose axis misses while the others meet is left out: a piece of
    the corner typed cylinder). Its faces: those of the cylinders' segments within the radius
    (plus 3 ``tol``) of ``c`` and beyond ``c`` along their own axis (the segment's bulk on the
    other side), and any other segment lying wholly that close to ``c`` that touches them or
    the vertex. They become a segment when a sphere fits them :data:`CORNER_BEAT` times closer
    (RMS) than their segments' surfaces do (a freeform piece fits nothing), they are
    :data:`CORNER_MIN_FACES` faces or more, and :func:`corner_sphere` gives them a surface
    (the sphere the fillets imply where that is within ``tol``).

    Parameters
    ----------
    V : (n, 3) float64
        Positions (distances are measured here).
    F : (m, 3) int64
        Triangles.
    labels : (m,) int64
        Segment of every face, changed in place.
    fits : dict
        Surface of every segment, changed in place (the corners, and the segments they came
        from refitted on what they keep).
    tol : float
        Fit tolerance (model units).
    W : (n, 3) float64, optional
        Positions the normals come from (a denoised copy of ``V``).
    FN : (m, 3) float64, optional
        Unit face normals.
    nxt : int, optional
        Label of the first new segment (default: one above the largest in ``fits``).

    Returns
    -------
    list of int
        The labels of the corners made.

    Examples
    --------
    The corner of a box rounded with radius 1: an octant of a sphere dealt out between three
    fillets (each face to the one it lies nearest to), each fillet a quarter tube of length 4:

    >>> import igl, numpy as np
    >>> from igl_heatseg.surfaces.segment_fit import fit_faces
    >>> V, F = igl.loop(*igl.icosahedron(), 2)
    >>> V /= np.linalg.norm(V, axis=1, keepdims=True)
    >>> octant = np.flatnonzero((V[F] > -1e-9).all(axis=(1, 2)))
    >>> def fillet(axis):                           # along -axis, from the sphere's equator
    ...     t = np.linspace(0, np.pi / 2, 7)
    ...     j, k = [i for i in range(3) if i != axis]
    ...     P = np.zeros((5, 7, 3))
    ...     P[..., j], P[..., k] = np.cos(t), np.sin(t)
    ...     P[..., axis] = -np.arange(5)[:, None]
    ...     i = (np.arange(4)[:, None] * 7 + np.arange(6)).ravel()
    ...     return P.reshape(-1, 3), np.r_[np.c_[i, i + 1, i + 8], np.c_[i, i + 8, i + 7]]
    >>> Vs, Fs = [V], [F[octant]]
    >>> for a in range(3):
    ...     P, T = fillet(a)
    ...     Fs.append(T + sum(len(v) for v in Vs))
    ...     Vs.append(P)
    >>> V, F = np.vstack(Vs), np.vstack(Fs)
    >>> labels = np.r_[np.argmin(V[F[:len(octant)]].mean(axis=1), axis=1),
    ...                np.repeat([0, 1, 2], 48)]
    >>> fits = {k: fit_faces(V, F, np.flatnonzero(labels == k), 0.1) for k in range(3)}
    >>> [fits[k].kind for k in range(3)]
    ['cylinder', 'cylinder', 'cylinder']
    >>> corner_blends(V, F, labels, fits, 0.1), fits[3].kind
    ([3], 'sphere')
    >>> np.flatnonzero(labels == 3).tolist() == list(range(len(octant)))
    True
    """
    nxt = max(fits) + 1 if nxt is None else nxt
    cyl = {k for k, s in fits.items() if s.kind == "cylinder"}
    if len(cyl) < 3:
        return []
    M = _vertex_label_incidence(F, labels, len(V))
    C = V[F].mean(axis=1)
    corners: list = []  # [centre, radius, set of labels, junction vertices]
    for v in np.flatnonzero(np.diff(M.indptr) >= 3):
        around = M.indices[M.indptr[v]:M.indptr[v + 1]]
        met = _fillets_meet(V[v], [int(k) for k in around if k in cyl], fits, tol)
        if met is None:
            continue
        c, rm, ks = met
        for corner in corners:  # the same corner seen from another junction vertex
            if np.linalg.norm(corner[0] - c) <= CORNER_RADIUS_SPREAD * rm + tol:
                corner[2].update(ks)
                corner[3].append(v)
                break
        else:
            corners.append([c, rm, set(ks), [v]])
    taken = np.zeros(len(F), dtype=bool)
    made, touched = [], set()
    for c, rm, ks, verts in corners:
        reach = rm + 3 * tol
        near = np.linalg.norm(C - c, axis=1) <= reach
        patch = []
        for k in sorted(ks):
            fk = np.flatnonzero(labels == k)
            t = (C[fk] - c) @ fits[k].params["axis"]
            bulk = float(np.mean(t))
            if abs(bulk) < 0.5 * rm:  # a cylinder running past the corner, not ending at it
                continue
            patch.append(fk[(np.sign(bulk) * t < 0) & near[fk]])
        patch = np.unique(np.concatenate(patch)) if patch else np.zeros(0, dtype=np.int64)
        around = np.union1d(M[verts].indices, M[np.unique(F[patch])].indices)
        for k in around:  # a piece of the corner with a segment already
            fk = np.flatnonzero(labels == k)
            if k not in ks and near[fk].all():
                patch = np.union1d(patch, fk)
        patch = patch[~taken[patch]]
        if len(patch) < CORNER_MIN_FACES:
            continue
        guess = Surface("sphere", {"center": c, "radius": rm})
        free = fit_faces(V, F, patch, tol, kinds=("sphere",), W=W, FN=FN)  # the best sphere
        u = corner_sphere(V, F, patch, tol, guess, W, FN, free)
        if u is None:
            continue
        best = min(u.rms, free.rms) if free.kind == "sphere" else u.rms
        own = [corner_rms(V, F, patch[labels[patch] == k], fits[k]) for k in
               np.unique(labels[patch])]
        own_rms = float(np.sqrt(np.mean(np.concatenate(own) ** 2)))
        if own_rms < CORNER_BEAT * best:
            continue
        log.debug("corner at %s: a sphere of radius %.3g within %.3g over %d faces of "
                  "segments %s (within %.3g)", np.round(c, 3), u.params["radius"], u.rms,
                  len(patch), sorted(set(labels[patch].tolist())), own_rms)
        touched.update(int(k) for k in np.unique(labels[patch]))
        taken[patch] = True
        labels[patch] = nxt
        fits[nxt] = u
        made.append(nxt)
        nxt += 1
    refit_segments(V, F, labels, fits, touched, tol, W, FN)
    return made


def corner_sphere(V, F, faces, tol: float, guess: Surface, W=None, FN=None,
                  free: Surface | None = None) -> Surface | None:
    """The sphere of a corner's faces: ``guess`` (the sphere its fillets imply, tangent to
    them), when it is within ``tol`` of the faces; else the sphere fitted to them, when that is
    within ``tol`` and its radius within :data:`CORNER_RADIUS_SPREAD` of ``guess``'s; else None.

    A fit to a few noisy faces leaves the radius loose (3.42 for fillets of 3.1 on tuning-3
    rounded_box_s6011_irregular_n0.05), and a B-Rep edge between a sphere and a fillet it
    should touch tangentially is then an ill-conditioned intersection.

    Parameters
    ----------
    V : (n, 3) float64
    F : (m, 3) int64
    faces : (f,) int64
        The corner's faces.
    tol : float
        Fit tolerance (model units).
    guess : Surface
        A sphere (centre where the fillets' axes meet, their mean radius).
    W : (n, 3) float64, optional
        Positions the normals come from.
    FN : (m, 3) float64, optional
        Unit face normals.
    free : Surface, optional
        The faces' sphere fit, when the caller has it (``fit_faces`` with ``kinds=("sphere",)``).

    Returns
    -------
    Surface or None

    Examples
    --------
    >>> import igl, numpy as np
    >>> V, F = igl.loop(*igl.icosahedron(), 2)
    >>> V /= np.linalg.norm(V, axis=1, keepdims=True)
    >>> cap = np.flatnonzero((V[F][..., 2] > 0.9).all(axis=1))        # a small cap
    >>> guess = Surface("sphere", {"center": np.zeros(3), "radius": 1.0})
    >>> s = corner_sphere(V, F, cap, 0.01, guess)
    >>> s.kind, round(s.params["radius"], 6), s.rms < 1e-6
    ('sphere', 1.0, True)
    >>> corner_sphere(V, F, cap, 0.01, Surface("sphere", {"center": np.zeros(3),
    ...                                                   "radius": 1.02})).params["radius"]
    1.0
    """
    P, N, w = vertex_samples(V, F, faces, W)
    u = fitted_surface("sphere", dict(guess.params), P, N, w, float(face_areas(V, F[faces]).sum()))
    if u is not None and explains(u, tol):
        return u
    u = fit_faces(V, F, faces, tol, kinds=("sphere",), W=W, FN=FN) if free is None else free
    r = guess.params["radius"]
    if (u.kind == "sphere" and explains(u, tol)
            and abs(u.params["radius"] - r) <= CORNER_RADIUS_SPREAD * r):
        return u
    return None
