"""Trimming curves between fitted segments: each boundary chain of a labelled mesh
(:func:`~igl_heatseg.mesh.topology.boundary_graph`) moved onto the intersection of its two
fitted surfaces where that intersection is well conditioned, else smoothed along the mesh.

A segment's boundary on the mesh is a polyline of triangle edges: on a noisy scan it zig-zags
about the true edge by a triangle, which no surface trim can use. Where two analytic surfaces
cross at a clear angle, their intersection *is* the edge: the chain's vertices are moved onto
it by Gauss-Newton on the two signed distances (:func:`onto_surfaces`), within a move limit
(the surfaces' deviations from the mesh plus half a mesh edge; farther, the intersection is not
the one the mesh shows). Where they meet tangentially (a fillet into its plane, a pipe into its
elbow), or a side is freeform or the mesh border, the intersection does not pin the curve down:
the chain is smoothed (Taubin's lambda|mu, no shrinkage) and put back onto the surfaces it
lies on; on an exact tessellation (no noise) the chain's vertices already lie on the true edge
when the segments are right, and the chain is kept as it is. Chain ends (corners, where three
or more sides meet) are placed first and held.

The CAD stage builds its B-Rep edges with the same projection (:func:`onto_surfaces`) and move
limit (:func:`move_limit`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import igl
import numpy as np
import scipy.sparse as sp

from ..mesh.topology import boundary_graph
from .model import Surface
from .segment_fit import GROW_TOL, corner_rms
from .tolerance import exact_tessellation, vertex_tolerance

__all__ = [
    "BoundaryCurve",
    "boundary_curves",
    "onto_surfaces",
    "move_limit",
    "GN_RCOND",
    "GN_ITERS",
    "MOVE_DEV_FACTOR",
    "MOVE_EDGE_FRACTION",
]

#: Singular values of the stacked surface normals below this fraction of the largest are
#: dropped in Gauss-Newton: two surfaces meeting at less than ~17 deg (a fillet running into
#: its plane) do not define their intersection well, and the step then only closes the
#: distances along the mean normal, staying near the mesh.
GN_RCOND = 0.15

#: Gauss-Newton iterations; quadratic convergence makes a handful enough for analytic pairs.
GN_ITERS = 12

#: A boundary point may move onto its surfaces' intersection by MOVE_DEV_FACTOR times the sum of
#: their deviations from the mesh, plus MOVE_EDGE_FRACTION of the mean edge length.
MOVE_DEV_FACTOR = 2.0
MOVE_EDGE_FRACTION = 0.5

#: A point lies on the intersection when its largest distance to the two surfaces is within this
#: fraction of the mean edge length after Gauss-Newton.
ON_SURFACE_REL = 1e-6

#: A chain is an intersection curve when this share of its points (its placed ends included) lie
#: on the intersection of its two surfaces, well conditioned there (smallest singular value of
#: the two normals at least GN_RCOND of the largest); else it is smoothed.
INTERSECTION_SHARE = 0.8

#: ... and when both surfaces fit the mesh along the chain: this share of each side's faces at
#: the chain's vertices lie within GROW_TOL x tol (corner RMS) of their segment's surface (a
#: segment holding a strip of its neighbour is tilted there, and its intersection is off the
#: edge: measured on a noisy plate, every such chain had at most 0.83, every good one 1.0).
FIT_SHARE = 0.9

#: ... and a surface whose fit RMS exceeds this share of tol (about 1.5 noise levels: tol is
#: 2.5 of them) is a compromise over faces of two surfaces, and does not pin a curve down
#: either (an unknown RMS, nan, is trusted; tuning gear_s1030_n0.1: its flanks merged with a
#: plane fit at 2.3 noise levels, and their intersections ran 0.4 mean edges off the true
#: edges, the mesh chains 0.08).
TRUST_RMS = 0.6

#: A segment of fewer faces does not pin a curve down: its surface is fitted to a handful of
#: vertices (a one-face plane goes through any triangle), so its side is treated as freeform.
EVIDENCE_FACES = 6

#: Taubin smoothing of the other chains: passes and the two factors.
SMOOTH_PASSES = 10
SMOOTH_LAMBDA, SMOOTH_MU = 0.5, -0.53


@dataclass
class BoundaryCurve:
    """One trimming curve: where segment ``left`` meets ``right`` (``-1``: the mesh border).

    Attributes
    ----------
    left, right : int
        The segments on either side; the curve runs counter-clockwise around ``left`` (seen from
        its mesh normals).
    points : (q, 3) float64
        The curve's points, one per vertex of the mesh chain, in order; ``points[0] ==
        points[-1]`` for a closed curve.
    verts : (q,) int64
        The mesh vertices (validated mesh ids) the points stand for.
    method : {"intersection", "smoothed", "chain"}
        On the two surfaces' intersection, the smoothed mesh chain, or the mesh chain itself
        (an exact tessellation's, projected onto the surfaces that fit along it).
    closed : bool
    moved : float
        Largest distance from a point to its mesh vertex (model units).
    """

    left: int
    right: int
    points: np.ndarray
    verts: np.ndarray
    method: str
    closed: bool
    moved: float

    @property
    def length(self) -> float:
        """Polyline length (model units)."""
        return float(np.linalg.norm(np.diff(self.points, axis=0), axis=1).sum())

    def to_dict(self) -> dict:
        """JSON-ready summary (the points themselves go to ``boundaries.obj``)."""
        return dict(left=self.left, right=self.right, method=self.method, closed=self.closed,
                    points=len(self.points), length=self.length, moved=self.moved)


def onto_surfaces(P, residuals, iters: int = GN_ITERS):
    """Move points to the nearest common point of several surfaces (Gauss-Newton).

    Parameters
    ----------
    P : (p, 3) float64
        Start points (mesh vertices or boundary samples).
    residuals : list of callable
        One to three surfaces, each ``X (p,3) -> (d (p,), G (p,3))``: signed distances and
        their unit gradients (for a :class:`Surface`: ``s.distance``, ``s.normals``).
    iters : int

    Returns
    -------
    X : (p, 3) float64
        Moved points; directions the surfaces do not pin down (ill-conditioned intersections,
        see :data:`GN_RCOND`) keep the start point's coordinate.
    res : (p,) float64
        Largest absolute signed distance of each moved point to the surfaces.

    Examples
    --------
    >>> import numpy as np
    >>> z = Surface("plane", {"point": np.zeros(3), "normal": np.array([0.0, 0, 1])})
    >>> x = Surface("plane", {"point": np.zeros(3), "normal": np.array([1.0, 0, 0])})
    >>> X, res = onto_surfaces(np.array([[0.3, 2.0, -0.2]]), [_residual(z), _residual(x)])
    >>> X.round(12).tolist(), float(res[0])
    ([[0.0, 2.0, 0.0]], 0.0)
    """
    X = np.array(P, dtype=np.float64, copy=True)
    for _ in range(iters):
        parts = [fn(X) for fn in residuals]
        r = np.stack([d for d, _ in parts], axis=1)  # (p, s)
        J = np.stack([n for _, n in parts], axis=1)  # (p, s, 3)
        step = np.einsum("pij,pj->pi", np.linalg.pinv(J, rcond=GN_RCOND), r)
        X -= step
        if np.abs(step).max(initial=0.0) < 1e-15 * (1.0 + np.abs(X).max(initial=0.0)):
            break
    res = np.abs(np.stack([fn(X)[0] for fn in residuals], axis=1)).max(axis=1)
    return X, res


def move_limit(devs, mean_edge: float) -> float:
    """How far a boundary point may move onto its surfaces' intersection: MOVE_DEV_FACTOR times
    the surfaces' deviations from the mesh (``devs``, non-finite ones left out) plus the sagitta
    allowance of MOVE_EDGE_FRACTION of a mesh edge; farther, the intersection is not the one the
    mesh shows (two nearly tangent surfaces meet elsewhere) and the point stays.

    Examples
    --------
    >>> move_limit([0.1, float("nan"), 0.2], 1.0)
    1.1
    """
    return MOVE_DEV_FACTOR * sum(d for d in devs if math.isfinite(d)) + \
        MOVE_EDGE_FRACTION * mean_edge


def _residual(s: Surface):
    return lambda X: (s.distance(X), s.normals(X))


def _well_conditioned(X, surfaces) -> np.ndarray:
    """Per point: the two surfaces' normals there are at least GN_RCOND apart (singular values)."""
    if len(surfaces) < 2:
        return np.zeros(len(X), dtype=bool)
    J = np.stack([s.normals(X) for s in surfaces], axis=1)
    sv = np.linalg.svd(J, compute_uv=False)
    return sv[:, -1] >= GN_RCOND * sv[:, 0]


def _on_intersection(X, surfaces, on_tol) -> np.ndarray:
    """Per point: on both surfaces (within ``on_tol``) where they cross well conditioned."""
    d = np.abs(np.stack([s.distance(X) for s in surfaces], axis=1)).max(axis=1)
    return (d <= max(on_tol, 1e-12)) & _well_conditioned(X, surfaces)


def _taubin(P, closed: bool):
    """Taubin smoothing of a polyline; the ends of an open one stay."""
    P = P.copy()
    body = P[:-1] if closed else P
    for _ in range(SMOOTH_PASSES):
        for f in (SMOOTH_LAMBDA, SMOOTH_MU):
            if closed:
                lap = 0.5 * (np.roll(body, 1, axis=0) + np.roll(body, -1, axis=0)) - body
            else:
                lap = np.zeros_like(body)
                lap[1:-1] = 0.5 * (body[:-2] + body[2:]) - body[1:-1]
            body = body + f * lap
    if closed:
        return np.vstack([body, body[:1]])
    return body


def boundary_curves(V, F, labels, surfaces, mean_edge: float | None = None,
                    tol: float | None = None, exact: bool | None = None) -> list:
    """The trimming curve of every boundary chain of a segmentation.

    Parameters
    ----------
    V : (n, 3) float64
    F : (m, 3) int64
        A validated, consistently oriented manifold mesh.
    labels : (m,) int64
        ``0..k-1``, every segment face-connected.
    surfaces : list of Surface, length k
        The fitted surface of each segment.
    mean_edge : float, optional
        Mean edge length (computed when omitted).
    tol : float, optional
        Fit tolerance (model units; default
        :func:`~igl_heatseg.surfaces.tolerance.vertex_tolerance`): a chain is an intersection
        curve only where both surfaces fit the faces along it (:data:`FIT_SHARE`).
    exact : bool, optional
        Whether the mesh is an exact tessellation
        (:func:`~igl_heatseg.surfaces.tolerance.exact_tessellation`, computed when omitted).

    Returns
    -------
    list of BoundaryCurve
        One per chain of :func:`~igl_heatseg.mesh.topology.boundary_graph`, in its order.

    Examples
    --------
    >>> import numpy as np
    >>> from scipy.spatial import Delaunay
    >>> x, y = np.meshgrid(np.linspace(-1, 1, 9), np.linspace(0, 1, 5))
    >>> F = Delaunay(np.c_[x.ravel(), y.ravel()]).simplices.astype(np.int64)
    >>> V = np.c_[x.ravel(), y.ravel(), np.abs(x.ravel())]          # a fold: two planes
    >>> V[V[:, 0] == 0, 2] += [0.01, -0.02, 0.015, 0.0, -0.01]      # noise on the crease
    >>> lab = (V[F].mean(axis=1)[:, 0] > 0).astype(np.int64)
    >>> s = np.sqrt(0.5)
    >>> S = [Surface("plane", {"point": np.zeros(3), "normal": np.array([s, 0, s])}),
    ...      Surface("plane", {"point": np.zeros(3), "normal": np.array([-s, 0, s])})]
    >>> fold = [c for c in boundary_curves(V, F, lab, S, tol=0.05) if c.right >= 0][0]
    >>> fold.method, float(np.abs(fold.points[:, [0, 2]]).max()) < 1e-12, round(fold.moved, 3)
    ('intersection', True, 0.02)
    """
    V = np.asarray(V, dtype=np.float64)
    F = np.asarray(F, dtype=np.int64)
    labels = np.asarray(labels, dtype=np.int64)
    k = len(surfaces)
    mean_edge = float(igl.avg_edge_length(V, F)) if mean_edge is None else float(mean_edge)
    graph = boundary_graph(V, F, labels, k, inner_kinks=False)
    on_tol = ON_SURFACE_REL * mean_edge
    tol = vertex_tolerance(V, F) if tol is None else float(tol)
    exact = exact_tessellation(V, F) if exact is None else bool(exact)
    pins = np.array([s.is_analytic and not s.rms > TRUST_RMS * tol for s in surfaces], dtype=bool)
    pins &= np.bincount(labels, minlength=k) >= EVIDENCE_FACES
    on = np.zeros(len(F), dtype=bool)  # faces on their own segment's surface
    for a in np.flatnonzero(pins):
        fa = np.flatnonzero(labels == a)
        on[fa] = corner_rms(V, F, fa, surfaces[a]) <= GROW_TOL * tol
    VF = sp.csr_matrix((np.ones(F.size), (F.ravel(), np.repeat(np.arange(len(F)), 3))),
                       shape=(len(V), len(F)))

    def fits_along(verts, side) -> bool:
        fs = VF[verts].indices
        fs = fs[labels[fs] == side]
        return bool(len(fs)) and on[fs].mean() >= FIT_SHARE

    def usable(sides, verts):
        """The surfaces of ``sides`` that pin the curve: analytic, of a segment with
        EVIDENCE_FACES faces, fitting its faces at ``verts`` (:data:`FIT_SHARE`)."""
        return [surfaces[s] for s in sides if s >= 0 and pins[s] and fits_along(verts, s)]

    def placed(P, ss):
        """P moved onto the surfaces ``ss`` where that stays within the move limit."""
        if not ss or not len(P):
            return P
        X, res = onto_surfaces(P, [_residual(s) for s in ss])
        limit = move_limit([s.max_dev for s in ss], mean_edge)
        ok = (res <= max(on_tol, 1e-12)) & (np.linalg.norm(X - P, axis=1) <= limit)
        return np.where(ok[:, None], X, P)

    corner = {int(v): placed(V[v][None], usable(graph.vertex_sides[v], [v]))[0]
              for v in graph.corners.tolist()}
    out = []
    for ch in graph.chains:
        ss = usable((ch.left, ch.right), ch.verts)
        P = V[ch.verts].copy()
        closed = ch.closed
        ends = [] if closed and int(ch.verts[0]) not in corner else [0, len(P) - 1]
        for i in ends:
            P[i] = corner[int(ch.verts[i])]
        inner = slice(1, len(P) - 1) if ends else slice(0, len(P) - 1)
        Q = P.copy()
        Q[inner] = placed(P[inner], ss)
        if len(ss) == 2 and _on_intersection(Q, ss, on_tol).mean() >= INTERSECTION_SHARE:
            P, method = Q, "intersection"
        else:  # smoothed (on noise), then put back onto the surfaces that fit along it
            S = P if exact else _taubin(P, closed and not ends)
            S[inner] = placed(S[inner], ss)
            if ends:
                S[0], S[-1] = P[0], P[-1]
            P, method = S, "chain" if exact else "smoothed"
        if closed:
            P[-1] = P[0]
        moved = float(np.linalg.norm(P - V[ch.verts], axis=1).max(initial=0.0))
        out.append(BoundaryCurve(int(ch.left), int(ch.right), P, ch.verts.copy(), method,
                                 bool(closed), moved))
    return out
