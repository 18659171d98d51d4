"""Fit-driven refinement of a segmentation: one fitted surface per segment.

On top of a heat segmentation (the paper's seeds and fields stay the initialisation):

1. **Fit** every segment (:func:`~igl_heatseg.surfaces.fit.fit_surface`: the simplest kind
   within the mesh's own tolerance, :func:`~igl_heatseg.surfaces.tolerance.vertex_tolerance`).
2. **Split** every segment that no surface explains by fit-driven region growing inside it
   (:func:`grow_regions`): seeds from smooth interiors, a surface fitted to the seed's rings,
   growth over faces whose corners lie on it, refits as the region grows (a small patch of a
   cylinder looks planar; the refit on the grown region finds the cylinder).
3. **Merge** adjacent segments that one surface explains within tolerance, cheapest union first
   (Attene et al. 2006): strips of a coarse cylinder, a plane split by noise.
4. **Move boundary faces** to the neighbouring surface they lie on, refitting between passes (a
   Lloyd loop as in variational shape approximation, Cohen-Steiner et al. 2004), so boundaries
   follow the crease instead of zig-zagging along triangle edges.

Distances are measured at the mesh vertices: the vertices of a CAD tessellation lie on the
true surface, its face centroids do not (they sit a chord's sagitta inside a curved face).
"""

from __future__ import annotations

import heapq
import logging
import math
import time
from dataclasses import dataclass, field

import igl
import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

from ..mesh.geometry import face_areas, face_normals
from .model import SURFACE_KINDS, Surface
from .samples import segment_adjacency, vertex_samples
from .select import fit_surface
from .tolerance import exact_tessellation, vertex_tolerance

__all__ = [
    "fit_segments",
    "SurfaceSegmentation",
    "refine_segmentation",
    "segment_adjacency",
    "grow_regions",
    "vertex_samples",
]

log = logging.getLogger(__name__)

#: A boundary face moves to a neighbour's surface when its corners' RMS distance to that surface
#: is below this fraction of the distance to its own.
MOVE_RATIO = 0.5

#: ... and only faces farther than this many tolerances from their own segment's surface.
MOVE_FLOOR = 0.01

#: Lloyd passes: refit, then move the faces on the current boundaries.
MOVE_PASSES = 4

#: Rounds of (merge, move boundary faces): a move can make two pieces of one surface adjacent.
ROUNDS = 3

#: A face joins a growing region when its corners' RMS distance to the region's surface is
#: within GROW_TOL x tol ...
GROW_TOL = 2.0

#: ... and its normal is within this angle of the surface normal at its centroid (radians; a
#: facet of a coarse cylinder has the surface normal at its centroid, a face across a crease
#: does not).
GROW_ANGLE = math.radians(25.0)

#: When growth stalls, faces within STALL_TOL x tol are tried in a refit of the region (a
#: cylinder first fitted as a plane on a small patch).
STALL_TOL = 6.0

#: Rings of neighbours around a seed face in its first fit.
SEED_RINGS = 2

#: Regions of fewer faces are not kept from a seed (its faces stay free for other seeds).
MIN_REGION_FACES = 3

#: Two unexplained segments of at most this many faces each are tried in a union.
MERGE_SMALL_FACES = 64

#: A union is fitted only if one part's surface is within PRECHECK_TOL x tol (RMS) of the
#: other part's vertices (sampled: about PRECHECK_SAMPLES of them). A part's surface that
#: misses its neighbour by more cannot become the union's surface, and a more general kind
#: fitting both would have fitted each part with the same kind.
PRECHECK_TOL = 10.0
PRECHECK_SAMPLES = 200

#: ... or when the face normals turn across their shared boundary by less than this on
#: average (radians): the facets of a coarse curved surface (a 9-facet circle turns 40 degrees
#: per facet) may join into one surface of a more general kind (strips -> cylinder).
UPGRADE_ANGLE = math.radians(40.0)

#: Parameters of each kind, and how many samples beyond them a fit needs to count as evidence
#: (the curved kinds need two; a single triangle of a coarse export is a planar face).
_PARAMS = {"plane": 3, "cylinder": 5, "cone": 6, "sphere": 4, "torus": 7}
MIN_EXTRA_SAMPLES = {"plane": 0, "cylinder": 2, "cone": 2, "sphere": 2, "torus": 2}

#: A fit whose surface normals disagree (by more than GROW_ANGLE) with the face normals on more
#: than this share of the segment's area does not explain the segment (a fan cap fitted as a
#: torus with its cylinder ring: a third; the faces of a noisy small hole: up to a tenth).
NORMAL_OFF_SHARE = 0.2

#: A segment's fit may leave out faces off its surface up to this share of its area (a
#: boundary one triangle off); beyond it the segment is not explained.
TRIM_SHARE = 0.05

#: ... tried on segments of TRIM_MIN_FACES faces or more whose best fit is within TRIM_RMS x
#: tol, or TRIM_REL x the segment's size, in RMS (one stray face of an exact tessellation: 17
#: tol, 0.2 % of the size). Trimming every unexplained fit (unions, seed patches) tripled the
#: run time.
TRIM_RMS = 2.0
TRIM_REL = 0.01
TRIM_MIN_FACES = 50

#: Rings of boundary faces left out of a segment's core fit, and the least share of the
#: segment the core must keep.
CORE_RINGS = 2
CORE_MIN_SHARE = 0.3

#: A core's surface stands for the whole segment when the segment's faces on it (corner RMS
#: within GROW_TOL x tol) hold this share of its area; else the segment is split.
CORE_EXPLAINS = 0.85

#: A region-growing split is kept when at least SPLIT_GOOD_SHARE of the area is in pieces
#: whose fit RMS is within SPLIT_RMS_RATIO x tol (measured: true faces 1e-6 tol on clean CAD
#: meshes and 0.3-0.5 tol at noise 0.1 edge; the fandisk's freeform blends 0.8-1.0 tol).
SPLIT_RMS_RATIO = 0.65
SPLIT_GOOD_SHARE = 0.6

#: The same bar on a noisy mesh, whose true faces fit at 0.6-0.85 tol (region fits carry their
#: boundaries' noise; measured on a noisy pipe elbow's cylinder and torus).
SPLIT_RMS_RATIO_NOISY = 0.9

#: Segments of fewer faces that lie on a neighbour's surface join it (noise shards along a crease).
SHARD_FACES = 8

#: Segments with fewer faces are fitted as freeform.
MIN_FIT_FACES = 1


@dataclass
class SurfaceSegmentation:
    """Labels with one fitted surface per segment.

    Attributes
    ----------
    labels : (m,) int64
        ``0..k-1``, largest segment first, every segment face-connected.
    surfaces : list of Surface, length k
        The fitted surface of each segment.
    tol : float
        The fit tolerance used (model units).
    split : int
        Segments split by region growing (step 2).
    merged : int
        Merges of adjacent segments (step 3).
    moved : int
        Boundary faces moved (step 4).
    timings : dict
    """

    labels: np.ndarray
    surfaces: list
    tol: float
    split: int = 0
    merged: int = 0
    moved: int = 0
    timings: dict = field(default_factory=dict)


def _fit(V, F, faces, tol, kinds=None, W=None, FN=None, trim=True) -> Surface:
    """Fit ``faces`` (positions from ``V``; normals from ``W`` when given, face normals ``FN``
    indexed by face id); ``trim``: try :func:`_trimmed_fit` when the fit fails on a few
    faces."""
    if len(faces) < MIN_FIT_FACES:
        return Surface("freeform", {"centroid": V[F[faces]].reshape(-1, 3).mean(axis=0)},
                       area=float(face_areas(V, F[faces]).sum()))
    P, N, w = vertex_samples(V, F, faces, W)
    # a kind needs more samples than parameters to be evidence (any 4 points lie on a sphere)
    allowed = tuple(k for k in (SURFACE_KINDS if kinds is None else kinds)
                    if k == "freeform" or len(P) >= _PARAMS[k] + MIN_EXTRA_SAMPLES[k])
    s = fit_surface(P, N, w, tol=tol, kinds=allowed or ("freeform",))
    if trim and not s.is_analytic and len(faces) >= TRIM_MIN_FACES and s.rms <= max(
        TRIM_RMS * tol, TRIM_REL * float(np.ptp(P, axis=0).max())
    ):  # a stray face of an exact tessellation puts the RMS far above its tiny tol
        s = _trimmed_fit(V, F, faces, tol, allowed, W, s, (P, N, w)) or s
    if s.is_analytic:
        # positions alone can be fooled: a fan cap (centre + rim) and a ring of a cylinder have
        # three (radius, height) profile points, which a torus always passes through. The face
        # normals must agree with the surface's too.
        FN = face_normals(V if W is None else W, F) if FN is None else FN
        if not _normals_agree(V, F, FN, faces, s):
            return Surface("freeform", {"centroid": P.mean(axis=0)}, rms=s.rms,
                           max_dev=s.max_dev, area=float(face_areas(V, F[faces]).sum()))
    return s


def _normals_agree(V, F, FN, faces, s: Surface) -> bool:
    """At most NORMAL_OFF_SHARE of the faces' area has normals over GROW_ANGLE off ``s``'s."""
    A = face_areas(V, F[faces])
    off = _normal_angle(V, F, FN, faces, s) > GROW_ANGLE
    return bool(A[off].sum() <= NORMAL_OFF_SHARE * A.sum())


def _trimmed_fit(V, F, faces, tol, kinds, W, free: Surface, samples) -> Surface | None:
    """A segment whose best surface is within tolerance in RMS but not in its largest deviation
    usually holds a few faces of a neighbour (a boundary a triangle off): fit without the faces
    whose corners are off that surface, when they are at most TRIM_SHARE of the area. The
    boundary moves then hand those faces to the neighbour they lie on."""
    P, N, w = samples  # the faces' vertex samples, as _fit took them
    loose = fit_surface(P, N, w, tol=max(tol, free.max_dev / 2.9), kinds=kinds)
    if not loose.is_analytic:
        return None
    A = face_areas(V, F[faces])
    # one least-trimmed-squares step: the stray faces tilt the loose fit, so rank the faces by
    # their distance to it, refit without the worst TRIM_SHARE of the area, then check
    d = np.abs(loose.distance(V[F[faces]].reshape(-1, 3))).reshape(-1, 3).max(axis=1)
    order = np.argsort(d, kind="stable")
    keep = np.zeros(len(faces), dtype=bool)
    keep[order[np.cumsum(A[order]) <= (1.0 - TRIM_SHARE) * A.sum()]] = True
    if keep.sum() < 2 * MIN_REGION_FACES:
        return None
    P, N, w = vertex_samples(V, F, faces[keep], W)
    s = fit_surface(P, N, w, tol=tol, kinds=kinds)
    if not s.is_analytic:
        return None
    d = np.abs(s.distance(V[F[faces]].reshape(-1, 3))).reshape(-1, 3).max(axis=1)
    on = d <= GROW_TOL * tol
    if A[~on].sum() > TRIM_SHARE * A.sum():
        return None
    P, N, w = vertex_samples(V, F, faces[on], W)
    s = fit_surface(P, N, w, tol=tol, kinds=kinds)
    return s if s.is_analytic else None


def _rms_to(V, F, faces, s: Surface) -> float:
    """RMS distance of (a sample of about PRECHECK_SAMPLES of) the faces' vertices to ``s``."""
    if not s.is_analytic:
        return math.inf
    verts = np.unique(F[faces])
    verts = verts[:: max(1, len(verts) // PRECHECK_SAMPLES)]
    d = s.distance(V[verts])
    return float(np.sqrt((d * d).mean()))


def _explains(s: Surface, tol: float) -> bool:
    return s.is_analytic and s.rms <= tol


def _corner_rms(V, F, faces, s: Surface) -> np.ndarray:
    if not s.is_analytic:
        return np.full(len(faces), np.inf)
    d = s.distance(V[F[faces]].reshape(-1, 3)).reshape(-1, 3)
    return np.sqrt((d * d).mean(axis=1))


def _normal_angle(V, F, FN, faces, s: Surface) -> np.ndarray:
    """Angle between each face's normal (``FN``, by face id) and the surface normal at its
    centroid's projection."""
    SN = s.normals(V[F[faces]].mean(axis=1))
    cos = np.abs(np.einsum("ij,ij->i", SN, FN[faces]))
    return np.arccos(np.clip(cos, -1.0, 1.0))


def _adjacency(F: np.ndarray) -> np.ndarray:
    TT, _ = igl.triangle_triangle_adjacency(np.ascontiguousarray(F, dtype=np.int64))
    return TT


def _fits_face(V, F, FN, faces, s, tol, k_tol):
    return (_corner_rms(V, F, faces, s) <= k_tol * tol) & (
        _normal_angle(V, F, FN, faces, s) <= GROW_ANGLE
    )


def _grow_one(V, F, FN, TT, free, seed, tol, W=None):
    """Grow one region from ``seed`` over ``free`` faces; returns (faces, surface), a freeform
    surface when no surface explains the seed's patch (its SEED_RINGS rings)."""
    region = np.zeros(len(F), dtype=bool)
    ring = np.array([seed])
    patch = np.array([seed])
    for _ in range(SEED_RINGS):  # rings across smooth edges only: a patch must not span a crease
        nb = TT[ring]
        src = np.repeat(ring, 3)
        nb = nb.ravel()
        ok = (nb >= 0) & free[np.maximum(nb, 0)]
        ok[ok] &= np.einsum("ij,ij->i", FN[src[ok]], FN[nb[ok]]) >= math.cos(UPGRADE_ANGLE)
        ring = np.setdiff1d(np.unique(nb[ok]), patch)
        patch = np.union1d(patch, ring)
    s = _fit(V, F, np.asarray(patch), tol, W=W, FN=FN)
    if not s.is_analytic:
        return np.array([seed]), s
    region[seed] = True
    fitted = 1
    stalled = False
    while True:
        cand = np.unique(TT[region].ravel())
        cand = cand[(cand >= 0)]
        cand = cand[free[cand] & ~region[cand]]
        ok = _fits_face(V, F, FN, cand, s, tol, GROW_TOL) if len(cand) else np.zeros(0, bool)
        if ok.any():
            region[cand[ok]] = True
            stalled = False
            n = int(region.sum())
            if n >= 2 * fitted:
                s2 = _fit(V, F, np.flatnonzero(region), tol, W=W, FN=FN)
                if _explains(s2, tol):
                    s, fitted = s2, n
            continue
        if stalled or not len(cand):
            break
        near = cand[_fits_face(V, F, FN, cand, s, tol, STALL_TOL)]
        if not len(near):
            break
        s2 = _fit(V, F, np.r_[np.flatnonzero(region), near], tol, W=W, FN=FN)
        if not _explains(s2, tol) or s2.max_dev > 3 * tol:
            break
        s, stalled = s2, True
    faces = np.flatnonzero(region)
    if fitted < len(faces):
        s2 = _fit(V, F, faces, tol, W=W, FN=FN)
        if _explains(s2, tol):
            s = s2
    return faces, s


def grow_regions(V, F, faces, tol, FN=None, TT=None, W=None) -> np.ndarray:
    """Split a face set into regions that one surface each explains, by region growing.

    Parameters
    ----------
    V : (n, 3) float64
    F : (m, 3) int64
    faces : (k,) int64
        The face set (a segment).
    tol : float
        Fit tolerance (model units).
    FN : (m, 3) float64, optional
        Face normals; TT : (m, 3) int64, optional, ``igl.triangle_triangle_adjacency``.
    W : (n, 3) float64, optional
        Positions for normals (a denoised copy of ``V``).

    Returns
    -------
    region : (k,) int64
        Region id of each face of ``faces``, ``0..r-1``; faces no surface explains form
        regions of their own (their connected pieces).
    """
    FN = face_normals(V if W is None else W, F) if FN is None else FN
    TT = _adjacency(F) if TT is None else TT
    free = np.zeros(len(F), dtype=bool)
    free[faces] = True
    # seeds from smooth interiors first: the largest normal change to a neighbour, ascending
    nb = TT[faces]
    cosn = np.where(nb >= 0, np.einsum("ij,ikj->ik", FN[faces], FN[np.maximum(nb, 0)]), 1.0)
    order = faces[np.argsort(-cosn.min(axis=1), kind="stable")]
    out = np.full(len(F), -1, dtype=np.int64)
    tried = np.zeros(len(F), dtype=bool)
    r = 0
    for seed in order.tolist():
        if not free[seed] or tried[seed]:
            continue
        grown, s = _grow_one(V, F, FN, TT, free, seed, tol, W)
        if not s.is_analytic:  # nor, mostly, the overlapping patches of its 1-ring: skip them
            tried[seed] = True
            tried[TT[seed][TT[seed] >= 0]] = True
            continue
        # a rectangle of a coarse export is two triangles: a small region is kept when its
        # surface fits it well inside the tolerance (noise shards are absorbed later)
        exact = s.is_analytic and s.rms <= SPLIT_RMS_RATIO * tol and len(grown) >= 2
        if len(grown) < MIN_REGION_FACES and not exact:
            tried[grown] = True
            continue
        out[grown] = r
        free[grown] = False
        r += 1
    rest = faces[out[faces] < 0]
    if len(rest):  # what no surface explains: its connected pieces
        sub = np.full(len(F), -1, dtype=np.int64)
        sub[rest] = 0
        comp = _face_connected(F, np.where(out >= 0, out, len(F) + 1 + sub), TT)
        _, inv = np.unique(comp[rest], return_inverse=True)
        out[rest] = r + inv
    return out[faces]


def _merge(V, F, labels, tol, fits: dict, rejected: set | None = None, W=None, FN=None) -> int:
    """Greedy merging of adjacent segments whose union one surface explains; cheapest first.

    ``rejected`` caches the unions found unexplained (keyed by both parts' faces), so a later
    round does not refit a pair that has not changed.
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

    def agree(faces, s) -> bool:
        return _normals_agree(V, F, FNs, faces, s)

    def smooth(a, b) -> bool:
        """The boundary bends less than a crease: facets of one curved surface, maybe."""
        return bend.get((min(a, b), max(a, b)), math.pi) <= UPGRADE_ANGLE

    def push(a, b):
        # a union is fitted only when one part's surface already comes near the other part
        # (the union of two planes at an angle, or of a plane and a fillet, is never tried);
        # an unexplained piece (a shard of a thin band, a leftover of region growing) may join
        # a neighbour this way too. When one part's surface already explains the other part,
        # only its kind is refitted (one fit instead of the search over kinds).
        key = (len(faces_of[a]), int(faces_of[a].sum()), len(faces_of[b]), int(faces_of[b].sum()))
        if key in rejected:
            return
        da, db = _rms_to(V, F, faces_of[b], fits[a]), _rms_to(V, F, faces_of[a], fits[b])
        # normals too: a fan cap's vertices all lie on its cylinder's rim
        if da <= tol and _explains(fits[a], tol) and agree(faces_of[b], fits[a]):
            u = fits[a]  # a's surface explains b: no refit now (refitted once after the round)
        elif db <= tol and _explains(fits[b], tol) and agree(faces_of[a], fits[b]):
            u = fits[b]
        elif min(da, db) <= PRECHECK_TOL * tol or smooth(a, b) or (
            max(len(faces_of[a]), len(faces_of[b])) <= MERGE_SMALL_FACES
            and not _explains(fits[a], tol)
            and not _explains(fits[b], tol)
        ):
            # untrimmed (a union that needs faces cut off is not one surface), and the normals
            # of each part on its own (a small cap on a big cylinder's rim passes the union's)
            u = _fit(V, F, np.r_[faces_of[a], faces_of[b]], tol, W=W, FN=FN, trim=False)
            if u.is_analytic and not (agree(faces_of[a], u) and agree(faces_of[b], u)):
                u = None
        else:
            u = None
        if u is None or not _explains(u, tol):
            rejected.add(key)
        else:
            cost = min(da, db) if u is fits[a] or u is fits[b] else u.rms
            heapq.heappush(heap, (cost, a, b, id(u), u))

    for a, b in sorted(pairs):
        push(a, b)
    merged = 0
    while heap:
        _, a, b, _, u = heapq.heappop(heap)
        if find(a) != a or find(b) != b:  # stale: one side was merged since
            continue
        parent[b] = a
        faces_of[a] = np.concatenate([faces_of[a], faces_of.pop(b)])
        fits[a] = u
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
        fits[k] = _fit(V, F, faces_of[k], tol, W=W, FN=FN)
    return merged


def _move_boundary_faces(V, F, labels, fits: dict, tol: float, W=None, FN=None) -> int:
    """Lloyd passes: faces on boundaries go to the neighbouring surface clearly nearer to them;
    the segments that changed are refitted before the next pass."""
    moved = 0
    FN = face_normals(V if W is None else W, F) if FN is None else FN
    for _ in range(MOVE_PASSES):
        fa, fb = segment_adjacency(F, labels)
        if len(fa) == 0:
            break
        cand_face = np.r_[fa, fb]
        cand_label = np.r_[labels[fb], labels[fa]]
        own = np.full(len(F), np.inf)
        for k in np.unique(labels[cand_face]).tolist():
            sel = np.unique(cand_face[labels[cand_face] == k])
            own[sel] = _corner_rms(V, F, sel, fits[k])
        new = labels.copy()
        best = own.copy()
        for k in np.unique(cand_label).tolist():
            if not fits[k].is_analytic:
                continue
            sel = cand_face[cand_label == k]
            d = _corner_rms(V, F, sel, fits[k])
            ok = (d < MOVE_RATIO * own[sel]) & (d <= GROW_TOL * tol) & (d < best[sel])
            # a face on its own surface stays (rounding decides between two exact fits), and
            # the normals must agree (a fan cap's corners all lie on its cylinder's rim)
            ok &= own[sel] > MOVE_FLOOR * tol
            ok &= _normal_angle(V, F, FN, sel, fits[k]) <= GROW_ANGLE
            new[sel[ok]] = k
            best[sel[ok]] = d[ok]
        counts = np.bincount(new, minlength=labels.max() + 1)
        for k in np.flatnonzero((counts == 0) & (np.bincount(labels, minlength=len(counts)) > 0)):
            new[labels == k] = k  # never empty a segment
        changed = np.unique(np.r_[labels[new != labels], new[new != labels]])
        if len(changed) == 0:
            break
        moved += int((new != labels).sum())
        labels[:] = new
        for k in changed.tolist():
            fits[k] = _fit(V, F, np.flatnonzero(labels == k), tol, W=W, FN=FN)
    return moved


def _core(F, labels, faces, TT) -> np.ndarray:
    """The faces of a segment more than CORE_RINGS rings away from its boundary with other
    segments (all of them when that leaves under CORE_MIN_SHARE of the segment)."""
    core = np.zeros(len(F), dtype=bool)
    core[faces] = True
    for _ in range(CORE_RINGS):
        nb = TT[core]
        touches = ((nb >= 0) & ~core[np.maximum(nb, 0)]).any(axis=1)
        core[np.flatnonzero(core)[touches]] = False
    kept = np.flatnonzero(core)
    return kept if len(kept) >= CORE_MIN_SHARE * len(faces) else faces


def _real_split(V, F, parts, part_fits, tol, ratio=None) -> bool:
    """A split found real faces when most of the area lies in pieces fitted well inside the
    tolerance (``ratio`` x tol: true faces of an exact tessellation fit to round-off); a smooth
    freeform surface shatters into pieces each just within it, and stays whole."""
    ratio = SPLIT_RMS_RATIO if ratio is None else ratio
    A = np.array([face_areas(V, F[p]).sum() for p in parts])
    r = np.array([f.rms / tol if f.is_analytic else np.inf for f in part_fits])
    good = A[r <= ratio].sum()
    return bool(good >= SPLIT_GOOD_SHARE * A.sum())


def _smooth_teeth(V, F, labels, fits: dict, tol: float, TT, FN) -> int:
    """A face with two or three neighbours of another segment, on whose surface it lies
    (corners within GROW_TOL x tol, normal within GROW_ANGLE), joins it: the single-face teeth
    a noisy boundary leaves."""
    changed = 0
    for _ in range(MOVE_PASSES):
        nb = TT
        nl = np.where(nb >= 0, labels[np.maximum(nb, 0)], -1)
        other = nl != labels[:, None]
        cand = np.flatnonzero((other & (nl >= 0)).sum(axis=1) >= 2)
        if len(cand) == 0:
            break
        moved = 0
        new = labels.copy()
        for f in cand.tolist():
            ls, counts = np.unique(nl[f][other[f] & (nl[f] >= 0)], return_counts=True)
            if counts.max() < 2:
                continue
            k = int(ls[np.argmax(counts)])
            one = np.array([f])
            if (_corner_rms(V, F, one, fits[k])[0] <= GROW_TOL * tol
                    and _normal_angle(V, F, FN, one, fits[k])[0] <= GROW_ANGLE):
                new[f] = k
                moved += 1
        if moved == 0:
            break
        labels[:] = new
        changed += moved
    return changed


def _absorb_shards(V, F, labels, fits: dict, tol: float, TT, FN) -> np.ndarray:
    """Small segments (fewer than SHARD_FACES faces) that lie on a neighbour's surface (corner
    RMS within GROW_TOL x tol, normals agreeing) join it; unexplained ones of fewer than
    MIN_REGION_FACES faces join the nearest neighbour whatever the distance. A true small face
    (a chamfer two triangles wide) is off its neighbours' surfaces and explained by its own: it
    stays."""
    labels = labels.copy()
    counts = np.bincount(labels)
    for k in np.flatnonzero((counts > 0) & (counts < SHARD_FACES)).tolist():
        faces = np.flatnonzero(labels == k)
        nb = np.unique(labels[TT[faces][TT[faces] >= 0]])
        nb = [j for j in nb.tolist() if j != k]
        if not nb:
            continue
        d = [float(np.sqrt(np.mean(_corner_rms(V, F, faces, fits[j]) ** 2))) for j in nb]
        j = int(np.argmin(d))
        tiny = len(faces) < MIN_REGION_FACES and not _explains(fits[k], tol)
        on = d[j] <= GROW_TOL * tol and _normals_agree(V, F, FN, faces, fits[nb[j]])
        if on or tiny:
            labels[faces] = nb[j]
    return labels


def _face_connected(F, labels, TT=None) -> np.ndarray:
    """Split every label into its face-connected pieces; returns piece ids ``0..p-1``."""
    TT = _adjacency(F) if TT is None else TT
    fa = np.repeat(np.arange(len(F)), 3)
    fb = TT.ravel()
    keep = (fb >= 0) & (labels[np.maximum(fb, 0)] == labels[fa])
    A = sp.csr_matrix((np.ones(int(keep.sum())), (fa[keep], fb[keep])), shape=(len(F),) * 2)
    return connected_components(A, directed=False)[1].astype(np.int64)


def refine_segmentation(
    V: np.ndarray,
    F: np.ndarray,
    labels: np.ndarray,
    tol: float | None = None,
    *,
    split: bool = True,
    merge: bool = True,
    normals_from: np.ndarray | None = None,
    progress=None,
) -> SurfaceSegmentation:
    """Fit a surface to every segment; split, merge and move boundaries by the fits.

    Parameters
    ----------
    V : (n, 3) float64
    F : (m, 3) int64
        A validated mesh.
    labels : (m,) int64
        Initial segmentation (e.g. the heat segmentation).
    tol : float, optional
        Fit tolerance (model units); default
        :func:`~igl_heatseg.surfaces.tolerance.vertex_tolerance` (distances are measured at
        vertices, which lie on the true surface whatever the facet size).
    split : bool
        Split segments that no surface explains (step 2).
    merge : bool
        Merge adjacent segments that one surface explains (step 3).
    normals_from : (n, 3) float64, optional
        Positions the normals are taken from (a denoised copy of ``V``: noisy face normals
        mislead seeds and growth); distances are always measured on ``V``.
    progress : callable(stage, fraction), optional

    Returns
    -------
    SurfaceSegmentation

    Examples
    --------
    >>> import igl, numpy as np
    >>> V, F = igl.loop(*igl.icosahedron(), 3)
    >>> V /= np.linalg.norm(V, axis=1, keepdims=True)          # a sphere tessellation
    >>> r = refine_segmentation(V, F, (V[F].mean(axis=1)[:, 0] > 0).astype(np.int64))
    >>> [s.kind for s in r.surfaces], r.merged                 # two halves merge into one
    (['sphere'], 1)
    """
    progress = progress or (lambda stage, fraction=1.0: None)
    V = np.ascontiguousarray(V, dtype=np.float64)
    F = np.ascontiguousarray(F, dtype=np.int64)
    t0 = time.perf_counter()
    timings = {}
    W = None if normals_from is None else np.ascontiguousarray(normals_from, dtype=np.float64)
    TT = _adjacency(F)
    FN = face_normals(V if W is None else W, F)
    labels = _face_connected(F, np.asarray(labels, dtype=np.int64), TT)
    tol = vertex_tolerance(V, F) if tol is None else float(tol)
    exact = exact_tessellation(V, F)
    split_ratio = SPLIT_RMS_RATIO if exact else SPLIT_RMS_RATIO_NOISY
    timings["tolerance"] = time.perf_counter() - t0

    t = time.perf_counter()
    ks = np.unique(labels).tolist()
    fits = {}
    n_split = 0
    nxt = max(ks) + 1
    for i, k in enumerate(ks):
        progress("fit", i / max(len(ks), 1))
        faces = np.flatnonzero(labels == k)
        s = _fit(V, F, faces, tol, W=W, FN=FN)
        if not _explains(s, tol) and not exact:
            # a noisy boundary carries a few of the neighbours' faces: fit the core (an exact
            # tessellation's boundaries are exact: there a segment off its surface is split)
            core = _core(F, labels, faces, TT)
            if len(core) < len(faces):
                s_core = _fit(V, F, core, tol, W=W, FN=FN)
                A = face_areas(V, F[faces])
                on = _corner_rms(V, F, faces, s_core) <= GROW_TOL * tol
                if _explains(s_core, tol) and A[on].sum() >= CORE_EXPLAINS * A.sum():
                    s = s_core
        if split and not _explains(s, tol) and len(faces) >= 2 * MIN_REGION_FACES:
            sub = grow_regions(V, F, faces, tol, FN, TT, W)
            parts = [faces[sub == r] for r in range(int(sub.max()) + 1)]
            part_fits = [_fit(V, F, part, tol, W=W, FN=FN) for part in parts]
            if len(parts) > 1 and _real_split(V, F, parts, part_fits, tol, split_ratio):
                n_split += 1
                for r, (part, fr) in enumerate(zip(parts, part_fits, strict=True)):
                    lab = k if r == 0 else nxt
                    nxt += r > 0
                    labels[part] = lab
                    fits[lab] = fr
                continue
        fits[k] = s
    timings["fit_split"] = time.perf_counter() - t

    merged = moved = 0
    timings["merge"] = timings["boundaries"] = 0.0
    rejected: set = set()
    for _ in range(ROUNDS):  # moves can make segments adjacent that a merge then joins
        t = time.perf_counter()
        progress("merge", 0.0)
        m_round = _merge(V, F, labels, tol, fits, rejected, W, FN) if merge else 0
        timings["merge"] += time.perf_counter() - t
        t = time.perf_counter()
        progress("boundaries", 0.0)
        mv_round = _move_boundary_faces(V, F, labels, fits, tol, W, FN)
        mv_round += _smooth_teeth(V, F, labels, fits, tol, TT, FN)
        pieces = _face_connected(F, labels, TT)  # a move may cut a segment in two
        if len(np.unique(pieces)) != len(fits):
            labels = pieces
            fits = {k: _fit(V, F, np.flatnonzero(labels == k), tol, W=W, FN=FN)
                    for k in np.unique(labels)}
        timings["boundaries"] += time.perf_counter() - t
        merged += m_round
        moved += mv_round
        if m_round == 0 and mv_round == 0:
            break
    t = time.perf_counter()
    labels = _absorb_shards(V, F, labels, fits, tol, TT, FN)
    timings["shards"] = time.perf_counter() - t

    t = time.perf_counter()
    area = face_areas(V, F)
    _, inv = np.unique(labels, return_inverse=True)
    order = np.argsort(-np.bincount(inv, weights=area), kind="stable")
    rank = np.empty_like(order)
    rank[order] = np.arange(len(order))
    labels = rank[inv].astype(np.int64)
    surfaces = [_fit(V, F, np.flatnonzero(labels == k), tol, W=W, FN=FN) for k in range(len(order))]
    timings["final_fit"] = time.perf_counter() - t
    progress("surfaces", 1.0)
    log.info("surfaces: %d segments (%d split, %d merges, %d faces moved), tol %.3g",
             len(surfaces), n_split, merged, moved, tol)
    return SurfaceSegmentation(labels, surfaces, tol, n_split, merged, moved, timings)


def fit_segments(
    V: np.ndarray,
    F: np.ndarray,
    labels: np.ndarray,
    tol: float | None = None,
    normals_from: np.ndarray | None = None,
) -> list:
    """One fitted surface per segment, the labels as they are.

    Parameters
    ----------
    V : (n, 3) float64
    F : (m, 3) int64
    labels : (m,) int64
        ``0..k-1``.
    tol : float, optional
        Default :func:`~igl_heatseg.surfaces.tolerance.vertex_tolerance`.
    normals_from : (n, 3) float64, optional
        Positions the normals come from (a denoised copy of ``V``).

    Returns
    -------
    surfaces : list of Surface, length k
        Fitted at the vertices, a few stray boundary faces trimmed (as in
        :func:`refine_segmentation`).

    Examples
    --------
    >>> import igl, numpy as np
    >>> V, F = igl.loop(*igl.icosahedron(), 3)
    >>> V /= np.linalg.norm(V, axis=1, keepdims=True)
    >>> [s.kind for s in fit_segments(V, F, np.zeros(len(F), dtype=np.int64))]
    ['sphere']
    """
    V = np.ascontiguousarray(V, dtype=np.float64)
    F = np.ascontiguousarray(F, dtype=np.int64)
    W = None if normals_from is None else np.ascontiguousarray(normals_from, dtype=np.float64)
    tol = vertex_tolerance(V, F) if tol is None else float(tol)
    FN = face_normals(V if W is None else W, F)
    k = int(labels.max()) + 1 if len(labels) else 0
    return [_fit(V, F, np.flatnonzero(labels == i), tol, W=W, FN=FN) for i in range(k)]
