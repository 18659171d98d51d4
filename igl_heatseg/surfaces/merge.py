"""Step 3 of the fit-driven refinement: merging adjacent segments that one surface explains.

Cheapest union first (Attene et al. 2006): strips of a coarse cylinder, a plane split by noise.
A union is fitted only when it may be one surface (:data:`PRECHECK_TOL`,
:data:`UPGRADE_ANGLE`, :data:`MERGE_SMALL_FACES`); a union refused once is not fitted again
while its parts are unchanged, or while a part has only grown by segments its own surface
explained (its surface object is the same) next to an unchanged neighbour.
"""

from __future__ import annotations

import heapq
import itertools
import math

import numpy as np

from ..mesh.geometry import face_normals
from .samples import segment_adjacency
from .segment_fit import explains, fit_faces, normals_agree, precheck_vertices, rms_to
from .tolerance import K_NOISE

__all__ = ["merge_segments", "MERGE_SMALL_FACES", "PRECHECK_TOL", "UPGRADE_ANGLE",
           "MERGE_NOISE_RATIO", "MERGE_NOISE_SLACK"]

#: Two unexplained segments of at most this many faces each are tried in a union.
MERGE_SMALL_FACES = 64

#: A union is fitted only if one part's surface is within PRECHECK_TOL x tol (RMS) of the
#: other part's vertices (:func:`~igl_heatseg.surfaces.segment_fit.rms_to`). A part's surface
#: that misses its neighbour by more cannot become the union's surface, and a more general
#: kind fitting both would have fitted each part with the same kind.
PRECHECK_TOL = 10.0

#: ... or when the face normals turn across their shared boundary by less than this on
#: average (radians): the facets of a coarse curved surface (a 9-facet circle turns 40 degrees
#: per facet) may join into one surface of a more general kind (strips -> cylinder).
UPGRADE_ANGLE = math.radians(40.0)

#: A merge on a noisy mesh: the worse part's RMS to the union's surface is at most this times the
#: noise level plus MERGE_NOISE_SLACK x tol. The noise level is the better of the parts' own fit
#: RMS (a part mixing two surfaces fits worse than the noise), floored at tol / K_NOISE (a few
#: faces fit better than the noise). As ``segmentation.primitive_merge``'s MERGE_RATIO and
#: MERGE_SLACK.
MERGE_NOISE_RATIO = 1.3
MERGE_NOISE_SLACK = 0.1


def merge_segments(V, F, labels, tol, fits: dict, rejected: set | None = None, W=None,
                   FN=None, noisy: bool = False) -> int:
    """Greedy merging of adjacent segments whose union one surface explains; cheapest first.

    Step 3 of :func:`~igl_heatseg.surfaces.refine.refine_segmentation` (see the module
    docstring). Modifies ``labels`` and ``fits`` in place.

    Parameters
    ----------
    V : (n, 3) float64
    F : (m, 3) int64
    labels : (m,) int64
        Segment of each face; merged segments take the label of the one they join.
    tol : float
        Fit tolerance (model units).
    fits : dict
        Segment label -> its fitted :class:`~igl_heatseg.surfaces.model.Surface`; merged
        labels are removed, every merged segment refitted on all its faces.
    rejected : set, optional
        Unions found unexplained (keyed by both parts' faces), shared between rounds so a
        later round does not refit a pair that has not changed; updated in place.
    W : (n, 3) float64, optional
        Denoised positions for the face normals (default ``V``).
    FN : (m, 3) float64, optional
        Unit face normals (default from ``W``).
    noisy : bool
        The mesh is a noisy scan: a union must fit both parts about as well as their own fits
        (:data:`MERGE_NOISE_RATIO`).

    Returns
    -------
    int
        Merges made.

    Examples
    --------
    >>> import numpy as np
    >>> from igl_heatseg.surfaces.segment_fit import fit_faces
    >>> x, y = np.meshgrid(np.arange(5.0), np.arange(3.0))
    >>> V = np.c_[x.ravel(), y.ravel(), np.zeros(15)]
    >>> F = np.array([[r * 5 + c, r * 5 + c + 1, r * 5 + c + 6] for r in range(2)
    ...               for c in range(4)] + [[r * 5 + c, r * 5 + c + 6, r * 5 + c + 5]
    ...               for r in range(2) for c in range(4)])
    >>> labels = (V[F].mean(axis=1)[:, 0] > 2).astype(np.int64)    # one plane cut in two
    >>> fits = {k: fit_faces(V, F, np.flatnonzero(labels == k), 1e-3) for k in (0, 1)}
    >>> merge_segments(V, F, labels, 1e-3, fits), sorted(fits), np.unique(labels).tolist()
    (1, [0], [0])
    """
    rejected = set() if rejected is None else rejected
    dirty: set = set()
    parent = {k: k for k in fits}

    def find(a):
        while parent[a] != a:
            parent[a] = parent[parent[a]]
            a = parent[a]
        return a

    faces_of = {k: np.flatnonzero(labels == k) for k in fits}
    fa, fb = segment_adjacency(F, labels)
    la, lb = np.minimum(labels[fa], labels[fb]), np.maximum(labels[fa], labels[fb])
    FNs = face_normals(V if W is None else W, F) if FN is None else FN
    turn = np.arccos(np.clip(np.einsum("ij,ij->i", FNs[fa], FNs[fb]), -1.0, 1.0))
    bend: dict = {}  # mean turn of the face normals across each pair's shared edges
    for a, b, x in zip(la.tolist(), lb.tolist(), turn.tolist(), strict=True):
        sx, n = bend.get((a, b), (0.0, 0))
        bend[(a, b)] = (sx + x, n + 1)
    bend = {k: sx / n for k, (sx, n) in bend.items()}
    pairs = set(bend)
    nbrs: dict[int, set] = {k: set() for k in fits}
    for a, b in pairs:
        nbrs[a].add(b)
        nbrs[b].add(a)
    heap = []
    order = itertools.count()  # ties in cost: pushing order (never compares the surfaces)
    torus_ids: set = set()  # the unions _torus_union fitted (their ids; kept in the heap)
    tori: set = set()  # the segments merged on such a torus (their refit keeps it)
    # the pairs refused in this round, with the surface of one side and the faces of the other
    # then: a side that has since grown only by segments its own surface explained (its
    # surface is the same object: merges that keep a part's fit do not refit it) is still
    # refused next to an unchanged neighbour. A plane absorbing a hundred shards re-pushed
    # every fillet piece beside it after every merge (rounded_box_s1000: 610 segments, 4,992
    # union fits, 27 s in this function)
    refused: dict = {}

    def still_refused(a, c) -> bool:
        was = refused.get((a, c))
        return was is not None and was[0] is fits[a] and was[1] is faces_of[c]

    def agree(faces, s) -> bool:
        return normals_agree(V, F, FNs, faces, s, raw=W is not None)

    # the vertices rms_to measures, per faces array (a merge replaces a segment's array, never
    # changes it; the array is kept with them, so its id is not reused): the same faces are
    # measured against each neighbour's surface after every merge (rounded_box_s6000, tuning-3:
    # 103,276 measures, 28 of 70 s in np.unique under cProfile)
    measured: dict = {}

    def rms(faces, s) -> float:
        got = measured.get(id(faces))
        if got is None or got[0] is not faces:
            got = measured[id(faces)] = (faces, precheck_vertices(F, faces))
        return rms_to(V, F, faces, s, verts=got[1])

    def smooth(a, b) -> bool:
        """The boundary bends less than a crease: facets of one curved surface, maybe."""
        return bend.get((min(a, b), max(a, b)), math.pi) <= UPGRADE_ANGLE

    def _torus_union(a, b, bar):
        """For a cylinder union too loose for the noise bar: the union's torus, when it fits
        both parts within ``bar``, explains the union and its normals agree; else None (any
        more general kind for any kind cost f24 plate_s24006 its type and domed_cap_s24010
        coverage .915 -> .733)."""
        g = fit_faces(V, F, np.r_[faces_of[a], faces_of[b]], tol, kinds=("torus",), W=W,
                      FN=FN, trim=False)
        if not (g.kind == "torus" and explains(g, tol)
                and max(rms(faces_of[a], g), rms(faces_of[b], g)) <= bar
                and agree(faces_of[a], g) and agree(faces_of[b], g)):
            return None
        torus_ids.add(id(g))
        return g

    def push(a, b):
        # a union is fitted only when one part's surface already comes near the other part
        # (the union of two planes at an angle, or of a plane and a fillet, is never tried);
        # an unexplained piece (a shard of a thin band, a leftover of region growing) may join
        # a neighbour this way too. When one part's surface already explains the other part,
        # only its kind is refitted (one fit instead of the search over kinds).
        key = (len(faces_of[a]), int(faces_of[a].sum()), len(faces_of[b]), int(faces_of[b].sum()))
        if key in rejected or still_refused(a, b) or still_refused(b, a):
            return
        da, db = rms(faces_of[b], fits[a]), rms(faces_of[a], fits[b])
        # normals too: a fan cap's vertices all lie on its cylinder's rim
        if da <= tol and explains(fits[a], tol) and agree(faces_of[b], fits[a]):
            u = fits[a]  # a's surface explains b: no refit now (refitted once after the round)
        elif db <= tol and explains(fits[b], tol) and agree(faces_of[a], fits[b]):
            u = fits[b]
        elif min(da, db) <= PRECHECK_TOL * tol or smooth(a, b) or (
            max(len(faces_of[a]), len(faces_of[b])) <= MERGE_SMALL_FACES
            and not explains(fits[a], tol)
            and not explains(fits[b], tol)
        ):
            # untrimmed (a union that needs faces cut off is not one surface), and the normals
            # of each part on its own (a small cap on a big cylinder's rim passes the union's)
            u = fit_faces(V, F, np.r_[faces_of[a], faces_of[b]], tol, W=W, FN=FN, trim=False)
            if u.is_analytic and not (agree(faces_of[a], u) and agree(faces_of[b], u)):
                u = None
        else:
            u = None
        if u is not None and noisy and explains(u, tol):
            # on noise, each part's own fit gives its noise level: the union's surface must
            # fit both parts about as well (a dome's sphere explains the short cylinder below
            # it within tolerance, but clearly worse than the cylinder's own fit)
            noise = max(min(fits[a].rms, fits[b].rms), tol / K_NOISE)  # the better fit's
            bar = MERGE_NOISE_RATIO * noise + MERGE_NOISE_SLACK * tol
            worse = max(da if u is fits[a] else rms(faces_of[b], u),
                        db if u is fits[b] else rms(faces_of[a], u))
            if worse > bar and u.kind == "cylinder":
                # the simplest kind within tolerance may be loose where a torus fits both
                # parts at their noise (two bands of a pipe's bend, each a cylinder: their
                # union is a cylinder within tolerance, a torus within the noise)
                u = _torus_union(a, b, bar)
            elif worse > bar:
                u = None
        if u is None or not explains(u, tol):
            rejected.add(key)
            refused[(a, b)] = (fits[a], faces_of[b])
            refused[(b, a)] = (fits[b], faces_of[a])
        else:
            cost = min(da, db) if u is fits[a] or u is fits[b] else u.rms
            heapq.heappush(heap, (cost, a, b, next(order), u, key, faces_of[a], faces_of[b]))

    for a, b in sorted(pairs):
        push(a, b)
    merged = 0
    start = {k: (faces_of[k], fits[k]) for k in fits}
    group = {k: ([k], []) for k in fits}  # the segments merged into k, and the pairs' keys
    while heap:
        _, a, b, _, u, key, fa, fb = heapq.heappop(heap)
        if find(a) != a or find(b) != b:  # stale: one side was merged since
            continue
        if not ((faces_of[a] is fa or u is fits[a]) and (faces_of[b] is fb or u is fits[b])):
            # stale too: a side has grown since the pair was measured, and ``u`` was fitted to
            # its old faces, or is the other side's surface, which measured only its old faces
            # (a chamfer that absorbed a one-face segment joined the plane that had explained
            # that face: tuning countersunk_plate_s1039, its bottom chamfer lost). The grown
            # side's pairs were pushed again when it grew.
            continue
        parent[b] = a
        gb = group.pop(b)
        group[a] = (group[a][0] + gb[0], group[a][1] + gb[1] + [key])
        faces_of[a] = np.concatenate([faces_of[a], faces_of.pop(b)])
        fits[a] = u
        if id(u) in torus_ids:
            tori.add(a)
        dirty.add(a)
        dirty.discard(b)
        del fits[b]
        for c in nbrs[b] - {a}:  # the merged boundary bends as little as its smoothest part
            key_b, key_a = (min(b, c), max(b, c)), (min(a, c), max(a, c))
            bend[key_a] = min(bend.get(key_a, math.pi), bend.get(key_b, math.pi))
        nbrs[a] = (nbrs[a] | nbrs.pop(b)) - {a, b}
        for c in nbrs[a]:
            nbrs[c] = (nbrs[c] - {b}) | {a}
        merged += 1
        for c in sorted(nbrs[a]):
            push(a, c)
    for k, faces in faces_of.items():
        labels[faces] = k
    for k in dirty:  # one refit per merged segment, on all its faces
        fits[k] = fit_faces(V, F, faces_of[k], tol, W=W, FN=FN)
        if k in tori and fits[k].kind != "torus":  # the kind that fits at the noise
            g = fit_faces(V, F, faces_of[k], tol, kinds=("torus",), W=W, FN=FN)
            fits[k] = g if g.kind == "torus" and explains(g, tol) else fits[k]
        members, keys = group[k]
        if noisy and not explains(fits[k], tol) and any(explains(start[o][1], tol)
                                                         for o in members):
            # on noise a chain of merges can drift off every surface: undo it
            for o in members:
                labels[start[o][0]] = o
                fits[o] = start[o][1]
            rejected.update(keys)
            merged -= len(members) - 1
    return merged
