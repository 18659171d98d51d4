"""Fit-driven refinement of a segmentation: one fitted surface per segment.

On top of a heat segmentation (the paper's seeds and fields stay the initialisation):

1. **Fit** every segment (:func:`~igl_heatseg.surfaces.fit.fit_surface`: the simplest kind
   within the mesh's own tolerance, :func:`~igl_heatseg.surfaces.tolerance.vertex_tolerance`).
2. **Split** every segment that no surface explains by fit-driven region growing inside it
   (:func:`grow_regions`): seeds from smooth interiors, a surface fitted to the seed's rings,
   growth over faces whose corners lie on it, refits as the region grows (a small patch of a
   cylinder looks planar; the refit on the grown region finds the cylinder; on an exact
   tessellation a seed whose rings no surface explains is fitted on its rings across flat edges:
   slivers of a plane beside a tangent fillet). On an exact tessellation, the faces off their
   segment's surface and the faces of tiny segments are then gathered and grown again
   (:func:`_regrow_strays`): a chamfer one triangle wide, dealt out between its two neighbours
   by the heat fields, becomes one cone. On a noisy mesh, so do
   the seams of two segments that one surface explains far better than the two (a fillet two
   triangles wide dealt out down its middle: :mod:`~igl_heatseg.surfaces.seams`); and a segment
   whose surface explains it but fits worse than a merge accepts of a union
   (:data:`OVERFIT_RATIO`) is split too, at that tighter tolerance: two faces joined smoothly.
3. **Merge** adjacent segments that one surface explains within tolerance, cheapest union first
   (Attene et al. 2006): strips of a coarse cylinder, a plane split by noise
   (:mod:`~igl_heatseg.surfaces.merge`).
4. **Move boundary faces** to the neighbouring surface they lie on, refitting between passes (a
   Lloyd loop as in variational shape approximation, Cohen-Steiner et al. 2004), so boundaries
   follow the crease instead of zig-zagging along triangle edges.
5. On a noisy mesh, **place the boundaries of tangent joins** by a minimum cut, then merge again
   (:mod:`~igl_heatseg.surfaces.boundary_cut`): step 4 leaves the heat fields' zig-zag there.
   Then a segment fitting worse than the noise is split where it falls apart into surfaces
   fitting clearly better, else gives neighbours the faces on their surfaces (:mod:`.loose`);
   after step 6, tangent pipe joints get their border (:mod:`.joints`).
6. **Shed strays**: a border face standing across its analytic surface goes to the neighbour
   it faces (:mod:`~igl_heatseg.surfaces.strays`; step 4 gives faces only to analytic
   neighbours that fit them, so a freeform neighbour's triangle stayed); on a noisy mesh a
   patch of such faces that no neighbour takes becomes a segment (a blind hole's bottom in
   its wall's segment: :func:`~igl_heatseg.surfaces.strays.cut_caps`). On an exact
   tessellation, small pieces a segment holds only across creases leave it, unless they lie
   on its surface (a coarse small hole's facets) (:func:`~.strays.split_at_creases`); a small
   segment's faces go to the neighbours they lie on (:func:`~.strays.dissolve_mixtures`), step
   3 runs once more (a coarse cylinder's facet strips, which a cap's triangle among them kept
   apart), and a flat that a cylinder through its corners took leaves it
   (:func:`~.strays.split_chords`). Where three or more fillets of one radius meet and deal out
   their corner between them, the sphere their axes imply gets its own segment
   (:func:`~igl_heatseg.surfaces.seams.corner_blends`).

Distances are measured at the mesh vertices: the vertices of a CAD tessellation lie on the
true surface, its face centroids do not (they sit a chord's sagitta inside a curved face).
"""

from __future__ import annotations

import hashlib
import logging
import math
import time
from dataclasses import dataclass, field

import igl
import numpy as np

from ..mesh.geometry import face_areas, face_normals
from ..mesh.topology import label_pieces
from .axes import snap_to_axes
from .boundary_cut import swap_boundaries
from .joints import tangent_joints
from .loose import absorb_loose, split_loose
from .merge import MERGE_NOISE_RATIO, MERGE_NOISE_SLACK, UPGRADE_ANGLE, merge_segments
from .samples import normal_positions, segment_adjacency, vertex_samples
from .seams import corner_blends, corner_sphere, seam_blends
from .segment_fit import (
    GROW_ANGLE,
    GROW_TOL,
    MIN_REGION_FACES,
    closer_kind,
    corner_max_dev,
    corner_rms,
    explains,
    fit_faces,
    normal_angle,
    refit_segments,
)
from .split import (
    SPLIT_GOOD_SHARE,
    SPLIT_RMS_RATIO,
    SPLIT_RMS_RATIO_NOISY,
    consistent_faces,
    crease_regions,
    evidence,
    face_pieces,
    fold_weak,
    ransac_regions,
    real_split,
)
from .strays import (
    SHARD_FACES,
    absorb_shards,
    cut_caps,
    dissolve_mixtures,
    shed_strays,
    split_at_creases,
    split_chords,
)
from .tolerance import K_NOISE, exact_tessellation, vertex_tolerance

__all__ = [
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

#: When growth stalls, faces within STALL_TOL x tol are tried in a refit of the region (a
#: cylinder first fitted as a plane on a small patch).
STALL_TOL = 6.0

#: Rings of neighbours around a seed face in its first fit.
SEED_RINGS = 2

#: On an exact tessellation a seed whose rings no surface explains is fitted on its rings across
#: flat edges (normals within this angle) when they hold FLAT_SEED_FACES faces (not a cylinder's
#: 2-triangle facet): a coarse plane of slivers by tangent fillets (f41 housing_s41034_coarse_n0).
FLAT_SEED_ANGLE = math.radians(0.5)
FLAT_SEED_FACES = 3

#: Rings of boundary faces left out of a segment's core fit, and the least share of the
#: segment the core must keep.
CORE_RINGS = 2
CORE_MIN_SHARE = 0.3

#: A core's surface stands for the whole segment when the segment's faces on it (corner RMS
#: within GROW_TOL x tol) hold this share of its area; else the segment is split.
CORE_EXPLAINS = 0.85

#: On a noisy mesh, a face is off its segment's surface for :func:`_regrow_strays` when one of
#: its corners is farther than this x tol. tol is 2.5 noise levels, so this is 5 of them, which
#: Gaussian noise alone passes at about one vertex in 2 million. On the housing rim of
#: :func:`_regrow_strays` the corners' RMS at 3 x tol took 23 of its 208 faces (the rim is
#: tilted: its faces next to a plane lie close to it), at 2 x tol 158. The farthest corner
#: (not the RMS) also takes the row of a narrow face whose faces have one corner on it and two
#: on the neighbour: without it the rim of f21 housing_s21002_frontal_n0.1 (146 faces, dealt
#: out between 6 planes) was gathered in pieces under REGROW_MIN_FACES_NOISY, and the CAD
#: build faceted all 6 planes.
STRAY_TOL_NOISY = 2.0

#: ... and a region grown again from them becomes a segment with at least this many faces:
#: where noisy faces meet at a junction, regions of 3-31 faces off every neighbour's surface
#: became segments (f18 knob_s18003_frontal_n0.2: 32 -> 44 segments without this bar, 32 with
#: it; f20 sprocket_s20001_frontal_n0.05: 110 -> 134, with it 112).
REGROW_MIN_FACES_NOISY = 20

#: On a noisy mesh a segment whose surface explains it (RMS within tol) but fits worse than
#: this x tol fits worse than the merges accept of a union (the noise level tol / K_NOISE times
#: MERGE_NOISE_RATIO, plus MERGE_NOISE_SLACK x tol): two faces joined smoothly that the heat
#: fields left as one segment (a plane running tangentially into a cylinder of radius 20 at
#: noise 0.05: one torus at 0.7 tol). It is split as an unexplained one, with this x tol as the
#: tolerance; the split must still be real (:func:`~.split.real_split`), so a single noisy
#: surface whose fit is a little worse stays whole.
OVERFIT_RATIO = MERGE_NOISE_RATIO / K_NOISE + MERGE_NOISE_SLACK


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
        Boundary faces moved (steps 4 and 6).
    timings : dict
    coaxial : int
        Planes retyped as cylinders or cones about the part's axes
        (:func:`~igl_heatseg.surfaces.axes.snap_to_axes`).
    """

    labels: np.ndarray
    surfaces: list
    tol: float
    split: int = 0
    merged: int = 0
    moved: int = 0
    timings: dict = field(default_factory=dict)
    coaxial: int = 0


def _adjacency(F: np.ndarray) -> np.ndarray:
    TT, _ = igl.triangle_triangle_adjacency(np.ascontiguousarray(F, dtype=np.int64))
    return TT


def _seed_patch(FN, TT, free, seed, angle):
    """The seed and its SEED_RINGS rings of free faces across edges whose normals turn by less
    than ``angle``."""
    ring = np.array([seed])
    patch = np.array([seed])
    for _ in range(SEED_RINGS):  # rings across smooth edges only: a patch must not span a crease
        nb = TT[ring]
        src = np.repeat(ring, 3)
        nb = nb.ravel()
        ok = (nb >= 0) & free[np.maximum(nb, 0)]
        ok[ok] &= np.einsum("ij,ij->i", FN[src[ok]], FN[nb[ok]]) >= math.cos(angle)
        ring = np.setdiff1d(np.unique(nb[ok]), patch)
        patch = np.union1d(patch, ring)
    return patch


def _grow_one(V, F, FN, TT, free, seed, tol, W=None, flat_seeds=False):
    """Grow one region from ``seed`` over ``free`` faces; returns (faces, surface, own): the
    surface is a freeform one when no surface explains the seed's patch (its SEED_RINGS rings;
    with ``flat_seeds``, then its rings across flat edges, FLAT_SEED_ANGLE); own is the fit of
    exactly ``faces`` when one was made, else None."""
    region = np.zeros(len(F), dtype=bool)
    patch = _seed_patch(FN, TT, free, seed, UPGRADE_ANGLE)
    s = fit_faces(V, F, patch, tol, W=W, FN=FN)
    if not s.is_analytic and flat_seeds:
        flat = _seed_patch(FN, TT, free, seed, FLAT_SEED_ANGLE)
        if len(flat) >= FLAT_SEED_FACES:
            s = fit_faces(V, F, flat, tol, W=W, FN=FN)
    if not s.is_analytic:
        return np.array([seed]), s, None
    region[seed] = True
    fitted = 1
    own_n = -1  # the region's size when s was fitted to exactly the region, else -1
    stalled = False
    while True:
        cand = np.unique(TT[region].ravel())
        cand = cand[(cand >= 0)]
        cand = cand[free[cand] & ~region[cand]]
        ok = consistent_faces(V, F, FN, cand, s, tol, GROW_TOL) if len(cand) else np.zeros(0, bool)
        if ok.any():
            region[cand[ok]] = True
            stalled = False
            n = int(region.sum())
            if n >= 2 * fitted:
                s2 = fit_faces(V, F, np.flatnonzero(region), tol, W=W, FN=FN)
                if explains(s2, tol):
                    s, fitted, own_n = s2, n, n
            continue
        if stalled or not len(cand):
            break
        near = cand[consistent_faces(V, F, FN, cand, s, tol, STALL_TOL)]
        if not len(near):
            break
        s2 = fit_faces(V, F, np.r_[np.flatnonzero(region), near], tol, W=W, FN=FN)
        if not explains(s2, tol) or s2.max_dev > 3 * tol:
            break
        s, stalled, own_n = s2, True, -1  # (fitted to more than the region)
    faces = np.flatnonzero(region)
    own = s if own_n == len(faces) else None
    if fitted < len(faces):
        own = fit_faces(V, F, faces, tol, W=W, FN=FN)
        if explains(own, tol):
            s = own
    return faces, s, own


def grow_regions(V, F, faces, tol, FN=None, TT=None, W=None, good_rms=None,
                 noisy=False, flat_seeds=False) -> np.ndarray:
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
    good_rms : float, optional
        Give up as soon as no split can be real (:func:`~.split.real_split` with this ratio): when
        regions fitted worse than ``good_rms`` x tol already cover more than
        ``1 - SPLIT_GOOD_SHARE`` of the area (a smooth freeform segment, which shatters into
        regions each just within the tolerance); then every face gets region 0.
    noisy : bool
        With ``good_rms``: a region counts as fitted worse only when its fit is evidence
        (:func:`~.split.evidence`), as in :func:`~.split.real_split` on a noisy mesh.
    flat_seeds : bool
        A seed whose rings no surface explains is tried on its rings across flat edges
        (FLAT_SEED_ANGLE), when they hold FLAT_SEED_FACES faces or more (for exact
        tessellations, whose flat faces are flat to round-off).

    Returns
    -------
    region : (k,) int64
        Region id of each face of ``faces``, ``0..r-1``; faces no surface explains form
        regions of their own (their connected pieces).

    Examples
    --------
    >>> import numpy as np
    >>> from scipy.spatial import Delaunay
    >>> x, y = np.meshgrid(np.linspace(-1, 1, 9), np.linspace(0, 1, 5))
    >>> V = np.c_[x.ravel(), y.ravel(), np.abs(x.ravel())]          # a fold: two planes
    >>> F = Delaunay(V[:, :2]).simplices.astype(np.int64)
    >>> np.bincount(grow_regions(V, F, np.arange(len(F)), 1e-6))
    array([32, 32])
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
    if good_rms is not None:
        area = face_areas(V, F[faces])
        lost_bar, lost = (1.0 - SPLIT_GOOD_SHARE) * area.sum(), 0.0
        area_of = np.zeros(len(F))
        area_of[faces] = area
    for seed in order.tolist():
        if not free[seed] or tried[seed]:
            continue
        grown, s, own = _grow_one(V, F, FN, TT, free, seed, tol, W, flat_seeds)
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
        if good_rms is None:
            continue
        own = fit_faces(V, F, grown, tol, W=W, FN=FN) if own is None else own
        if (not own.is_analytic or own.rms > good_rms * tol) and (
                not noisy or evidence(F, grown, own)):
            lost += area_of[grown].sum()
            if lost > lost_bar:  # the good regions can no longer hold SPLIT_GOOD_SHARE
                return np.zeros(len(faces), dtype=np.int64)
    rest = faces[out[faces] < 0]
    if len(rest):  # what no surface explains: its connected pieces
        out[rest] = r + face_pieces(F, TT, rest)
    return out[faces]


def _move_boundary_faces(V, F, labels, fits: dict, tol: float, W=None, FN=None, TT=None) -> int:
    """Lloyd passes: faces on boundaries go to the neighbouring surface clearly nearer to them;
    the segments that changed are refitted before the next pass."""
    moved = 0
    FN = face_normals(V if W is None else W, F) if FN is None else FN
    for _ in range(MOVE_PASSES):
        fa, fb = segment_adjacency(F, labels, TT)
        if len(fa) == 0:
            break
        cand_face = np.r_[fa, fb]
        cand_label = np.r_[labels[fb], labels[fa]]
        own = np.full(len(F), np.inf)
        for k in np.unique(labels[cand_face]).tolist():
            sel = np.unique(cand_face[labels[cand_face] == k])
            own[sel] = corner_rms(V, F, sel, fits[k])
        new = labels.copy()
        best = own.copy()
        for k in np.unique(cand_label).tolist():
            if not fits[k].is_analytic:
                continue
            sel = cand_face[cand_label == k]
            d = corner_rms(V, F, sel, fits[k])
            ok = (d < MOVE_RATIO * own[sel]) & (d <= GROW_TOL * tol) & (d < best[sel])
            # a face on its own surface stays (rounding decides between two exact fits), and
            # the normals must agree (a fan cap's corners all lie on its cylinder's rim)
            ok &= own[sel] > MOVE_FLOOR * tol
            ok &= normal_angle(V, F, FN, sel, fits[k]) <= GROW_ANGLE
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
            fits[k] = fit_faces(V, F, np.flatnonzero(labels == k), tol, W=W, FN=FN)
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
            if (corner_rms(V, F, one, fits[k])[0] <= GROW_TOL * tol
                    and normal_angle(V, F, FN, one, fits[k])[0] <= GROW_ANGLE):
                new[f] = k
                moved += 1
        if moved == 0:
            break
        labels[:] = new
        changed += moved
    return changed


def _regrow_strays(V, F, labels, fits: dict, tol: float, TT, W, FN, nxt: int,
                   exact: bool = True) -> int:
    """The faces off their segment's surface (corner RMS above GROW_TOL x tol; on a noisy mesh a
    corner farther than STRAY_TOL_NOISY x tol) and, on an exact tessellation, the faces of segments
    under SHARD_FACES faces, gathered, are grown into regions again (:func:`grow_regions`); a region
    that one surface explains, of at least MIN_REGION_FACES faces (on a noisy mesh:
    REGROW_MIN_FACES_NOISY, and evidence, :func:`~.split.evidence`), across two segments or more,
    becomes a segment. The heat fields give each triangle of a chamfer one triangle wide (no vertex
    inside it) the label of two of its corners, so the band alternates between its two neighbours,
    and no segment holds two of its faces side by side; on noise the same happens to a narrow face a
    few triangles wide (the rim of f19 housing_s19002_frontal_n0.1, dealt out between 7 planes, its
    vertices up to 3.4 off them at a tolerance of 0.64: the CAD build faceted all of them). Returns
    the segments made."""
    counts = np.bincount(labels)
    stray = np.zeros(len(F), dtype=bool)
    if exact:
        stray[counts[labels] < SHARD_FACES] = True
    bar = (GROW_TOL if exact else STRAY_TOL_NOISY) * tol
    for k, s in fits.items():
        if s.is_analytic and counts[k] >= SHARD_FACES:
            faces = np.flatnonzero(labels == k)
            if exact:
                stray[faces[corner_rms(V, F, faces, s) > bar]] = True
            else:  # a face with one corner off: the narrow face's row beside its neighbour
                stray[faces[corner_max_dev(V, F, faces, s) > bar]] = True
    cand = np.flatnonzero(stray)
    if len(cand) < MIN_REGION_FACES:
        return 0
    sub = grow_regions(V, F, cand, tol, FN, TT, W)
    made, touched = 0, set()
    for r in range(int(sub.max()) + 1):
        part = cand[sub == r]
        if len(part) < MIN_REGION_FACES or len(np.unique(labels[part])) < 2:
            continue  # (a region within one segment: the segment's own business)
        u = fit_faces(V, F, part, tol, W=W, FN=FN)
        if not explains(u, tol) or not (exact or (evidence(F, part, u)
                                                   and len(part) >= REGROW_MIN_FACES_NOISY)):
            continue
        touched.update(np.unique(labels[part]).tolist())
        labels[part] = nxt
        fits[nxt] = u
        nxt += 1
        made += 1
    refit_segments(V, F, labels, fits, touched, tol, W, FN)  # what the regions left, once
    return made


def _reconnect(V, F, labels, fits: dict, tol: float, TT, W, FN):
    """(labels, fits) with every segment face-connected: when a segment fell apart, every
    piece gets its own label and all segments are refitted."""
    pieces = _face_connected(F, labels, TT)
    if len(np.unique(pieces)) == len(fits):
        return labels, fits
    return pieces, {k: fit_faces(V, F, np.flatnonzero(pieces == k), tol, W=W, FN=FN)
                    for k in np.unique(pieces)}


def _face_connected(F, labels, TT=None) -> np.ndarray:
    """Split every label into its face-connected pieces; returns piece ids ``0..p-1``."""
    return label_pieces(F, labels, _adjacency(F) if TT is None else TT)


def _split(V, F, faces, tol, FN, TT, W, ratio, exact, unsplit):
    """Region growing, then on a noisy mesh RANSAC
    (:func:`~igl_heatseg.surfaces.split.ransac_regions`) and on an exact tessellation a cut at
    the set's own creases (:func:`~igl_heatseg.surfaces.split.crease_regions`: faces a few
    triangles wide, which growth breaks into pieces that are no evidence), until one finds
    real faces
    (:func:`~igl_heatseg.surfaces.split.real_split`); else ``(None, None)``, and the face set's
    digest goes into ``unsplit``, whose sets are not tried again (the split
    is deterministic; a smooth scan's second pass repeated half its refinement). On an exact
    tessellation growth is held to round-off and does not stall on small holes, and RANSAC
    shattered freeform blends (fandisk robust: 36 -> 87 segments, 50 one-face)."""
    key = hashlib.blake2b(np.asarray(faces, dtype=np.int64).tobytes(), digest_size=16).digest()
    if key in unsplit:
        return None, None
    for how in ("grow", "crease") if exact else ("grow", "ransac"):
        if how == "grow":
            sub = grow_regions(V, F, faces, tol, FN, TT, W, ratio, not exact, exact)
        elif how == "crease":
            sub = crease_regions(V, F, faces, tol, TT, W, FN)
        else:
            sub = ransac_regions(V, F, faces, tol, FN, TT, W)
        parts = [faces[sub == r] for r in range(int(sub.max()) + 1)]
        part_fits = [fit_faces(V, F, part, tol, W=W, FN=FN) for part in parts]
        if not exact and len(parts) > 1:
            parts, part_fits = fold_weak(V, F, TT, tol, W, FN, parts, part_fits, how == "ransac")
        if len(parts) > 1 and real_split(V, F, parts, part_fits, tol, ratio, not exact):
            return parts, part_fits
    unsplit.add(key)
    return None, None


def _overfit(s, tol, exact) -> bool:
    """A noisy segment its surface explains, but worse than a merge would accept
    (:data:`OVERFIT_RATIO`)."""
    return not exact and explains(s, tol) and s.rms > OVERFIT_RATIO * tol


def _split_segment(V, F, faces, s, tol, FN, TT, W, ratio, exact, unsplit):
    """:func:`_split` of one segment fitted by ``s``: an unexplained one at ``tol``, an
    over-fitted one (:func:`_overfit`) at OVERFIT_RATIO x tol, its parts then refitted at
    ``tol``."""
    if not _overfit(s, tol, exact):
        return _split(V, F, faces, tol, FN, TT, W, ratio, exact, unsplit)
    return _split_refit(V, F, faces, OVERFIT_RATIO * tol, tol, FN, TT, W, ratio, exact, unsplit)


def _by_area(labels, area):
    """Labels renumbered by decreasing segment area, and each segment's faces."""
    _, inv = np.unique(labels, return_inverse=True)
    order = np.argsort(-np.bincount(inv, weights=area), kind="stable")
    rank = np.empty_like(order)
    rank[order] = np.arange(len(order))
    labels = rank[inv].astype(np.int64)
    return labels, [np.flatnonzero(labels == k) for k in range(len(order))]


def _split_refit(V, F, faces, t, tol, FN, TT, W, ratio, exact, unsplit):
    """:func:`_split` at the tighter tolerance ``t``, the parts then refitted at ``tol``."""
    parts, _ = _split(V, F, faces, t, FN, TT, W, ratio, exact, unsplit)
    if parts is None:
        return None, None
    return parts, [fit_faces(V, F, part, tol, W=W, FN=FN) for part in parts]


def _split_unexplained(V, F, labels, fits, tol, TT, W, FN, ratio, exact, unsplit) -> int:
    """Split again the segments that no surface explains after the merges, moves and cuts
    (:func:`_split`; they mix faces the first split never saw together); labels and fits in
    place. Returns the number of segments split."""
    n = 0
    nxt = int(labels.max()) + 1
    for k in [k for k, s in fits.items() if not explains(s, tol) or _overfit(s, tol, exact)]:
        faces = np.flatnonzero(labels == k)
        if len(faces) < 2 * MIN_REGION_FACES:
            continue
        parts, part_fits = _split_segment(V, F, faces, fits[k], tol, FN, TT, W, ratio, exact,
                                          unsplit)
        for r, (part, fr) in enumerate(zip(parts or [], part_fits or [], strict=True)):
            lab = k if r == 0 else nxt
            nxt += r > 0
            labels[part] = lab
            fits[lab] = fr
        n += parts is not None
    return n


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
    exact: bool | None = None,
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
    exact : bool, optional
        Whether the mesh is an exact tessellation
        (:func:`~igl_heatseg.surfaces.tolerance.exact_tessellation`, computed when omitted).

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
    W = normal_positions(V, normals_from)
    TT = _adjacency(F)
    FN = face_normals(V if W is None else W, F)
    labels = _face_connected(F, np.asarray(labels, dtype=np.int64), TT)
    tol = vertex_tolerance(V, F) if tol is None else float(tol)
    exact = exact_tessellation(V, F) if exact is None else bool(exact)
    split_ratio = SPLIT_RMS_RATIO if exact else SPLIT_RMS_RATIO_NOISY
    timings["tolerance"] = time.perf_counter() - t0

    t = time.perf_counter()
    ks = np.unique(labels).tolist()
    fits = {}
    n_split = 0
    unsplit: set = set()  # the face sets _split left whole
    nxt = max(ks) + 1
    for i, k in enumerate(ks):
        progress("fit", i / max(len(ks), 1))
        faces = np.flatnonzero(labels == k)
        s = fit_faces(V, F, faces, tol, W=W, FN=FN)
        if not explains(s, tol) and not exact:
            # a noisy boundary carries a few of the neighbours' faces: fit the core (an exact
            # tessellation's boundaries are exact: there a segment off its surface is split)
            core = _core(F, labels, faces, TT)
            if len(core) < len(faces):
                s_core = fit_faces(V, F, core, tol, W=W, FN=FN)
                A = face_areas(V, F[faces])
                on = corner_rms(V, F, faces, s_core) <= GROW_TOL * tol
                if explains(s_core, tol) and A[on].sum() >= CORE_EXPLAINS * A.sum():
                    s = s_core
        if split and len(faces) >= 2 * MIN_REGION_FACES and (
                not explains(s, tol) or _overfit(s, tol, exact)):
            parts, part_fits = _split_segment(V, F, faces, s, tol, FN, TT, W, split_ratio,
                                              exact, unsplit)
            if parts is not None:
                n_split += 1
                for r, (part, fr) in enumerate(zip(parts, part_fits, strict=True)):
                    lab = k if r == 0 else nxt
                    nxt += r > 0
                    labels[part] = lab
                    fits[lab] = fr
                continue
        fits[k] = s
    if split:
        n_split += _regrow_strays(V, F, labels, fits, tol, TT, W, FN, nxt, exact)
        if not exact:  # a narrow fillet dealt out down its middle (noise hides it otherwise)
            n_split += seam_blends(V, F, labels, fits, tol, TT, W, FN)
        labels, fits = _reconnect(V, F, labels, fits, tol, TT, W, FN)  # old segments may split
    timings["fit_split"] = time.perf_counter() - t

    merged = moved = 0
    timings["merge"] = timings["boundaries"] = 0.0
    rejected: set = set()
    for _ in range(ROUNDS):  # moves can make segments adjacent that a merge then joins
        t = time.perf_counter()
        progress("merge", 0.0)
        m_round = (merge_segments(V, F, labels, tol, fits, rejected, W, FN, not exact)
                   if merge else 0)
        timings["merge"] += time.perf_counter() - t
        t = time.perf_counter()
        progress("boundaries", 0.0)
        mv_round = _move_boundary_faces(V, F, labels, fits, tol, W, FN, TT)
        mv_round += _smooth_teeth(V, F, labels, fits, tol, TT, FN)
        labels, fits = _reconnect(V, F, labels, fits, tol, TT, W, FN)  # a move may cut one
        timings["boundaries"] += time.perf_counter() - t
        merged += m_round
        moved += mv_round
        if m_round == 0 and mv_round == 0:
            break
    t = time.perf_counter()
    if not exact:  # step 5 (an exact tessellation's boundaries are its creases already)
        for k in (cut := swap_boundaries(V, F, labels, fits, tol, TT, FN)):
            fits[k] = fit_faces(V, F, np.flatnonzero(labels == k), tol, W=W, FN=FN)
        labels, fits = _reconnect(V, F, labels, fits, tol, TT, W, FN)
        if cut and merge:  # what the cut left of a segment may join a neighbour's surface
            merged += merge_segments(V, F, labels, tol, fits, rejected, W, FN, not exact)
    timings["boundary_cut"] = time.perf_counter() - t
    t = time.perf_counter()
    late = _split_unexplained(V, F, labels, fits, tol, TT, W, FN, split_ratio, exact,
                              unsplit) if split else 0
    if split and not exact:  # a loose segment: split near the noise, else given away
        loose_unsplit: set = set()  # (a face set left whole at tol may split nearer the noise)
        late += split_loose(V, F, labels, fits, tol, lambda faces, t_split: _split_refit(
            V, F, faces, t_split, tol, FN, TT, W, split_ratio, exact, loose_unsplit))
        late += absorb_loose(V, F, labels, fits, tol, TT, W, FN)
    if late:
        labels, fits = _reconnect(V, F, labels, fits, tol, TT, W, FN)
        merged += (merge_segments(V, F, labels, tol, fits, rejected, W, FN, not exact)
                   if merge else 0)
    timings["split_again"] = time.perf_counter() - t
    t = time.perf_counter()
    labels = absorb_shards(V, F, labels, fits, tol, TT, FN, W, exact)
    shed_strays(V, F, labels, fits, tol, TT, FN)  # the segments are refitted below
    if split and not exact:  # (an exact tessellation's caps leave at their creases, below)
        n_split += cut_caps(V, F, labels, fits, tol, TT, FN, W)
        moved += tangent_joints(V, F, labels, fits, TT, tol / K_NOISE)  # (refitted below)
    corners = corner_blends(V, F, labels, fits, tol, W, FN) if split else []
    n_split += len(corners)
    guesses = {c: fits[c] for c in corners}
    corner_of = np.full(len(F), -1)
    for c in corners:
        corner_of[labels == c] = c
    if exact:  # no segment of a CAD tessellation runs across a crease
        labels, crease_moved = split_at_creases(F, labels, TT, FN, face_areas(V, F), V, tol, W)
        if crease_moved:  # a piece sent to a neighbour's piece that left too is cut off
            labels = label_pieces(F, labels, TT)
        moved += crease_moved
    timings["shards"] = time.perf_counter() - t

    t = time.perf_counter()
    area = face_areas(V, F)
    labels, faces_of = _by_area(labels, area)
    surfaces = [fit_faces(V, F, faces, tol, W=W, FN=FN) for faces in faces_of]
    if exact and merge:  # strays and creases dealt with, mixtures go to their neighbours,
        # what one surface explains merges (a coarse cylinder's facets, kept apart by a cap's
        # triangle among them), and chords leave (which a merge by corners would take again)
        for step in (dissolve_mixtures, merge_segments, split_chords):
            fits = dict(enumerate(surfaces))
            if step is merge_segments:
                merged += (n := merge_segments(V, F, labels, tol, fits, rejected, W, FN))
            else:
                labels, n = step(V, F, labels, fits, tol, TT, FN, W)
            if n:
                labels, faces_of = _by_area(labels, area)
                surfaces = [fit_faces(V, F, faces, tol, W=W, FN=FN) for faces in faces_of]
    if not exact:  # a loose cylinder where a torus fits at the noise (the median fit's)
        noise = float(np.median([s.rms for s in surfaces if s.is_analytic] or [math.inf]))
        surfaces = [closer_kind(V, F, faces, s, tol, W, FN, noise)
                    for faces, s in zip(faces_of, surfaces, strict=True)]
    for k in np.unique(labels[corner_of >= 0]):  # a corner's sphere, not a cone as close
        faces = faces_of[k]
        if (corner_of[faces] == corner_of[faces[0]]).all():
            s = corner_sphere(V, F, faces, tol, guesses[corner_of[faces[0]]], W, FN)
            surfaces[k] = surfaces[k] if s is None else s
    surfaces, coaxial = snap_to_axes(V, F, labels, surfaces, tol, W, FN)
    timings["final_fit"] = time.perf_counter() - t
    progress("surfaces", 1.0)
    log.info("surfaces: %d segments (%d split, %d merges, %d faces moved, %d planes made "
             "coaxial), tol %.3g", len(surfaces), n_split, merged, moved, coaxial, tol)
    return SurfaceSegmentation(labels, surfaces, tol, n_split, merged, moved, timings, coaxial)
