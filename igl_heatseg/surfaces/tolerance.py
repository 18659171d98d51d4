"""A mesh's own fit tolerance, from its vertex noise (:func:`noise_level`), the chord error of its
curved facets and its edge length (:func:`fit_tolerance`).
"""

from __future__ import annotations

import math

import igl
import numpy as np
from scipy.stats import chi2

from ..errors import MeshError
from .checks import check_faces, check_mesh
from .lm import rownorm

__all__ = [
    "noise_level", "fit_tolerance", "vertex_tolerance", "exact_tessellation"]

#: fit_tolerance: multiple of the noise level (rms of vertex noise; a fit's rms over vertices and
#: face centroids is ~0.8 of it, so 2.5 leaves room for the noise estimate's own error).
K_NOISE = 2.5
#: fit_tolerance: multiple of the tessellation's chord (sagitta) error.
K_CHORD = 1.0
#: fit_tolerance: floor as a fraction of the mean edge length (float32 STL coordinates and
#: exporters' rounding; keeps the tolerance > 0 on a perfect mesh).
K_FLOOR = 1e-3

#: exact_tessellation: two faces are exactly coplanar when their normals' cosine is within this
#: of 1 (round-off of a CAD export; noise of 1e-3 edge already tilts faces by ~1e-3 rad, i.e.
#: 1 - cos ~ 5e-7), and a tessellation is exact when this share of its interior edges are
#: (measured: 0.09-0.90 on 24 generated clean and coarse parts, fandisk 0.36, psb_324 0.49;
#: 0 on every part with noise 0.1, 0.005 on the iron scan, 0.001 on rocker-arm).
EXACT_FLAT_COS = 1e-9
EXACT_FLAT_SHARE = 0.05
#: ... or when its :func:`noise_level` is at most this share of the mean edge length (a clean
#: part that is nearly all curved, with too few coplanar pairs: saddle_boss_s24004_irregular_n0,
#: 0.045 of its edges coplanar, noise 4e-5 edge lengths; measured 1e-9 to 4e-4 on the clean
#: dense meshes of ``../shared/data``, 0.004 on camelhead, 0.009 on psb_021_cup, 0.02 on
#: rocker-arm and the iron scan, 0.047 and more on every generated part with noise 0.05).
EXACT_NOISE = 1e-3
#: Dihedral angles (radians) above this are creases, not tessellated curvature (exporters
#: rarely use more than 30 degrees per facet).
CREASE_ANGLE = math.radians(40.0)
#: Dihedral angles below this are flat (no chord error to estimate).
FLAT_ANGLE = math.radians(0.5)
#: Quantile of the curved edges' chord errors taken as the mesh's chord error (robust to a few
#: badly shaped facets, covers the coarser curved surfaces).
CHORD_QUANTILE = 0.9
#: noise_level: least 1-ring size (vertex + neighbours) to fit a 6-coefficient quadric with
#: at least one residual degree of freedom.
QUAD_MIN_POINTS = 7


# ----------------------------------------------------------------------------- noise and tolerance


def noise_level(V, F) -> float:
    """Noise of the mesh's vertex positions (model units), near 0 on a clean tessellation.

    Each vertex with at least QUAD_MIN_POINTS - 1 neighbours gets a height-field quadric
    ``z = a x^2 + b xy + c y^2 + d x + e y + f`` fitted to itself and its 1-ring in their
    principal-axes frame; its residual variance ``RSS / dof`` (dof = ring size - 6) is divided
    by the median of ``chi2(dof) / dof`` and the noise is the square root of the median over the
    vertices (robust to creases and corners, which are a minority). The 1-ring is small enough
    that a quadric reproduces a coarsely tessellated cylinder or sphere (its vertices lie on
    the surface; the facets' chord error is not noise), yet has residual freedom everywhere but
    at low-valence vertices, which are skipped. Where the curvature varies (tori, freeform) a
    clean tessellation still leaves an O(h^3) cubic misfit: about 1 % of the edge length on a
    torus gridded at 15 degrees (0.4 of its chord error), 6 % at 36 degrees.

    Parameters
    ----------
    V : (n, 3) array_like of float64
        Vertices.
    F : (m, 3) array_like of int
        Triangles.

    Returns
    -------
    float
        Estimated standard deviation of the vertices' normal displacement (0 when no vertex has
        a large enough ring).

    Examples
    --------
    >>> import numpy as np
    >>> x, y = np.meshgrid(np.arange(8.0), np.arange(8.0))
    >>> V = np.c_[x.ravel(), y.ravel(), 0.1 * x.ravel() ** 2]     # a clean parabolic cylinder
    >>> i = np.arange(64).reshape(8, 8)[:-1, :-1].ravel()
    >>> F = np.r_[np.c_[i, i + 1, i + 9], np.c_[i, i + 9, i + 8]]
    >>> noise_level(V, F) < 1e-9
    True
    """
    V, F = check_mesh(V, F)
    A = igl.adjacency_matrix(F).tocsr()
    val = np.diff(A.indptr)
    h = igl.avg_edge_length(V, F)
    if not h > 0:
        return 0.0
    ratios = [_ring_quadric_ratios(V, A, val, n, h) for n in np.unique(val)
              if n + 1 >= QUAD_MIN_POINTS]
    ratios = np.concatenate(ratios) if ratios else np.zeros(0)
    return float(h * math.sqrt(np.median(ratios))) if len(ratios) else 0.0


def _ring_quadric_ratios(V, A, val, n, h):
    """``RSS / dof / median(chi2(dof) / dof)`` of the 1-ring quadric of every vertex of
    valence ``n`` (lengths in units of ``h``)."""
    vs = np.flatnonzero(val == n)
    nb = A.indices[A.indptr[vs][:, None] + np.arange(n)]
    X = np.concatenate([V[vs][:, None], V[nb]], axis=1) / h  # (g, n + 1, 3)
    X -= X.mean(axis=1, keepdims=True)
    _, E = np.linalg.eigh(np.einsum("gki,gkj->gij", X, X))
    L = np.einsum("gki,gij->gkj", X, E)  # columns: normal, minor, major tangent
    z, x, y = L[..., 0], L[..., 2], L[..., 1]
    B = np.stack([x * x, x * y, y * y, x, y, np.ones_like(x)], axis=-1)  # (g, n + 1, 6)
    BtB = np.einsum("gki,gkj->gij", B, B) + 1e-10 * np.eye(6)
    coef = np.linalg.solve(BtB, np.einsum("gki,gk->gi", B, z)[..., None])[..., 0]
    rss = np.sum((z - np.einsum("gki,gi->gk", B, coef)) ** 2, axis=1)
    dof = n + 1 - 6
    return rss / dof / (chi2.median(dof) / dof)


def _segment_chord_error(V, F, faces) -> float:
    """Chord error of one segment, known to be one surface (no crease cut): each edge, a chord
    of length ``c`` between vertices whose normals (from the segment's faces only) differ by
    ``theta``, has sagitta ``c / 2 tan(theta / 4)``; the CHORD_QUANTILE quantile of the edges
    with ``theta >= FLAT_ANGLE`` (so a few mislabelled faces across a crease do not count)."""
    verts, inv = np.unique(F[faces], return_inverse=True)
    Vl, Fl = V[verts], inv.reshape(-1, 3).astype(np.int64)
    VN = igl.per_vertex_normals(Vl, Fl, igl.PER_VERTEX_NORMALS_WEIGHTING_TYPE_AREA)
    E = igl.edges(Fl)
    theta = np.arccos(np.clip(np.einsum("ij,ij->i", VN[E[:, 0]], VN[E[:, 1]]), -1.0, 1.0))
    keep = theta >= FLAT_ANGLE  # also drops nan normals of degenerate faces
    if not np.any(keep):
        return 0.0
    c = rownorm(Vl[E[keep, 0]] - Vl[E[keep, 1]])
    return float(np.quantile(0.5 * c * np.tan(theta[keep] / 4.0), CHORD_QUANTILE))


def _chord_error(V, F) -> float:
    """Chord (sagitta) error of the tessellation's curved facets: for each interior edge whose
    dihedral angle ``theta`` lies in [FLAT_ANGLE, CREASE_ANGLE], a circular arc through the two
    faces with their mean height ``c`` across the edge as chords has sagitta
    ``c / 2 tan(theta / 4)``; the CHORD_QUANTILE quantile of those."""
    TT = igl.triangle_triangle_adjacency(F)[0]
    f, e = np.nonzero(TT > np.arange(len(F))[:, None])  # each interior edge once
    g = TT[f, e]
    FN = igl.per_face_normals(V, F, np.zeros(3))
    theta = np.arccos(np.clip(np.einsum("ij,ij->i", FN[f], FN[g]), -1.0, 1.0))
    keep = (theta >= FLAT_ANGLE) & (theta <= CREASE_ANGLE)
    if not np.any(keep):
        return 0.0
    f, e, g, theta = f[keep], e[keep], g[keep], theta[keep]
    length = np.linalg.norm(V[F[f, (e + 1) % 3]] - V[F[f, e]], axis=1)
    dbl = igl.doublearea(V, F)
    c = 0.5 * (dbl[f] + dbl[g]) / np.maximum(length, 1e-300)
    return float(np.quantile(0.5 * c * np.tan(theta / 4.0), CHORD_QUANTILE))


def fit_tolerance(V, F, noise: float | None = None, faces=None) -> float:
    """Fit tolerance of a mesh, from its own noise, tessellation and size.

    ``tol = sqrt((K_NOISE * noise)^2 + (K_CHORD * chord)^2) + K_FLOOR * mean_edge``

    * ``noise`` (:func:`noise_level`) — a fit's residual on noisy samples is about the noise;
    * ``chord`` — the sagitta of the curved facets: a cylinder of radius r tessellated with
      facets of width c has its vertices on it but its face centroids up to
      ``r (1 - cos(c / 2r))`` inside, which a fit must accept (see :func:`_chord_error`);
    * ``K_FLOOR * mean_edge`` — keeps a perfect mesh's tolerance above round-off.

    Every term is a length of the mesh, so the tolerance scales with the mesh (scaled by 1000,
    the tolerance is 1000 times larger) and no constant is in model units.

    Parameters
    ----------
    V : (n, 3) array_like of float64
        Vertices.
    F : (m, 3) array_like of int
        Triangles.
    noise : float, optional
        Noise level if known (model units); estimated by :func:`noise_level` otherwise (over
        the whole mesh: pass it once computed when calling per segment).
    faces : (k,) array_like of int, or (m,) bool, optional
        One segment's faces: its own chord error instead of the whole mesh's (a coarse small
        hole next to a finely tessellated large fillet), from the turn of its vertex normals
        along each edge, without a crease cut (facets of a thin fillet may turn by 90 degrees).

    Returns
    -------
    float
        Tolerance (model units) for :func:`fit_surface` and :func:`within_tolerance`.

    Examples
    --------
    >>> import numpy as np
    >>> V = np.array([[0., 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]])
    >>> F = np.array([[0, 1, 2], [1, 3, 2]])
    >>> round(fit_tolerance(V, F, noise=0.01), 5)   # 2.5 * noise + 1e-3 * mean edge length
    0.02608
    """
    V, F = check_mesh(V, F)
    if noise is None:
        noise = noise_level(V, F)
    elif not (math.isfinite(noise) and noise >= 0):
        raise MeshError(f"noise must be a finite float >= 0, got {noise!r}")
    if faces is None:
        chord = _chord_error(V, F)
    else:
        chord = _segment_chord_error(V, F, check_faces(faces, len(F)))
    h = igl.avg_edge_length(V, F)
    return float(math.hypot(K_NOISE * noise, K_CHORD * chord) + K_FLOOR * h)


def vertex_tolerance(V, F, noise: float | None = None) -> float:
    """Fit tolerance for distances measured at the mesh's vertices only.

    ``tol = K_NOISE * noise + K_FLOOR * mean_edge``: :func:`fit_tolerance` without its chord
    term. The vertices of a clean tessellation lie on the true surface however coarse its facets
    (only face centroids sit a sagitta inside), so a fit to vertices is held to the noise level;
    on a coarse CAD export the chord term would let a plane absorb a cylinder's facets.

    Parameters
    ----------
    V : (n, 3) array_like of float64
    F : (m, 3) array_like of int
    noise : float, optional
        Noise level (model units); estimated by :func:`noise_level` otherwise.

    Returns
    -------
    float

    Examples
    --------
    >>> import numpy as np
    >>> t = np.linspace(0, 2 * np.pi, 13)[:-1]
    >>> ring = np.c_[np.cos(t), np.sin(t)]
    >>> V = np.r_[np.c_[ring, np.zeros(12)], np.c_[ring, np.ones(12)]]
    >>> F = np.array([[i, (i + 1) % 12, 12 + i] for i in range(12)]
    ...              + [[(i + 1) % 12, 12 + (i + 1) % 12, 12 + i] for i in range(12)])
    >>> round(vertex_tolerance(V, F), 5), round(fit_tolerance(V, F), 5)  # 12 facets: no chord
    (0.00079, 0.03486)
    """
    V, F = check_mesh(V, F)
    h = float(igl.avg_edge_length(V, F))
    if noise is None:  # 0 on an exact tessellation (one noise estimate serves both tests)
        share = _coplanar_share(V, F)
        noise = 0.0 if share is not None and share >= EXACT_FLAT_SHARE else noise_level(V, F)
        noise = 0.0 if share is not None and _quiet(noise, h) else noise
    return float(K_NOISE * noise + K_FLOOR * h)


def exact_tessellation(V, F) -> bool:
    """True for a noise-free tessellation: at least EXACT_FLAT_SHARE of its interior edges join
    two exactly coplanar faces (planes and the facet pairs of a coarse export); noise leaves
    none. On a coarse CAD export nearly every vertex lies on a crease, which
    :func:`noise_level`'s ring quadrics read as noise (measured: 0.14 on a 336-face block).
    A dense tessellation of a part that is nearly all curved has few coplanar pairs; it is exact
    when its :func:`noise_level` is at most :data:`EXACT_NOISE` mean edge lengths.

    Parameters
    ----------
    V : (n, 3) array_like of float64
    F : (m, 3) array_like of int

    Returns
    -------
    bool

    Examples
    --------
    >>> import numpy as np
    >>> V = np.array([[0., 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]])
    >>> exact_tessellation(V, np.array([[0, 1, 2], [1, 3, 2]]))
    True

    A sphere has no two coplanar faces; clean, it is exact, with noise of 0.05 edge lengths not:

    >>> import igl
    >>> V, F = igl.loop(*igl.icosahedron(), 3)
    >>> V /= np.linalg.norm(V, axis=1, keepdims=True)
    >>> h = igl.avg_edge_length(V, F)
    >>> noisy = V + np.random.default_rng(0).normal(scale=0.05 * h, size=V.shape)
    >>> exact_tessellation(V, F), exact_tessellation(noisy, F)
    (True, False)
    """
    V, F = check_mesh(V, F)
    share = _coplanar_share(V, F)
    if share is None:
        return False
    return share >= EXACT_FLAT_SHARE or _quiet(noise_level(V, F), igl.avg_edge_length(V, F))


def _coplanar_share(V, F) -> float | None:
    """Share of the interior edges that join two exactly coplanar faces (None: no interior
    edge)."""
    TT = igl.triangle_triangle_adjacency(F)[0]
    f, e = np.nonzero(TT > np.arange(len(F))[:, None])
    if len(f) == 0:
        return None
    FN = igl.per_face_normals(V, F, np.zeros(3))
    cos = np.einsum("ij,ij->i", FN[f], FN[TT[f, e]])
    return float(np.mean(cos >= 1.0 - EXACT_FLAT_COS))


def _quiet(noise: float, h: float) -> bool:
    """A noise level too low to be noise: at most EXACT_NOISE mean edge lengths ``h``."""
    return bool(noise <= EXACT_NOISE * h)
