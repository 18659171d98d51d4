"""A noisy segment that fits worse than the noise gives its neighbours the faces on their surfaces.

Two true faces joined smoothly (a pipe's cylinder running tangentially into its bend's torus)
may stay in one segment whose surface explains it within the tolerance, only more loosely than
the part's other segments fit: on tuning pipe_elbow_s1031_irregular_n0.2 a piece of 725 faces,
three quarters of the bend's torus and a quarter of the straight cylinder, fitted a cylinder at
1.28 times the noise (the other segments: 0.92-1.04 times). Its faces lie within the noise of
the neighbouring torus and cylinder segments' surfaces, each flooded from their shared
border; those segments take them (:func:`absorb_loose`).

A loose segment that holds two true faces with no segment of their own next to it (a
counterbore's flat bottom ring and its wall, one cone at 1.4-1.8 times the noise on tuning
plate_s1012_irregular_n0.1) is split instead, at a tolerance near the noise
(:func:`split_loose`).
"""
from __future__ import annotations

import math
from collections import deque

import numpy as np

from ..mesh.geometry import face_areas
from ..mesh.topology import label_pieces
from .segment_fit import GROW_ANGLE, corner_rms, fit_faces, normal_angle
from .tolerance import K_NOISE

__all__ = [
    "absorb_loose",
    "split_loose",
    "LOOSE_RATIO",
    "LOOSE_MIN_FACES",
    "LOOSE_ON_RATIO",
    "LOOSE_TAKE_SHARE",
    "LOOSE_SPLIT_K",
    "LOOSE_SPLIT_SHARE",
]

#: A segment is loose when its RMS is above this times the noise level: the median RMS of the
#: analytic segments of at least LOOSE_MIN_FACES faces, floored at tol / K_NOISE (the noise the
#: tolerance was made from). A receiving segment must stay within it too.
LOOSE_RATIO = 1.15

#: Segments of fewer faces are neither loose, nor receivers, nor counted in the noise level
#: (their RMS is no measure of the noise: a few faces fit better).
LOOSE_MIN_FACES = 30

#: A face goes to a neighbour when its corners' RMS distance to the neighbour's surface is at
#: most this times the noise level (three corners at noise sigma exceed 2 sigma with
#: probability 0.7 %), its normal within GROW_ANGLE of it, and it is reached from their shared
#: border through such faces.
LOOSE_ON_RATIO = 2.0

#: ... and only when the neighbours take at least this share of the loose segment's area (less
#: is a ragged border, which the boundary moves deal with).
LOOSE_TAKE_SHARE = 0.15

#: split_loose: a loose segment is split (region growing, then RANSAC) at this times the median
#: RMS of the part's analytic segments (unfloored; at most tol), and its pieces refitted at tol.
#: Tried on tuning at 1.5, 2 and 2.5 x: at 2 and more the growth still took the counterbore's
#: wall and floor into one plane (plate_s1012: pieces at 1.3-1.9 x the noise).
LOOSE_SPLIT_K = 1.5

#: ... and only when its second largest piece holds at least this share of its area: a fillet's
#: cylinder holding the faces of its corner sphere sheds them as a scrap, which the corner
#: blends (:func:`~.seams.corner_blends`) need in place.
LOOSE_SPLIT_SHARE = 0.15


def _flood(TT, faces, pos, start, ok) -> np.ndarray:
    """Faces (positions in ``faces``) reached from ``start`` through ``ok`` faces."""
    seen = np.zeros(len(faces), dtype=bool)
    seen[start] = True
    queue = deque(start.tolist())
    while queue:
        for j in TT[faces[queue.popleft()]]:
            p = pos[j] if j >= 0 else -1
            if p >= 0 and ok[p] and not seen[p]:
                seen[p] = True
                queue.append(p)
    return seen


def absorb_loose(V, F, labels, fits: dict, tol: float, TT, W=None, FN=None) -> int:
    """Give the faces of loose segments to the neighbours whose surfaces they lie on.

    A segment of a noisy mesh is loose when its fit's RMS is above LOOSE_RATIO x the noise level
    (see :data:`LOOSE_RATIO`). Each neighbour of LOOSE_MIN_FACES faces or more whose analytic
    surface fits at the noise floods the loose segment from their shared border through the
    faces within LOOSE_ON_RATIO x noise of its surface (normals within GROW_ANGLE); a face
    reached by two goes to the closer. The faces go when

    - the neighbours reach at least LOOSE_TAKE_SHARE of the area;
    - they fit their receivers' surfaces LOOSE_RATIO times better (RMS) than the segment's own
      surface fits them (a small fillet between two planes at noise 0.2 lies within the noise
      of both planes, but no closer to them than to its cylinder);
    - they fit their receivers' surfaces about as well as the receivers' own faces do (pooled
      RMS over the receivers' RMS at most LOOSE_RATIO: a small corner sphere between three
      fillets lies within the noise of the fillets' cylinders extended, not on them);
    - every receiver's refit stays within LOOSE_RATIO x noise (or its own RMS), and every
      piece of what is left fits within LOOSE_RATIO x noise.

    Pieces under LOOSE_MIN_FACES faces measure no surface: they go to the neighbour they touch
    most (a face whose noisy normal is off stops the flood). Labels and fits in place; the
    first piece left keeps the segment's id, the others get new ones.

    Parameters
    ----------
    V : (n, 3) float64
    F : (m, 3) int64
    labels : (m,) int64
        Segment id per face; changed in place.
    fits : dict
        Segment id -> Surface; changed in place (receivers refitted, pieces added, a segment
        wholly taken removed).
    tol : float
        Fit tolerance (model units).
    TT : (m, 3) int64
        Triangle-triangle adjacency (-1 on the border).
    W : (n, 3) float64, optional
        Positions for the fits' normals (see :func:`~.segment_fit.fit_faces`).
    FN : (m, 3) float64, optional
        Unit face normals.

    Returns
    -------
    int
        Loose segments that gave their faces away.

    Examples
    --------
    A noisy plane (arc length ``u < 0``) running tangentially into a 90-degree roll of radius 6,
    in three segments: the plane, a piece from ``u = -3`` to ``3`` across the join, the roll. The
    piece fits a cylinder at 2.4 times the plane's RMS; its faces go to the plane and the roll,
    whose border is then at the join (within a face).

    >>> import igl, numpy as np
    >>> from igl_heatseg.mesh.geometry import face_normals
    >>> from igl_heatseg.surfaces.segment_fit import fit_faces
    >>> u, w = np.meshgrid(np.linspace(-20, 9.4, 50), np.linspace(0, 20, 34), indexing="ij")
    >>> t = np.clip(u, 0, None) / 6
    >>> V = np.c_[np.where(u < 0, u, 6 * np.sin(t)).ravel(), w.ravel(),
    ...           np.where(u < 0, 0, 6 - 6 * np.cos(t)).ravel()]
    >>> i = (np.arange(49)[:, None] * 34 + np.arange(33)[None, :]).ravel()
    >>> F = np.r_[np.c_[i, i + 34, i + 1], np.c_[i + 1, i + 34, i + 35]]
    >>> V += np.random.default_rng(0).normal(0, 0.02, V.shape)
    >>> uf = u.ravel()[F].mean(axis=1)
    >>> labels = np.digitize(uf, [-3, 3]).astype(np.int64)
    >>> TT, FN = igl.triangle_triangle_adjacency(F)[0], face_normals(V, F)
    >>> fits = {k: fit_faces(V, F, np.flatnonzero(labels == k), 0.06, FN=FN) for k in (0, 1, 2)}
    >>> [fits[k].kind for k in fits], round(fits[1].rms / fits[0].rms, 1)
    (['plane', 'cylinder', 'cylinder'], 2.4)
    >>> absorb_loose(V, F, labels, fits, 0.06, TT, FN=FN), sorted(fits)
    (1, [0, 2])
    >>> bool(uf[labels == 0].max() < 0.6 and uf[labels == 2].min() > -0.6)
    True
    """
    found = _noise(labels, fits, tol)
    if found is None:
        return 0
    big, _, noise = found
    area = face_areas(V, F)
    loose = sorted((k for k in big if fits[k].rms > LOOSE_RATIO * noise),
                   key=lambda k: -fits[k].rms)
    pos = np.full(len(F), -1, dtype=np.int64)
    nxt = int(labels.max()) + 1
    n = 0
    for k in loose:
        faces = np.flatnonzero(labels == k)
        if not len(faces) or k not in fits or fits[k].rms <= LOOSE_RATIO * noise:
            continue
        pos[faces] = np.arange(len(faces))
        nl = np.where(TT[faces] >= 0, labels[np.maximum(TT[faces], 0)], -1)
        best = np.full(len(faces), np.inf)
        who = np.full(len(faces), -1, dtype=np.int64)
        for c in np.unique(nl).tolist():
            if c < 0 or c == k or c not in big or fits[c].rms > LOOSE_RATIO * noise:
                continue
            d = corner_rms(V, F, faces, fits[c])
            ok = (d <= LOOSE_ON_RATIO * noise) & (normal_angle(V, F, FN, faces, fits[c])
                                                   <= GROW_ANGLE)
            reached = _flood(TT, faces, pos, np.flatnonzero((nl == c).any(axis=1) & ok), ok)
            closer = reached & (d < best)
            best[closer], who[closer] = d[closer], c
        pos[faces] = -1
        taken = who >= 0
        if area[faces[taken]].sum() < LOOSE_TAKE_SHARE * area[faces].sum():
            continue
        own = corner_rms(V, F, faces[taken], fits[k])
        if LOOSE_RATIO * np.sqrt(np.mean(best[taken] ** 2)) > np.sqrt(np.mean(own**2)):
            continue  # its own surface fits them about as well (a small fillet between planes)
        plan = _plan(V, F, labels, fits, tol, TT, W, FN, faces, who, noise)
        if plan is None:
            continue
        receivers, pieces = plan
        for c, s in receivers.items():
            labels[faces[who == c]] = c
            fits[c] = s
        del fits[k]
        for part, s in pieces:
            if s is None:  # a scrap of the rest: to the neighbour it touches most
                nb = labels[TT[part][TT[part] >= 0]]
                nb = nb[(nb != k) & np.isin(nb, list(fits))]
                if len(nb):
                    labels[part] = np.bincount(nb).argmax()
                    continue
                s = fit_faces(V, F, part, tol, W=W, FN=FN)
            lab = k if k not in fits else nxt
            nxt += lab == nxt
            labels[part] = lab
            fits[lab] = s
        n += 1
    return n


def _noise(labels, fits: dict, tol: float):
    """The segments that measure the noise (analytic, LOOSE_MIN_FACES faces or more), their
    median RMS, and the noise level (that median floored at ``tol / K_NOISE``); None when
    there is no such segment."""
    size = dict(zip(*np.unique(labels, return_counts=True), strict=True))
    big = {k for k, s in fits.items() if s.is_analytic and size.get(k, 0) >= LOOSE_MIN_FACES}
    if not big:
        return None
    med = float(np.median([fits[k].rms for k in big]))
    return big, med, max(med, tol / K_NOISE)


def split_loose(V, F, labels, fits: dict, tol: float, split) -> int:
    """Split the loose segments that fall apart into surfaces fitting clearly better.

    A segment is loose as for :func:`absorb_loose` (analytic, LOOSE_MIN_FACES faces or more,
    RMS above LOOSE_RATIO x the noise level). ``split`` cuts it at LOOSE_SPLIT_K x the median
    RMS of the part's analytic segments (at most ``tol``): the growth then stops where a face
    leaves a surface by more than the noise, not by the tolerance (2.5 noise levels, within
    which one cone took a counterbore's floor and wall). The pieces are kept when their
    pooled RMS (area-weighted) is LOOSE_RATIO times below the segment's and the second largest
    holds LOOSE_SPLIT_SHARE of the area; a single surface that fits loosely everywhere (a
    noisier patch) falls into pieces that fit no better, and a scrap shed from one surface is
    left to the passes that deal out scraps.

    Parameters
    ----------
    V : (n, 3) float64
    F : (m, 3) int64
    labels : (m,) int64
        Segment id per face; changed in place (the first piece keeps the id, the others get
        new ones).
    fits : dict
        Segment id -> Surface; changed in place.
    tol : float
        Fit tolerance (model units).
    split : callable
        ``split(faces, t)`` -> ``(parts, part_fits)``, the pieces of a face set cut at
        tolerance ``t`` and their surfaces fitted at ``tol``, or ``(None, None)`` when it
        finds no real faces (refine's region growing and RANSAC).

    Returns
    -------
    int
        Segments split.

    Examples
    --------
    A noisy plane bent by 5 degrees at ``x = 0``, in three segments: the two flanks and a
    strip across the bend, which one cylinder explains at 1.5 times the flanks' RMS. The
    strip is cut at the bend.

    >>> import igl, numpy as np
    >>> from igl_heatseg.mesh.geometry import face_normals
    >>> from igl_heatseg.surfaces.refine import grow_regions
    >>> from igl_heatseg.surfaces.segment_fit import fit_faces
    >>> x, y = np.meshgrid(np.linspace(-20, 20, 81), np.linspace(0, 20, 41), indexing="ij")
    >>> z = np.tan(np.radians(5)) * np.clip(x, 0, None)
    >>> V = np.c_[x.ravel(), y.ravel(), z.ravel()]
    >>> V[:, 2] += np.random.default_rng(1).normal(0, 0.02, len(V))
    >>> i = (np.arange(80)[:, None] * 41 + np.arange(40)).ravel()
    >>> F = np.r_[np.c_[i, i + 41, i + 42], np.c_[i, i + 42, i + 1]]
    >>> xf = V[F].mean(axis=1)[:, 0]
    >>> labels = np.digitize(xf, [-6, 6]).astype(np.int64)
    >>> TT, FN = igl.triangle_triangle_adjacency(F)[0], face_normals(V, F)
    >>> tol = 0.05
    >>> fits = {k: fit_faces(V, F, np.flatnonzero(labels == k), tol, FN=FN) for k in (0, 1, 2)}
    >>> [fits[k].kind for k in fits], round(fits[1].rms / fits[0].rms, 1)
    (['plane', 'cylinder', 'plane'], 1.5)
    >>> def split(faces, t):
    ...     sub = grow_regions(V, F, faces, t, FN, TT)
    ...     parts = [faces[sub == r] for r in range(sub.max() + 1)]
    ...     return parts, [fit_faces(V, F, p, tol, FN=FN) for p in parts]
    >>> split_loose(V, F, labels, fits, tol, split)
    1
    >>> sorted(np.round([xf[labels == k].mean() for k in np.unique(labels)], 0).tolist())
    [-13.0, -3.0, 3.0, 13.0]
    """
    found = _noise(labels, fits, tol)
    if found is None:
        return 0
    big, med, noise = found
    area = face_areas(V, F)
    nxt = int(labels.max()) + 1
    n = 0
    for k in [k for k in fits if k in big and fits[k].rms > LOOSE_RATIO * noise]:
        faces = np.flatnonzero(labels == k)
        parts, part_fits = split(faces, min(tol, LOOSE_SPLIT_K * med))
        if parts is None or len(parts) < 2:
            continue
        A = np.array([area[p].sum() for p in parts])
        if np.sort(A)[-2] < LOOSE_SPLIT_SHARE * A.sum():
            continue
        r = np.array([s.rms if s.is_analytic else np.inf for s in part_fits])
        pooled = math.sqrt(float(np.sum(A * r**2) / A.sum()))
        if not math.isfinite(pooled) or LOOSE_RATIO * pooled > fits[k].rms:
            continue
        for i, (part, s) in enumerate(zip(parts, part_fits, strict=True)):
            lab = k if i == 0 else nxt
            nxt += i > 0
            labels[part] = lab
            fits[lab] = s
        n += 1
    return n


def _plan(V, F, labels, fits, tol, TT, W, FN, faces, who, noise):
    """The receivers' refits and the left pieces (with their fits; None for a piece under
    LOOSE_MIN_FACES faces), or None
    when the taken faces fit their receivers' surfaces worse than LOOSE_RATIO x the receivers'
    own RMS (pooled), or a receiver or a piece would fit worse than LOOSE_RATIO x noise."""
    receivers = {}
    taken = [(c, corner_rms(V, F, faces[who == c], fits[c]) / fits[c].rms)
             for c in np.unique(who[who >= 0]).tolist()]
    if np.sqrt(np.mean(np.concatenate([r for _, r in taken]) ** 2)) > LOOSE_RATIO:
        return None  # the faces lie on the receivers' surfaces extended, not on them
    for c, _ in taken:
        s = fit_faces(V, F, np.r_[np.flatnonzero(labels == c), faces[who == c]], tol, W=W, FN=FN)
        if not (s.is_analytic and s.rms <= max(LOOSE_RATIO * noise, fits[c].rms)):
            return None
        receivers[c] = s
    rest = faces[who < 0]
    pieces = []
    if len(rest):
        sub = np.full(len(F), -1, dtype=np.int64)
        sub[rest] = 0
        piece = label_pieces(F, sub, TT)[rest]
        for r in np.unique(piece):
            part = rest[piece == r]
            if len(part) < LOOSE_MIN_FACES:
                pieces.append((part, None))
                continue
            s = fit_faces(V, F, part, tol, W=W, FN=FN)
            if not (s.is_analytic and s.rms <= LOOSE_RATIO * noise):
                return None
            pieces.append((part, s))
    return receivers, pieces
