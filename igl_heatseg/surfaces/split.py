"""Splitting a segment that no surface explains: RANSAC regions (:func:`ransac_regions`), the
folding of pieces that are no evidence, and the test that a split found real faces
(:func:`real_split`).

Region growing (:func:`~igl_heatseg.surfaces.refine.grow_regions`) starts from the smoothest
faces and fits the simplest kind to a seed's rings. On a small noisy hole that fails: two rings of
a cylinder of radius 20 noise levels fit a plane, the growth over that plane stalls, and the
hole and the plane ring around it stay one unexplained segment. RANSAC (Schnabel et al. 2007)
draws its candidates from the whole segment instead: a plane from one face, a cylinder from one
face's rings (axis: the direction least seen in their normals), keeps the candidate whose
consistent faces hold most area, refits it to its connected faces and takes them out; then again
on what is left. The refinement runs it on noisy meshes only, when growth finds no real split.
"""

from __future__ import annotations

import math

import numpy as np

from ..mesh.geometry import face_areas, face_normals
from ..mesh.topology import label_pieces
from .model import Surface
from .profile import FEW_ROWS, profile_rows
from .samples import vertex_samples
from .segment_fit import (
    GROW_ANGLE,
    GROW_TOL,
    MIN_REGION_FACES,
    PARAMS,
    corner_rms,
    explains,
    fit_faces,
    normal_angle,
)
from .select import fit_surface

__all__ = [
    "ransac_regions",
    "crease_regions",
    "row_regions",
    "consistent_faces",
    "face_pieces",
    "cylinder_from_normals",
    "evidence",
    "fold_weak",
    "real_split",
    "SPLIT_RMS_RATIO",
    "SPLIT_RMS_RATIO_NOISY",
    "SPLIT_GOOD_SHARE",
]

#: A region-growing split is kept when at least SPLIT_GOOD_SHARE of the area is in pieces
#: whose fit RMS is within SPLIT_RMS_RATIO x tol (measured: true faces 1e-6 tol on clean CAD
#: meshes and 0.3-0.5 tol at noise 0.1 edge; the fandisk's freeform blends 0.8-1.0 tol).
SPLIT_RMS_RATIO = 0.65
SPLIT_GOOD_SHARE = 0.6

#: The same bar on a noisy mesh, whose true faces fit at 0.6-0.85 tol (region fits carry their
#: boundaries' noise; measured on a noisy pipe elbow's cylinder and torus).
SPLIT_RMS_RATIO_NOISY = 0.9
SPLIT_NOISY_SAMPLES = 4

#: RANSAC: candidates drawn per extracted region (each a plane and, where the face's rings turn,
#: a cylinder), from a fixed seed (the labels do not change from run to run).
RANSAC_TRIALS = 48
RANSAC_SEED = 0

#: ... a candidate is scored by the area of the faces whose corners lie within RANSAC_TOL x tol
#: of it (RMS) with normals within RANSAC_ANGLE: stricter than growth (GROW_TOL, GROW_ANGLE), so
#: a plane tangent to a small hole does not score the hole's faces near the tangent line.
RANSAC_TOL = 1.0
RANSAC_ANGLE = math.radians(15.0)

#: ... the cylinder candidate of a face comes from its rings of this many neighbours.
RANSAC_RINGS = 2

#: ... the chosen candidate is refitted (its kind only) to its connected consistent faces this
#: many times.
RANSAC_REFITS = 3

#: A cylinder candidate's normals must turn: the middle eigenvalue of their scatter at least this
#: share of the largest (else the rings are flat, and the plane candidate covers them).
FLAT_SCATTER = 1e-3


def consistent_faces(V, F, FN, faces, s, tol, k_tol, angle=GROW_ANGLE) -> np.ndarray:
    """Per face of ``faces``: its corners within ``k_tol`` x tol of ``s`` (RMS) and its normal
    within ``angle`` of ``s``'s (region growing's test, :data:`GROW_TOL`, :data:`GROW_ANGLE`).

    Returns
    -------
    (f,) bool
    """
    return (corner_rms(V, F, faces, s) <= k_tol * tol) & (normal_angle(V, F, FN, faces, s) <= angle)


def face_pieces(F, TT, faces) -> np.ndarray:
    """Edge-connected pieces of the face set ``faces`` on its own (its faces joined only
    through each other): piece ``0..p-1`` of each, numbered by their smallest face.

    Examples
    --------
    >>> import igl, numpy as np
    >>> F = np.array([[0, 1, 2], [1, 3, 2], [2, 3, 4], [3, 5, 4]])
    >>> face_pieces(F, igl.triangle_triangle_adjacency(F)[0], np.array([0, 2, 3])).tolist()
    [0, 1, 1]
    """
    lab = np.full(len(F), -1, dtype=np.int64)
    lab[faces] = 0
    _, inv = np.unique(label_pieces(F, lab, TT)[faces], return_inverse=True)
    return inv.reshape(-1).astype(np.int64)


def cylinder_from_normals(C, N, size: float) -> Surface | None:
    """A cylinder through points with their normals, without iterations: the axis is the
    direction the normals least point along (smallest eigenvector of ``N^T N``), the axis point
    the least-squares meeting point of the normal lines across it, the radius the mean distance.

    Parameters
    ----------
    C : (p, 3) float64
        Points (face centroids).
    N : (p, 3) float64
        Unit normals at the points (either orientation).
    size : float
        The data's extent: a radius above 20 x size is a plane, and gives ``None``.

    Returns
    -------
    Surface or None
        ``None`` when the normals do not turn (:data:`FLAT_SCATTER`) or the radius is not finite.

    Examples
    --------
    >>> import numpy as np
    >>> t = np.linspace(0, 1, 6); z = np.repeat([0.0, 1.0], 6)
    >>> N = np.c_[np.cos(np.r_[t, t]), np.sin(np.r_[t, t]), np.zeros(12)]
    >>> s = cylinder_from_normals(3 * N + np.c_[0 * z, 0 * z, z], N, 3.0)
    >>> round(s.params["radius"], 6), np.round(np.abs(s.params["axis"]), 6).tolist()
    (3.0, [0.0, 0.0, 1.0])
    """
    w, E = np.linalg.eigh(N.T @ N)
    if not w[1] >= FLAT_SCATTER * w[2]:
        return None
    a = E[:, 0]
    P = np.eye(3) - np.outer(a, a)
    M = N @ P
    M /= np.maximum(np.linalg.norm(M, axis=1, keepdims=True), 1e-300)
    # minimise sum |(P - m m^T)(c - p)|^2: the distances to the normal lines across the axis,
    # with the free axial coordinate held at the points' mean
    Q = P[None] - M[:, :, None] * M[:, None, :]
    S = Q.sum(axis=0) + np.outer(a, a)
    b = np.einsum("pij,pj->i", Q, C) + a * (a @ C.mean(axis=0))
    try:
        c = np.linalg.solve(S, b)
    except np.linalg.LinAlgError:
        return None
    r = float(np.linalg.norm((C - c) @ P, axis=1).mean())
    if not (math.isfinite(r) and 0 < r <= 20 * size):
        return None
    return Surface("cylinder", {"point": c, "axis": a, "radius": r})


def _rings(TT, inside, f, rings):
    patch = np.array([f])
    for _ in range(rings):
        nb = TT[patch].ravel()
        nb = nb[nb >= 0]
        patch = np.union1d(patch, nb[inside[nb]])
    return patch


def _largest_piece(F, TT, faces, idx):
    """The positions ``idx`` (into ``faces``) of the largest edge-connected piece."""
    pid = face_pieces(F, TT, faces[idx])
    return idx[pid == np.bincount(pid).argmax()]


def ransac_regions(V, F, faces, tol, FN, TT, W=None) -> np.ndarray:
    """Split a face set into regions that one plane or cylinder each explains, by RANSAC.

    Each round draws :data:`RANSAC_TRIALS` faces of what is left; each gives a plane (its
    centroid and normal) and a cylinder (:func:`cylinder_from_normals` of its
    :data:`RANSAC_RINGS` rings). The candidate whose consistent faces (:data:`RANSAC_TOL`,
    :data:`RANSAC_ANGLE`) hold the most area is refitted to the largest connected piece of the
    faces consistent with it (growth bars, ``GROW_TOL``), its kind only, up to
    :data:`RANSAC_REFITS` times; that piece is a region when its refit explains it. Rounds stop
    when no region of MIN_REGION_FACES faces is found. A cone, sphere or torus face comes out as
    the region its best plane or cylinder explains, or not at all, and the refinement's fits and
    merges type it after.

    Parameters
    ----------
    V : (n, 3) float64
    F : (m, 3) int64
    faces : (k,) int64
        The face set (a segment).
    tol : float
        Fit tolerance (model units).
    FN : (m, 3) float64
        Unit face normals (from the denoised positions, when there are).
    TT : (m, 3) int64
        ``igl.triangle_triangle_adjacency(F)[0]``.
    W : (n, 3) float64, optional
        Positions for normals (as :func:`~igl_heatseg.surfaces.segment_fit.fit_faces`).

    Returns
    -------
    region : (k,) int64
        Region id of each face of ``faces``, ``0..r-1``; faces in no region form regions of
        their own (their connected pieces), numbered after.

    Examples
    --------
    >>> import numpy as np
    >>> from scipy.spatial import Delaunay
    >>> from igl_heatseg.mesh.geometry import face_normals
    >>> x, y = np.meshgrid(np.linspace(-1, 1, 9), np.linspace(0, 1, 5))
    >>> V = np.c_[x.ravel(), y.ravel(), np.abs(x.ravel())]          # a fold: two planes
    >>> F = Delaunay(V[:, :2]).simplices.astype(np.int64)
    >>> import igl; TT = igl.triangle_triangle_adjacency(F)[0]
    >>> np.bincount(ransac_regions(V, F, np.arange(len(F)), 1e-6, face_normals(V, F), TT))
    array([32, 32])
    """
    faces = np.asarray(faces, dtype=np.int64)
    rng = np.random.default_rng(RANSAC_SEED)
    C = V[F[faces]].mean(axis=1)
    pos = np.full(len(F), -1, dtype=np.int64)
    pos[faces] = np.arange(len(faces))
    size = float(np.ptp(C, axis=0).max()) if len(faces) else 0.0
    A = face_areas(V, F[faces])
    out = np.full(len(faces), -1, dtype=np.int64)
    r = 0
    while True:
        rem = np.flatnonzero(out < 0)
        if len(rem) < 2 * MIN_REGION_FACES:
            break
        inside = np.zeros(len(F), dtype=bool)
        inside[faces[rem]] = True
        best, best_area = None, 0.0
        for i in rng.integers(len(rem), size=RANSAC_TRIALS):
            f = faces[rem[i]]
            cands = [Surface("plane", {"point": C[rem[i]], "normal": FN[f]})]
            patch = _rings(TT, inside, f, RANSAC_RINGS)
            if len(patch) >= PARAMS["cylinder"] + 1:
                cyl = cylinder_from_normals(C[pos[patch]], FN[patch], size)
                cands += [cyl] if cyl is not None else []
            for s in cands:
                ok = consistent_faces(V, F, FN, faces[rem], s, tol, RANSAC_TOL, RANSAC_ANGLE)
                area = A[rem[ok]].sum()
                if area > best_area:
                    best, best_area = s, area
        region, s = None, best
        for _ in range(RANSAC_REFITS if best is not None else 0):
            idx = rem[consistent_faces(V, F, FN, faces[rem], s, tol, GROW_TOL)]
            if len(idx) < MIN_REGION_FACES:
                break
            idx = _largest_piece(F, TT, faces, idx)
            s2 = fit_faces(V, F, faces[idx], tol, kinds=(s.kind,), W=W, FN=FN)
            if not explains(s2, tol):
                break
            s, region = s2, idx
        if region is None or len(region) < MIN_REGION_FACES:
            break
        out[region] = r
        r += 1
    rest = np.flatnonzero(out < 0)
    if len(rest):
        out[rest] = r + face_pieces(F, TT, faces[rest])
    return out


#: crease_regions: the edges cut are those above the widest gap between the segment's dihedral
#: angles, when the angles above it are at least this multiple of those below (the facets of
#: a tessellated curve turn by their angular step, a crease by its own angle; a thread's
#: valley turns by exactly twice its flank-to-crest crease, so 2 is too strict by round-off:
#: every piece of the cut must be a surface anyway) ...
CREASE_GAP_RATIO = 1.5
#: ... and at least this angle. Where every vertex is on a border (one-row strips) nothing but
#: the angle tells a crease from the rows of a smooth surface of revolution, each exactly a
#: cone: the shallowest crease looked for is a thread's (flank to crest 30 degrees for a
#: 60-degree thread; 32-34 between the facets of a clean bolt), the rows of a quarter circle in
#: six turn by 15.
CREASE_MIN_ANGLE = math.radians(25.0)
#: Gaps tried, widest first, until one cuts the set into surfaces.
CREASE_TRIES = 3


def crease_regions(V, F, faces, tol, TT, W=None, FN=None) -> np.ndarray:
    """Split a face set of an exact tessellation at its creases, the crease angle read from it.

    The angles between adjacent face normals inside the set are sorted; the edges above the
    widest gap between consecutive angles (when those above it are at least
    :data:`CREASE_GAP_RATIO` times the largest below and :data:`CREASE_MIN_ANGLE`) are cut,
    and each edge-connected piece left is a region. The split is kept only when every piece is
    one analytic surface, fitted within SPLIT_RMS_RATIO x tol, and the fit is evidence
    (:func:`evidence`: SPLIT_NOISY_SAMPLES x its parameters in vertices, so that single
    facets, which fit a plane exactly, are no regions); else the set is one region.

    A clean bolt's thread ridge (a cone flank, a cylinder crest and a cone flank, a few
    triangles wide; facets turning by 5 degrees, creases by 32) is split this way, where region
    growing breaks the flanks into pieces of 8-12 faces that are no evidence; a freeform blend,
    whose pieces are no analytic surface, stays whole.

    Parameters
    ----------
    V : (n, 3) float64
        Positions (exact: normals and distances are taken here).
    F : (m, 3) int64
    faces : (k,) int64
        The face set (a segment).
    tol : float
        Fit tolerance (model units).
    TT : (m, 3) int64
        ``igl.triangle_triangle_adjacency(F)[0]``.
    W, FN : optional
        As for :func:`~igl_heatseg.surfaces.segment_fit.fit_faces` (the pieces' fits).

    Returns
    -------
    region : (k,) int64
        Region id of each face of ``faces``, ``0..r-1`` (all 0 when not split).

    Examples
    --------
    A strip folded 30 degrees along a line of its edges is cut there:

    >>> import numpy as np, igl
    >>> from scipy.spatial import Delaunay
    >>> x, y = np.meshgrid(np.linspace(-1, 1, 9), np.linspace(0, 1, 5))
    >>> V = np.c_[x.ravel(), y.ravel(), np.tan(np.radians(30)) * np.maximum(x.ravel(), 0)]
    >>> F = Delaunay(V[:, :2]).simplices.astype(np.int64)
    >>> TT = igl.triangle_triangle_adjacency(F)[0]
    >>> np.bincount(crease_regions(V, F, np.arange(len(F)), 1e-6, TT))
    array([32, 32])
    """
    faces = np.asarray(faces, dtype=np.int64)
    one = np.zeros(len(faces), dtype=np.int64)
    inside = np.zeros(len(F), dtype=bool)
    inside[faces] = True
    a, b = np.repeat(faces, 3), TT[faces].ravel()
    ok = b >= 0
    ok[ok] = inside[b[ok]]
    a, b = a[ok], b[ok]
    if len(a) < 2:
        return one
    N = np.zeros((len(F), 3))
    N[faces] = face_normals(V, F[faces])
    ang = np.arccos(np.clip(np.einsum("ij,ij->i", N[a], N[b]), -1.0, 1.0))
    u = np.unique(ang)[::-1]
    if len(u) < 2:
        return one
    gap = u[:-1] - u[1:]
    ok = u[:-1] >= np.maximum(CREASE_GAP_RATIO * u[1:], CREASE_MIN_ANGLE)
    # the widest gap first; when its pieces are not all surfaces, the next widest (two thread
    # ridges meet at a valley of 72-74 degrees, their flanks and crests at 36-37: the valleys
    # alone leave ridges, each cut by its rows then, row_regions)
    for i in sorted(np.flatnonzero(ok).tolist(), key=lambda i: -gap[i])[:CREASE_TRIES]:
        region = _cut_at(V, F, faces, tol, TT, W, FN, a, b, ang > 0.5 * (u[i] + u[i + 1]))
        if region is not None:
            return region
    return row_regions(V, F, faces, tol, TT, W, FN)  # no angle tells the creases: the rows


def _cut_at(V, F, faces, tol, TT, W, FN, a, b, cut):
    """The pieces of ``faces`` left by cutting the face pairs ``(a, b)[cut]``, when each is one
    analytic surface (within SPLIT_RMS_RATIO x tol, and evidence) or its rows are
    (:func:`row_regions`); else None."""
    TTc = TT.copy()
    fa, fb = a[cut], b[cut]
    for j in range(3):  # each pair cut is listed from both of its faces
        hit = TTc[fa, j] == fb
        TTc[fa[hit], j] = -1
    region = face_pieces(F, TTc, faces)
    if region.max() == 0:
        return None
    nxt = int(region.max()) + 1
    for r in range(nxt):
        at = np.flatnonzero(region == r)
        part = faces[at]
        if not _surfaces(V, F, [part], tol, W, FN):
            rows = row_regions(V, F, part, tol, TT, W, FN)
            if rows.max() == 0:
                return None
            region[at] = np.where(rows == 0, r, nxt + rows - 1)
            nxt += int(rows.max())
    return region


def _surfaces(V, F, parts, tol, W, FN) -> bool:
    """Every part is one analytic surface within SPLIT_RMS_RATIO x tol, and evidence."""
    for part in parts:
        s = fit_faces(V, F, part, tol, W=W, FN=FN)
        if not (s.is_analytic and s.rms <= SPLIT_RMS_RATIO * tol and evidence(F, part, s)):
            return False
    return True


def row_regions(V, F, faces, tol, TT, W=None, FN=None) -> np.ndarray:
    """Split a face set of an exact tessellation into the bands between its rows, when a torus
    fits its vertices on a few rows that are no torus (:func:`~.profile.torus_evidence`).

    A clean bolt's thread ridge of 24 facets per turn: its flank-to-crest creases turn by 36
    degrees and its facets by 24-30, so no angle tells them apart (:func:`crease_regions`);
    but its vertices lie on four circles about the torus's axis, and the bands between them
    are the flanks and the crest. The split is kept only when every band's connected pieces
    are analytic surfaces (as :func:`crease_regions`).

    Parameters
    ----------
    V : (n, 3) float64
    F : (m, 3) int64
    faces : (k,) int64
        The face set.
    tol : float
        Fit tolerance (model units).
    TT : (m, 3) int64
        ``igl.triangle_triangle_adjacency(F)[0]``.
    W, FN : optional
        As for :func:`~igl_heatseg.surfaces.segment_fit.fit_faces`.

    Returns
    -------
    region : (k,) int64
        Region id of each face of ``faces``, ``0..r-1`` (all 0 when not split).

    Examples
    --------
    A cone, a cylinder and a cone band, 24 facets per turn, are three surfaces:

    >>> import igl, numpy as np
    >>> t = np.linspace(0, 2 * np.pi, 24, endpoint=False)
    >>> V = np.array([[r * np.cos(u), r * np.sin(u), z] for r, z in
    ...               [(9.3, 0.0), (10.0, 0.9), (10.0, 1.4), (9.3, 2.3)] for u in t])
    >>> F = np.array([f for i in range(3) for j in range(24) for f in (
    ...     [24 * i + j, 24 * i + (j + 1) % 24, 24 * (i + 1) + j],
    ...     [24 * i + (j + 1) % 24, 24 * (i + 1) + (j + 1) % 24, 24 * (i + 1) + j])])
    >>> TT = igl.triangle_triangle_adjacency(F)[0]
    >>> np.bincount(row_regions(V, F, np.arange(len(F)), 1e-6, TT)).tolist()
    [48, 48, 48]
    """
    faces = np.asarray(faces, dtype=np.int64)
    one = np.zeros(len(faces), dtype=np.int64)
    if len(faces) < 2 * MIN_REGION_FACES:
        return one
    s = fit_surface(*vertex_samples(V, F, faces, W), tol=tol, kinds=("torus",))
    if s.kind != "torus" or not explains(s, tol):
        return one
    verts, row = profile_rows(V, F, faces, s)
    if row is None or not 2 < int(row.max()) + 1 <= FEW_ROWS:
        return one
    row_of = np.zeros(len(V), dtype=np.int64)
    row_of[verts] = row
    lab = np.full(len(F), -1, dtype=np.int64)
    lab[faces] = row_of[F[faces]].min(axis=1)  # the band between a face's rows
    _, region = np.unique(label_pieces(F, lab, TT)[faces], return_inverse=True)
    region = region.reshape(-1).astype(np.int64)
    if region.max() == 0:
        return one
    parts = [faces[region == r] for r in range(int(region.max()) + 1)]
    return region if _surfaces(V, F, parts, tol, W, FN) else one


def evidence(F, part, s) -> bool:
    """A fit on a noisy mesh is evidence with SPLIT_NOISY_SAMPLES x its parameters in vertices
    (two noisy triangles fit a plane exactly).

    Examples
    --------
    >>> import numpy as np
    >>> from igl_heatseg.surfaces.model import Surface
    >>> s = Surface("plane", {"point": np.zeros(3), "normal": np.array([0.0, 0, 1])})
    >>> F = np.array([[0, 1, 2], [1, 3, 2]])
    >>> evidence(F, np.array([0, 1]), s)                     # 4 vertices, 12 needed
    False
    """
    return len(np.unique(F[part])) >= SPLIT_NOISY_SAMPLES * PARAMS.get(s.kind, 1)


def fold_weak(V, F, TT, tol, W, FN, parts, part_fits, keep_explained=False):
    """Pieces of a split of a noisy segment whose fit is no evidence (:func:`evidence`; the
    leftovers of region growing along a noisy crease) join the adjacent piece they share most
    edges with, smallest first; the pieces that grew are refitted, and a piece that its surface
    explained and no longer does with them gives them back (they stay pieces: four triangles of
    a noisy plate made its hole's wall freeform). With ``keep_explained`` (a
    RANSAC split), a piece that its fit explains stays (a region of a few faces of a plane, which
    the merges then join to the rest of its plane) unless it has fewer than MIN_REGION_FACES
    faces, which no fit makes evidence (one face lies on any plane): such a piece joins the
    adjacent piece on whose surface its corners lie closest (a face across a noisy crease
    stays with one of its two planes instead of becoming a segment).

    Returns
    -------
    parts : list of (f_i,) int64
    fits : list of Surface
    """
    piece = np.full(len(F), -1, dtype=np.int64)
    for r, part in enumerate(parts):
        piece[part] = r
    grown: set = set()
    folded: dict = {}  # piece -> the pieces folded into it
    parts, part_fits = list(parts), list(part_fits)
    alive = len(parts)  # pieces not folded yet (every piece has faces)
    for r in sorted(range(len(parts)), key=lambda r: len(parts[r])):
        if alive <= 1:
            break
        sliver = keep_explained and len(parts[r]) < MIN_REGION_FACES
        if not sliver and (evidence(F, parts[r], part_fits[r]) or (
                keep_explained and explains(part_fits[r], tol))):
            continue  # (a grown piece only gained vertices)
        nb = piece[TT[parts[r]][TT[parts[r]] >= 0]]
        nb = nb[(nb >= 0) & (nb != r)]
        if len(nb) == 0:
            continue
        j = int(np.bincount(nb).argmax())
        if sliver:
            near = {int(c): float(corner_rms(V, F, parts[r], part_fits[c]).mean())
                    for c in np.unique(nb) if part_fits[c].is_analytic}
            j = min(near, key=near.get) if near else j
        piece[parts[r]] = j
        folded.setdefault(j, []).append(parts[r])  # (with what was folded into it)
        folded.pop(r, None)
        grown.discard(r)
        parts[j] = np.concatenate([parts[j], parts[r]])
        parts[r] = parts[r][:0]
        grown.add(j)
        alive -= 1
    for j in sorted(grown):
        fits_j = fit_faces(V, F, parts[j], tol, W=W, FN=FN)
        if explains(fits_j, tol) or not explains(part_fits[j], tol):
            part_fits[j] = fits_j
            continue
        # the folded pieces cost the piece its surface: they stay pieces of their own
        # (a cylinder wall of 50 faces with four shards of the plane around it: freeform)
        for q in folded[j]:
            parts[j] = parts[j][~np.isin(parts[j], q)]
            parts.append(q)
            part_fits.append(fit_faces(V, F, q, tol, W=W, FN=FN))
    keep = [r for r in range(len(parts)) if len(parts[r])]
    return [parts[r] for r in keep], [part_fits[r] for r in keep]


def real_split(V, F, parts, part_fits, tol, ratio=None, noisy=False) -> bool:
    """A split found real faces when most of the area lies in pieces fitted well inside the
    tolerance (``ratio`` x tol: true faces of an exact tessellation fit to round-off); a smooth
    freeform surface shatters into pieces each just within it, and stays whole. On a noisy mesh
    a piece counts only when its fit is evidence (:func:`evidence`).

    Returns
    -------
    bool
    """
    ratio = SPLIT_RMS_RATIO if ratio is None else ratio
    A = np.array([face_areas(V, F[p]).sum() for p in parts])
    r = np.array([f.rms / tol if f.is_analytic else np.inf for f in part_fits])
    if noisy:
        r[[not evidence(F, p, f) for p, f in zip(parts, part_fits, strict=True)]] = np.inf
    good = A[r <= ratio].sum()
    return bool(good >= SPLIT_GOOD_SHARE * A.sum())
