"""Blends split down their middle: a narrow fillet dealt out half to each of the two faces it
joins, found along their seam and given a segment of its own (:func:`seam_blends`).

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

from .samples import segment_adjacency
from .segment_fit import explains, fit_faces, refit_segments
from .split import evidence

__all__ = ["seam_blends", "SEAM_BEAT", "SEAM_OWN", "SEAM_MIN_FACES", "SEAM_MAX_SHARE"]

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
