"""Border faces that stand across their segment's surface go to the neighbour they face.

A triangle of a gear's tooth flank labelled with the gear's side plane has two corners on
the plane and the third an edge length off it, its normal square to the plane's. The Lloyd
moves of :mod:`.refine` give a face only to an analytic neighbour that fits it, so a stray of
a freeform neighbour (the flank) stays, and the side plane, 1,844 faces, then deviates from
its segment by 1.2 % of the diagonal because of two such triangles (gear_s1019, a tuning
part): the B-Rep stage faceted it (:func:`shed_strays`). A patch of such faces that no
neighbour can take (the fan closing a small blind hole, in its wall's segment) becomes a
segment of its own (:func:`cut_caps`).
"""
from __future__ import annotations

import math

import numpy as np

from ..mesh.geometry import face_areas
from ..mesh.topology import label_pieces
from .segment_fit import (
    GROW_ANGLE,
    GROW_TOL,
    MIN_REGION_FACES,
    corner_max_dev,
    corner_rms,
    explains,
    fit_faces,
    mean_normal_agrees,
    normal_angle,
    normals_agree,
    refit_segments,
)
from .tolerance import CREASE_ANGLE

__all__ = ["shed_strays", "split_at_creases", "cut_caps", "absorb_shards", "dissolve_mixtures",
           "split_chords"]

#: Segments of fewer faces that lie on a neighbour's surface join it (noise shards along a crease).
SHARD_FACES = 8

#: On a noisy mesh a segment of fewer than MIN_REGION_FACES faces and under this share of the
#: mesh's area joins a neighbour that then still fits one surface. Set from face counts,
#: not scores: a dense mesh's triangle is 3e-5 - 2e-4 of its area (5k - 30k faces), where one
#: or two faces are never a face of the part; a coarse export's is 1e-3 - 2e-3 (500 - 1,000
#: faces), where a chamfer can be two triangles.
SHARD_AREA = 5e-4

#: ... and on a noisy mesh a shard whose corners are within SHARD_ON_TOL x tol (RMS) of a
#: neighbour's surface joins it when the shard's mean normal (area-weighted sum of its face
#: normals) is within GROW_ANGLE of the surface's there, though its faces' own normals are not:
#: at noise 0.2 a fifth of the faces' normals are over GROW_ANGLE off, so a shard of 3-7 faces
#: on a narrow cylinder failed :func:`~.segment_fit.normals_agree` (tuning-3
#: domed_cap_s6027_frontal_n0.2: three shards of a narrow cylinder, 0.29-0.44 tol from its
#: segment's surface, stayed segments). Held to tol, not GROW_TOL x tol: the corners of a
#: chamfer one row of triangles wide all lie on its neighbours, and its mean normal, not its
#: distance, keeps it.
SHARD_ON_TOL = 1.0

#: A border face is a stray when its normal is more than this angle from its surface's ...
STRAY_ANGLE = math.radians(60.0)

#: ... and its corners' RMS distance to the surface is above this many tolerances.
STRAY_TOL = 2.0

#: cut_caps: a patch of faces standing across their segment's surface becomes a segment with at
#: least this many faces (a fan closing a small blind hole: 7 on f21 housing_s21002) ...
CAP_MIN_FACES = 4

#: ... and at most this share of the segment's faces.
CAP_MAX_SHARE = 0.25

#: Passes (a stray behind a stray is on the border after the first one has gone).
STRAY_PASSES = 3

#: dissolve_mixtures: segments of at most this many faces are looked at (a coarse export's
#: mixtures hold 2-6 faces: a plane's sliver and a facet of each cylinder beside it).
MIXTURE_MAX_FACES = 12

#: split_chords: a face of a curved segment of an exact tessellation is a chord across it, not a
#: facet of it, when its centroid is more than this many times the segment's median centroid
#: distance from the surface (a facet's sagitta grows with its width squared: up to 3 times
#: wider facets pass) ...
CHORD_RATIO = 10.0

#: ... and more than this many tolerances (GROW_TOL: a face the growth would not take) ...
CHORD_TOL = 2.0

#: ... when such faces hold at least this share of the segment's area: the surface was fitted
#: through a flat (91 % of the housing's 6-face segment), not past a few border faces of a
#: neighbouring fillet (10 faces, 0.1 % of a 2,848-face cylinder on f40 saddle_boss_s40004
#: irregular, which the chord pass cut into 6 more segments).
CHORD_SHARE = 0.25

#: split_at_creases: a piece of a segment joined to the rest only across creases leaves it when
#: its area is at most this share of the segment's (a two-facet fillet's halves stay).
CREASE_PIECE_SHARE = 0.15


def split_at_creases(F: np.ndarray, labels: np.ndarray, TT: np.ndarray, FN: np.ndarray,
                     area: np.ndarray, V: np.ndarray | None = None, tol: float | None = None,
                     W: np.ndarray | None = None) -> tuple[np.ndarray, int]:
    """Segments of an exact tessellation cut at their inner creases; small pieces leave.

    On a CAD tessellation a crease (faces turning by more than
    :data:`~igl_heatseg.surfaces.tolerance.CREASE_ANGLE`) is where two faces of the part meet,
    so the faces of one segment joined only across a crease belong to two faces: fandisk's
    large freeform segment held a five-triangle strip of its neighbour folded across the crease,
    a coarse gear's flank segment the two triangles of its tooth's tip land. Each segment's
    largest crease-free piece keeps it; a piece of at most :data:`CREASE_PIECE_SHARE` of the
    segment's area goes to the neighbouring segment it joins across the most smooth edges, or
    becomes a segment of its own when it joins none smoothly.

    A crease can also be the tessellation's: the facets of a hole of radius 0.5 exported with
    edges of about 1 turn by 60-90 degrees. So, given ``V`` and ``tol``, a piece stays when its
    segment is one analytic surface within ``tol`` (fitted to all its faces) and every face of
    the piece has its corners on it (RMS within ``tol``) and its normal within
    :data:`STRAY_ANGLE` of it (a cap's triangle with its three corners on the rim of a hole
    lies on the hole's cylinder too, square to it).

    Parameters
    ----------
    F : (m, 3) int64
    labels : (m,) int64
    TT : (m, 3) int64
        Face adjacency (-1 on a border).
    FN : (m, 3) float64
        Unit face normals.
    area : (m,) float64
        Face areas.
    V : (n, 3) float64, optional
        Vertex positions; with ``tol``, the pieces on their segment's surface stay.
    tol : float, optional
        Fit tolerance (model units).
    W : (n, 3) float64, optional
        Positions the fits take normals from (:func:`~.segment_fit.fit_faces`).

    Returns
    -------
    labels : (m,) int64
        A new array (new segments numbered after the largest label).
    moved : int
        Faces that changed segment.

    Examples
    --------
    >>> import numpy as np, igl
    >>> V = np.array([[0., 0, 0], [4, 0, 0], [4, 4, 0], [0, 4, 0], [0, 0, 1], [4, 0, 1]])
    >>> F = np.array([[0, 1, 2], [0, 2, 3], [1, 0, 4], [1, 4, 5]])  # a floor and a wall
    >>> TT = igl.triangle_triangle_adjacency(F)[0]
    >>> FN = igl.per_face_normals(V, F, np.zeros(3))
    >>> split_at_creases(F, np.zeros(4, np.int64), TT, FN, np.array([8., 8, .5, .5]))
    (array([0, 0, 1, 1]), 2)
    """
    ok = TT >= 0
    cos = np.einsum("fkj,fj->fk", FN[np.where(ok, TT, 0)], FN)
    crease = ok & (cos < math.cos(CREASE_ANGLE))
    pieces = label_pieces(F, labels, np.where(crease, -1, TT))
    piece_area = np.bincount(pieces, weights=area)
    seg_area = np.bincount(labels, weights=area)
    out = labels.copy()
    nxt = int(labels.max()) + 1
    moved = 0
    for lab in np.unique(labels):
        ps = np.unique(pieces[labels == lab])
        if len(ps) < 2:
            continue
        keep = ps[np.argmax(piece_area[ps])]
        small = [p for p in ps if p != keep and piece_area[p] <= CREASE_PIECE_SHARE * seg_area[lab]]
        if small and V is not None and tol is not None:
            faces = np.flatnonzero(labels == lab)
            s = fit_faces(V, F, faces, tol, W=W, FN=FN)
            on = np.zeros(len(F), dtype=bool)
            if explains(s, tol):
                on[faces] = (corner_rms(V, F, faces, s) <= tol) & (
                    normal_angle(V, F, FN, faces, s) <= STRAY_ANGLE)
            small = [p for p in small if not on[pieces == p].all()]
        for p in small:
            fp = np.flatnonzero(pieces == p)
            nb = TT[fp]
            others = labels[nb[(nb >= 0) & ~crease[fp]]]
            others = others[others != lab]
            if len(others):
                vals, counts = np.unique(others, return_counts=True)
                out[fp] = vals[np.argmax(counts)]
            else:
                out[fp] = nxt
                nxt += 1
            moved += len(fp)
    return out, moved


def _stands_across(V, F, FN, faces, s, tol, farthest: bool = False) -> np.ndarray:
    """Which of ``faces`` stand across the analytic surface ``s`` (far and turned away); far
    by the corners' RMS distance, or with ``farthest`` by the farthest corner's."""
    far = (corner_max_dev if farthest else corner_rms)(V, F, faces, s)
    return (far > STRAY_TOL * tol) & (normal_angle(V, F, FN, faces, s) > STRAY_ANGLE)


def _takes(V, F, FN, f, s, tol) -> bool:
    """A neighbouring segment fitted by ``s`` can take the stray face ``f``: it is freeform (or
    unfitted), or the face does not stand across its surface too."""
    return s is None or not s.is_analytic or not _stands_across(V, F, FN, np.array([f]), s,
                                                                tol)[0]


def shed_strays(V: np.ndarray, F: np.ndarray, labels: np.ndarray, fits: dict, tol: float,
                TT: np.ndarray, FN: np.ndarray) -> int:
    """Move, in place, the stray border faces of analytic segments to the neighbouring
    segment across their edge whose face's normal is nearest to theirs, among those that take
    them.

    A face on a segment's border is a stray when its normal is more than STRAY_ANGLE from
    its surface's normal and its corners' RMS distance to the surface is above STRAY_TOL
    ``tol``: it stands across the surface (a flank triangle on a side plane), which noise
    does not do. A neighbour takes a stray when it is freeform or the stray does not stand
    across its surface too (a triangle of a recessed floor between two walls stays: given to
    the wall across the way, it made a noisy housing's 850-face plane freeform). A segment is
    never emptied nor cut apart (then its strays stay).

    Parameters
    ----------
    V : (n, 3) float64
    F : (m, 3) int64
    labels : (m,) int64
        Segment of every face; updated in place.
    fits : dict
        Segment -> Surface (fitted to it).
    tol : float
        Fit tolerance (model units).
    TT : (m, 3) int64
        Face across each edge (``igl.triangle_triangle_adjacency``), -1 on the mesh border.
    FN : (m, 3) float64
        Unit face normals.

    Returns
    -------
    int
        Faces moved.

    Examples
    --------
    >>> import igl, numpy as np
    >>> from igl_heatseg.mesh.geometry import face_normals
    >>> from igl_heatseg.surfaces.model import Surface
    >>> V = np.array([[0., 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [1, 0, -1], [1, 1, -1]])
    >>> F = np.array([[0, 1, 2], [0, 2, 3], [1, 4, 5], [1, 5, 2]])  # a square, a wall
    >>> labels = np.array([0, 0, 0, 1])   # face 2 is a wall triangle labelled with the square
    >>> fits = {0: Surface("plane", {"point": np.zeros(3), "normal": np.array([0., 0, 1])}),
    ...         1: Surface("plane", {"point": np.ones(3), "normal": np.array([1., 0, 0])})}
    >>> TT = igl.triangle_triangle_adjacency(F)[0]
    >>> shed_strays(V, F, labels, fits, 0.01, TT, face_normals(V, F)), labels.tolist()
    (1, [0, 0, 1, 1])
    """
    moved = 0
    for _ in range(STRAY_PASSES):
        across = np.where(TT >= 0, labels[np.maximum(TT, 0)], -1)
        other = (TT >= 0) & (across != labels[:, None])
        border = np.flatnonzero(other.any(axis=1))
        strays = []
        for k in np.unique(labels[border]).tolist():
            s = fits.get(k)
            if s is None or not s.is_analytic:
                continue
            sel = border[labels[border] == k]
            strays.extend(sel[_stands_across(V, F, FN, sel, s, tol)].tolist())
        if not strays:
            break
        new = labels.copy()
        for f in strays:
            js = TT[f][other[f]]
            js = js[[_takes(V, F, FN, f, fits.get(int(labels[j])), tol) for j in js]]
            if len(js):
                new[f] = labels[js[np.argmax(FN[js] @ FN[f])]]
        counts = np.bincount(new, minlength=labels.max() + 1)
        for k in np.flatnonzero((counts == 0) & (np.bincount(labels, minlength=len(counts)) > 0)):
            new[labels == k] = k  # never empty a segment
        pieces = label_pieces(F, new, TT)
        for k in np.unique(labels[new != labels]).tolist():
            if len(np.unique(pieces[new == k])) > 1:  # nor cut one apart: its strays stay
                new[labels == k] = k
        n = int((new != labels).sum())
        if n == 0:
            break
        moved += n
        labels[:] = new
    return moved


def cut_caps(V: np.ndarray, F: np.ndarray, labels: np.ndarray, fits: dict, tol: float,
             TT: np.ndarray, FN: np.ndarray, W: np.ndarray | None = None) -> int:
    """Give every patch of faces that stands across its analytic segment's surface, and that
    one surface explains, a segment of its own (in place).

    A face stands across when its normal is more than STRAY_ANGLE from its surface's and its
    farthest corner is more than STRAY_TOL ``tol`` off it. :func:`shed_strays` moves such faces
    to a neighbour; a patch with no neighbour to take it stays: the fan closing a small blind
    hole, labelled with the hole's wall, a plane across the cylinder (f21
    housing_s21002_frontal_n0.1: four such caps of 7 faces, and the CAD build faceted the four
    walls for them). A patch (edge-connected) becomes a segment when it has CAP_MIN_FACES faces
    or more, at most CAP_MAX_SHARE of its segment's, and an analytic fit within ``tol`` whose
    normals agree with the faces', unless that empties its segment or cuts it apart.

    Parameters
    ----------
    V : (n, 3) float64
    F : (m, 3) int64
    labels : (m,) int64
        Segment of every face; updated in place (new segments numbered after the largest).
    fits : dict
        Segment -> Surface; the new segments' fits are added, their old segments refitted.
    tol : float
        Fit tolerance (model units).
    TT : (m, 3) int64
        ``igl.triangle_triangle_adjacency(F)[0]``.
    FN : (m, 3) float64
        Unit face normals.
    W : (n, 3) float64, optional
        Positions the normals come from.

    Returns
    -------
    int
        Segments made.

    Examples
    --------
    A blind hole (a 12-sided prism, radius 1) whose bottom fan is labelled with its wall:

    >>> import igl, numpy as np
    >>> from igl_heatseg.mesh.geometry import face_normals
    >>> from igl_heatseg.surfaces.segment_fit import fit_faces
    >>> t = np.linspace(0, 2 * np.pi, 12, endpoint=False)
    >>> ring = np.c_[np.cos(t), np.sin(t)]
    >>> V = np.vstack([[[0.0, 0, 0]]] + [np.c_[ring, np.full(12, z)] for z in (0, 1, 2, 3)])
    >>> i, j = np.arange(12), (np.arange(12) + 1) % 12
    >>> F = np.r_[np.c_[np.zeros(12, int), 1 + j, 1 + i]]             # the bottom fan
    >>> for r in range(3):
    ...     a, b = 1 + 12 * r, 13 + 12 * r
    ...     F = np.r_[F, np.c_[a + i, a + j, b + j], np.c_[a + i, b + j, b + i]]
    >>> labels = np.zeros(len(F), dtype=np.int64)
    >>> fits = {0: fit_faces(V, F, np.arange(12, len(F)), 0.01)}     # the wall's cylinder
    >>> TT = igl.triangle_triangle_adjacency(F)[0]
    >>> cut_caps(V, F, labels, fits, 0.01, TT, face_normals(V, F)), fits[1].kind
    (1, 'plane')
    >>> np.flatnonzero(labels == 1).tolist() == list(range(12))
    True
    """
    made = 0
    nxt = max(fits) + 1 if fits else int(labels.max()) + 1
    for k in sorted(fits):
        s = fits[k]
        if not s.is_analytic:
            continue
        faces = np.flatnonzero(labels == k)
        across = faces[_stands_across(V, F, FN, faces, s, tol, farthest=True)]
        if len(across) < CAP_MIN_FACES:
            continue
        sub = np.full(len(F), -1, dtype=np.int64)
        sub[across] = 0
        pieces = label_pieces(F, sub, TT)
        cut = False
        for p in np.unique(pieces[across]).tolist():
            patch = across[pieces[across] == p]
            if not (CAP_MIN_FACES <= len(patch) <= CAP_MAX_SHARE * len(faces)):
                continue
            u = fit_faces(V, F, patch, tol, W=W, FN=FN)
            if not explains(u, tol):
                continue
            rest = np.setdiff1d(np.flatnonzero(labels == k), patch)
            keep = np.full(len(F), -1, dtype=np.int64)
            keep[rest] = 0
            if len(rest) == 0 or len(np.unique(label_pieces(F, keep, TT)[rest])) > 1:
                continue  # never empty a segment nor cut it apart
            labels[patch] = nxt
            fits[nxt] = u
            nxt += 1
            made += 1
            cut = True
        if cut:
            refit_segments(V, F, labels, fits, [k], tol, W, FN)
    return made


def absorb_shards(V, F, labels, fits: dict, tol: float, TT, FN, W=None,
                   exact=True) -> np.ndarray:
    """Small segments join the neighbour they lie on; a true small face stays.

    A segment of fewer than SHARD_FACES faces joins its nearest neighbour (corner RMS) when it
    lies on the neighbour's surface (within GROW_TOL x tol, normals agreeing; on a noisy mesh
    also a shard under SHARD_AREA of the area within SHARD_ON_TOL x tol whose mean normal
    agrees), and whatever the distance when it has fewer than MIN_REGION_FACES faces and its
    own fit does not explain it. A true small face (a chamfer two triangles wide) is off its
    neighbours' surfaces and explained by its own: it stays. On a noisy mesh (not ``exact``) a
    small segment of fewer than MIN_REGION_FACES faces, whose fit is no evidence, also joins
    the nearest neighbour that one surface then still explains with it (the shards a split
    leaves of a small face cut up by the noise).

    Parameters
    ----------
    V : (n, 3) float64
    F : (m, 3) int64
    labels : (m,) int64
        Segment id per face (not changed).
    fits : dict
        Segment id -> Surface; a noisy shard's receiver gets its refit here.
    tol : float
        Fit tolerance (model units).
    TT : (m, 3) int64
        Triangle-triangle adjacency (-1 on the border).
    FN : (m, 3) float64
        Unit face normals.
    W : (n, 3) float64, optional
        Positions for the fits' normals (see :func:`~.segment_fit.fit_faces`).
    exact : bool
        Whether the mesh is an exact tessellation.

    Returns
    -------
    (m,) int64
        The new labels (ids of the segments that took shards; the shards' ids are gone).

    Examples
    --------
    Two triangles of a flat grid labelled apart lie on the plane of the rest, and join it.

    >>> import igl, numpy as np
    >>> from igl_heatseg.mesh.geometry import face_normals
    >>> from igl_heatseg.surfaces.segment_fit import fit_faces
    >>> x, y = np.meshgrid(np.arange(7.0), np.arange(7.0), indexing="ij")
    >>> V = np.c_[x.ravel(), y.ravel(), np.zeros(49)]
    >>> i = (np.arange(6)[:, None] * 7 + np.arange(6)).ravel()
    >>> F = np.r_[np.c_[i, i + 7, i + 8], np.c_[i, i + 8, i + 1]]
    >>> labels = np.zeros(len(F), dtype=np.int64); labels[[0, 36]] = 1
    >>> TT, FN = igl.triangle_triangle_adjacency(F)[0], face_normals(V, F)
    >>> fits = {k: fit_faces(V, F, np.flatnonzero(labels == k), 1e-3, FN=FN) for k in (0, 1)}
    >>> np.unique(absorb_shards(V, F, labels, fits, 1e-3, TT, FN)).tolist()
    [0]
    """
    labels = labels.copy()
    counts = np.bincount(labels)
    total = float(face_areas(V, F).sum())
    for k in np.flatnonzero((counts > 0) & (counts < SHARD_FACES)).tolist():
        faces = np.flatnonzero(labels == k)
        nb = np.unique(labels[TT[faces][TT[faces] >= 0]])
        nb = [j for j in nb.tolist() if j != k]
        if not nb:
            continue
        d = [float(np.sqrt(np.mean(corner_rms(V, F, faces, fits[j]) ** 2))) for j in nb]
        j = int(np.argmin(d))
        tiny = len(faces) < MIN_REGION_FACES and not explains(fits[k], tol)
        on = d[j] <= GROW_TOL * tol and normals_agree(V, F, FN, faces, fits[nb[j]])
        small = face_areas(V, F[faces]).sum() < SHARD_AREA * total
        on = on or (not exact and small and d[j] <= SHARD_ON_TOL * tol
                    and fits[nb[j]].is_analytic and mean_normal_agrees(V, F, faces, fits[nb[j]]))
        if on or tiny:
            labels[faces] = nb[j]
        elif not exact and len(faces) < MIN_REGION_FACES and small:
            for i in np.argsort(d).tolist():
                if not explains(fits[nb[i]], tol):
                    continue
                union = np.r_[np.flatnonzero(labels == nb[i]), faces]
                u = fit_faces(V, F, union, tol, W=W, FN=FN)
                if explains(u, tol):
                    labels[faces] = nb[i]
                    fits[nb[i]] = u
                    break
    return labels


def dissolve_mixtures(V, F, labels, fits: dict, tol: float, TT, FN,
                      W=None) -> tuple[np.ndarray, int]:
    """On an exact tessellation, the faces of a small segment that lie on a neighbour's
    surface are dealt out to those neighbours, face by face.

    Between a plane and two cylinders of a coarse CAD export, a plane's sliver and one facet of
    each cylinder can end up as a segment of their own. Such a mixture is often explained by a
    surface of its own: the corners of any two coaxial circles lie on one sphere, and a sphere
    fitted their 6 corners to 1e-15 on f39 housing_s39034_coarse_n0, a 4-face segment that the
    B-Rep built 1.2 % of the diagonal off the true part. Each face is then a face of a
    neighbour instead: its three corners within ``tol`` of the neighbour's surface, its normal
    within GROW_ANGLE of the surface's. A face goes to such a neighbour that it touches, or
    that a face of the segment already dealt to it touches (nearest corners first). Receivers
    are analytic segments with more faces than the segment; segments are taken smallest first.
    When faces are left, they stay a segment only if they are one piece that a surface of
    their own explains (the housing's mixture: a whole 2-triangle plane face between the
    cylinders' facets); else the segment is left as it was. A true small face is not a
    mixture: a chamfer's triangle has corners on both its neighbours' surfaces (on neither
    alone), a cap's fan triangle with its corners on a cylinder's rim stands square to it.

    Parameters
    ----------
    V : (n, 3) float64
    F : (m, 3) int64
    labels : (m,) int64
        Segment of every face (not changed).
    fits : dict
        Segment -> Surface (fitted to it); a segment that keeps some faces gets their fit.
    tol : float
        Fit tolerance (model units).
    TT : (m, 3) int64
        Face across each edge (``igl.triangle_triangle_adjacency``), -1 on the mesh border.
    FN : (m, 3) float64
        Unit face normals.
    W : (n, 3) float64, optional
        Positions for the fits' normals (see :func:`~.segment_fit.fit_faces`).

    Returns
    -------
    labels : (m,) int64
        Ids as before; a segment dealt out whole is gone.
    int
        Segments that gave faces away.

    Examples
    --------
    A roof: the planes z = x - y (segment 0) and z = 0 (segment 1) meet along the diagonal
    of a grid; a segment of one triangle of each across the ridge is dealt back.

    >>> import igl, numpy as np
    >>> from igl_heatseg.mesh.geometry import face_normals
    >>> from igl_heatseg.surfaces.model import Surface
    >>> x, y = np.meshgrid(np.arange(4.0), np.arange(4.0), indexing="ij")
    >>> V = np.c_[x.ravel(), y.ravel(), np.maximum(x - y, 0).ravel()]   # a roof: z=0, z=x-y
    >>> i = (np.arange(3)[:, None] * 4 + np.arange(3)).ravel()
    >>> F = np.r_[np.c_[i, i + 4, i + 5], np.c_[i, i + 5, i + 1]]
    >>> labels = (V[F].mean(axis=1)[:, 2] == 0).astype(np.int64)    # the two sides
    >>> labels[[4, 13]] = 2                                 # a mixture across the ridge
    >>> fits = {0: Surface("plane", {"point": np.zeros(3), "normal": np.array([-1., 1, 1])}),
    ...         1: Surface("plane", {"point": np.zeros(3), "normal": np.array([0., 0, 1])}),
    ...         2: Surface("sphere", {"center": np.zeros(3), "radius": 9.0})}
    >>> fits[0].params["normal"] /= np.sqrt(3)
    >>> TT = igl.triangle_triangle_adjacency(F)[0]
    >>> new, n = dissolve_mixtures(V, F, labels, fits, 1e-6, TT, face_normals(V, F))
    >>> n, new[[4, 13]].tolist()
    (1, [0, 1])
    """
    labels = labels.copy()
    counts = np.bincount(labels)
    dissolved = 0
    for k in np.argsort(counts, kind="stable").tolist():
        n = int(counts[k])
        if n == 0 or n > MIXTURE_MAX_FACES:
            continue
        faces = np.flatnonzero(labels == k)
        nbrs = TT[faces]
        nb = np.unique(labels[nbrs[nbrs >= 0]])
        nb = [j for j in nb.tolist() if j != k and counts[j] > n
              and fits.get(j) is not None and fits[j].is_analytic]
        if not nb:
            continue
        dev = np.full((len(faces), len(nb)), np.inf)
        for c, j in enumerate(nb):
            on = ((corner_max_dev(V, F, faces, fits[j]) <= tol)
                  & (normal_angle(V, F, FN, faces, fits[j]) <= GROW_ANGLE))
            dev[on, c] = corner_rms(V, F, faces[on], fits[j])
        home = np.full(len(F), -1)
        home[faces] = -2  # not dealt yet
        while True:
            dealt = False
            for r in np.argsort(dev.min(axis=1), kind="stable").tolist():
                f = faces[r]
                if home[f] != -2:
                    continue
                around = TT[f][TT[f] >= 0]
                reach = set(labels[around[labels[around] != k]].tolist())
                reach |= set(home[around[home[around] >= 0]].tolist())
                for c in np.argsort(dev[r], kind="stable").tolist():
                    if np.isfinite(dev[r, c]) and nb[c] in reach:
                        home[f] = nb[c]
                        dealt = True
                        break
            if not dealt:
                break
        dealt = home[faces] >= 0
        if not dealt.any():
            continue
        rest = faces[~dealt]
        if len(rest):  # what stays is one piece of one surface, or nothing moves
            sub = np.full(len(F), -1)
            sub[rest] = 0
            if len(np.unique(label_pieces(F, sub, TT)[rest])) > 1:
                continue
            s = fit_faces(V, F, rest, tol, W=W, FN=FN)
            if not explains(s, tol):
                continue
            fits[k] = s
        labels[faces[dealt]] = home[faces[dealt]]
        counts = np.bincount(labels, minlength=len(counts))
        dissolved += 1
    return labels, dissolved


def split_chords(V, F, labels, fits: dict, tol: float, TT, FN=None,
                 W=None) -> tuple[np.ndarray, int]:
    """On an exact tessellation, the faces a curved segment's surface passes through at their
    corners but not near their middle become segments of their own.

    A coarse export's vertices lie on its surfaces, its facets' middles a sagitta inside. On f41
    housing_s41034_coarse_n0 a flat of two long triangles between one facet of each of two
    cylinders had its four corners on one circle with theirs: one cylinder fitted the 6 faces
    to 1e-14 at their corners, its face bulged 4.8 units past the flat, and the B-Rep was 35 %
    too large. A face whose centroid is more than CHORD_RATIO times the segment's median
    centroid distance from the surface, and more than CHORD_TOL ``tol``, is such a chord. When
    the chords hold CHORD_SHARE of a segment's area, they leave it, and every segment is then
    cut into its connected pieces (the facets on either side of a flat).

    Parameters
    ----------
    V : (n, 3) float64
    F : (m, 3) int64
    labels : (m,) int64
        Segment of every face (not changed).
    fits : dict
        Segment -> Surface (fitted to it); only the cylinders, cones, spheres and tori are
        looked at.
    tol : float
        Fit tolerance (model units).
    TT : (m, 3) int64
        Face across each edge (``igl.triangle_triangle_adjacency``), -1 on the mesh border.
    FN, W : optional
        Not used (the signature of :func:`dissolve_mixtures`).

    Returns
    -------
    labels : (m,) int64
        Ids of the connected pieces (:func:`~igl_heatseg.mesh.topology.label_pieces`) when a
        chord left, else the labels as they were; the segments must then be refitted.
    int
        Segments that lost chords.

    Examples
    --------
    Four facets of a 16-gon prism around the z axis, and a chord of the same circle spanning
    the next four (its two triangles' corners are on the circle too):

    >>> import igl, numpy as np
    >>> from igl_heatseg.surfaces.model import Surface
    >>> t = np.radians([0, 22.5, 45, 67.5, 90, 180])
    >>> V = np.r_[np.c_[np.cos(t), np.sin(t), 0 * t], np.c_[np.cos(t), np.sin(t), 0 * t + 1]]
    >>> i = np.arange(5)
    >>> F = np.r_[np.c_[i, i + 1, i + 7], np.c_[i, i + 7, i + 6]]
    >>> cyl = Surface("cylinder", {"point": np.zeros(3), "axis": np.array([0., 0, 1]),
    ...                            "radius": 1.0})
    >>> labels = np.zeros(len(F), dtype=np.int64)
    >>> new, n = split_chords(V, F, labels, {0: cyl}, 1e-6, igl.triangle_triangle_adjacency(F)[0])
    >>> n, new.tolist()
    (1, [0, 0, 0, 0, 1, 0, 0, 0, 0, 1])
    """
    labels = labels.copy()
    C = V[F].mean(axis=1)
    area = face_areas(V, F)
    chord = np.zeros(len(F), dtype=bool)
    n = 0
    for k, s in fits.items():
        if not s.is_analytic or s.kind == "plane":
            continue
        faces = np.flatnonzero(labels == k)
        if len(faces) < 2:
            continue
        d = np.abs(s.distance(C[faces]))
        out = (d > CHORD_RATIO * np.median(d)) & (d > CHORD_TOL * tol)
        if out.any() and not out.all() and area[faces[out]].sum() >= CHORD_SHARE * area[
                faces].sum():
            chord[faces[out]] = True
            n += 1
    if n:  # the chords apart, and every segment in its pieces (what a chord held together)
        labels[chord] = labels.max() + 1
        labels = label_pieces(F, labels, TT)
    return labels, n
