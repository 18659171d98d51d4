"""One fitted surface per set of faces: the fits that :mod:`~igl_heatseg.surfaces.refine` splits,
merges and moves boundaries with, and :func:`fit_segments` for labels as they are.

A segment is fitted at its vertices (:func:`~igl_heatseg.surfaces.samples.vertex_samples`) with
the simplest kind within tolerance (:func:`~igl_heatseg.surfaces.select.fit_surface`), a few
stray boundary faces trimmed, and the face normals checked against the surface's: positions alone
can be fooled (a fan cap's centre and rim lie on a torus through its cylinder's rim).
"""

from __future__ import annotations

import math

import numpy as np

from ..mesh.geometry import face_areas, face_normals
from .model import SURFACE_KINDS, Surface
from .profile import torus_evidence
from .samples import normal_positions, vertex_samples
from .select import fit_surface, sphere_over_cone
from .tolerance import vertex_tolerance

__all__ = [
    "fit_faces",
    "fit_segments",
    "refit_segments",
    "normals_agree",
    "mean_normal_agrees",
    "precheck_vertices",
    "rms_to",
    "explains",
    "corner_rms",
    "normal_angle",
    "closer_kind",
]

#: A face joins a growing region when its corners' RMS distance to the region's surface is
#: within GROW_TOL x tol ...
GROW_TOL = 2.0

#: ... and its normal is within this angle of the surface normal at its centroid (radians; a
#: facet of a coarse cylinder has the surface normal at its centroid, a face across a crease
#: does not).
GROW_ANGLE = math.radians(25.0)

#: Regions of fewer faces are not kept from a seed (its faces stay free for other seeds).
MIN_REGION_FACES = 3

#: Vertices sampled by :func:`rms_to`.
PRECHECK_SAMPLES = 200

#: Parameters of each kind, and how many samples beyond them a fit needs to count as evidence
#: (the curved kinds need two; a single triangle of a coarse export is a planar face).
PARAMS = {"plane": 3, "cylinder": 5, "cone": 6, "sphere": 4, "torus": 7}
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
#: tol, 0.2 % of the size). Trimming every unexplained fit (unions, seed patches) once tripled
#: the run time; the RMS bars keep it cheap (12 instead of 50 faces: robust mode 5-15 % slower
#: on rocker-arm and a plate). A coarse bolt's shank is 44 faces: with 5 slivers of its fillet
#: it was freeform.
TRIM_RMS = 2.0
TRIM_REL = 0.01
TRIM_MIN_FACES = 12

#: Segments with fewer faces are fitted as freeform.
MIN_FIT_FACES = 1

#: closer_kind, on a noisy mesh: a segment's cylinder within tolerance gives way to a torus
#: that fits it this many times closer (RMS) ...
CLOSER_KIND_RATIO = 1.4

#: ... when its own RMS is over this share of the tolerance (the true surface fits at about
#: 0.3-0.4 tol: the tolerance is 2.5 noise levels) ...
CLOSER_KIND_LOOSE = 0.5

#: ... and the torus fits at the noise: its RMS at most this times the part's noise (the
#: median RMS of its segments' fits). A cylinder segment holding a few faces of the fillet
#: next to it fits a torus closer too, but not at the noise (tuning flange_s1003_frontal_n0.2:
#: 0.546, the median 0.459).
CLOSER_KIND_NOISE = 1.1


def fit_faces(V, F, faces, tol, kinds=None, W=None, FN=None, trim=True) -> Surface:
    """The simplest surface within ``tol`` of a set of faces' vertices, its normals checked.

    Parameters
    ----------
    V : (n, 3) float64
        Positions (distances are measured here).
    F : (m, 3) int64
    faces : (f,) int64
        Face ids of the segment.
    tol : float
        RMS tolerance (model units).
    kinds : sequence of str, optional
        Kinds to try (default :data:`~igl_heatseg.surfaces.model.SURFACE_KINDS`); a kind needs
        :data:`PARAMS` + :data:`MIN_EXTRA_SAMPLES` vertices to be tried.
    W : (n, 3) float64, optional
        Positions the normals come from (a denoised copy of ``V``).
    FN : (m, 3) float64, optional
        Unit face normals by face id (computed from ``W`` or ``V`` when not given).
    trim : bool
        When no kind fits, refit without stray faces up to TRIM_SHARE of the area (a boundary a
        triangle off); and a simpler kind that explains all but TRIM_SHARE of the area that
        way replaces a curved fit (:func:`_simpler_on_most`: a slot's wall and one facet of
        each round end lie on a sphere).

    Returns
    -------
    Surface
        The simplest kind within ``tol`` whose normals agree with the faces'
        (:func:`normals_agree`); when they disagree, the more complex kinds are fitted in turn.
        ``freeform`` (with the simplest fit's ``rms``) when no kind passes both.

    Examples
    --------
    >>> import igl, numpy as np
    >>> V, F = igl.loop(*igl.icosahedron(), 2)
    >>> V /= np.linalg.norm(V, axis=1, keepdims=True)
    >>> s = fit_faces(V, F, np.arange(len(F)), 1e-3)
    >>> s.kind, round(s.params["radius"], 6)
    ('sphere', 1.0)
    """
    if len(faces) < MIN_FIT_FACES:
        return Surface("freeform", {"centroid": V[F[faces]].reshape(-1, 3).mean(axis=0)},
                       area=float(face_areas(V, F[faces]).sum()))
    P, N, w = vertex_samples(V, F, faces, W)
    # a kind needs more samples than parameters to be evidence (any 4 points lie on a sphere)
    allowed = tuple(k for k in (SURFACE_KINDS if kinds is None else kinds)
                    if k == "freeform" or len(P) >= PARAMS[k] + MIN_EXTRA_SAMPLES[k])
    tried: list = []
    s = fit_surface(P, N, w, tol=tol, kinds=allowed or ("freeform",), candidates=tried)
    if trim and not s.is_analytic and len(faces) >= TRIM_MIN_FACES and s.rms <= max(
        TRIM_RMS * tol, TRIM_REL * float(np.ptp(P, axis=0).max())
    ):  # a stray face of an exact tessellation puts the RMS far above its tiny tol
        s = _trimmed_fit(V, F, faces, tol, allowed, W, s, (P, N, w)) or s
    # positions alone can be fooled: a fan cap (centre + rim) and a ring of a cylinder have
    # three (radius, height) profile points, which a torus always passes through. The face
    # normals must agree with the surface's too; when they do not, the more complex kinds are
    # tried (a noisy quarter fillet is within tolerance of a plane by distance alone).
    if not s.is_analytic:
        return s
    first = s
    FN = face_normals(V if W is None else W, F) if FN is None else FN
    while s.is_analytic:
        # a torus through the few rows of an exact tessellation is no evidence unless it is
        # tangent to its neighbours (a bolt's thread ridge: cone, cylinder, cone)
        if normals_agree(V, F, FN, faces, s, raw=W is not None) and (
                s.kind != "torus" or torus_evidence(V, F, faces, s, FN)):
            return _simpler_on_most(V, F, faces, tol, s, tried, W, FN) if trim else s
        rest = allowed[allowed.index(s.kind) + 1:]
        if not rest:
            break
        s = fit_surface(P, N, w, tol=tol, kinds=rest)
    return Surface("freeform", {"centroid": P.mean(axis=0)}, rms=first.rms,
                   max_dev=first.max_dev, area=float(face_areas(V, F[faces]).sum()))


def _simpler_on_most(V, F, faces, tol, s: Surface, tried: list, W, FN) -> Surface:
    """A simpler kind than ``s`` that explains all but at most TRIM_SHARE of the area, else ``s``.

    Any six points of a slot's flat wall (two long triangles) and of the first facet of each
    round end lie on one sphere, and an exact tessellation's tolerance then takes it over the
    plane those facets leave by 0.2 units: the sphere bulges 1.8 units between the wall's
    vertices. A curved fit is kept only when no simpler candidate (``tried``, fitted to the
    same samples) explains the segment without a few faces (:func:`_faces_on_trimmed`), its
    refit on the rest within tolerance with agreeing normals. The faces left out are handed
    to the neighbour they lie on by the boundary moves. A cone is not taken over a sphere
    that fits it :data:`~.select.SPHERE_OVER_CONE` times closer (a noisy dome)."""
    rank = SURFACE_KINDS.index
    for c in (c for c in tried if rank(c.kind) < rank(s.kind) and not sphere_over_cone(s, c)):

        def refit(sub, kind=c.kind):
            return _kind_on(V, F, sub, tol, kind, W)

        on = _faces_on_trimmed(V, F, faces, tol, c, refit)
        if on is None or on.all():
            continue
        t = _kind_on(V, F, faces[on], tol, c.kind, W)
        if t is not None and normals_agree(V, F, FN, faces[on], t, raw=W is not None):
            return t
    return s


def _kind_on(V, F, faces, tol, kind, W) -> Surface | None:
    """The fit of one kind to ``faces`` when it has enough samples and is within ``tol``."""
    P, N, w = vertex_samples(V, F, faces, W)
    if len(P) < PARAMS[kind] + MIN_EXTRA_SAMPLES[kind]:
        return None
    t = fit_surface(P, N, w, tol=tol, kinds=(kind,))
    return t if t.is_analytic else None


def _faces_on_trimmed(V, F, faces, tol, start: Surface, refit, min_kept: int = 0):
    """One least-trimmed-squares step from ``start``: the faces farthest from it, TRIM_SHARE of
    the area, left out and ``refit(kept faces) -> Surface or None`` fitted to the rest; then
    the faces within GROW_TOL x tol of that fit, as a mask over ``faces``, when they leave out
    at most TRIM_SHARE of the area (else, or when fewer than ``min_kept`` faces were kept or
    the refit failed, None)."""
    A = face_areas(V, F[faces])
    order = np.argsort(corner_max_dev(V, F, faces, start), kind="stable")
    keep = np.zeros(len(faces), dtype=bool)
    keep[order[np.cumsum(A[order]) <= (1.0 - TRIM_SHARE) * A.sum()]] = True
    if keep.sum() < max(min_kept, 1):  # one face can hold more than the share kept
        return None
    s = refit(faces[keep])
    if s is None:
        return None
    on = corner_max_dev(V, F, faces, s) <= GROW_TOL * tol
    return None if A[~on].sum() > TRIM_SHARE * A.sum() else on


def mean_normal_agrees(V, F, faces, s: Surface) -> bool:
    """The faces' mean normal is within GROW_ANGLE of ``s``'s normals there.

    Both means are area-weighted sums: of the faces' normals, and of ``s``'s normals at their
    centroids. Noise tilts each face (at noise 0.2 edge lengths a fifth of the faces are over
    GROW_ANGLE off, and :func:`normals_agree` fails on a few faces), not their sum.

    Parameters
    ----------
    V : (n, 3) float64
    F : (m, 3) int64
    faces : (f,) int64
    s : Surface
        Analytic.

    Returns
    -------
    bool
        Either orientation agrees.

    Examples
    --------
    >>> import numpy as np
    >>> from igl_heatseg.mesh.geometry import face_normals
    >>> from igl_heatseg.surfaces.model import Surface
    >>> V = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0.5]])
    >>> F = np.array([[0, 1, 2], [1, 3, 2]])       # the second face tilted by 35 degrees
    >>> z = Surface("plane", {"point": np.zeros(3), "normal": np.array([0.0, 0, -1])})
    >>> mean_normal_agrees(V, F, np.arange(2), z), normals_agree(V, F, face_normals(V, F), [1], z)
    (True, False)
    """
    Fs = F[faces]
    A = face_areas(V, Fs)[:, None]
    N = face_normals(V, Fs) * A
    S = s.normals(V[Fs].mean(axis=1)) * A
    S *= np.where(np.einsum("ij,ij->i", S, N) < 0, -1.0, 1.0)[:, None]  # either orientation
    n, m = N.sum(axis=0), S.sum(axis=0)
    den = float(np.linalg.norm(n) * np.linalg.norm(m))
    return bool(den > 0 and float(n @ m) / den >= math.cos(GROW_ANGLE))


def normals_agree(V, F, FN, faces, s: Surface, raw: bool = False) -> bool:
    """At most NORMAL_OFF_SHARE of the faces' area has normals over GROW_ANGLE off ``s``'s.

    Parameters
    ----------
    V : (n, 3) float64
    F : (m, 3) int64
    FN : (m, 3) float64
        Unit face normals by face id (either orientation: the angle ignores the sign).
    faces : (f,) int64
    s : Surface
        Analytic.
    raw : bool
        When ``FN`` disagrees, also try the faces' own normals from ``V`` and agree when those
        do. For ``FN`` from a denoised copy of ``V``: the bilateral filter tilts a narrow face
        towards its wider neighbours (measured on tuning plate_s1001_frontal_n0.05: 42-86 % of
        the area of 8 small planes and cones over 25 degrees off, against none of their raw
        normals at noise 0.05), and a plane fitted within tolerance was then typed freeform.
        Raw normals of noise 0.2 are over 25 degrees off on about a fifth of the area, so there
        they rarely agree and the denoised ones decide.

    Returns
    -------
    bool

    Examples
    --------
    >>> import numpy as np
    >>> from igl_heatseg.surfaces.model import Surface
    >>> V = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0]]); F = np.array([[0, 1, 2]])
    >>> z = Surface("plane", {"point": np.zeros(3), "normal": np.array([0.0, 0, 1])})
    >>> x = Surface("plane", {"point": np.zeros(3), "normal": np.array([1.0, 0, 0])})
    >>> FN = np.array([[0.0, 0, -1]])
    >>> normals_agree(V, F, FN, [0], z), normals_agree(V, F, FN, [0], x)
    (True, False)
    """
    A = face_areas(V, F[faces])
    off = normal_angle(V, F, FN, faces, s) > GROW_ANGLE
    if A[off].sum() <= NORMAL_OFF_SHARE * A.sum():
        return True
    if not raw:
        return False
    Fs = F[faces]
    off = normal_angle(V, Fs, face_normals(V, Fs), np.arange(len(Fs)), s) > GROW_ANGLE
    return bool(A[off].sum() <= NORMAL_OFF_SHARE * A.sum())


def _trimmed_fit(V, F, faces, tol, kinds, W, free: Surface, samples) -> Surface | None:
    """A segment whose best surface is within tolerance in RMS but not in its largest deviation
    usually holds a few faces of a neighbour (a boundary a triangle off): fit without the faces
    whose corners are off that surface, when they are at most TRIM_SHARE of the area. The
    boundary moves then hand those faces to the neighbour they lie on."""
    P, N, w = samples  # the faces' vertex samples, as fit_faces took them
    loose = fit_surface(P, N, w, tol=max(tol, free.max_dev / 2.9), kinds=kinds)
    if not loose.is_analytic:
        return None

    def refit(sub):
        s = fit_surface(*vertex_samples(V, F, sub, W), tol=tol, kinds=kinds)
        return s if s.is_analytic else None

    # the stray faces tilt the loose fit: one least-trimmed-squares step from it
    on = _faces_on_trimmed(V, F, faces, tol, loose, refit, min_kept=2 * MIN_REGION_FACES)
    return None if on is None else refit(faces[on])


def precheck_vertices(F, faces) -> np.ndarray:
    """The vertices :func:`rms_to` measures: of the faces' ``k`` distinct vertices (ascending),
    every ``max(1, k // PRECHECK_SAMPLES)``-th.

    Parameters
    ----------
    F : (m, 3) int64
    faces : (f,) int64

    Returns
    -------
    (about PRECHECK_SAMPLES or fewer,) int64
        Vertex ids.

    Examples
    --------
    >>> import numpy as np
    >>> precheck_vertices(np.array([[0, 1, 2], [2, 1, 3]]), [1, 0]).tolist()
    [0, 1, 2, 3]
    """
    verts = np.unique(F[faces])
    return verts[:: max(1, len(verts) // PRECHECK_SAMPLES)]


def rms_to(V, F, faces, s: Surface, verts=None) -> float:
    """RMS distance of (a sample of about PRECHECK_SAMPLES of) the faces' vertices to ``s``.

    Parameters
    ----------
    V : (n, 3) float64
    F : (m, 3) int64
    faces : (f,) int64
    s : Surface
    verts : (k,) int64, optional
        :func:`precheck_vertices` of ``faces``, when the caller keeps them (the same faces
        measured against many surfaces).

    Returns
    -------
    float
        Model units; ``inf`` for a freeform ``s``.

    Examples
    --------
    >>> import numpy as np
    >>> from igl_heatseg.surfaces.model import Surface
    >>> V = np.array([[0.0, 0, 1], [1, 0, 1], [0, 1, 1]]); F = np.array([[0, 1, 2]])
    >>> rms_to(V, F, [0], Surface("plane", {"point": np.zeros(3), "normal": np.array([0.0, 0, 1])}))
    1.0
    """
    if not s.is_analytic:
        return math.inf
    if verts is None:
        verts = precheck_vertices(F, faces)
    d = s.distance(V[verts])
    return float(np.sqrt((d * d).mean()))


def refit_segments(V, F, labels, fits: dict, ks, tol: float, W=None, FN=None) -> None:
    """Refit, in place, the segments ``ks`` after faces left them: ``fits[k]`` becomes the fit
    of what segment ``k`` still holds (:func:`fit_faces`), or is removed when it holds nothing.

    Examples
    --------
    >>> import numpy as np
    >>> V = np.array([[0., 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]])
    >>> F = np.array([[0, 1, 2], [1, 3, 2]])
    >>> fits = {0: None, 1: None}
    >>> refit_segments(V, F, np.array([0, 0]), fits, [0, 1], 0.01)
    >>> fits[0].kind, 1 in fits
    ('plane', False)
    """
    for k in ks:
        rest = np.flatnonzero(labels == k)
        if len(rest):
            fits[k] = fit_faces(V, F, rest, tol, W=W, FN=FN)
        else:
            del fits[k]


def explains(s: Surface, tol: float) -> bool:
    """An analytic surface whose RMS is within ``tol``.

    Examples
    --------
    >>> import numpy as np
    >>> from igl_heatseg.surfaces.model import Surface
    >>> s = Surface("sphere", {"center": np.zeros(3), "radius": 1.0}, rms=0.2)
    >>> explains(s, 0.3), explains(s, 0.1)
    (True, False)
    """
    return s.is_analytic and s.rms <= tol


def corner_rms(V, F, faces, s: Surface) -> np.ndarray:
    """RMS distance of each face's three corners to ``s``.

    Parameters
    ----------
    V : (n, 3) float64
    F : (m, 3) int64
    faces : (f,) int64
    s : Surface

    Returns
    -------
    (f,) float64
        Model units; ``inf`` for a freeform ``s``.

    Examples
    --------
    >>> import numpy as np
    >>> from igl_heatseg.surfaces.model import Surface
    >>> V = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 3]]); F = np.array([[0, 1, 2]])
    >>> z = Surface("plane", {"point": np.zeros(3), "normal": np.array([0.0, 0, 1])})
    >>> corner_rms(V, F, [0], z)
    array([1.73205081])
    """
    if not s.is_analytic:
        return np.full(len(faces), np.inf)
    d = s.distance(V[F[faces]].reshape(-1, 3)).reshape(-1, 3)
    return np.sqrt((d * d).mean(axis=1))


def corner_max_dev(V, F, faces, s: Surface) -> np.ndarray:
    """Largest distance of each face's three corners to ``s``.

    Parameters
    ----------
    V : (n, 3) float64
    F : (m, 3) int64
    faces : (f,) int64
    s : Surface

    Returns
    -------
    (f,) float64
        ``inf`` for a freeform ``s``.

    Examples
    --------
    >>> import numpy as np
    >>> from igl_heatseg.surfaces.model import Surface
    >>> V = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 3]]); F = np.array([[0, 1, 2]])
    >>> z = Surface("plane", {"point": np.zeros(3), "normal": np.array([0.0, 0, 1])})
    >>> corner_max_dev(V, F, [0], z)
    array([3.])
    """
    if not s.is_analytic:
        return np.full(len(faces), np.inf)
    return np.abs(s.distance(V[F[faces]].reshape(-1, 3))).reshape(-1, 3).max(axis=1)


def normal_angle(V, F, FN, faces, s: Surface) -> np.ndarray:
    """Angle between each face's normal and the surface normal at its centroid's projection.

    Parameters
    ----------
    V : (n, 3) float64
    F : (m, 3) int64
    FN : (m, 3) float64
        Unit face normals by face id.
    faces : (f,) int64
    s : Surface
        Analytic.

    Returns
    -------
    (f,) float64
        Radians in [0, pi/2] (unsigned: the two orientations count as one).

    Examples
    --------
    >>> import numpy as np
    >>> from igl_heatseg.surfaces.model import Surface
    >>> V = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0]]); F = np.array([[0, 1, 2]])
    >>> s = Surface("plane", {"point": np.zeros(3), "normal": np.array([0.0, 0, 1])})
    >>> float(np.degrees(normal_angle(V, F, np.array([[1.0, 0, 1]]) / np.sqrt(2), [0], s)[0]))
    45.0
    """
    SN = s.normals(V[F[faces]].mean(axis=1))
    cos = np.abs(np.einsum("ij,ij->i", SN, FN[faces]))
    return np.arccos(np.clip(cos, -1.0, 1.0))


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
        Fitted at the vertices, a few stray boundary faces trimmed (:func:`fit_faces`, as in
        :func:`~igl_heatseg.surfaces.refine.refine_segmentation`).

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
    W = normal_positions(V, normals_from)
    tol = vertex_tolerance(V, F) if tol is None else float(tol)
    FN = face_normals(V if W is None else W, F)
    k = int(labels.max()) + 1 if len(labels) else 0
    return [fit_faces(V, F, np.flatnonzero(labels == i), tol, W=W, FN=FN) for i in range(k)]


def closer_kind(V, F, faces, s: Surface, tol: float, W=None, FN=None,
                noise: float = math.inf) -> Surface:
    """For a loose cylinder ``s`` (RMS over :data:`CLOSER_KIND_LOOSE` tol), a torus that fits
    the faces :data:`CLOSER_KIND_RATIO` times closer, and within :data:`CLOSER_KIND_NOISE`
    times ``noise``; else ``s``.

    The simplest kind within tolerance can be loose where the tolerance is a few noise levels:
    half a pipe's bend is a cylinder within tolerance (RMS 0.227, tol 0.374 on f24
    pipe_elbow_s24014_frontal_n0.1) and a torus within the noise (0.144, the noise level about
    0.15). Only the cylinder gives way, and only to a torus: letting every kind give way to any
    more general one retyped a noisy flange's faces (tuning flange_s1003_frontal_n0.2, type
    .941 -> .828).

    Parameters
    ----------
    V : (n, 3) float64
    F : (m, 3) int64
    faces : (f,) int64
        The segment's faces.
    s : Surface
        Their fit (:func:`fit_faces`).
    tol : float
        Fit tolerance (model units).
    W : (n, 3) float64, optional
        Positions the normals come from.
    FN : (m, 3) float64, optional
        Unit face normals.
    noise : float
        The part's noise level (model units; default: no bound).

    Returns
    -------
    Surface

    Examples
    --------
    A band of a torus (major radius 6, minor 1, a twelfth of a turn), with noise: a cylinder
    fits it within a tolerance of 0.06, a torus at the noise.

    >>> import numpy as np
    >>> u, v = np.meshgrid(np.linspace(0, np.pi / 6, 40), np.linspace(0, 2 * np.pi, 24)[:-1])
    >>> u, v = u.ravel(), v.ravel()
    >>> V = np.c_[(6 + np.cos(v)) * np.cos(u), (6 + np.cos(v)) * np.sin(u), np.sin(v)]
    >>> V += np.random.default_rng(0).normal(scale=0.015, size=V.shape)
    >>> i = (np.arange(22)[:, None] * 40 + np.arange(39)).ravel()
    >>> F = np.r_[np.c_[i, i + 1, i + 41], np.c_[i, i + 41, i + 40]]
    >>> s = fit_faces(V, F, np.arange(len(F)), 0.06)
    >>> t = closer_kind(V, F, np.arange(len(F)), s, 0.06)
    >>> s.kind, t.kind, round(t.params["major_radius"], 1), round(t.params["minor_radius"], 1)
    ('cylinder', 'torus', 6.0, 1.0)
    >>> closer_kind(V, F, np.arange(len(F)), s, 0.06, noise=0.01).kind   # not at that noise
    'cylinder'
    """
    if s.kind != "cylinder" or s.rms <= CLOSER_KIND_LOOSE * tol:
        return s
    g = fit_faces(V, F, faces, tol, kinds=("torus",), W=W, FN=FN)
    if (g.kind == "torus" and explains(g, tol) and g.rms * CLOSER_KIND_RATIO <= s.rms
            and g.rms <= CLOSER_KIND_NOISE * noise):
        return g
    return s
