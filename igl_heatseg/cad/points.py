"""Where the B-Rep's vertices and edge samples go: mesh corners and boundary samples moved onto
the common point of their segments' surfaces (or, on a noisy mesh, between surfaces that pass
each other, :func:`~.geometry.settle_on_surfaces`), within the move limit. Part of
:func:`~.build.build_brep`; ``ctx`` is its build context (tolerances, surfaces' deviations,
the OCC builder, and the segments whose edges stay on the mesh: ``ctx["strict"]``)."""

from __future__ import annotations

import logging
import math

import numpy as np

from igl_heatseg.surfaces.boundaries import move_limit

from ._ocp import require_ocp

require_ocp()

from . import geometry  # noqa: E402

logger = logging.getLogger(__name__)

__all__ = ["place_vertices", "edge_points", "move_vertex", "MIN_EDGE_SAMPLES"]

#: Minimum number of samples along an edge before it is fitted (straight 2-vertex chains get
#: midpoints, so that the intersection of curved surfaces is followed between mesh vertices).
MIN_EDGE_SAMPLES = 24


def place_vertices(V, graph, projs, ctx) -> dict:
    """B-Rep vertex positions: each corner on the common point of the surfaces around it.

    Parameters
    ----------
    V : (n, 3) float64
        Mesh vertices.
    graph : BoundaryGraph
        The segments' boundary chains, corners and the segments around each corner.
    projs : list of Projector or None
        Per segment, its built surface (None: faceted).
    ctx : dict
        The build context (``curve_tol``, ``devs``, ``mean_edge``, ``noisy``, ``strict``;
        ``between`` gets the segments around corners settled between their surfaces).

    Returns
    -------
    dict
        Corner vertex id -> (3,) position (the mesh vertex where the surfaces do not bring it
        within the move limit; both ends of a chain stay at the mesh when they would meet).
    """
    pos = {}
    for v in graph.corners.tolist():
        sides = graph.vertex_sides[v]
        ps = [projs[s] for s in sides if s >= 0 and projs[s] is not None]
        X = V[v]
        if ps:
            Y, moved, between = geometry.settle_on_surfaces(
                V[v][None], ps, ctx["curve_tol"], _move_limit(ctx, sides), _between(ctx, sides))
            X = Y[0]
            if between[0]:
                ctx["between"].update(s for s in sides if s >= 0)
            elif not moved[0]:
                logger.debug("vertex %d: surfaces ill-conditioned, mesh vertex", v)
        pos[v] = X
    for ch in graph.chains:  # two corners moved onto one point would make a null edge
        a, b = int(ch.verts[0]), int(ch.verts[-1])
        if a != b and np.linalg.norm(pos[a] - pos[b]) <= ctx["curve_tol"]:
            pos[a], pos[b] = V[a], V[b]
    return pos


def _between(ctx, sides) -> bool:
    """Whether points of a noisy mesh may settle between surfaces that do not meet
    (:func:`~.geometry.settle_on_surfaces`): not next to a segment whose sewn face came out
    invalid with such points (``ctx["strict"]``)."""
    return ctx["noisy"] and not any(s in ctx["strict"] for s in sides)


def _move_limit(ctx, sides) -> float:
    """How far a boundary point may move onto its surfaces' intersection
    (:func:`igl_heatseg.surfaces.boundaries.move_limit` of the built surfaces' deviations)."""
    return move_limit([ctx["devs"][s] for s in sides if s >= 0], ctx["mean_edge"])


def _samples(P: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Polyline subdivided to at least MIN_EDGE_SAMPLES points; index of each original point."""
    nseg = len(P) - 1
    s = max(1, math.ceil(MIN_EDGE_SAMPLES / nseg))
    t = np.arange(s) / s
    Q = (P[:-1, None, :] * (1 - t)[None, :, None] + P[1:, None, :] * t[None, :, None])
    return np.vstack([Q.reshape(-1, 3), P[-1:]]), np.arange(nseg + 1) * s


def _seam_polyline(chain, V, projs, ctx):
    """A closed chain on a periodic surface restarted on that surface's seam (u = 0), so that
    the seam ShapeFix_Face adds runs through the chain's vertex instead of splitting the
    circle (near a mesh vertex that split leaves a sliver edge the sewing drops)."""
    for side in (chain.left, chain.right):
        if side < 0 or projs[side] is None:
            continue
        frame = geometry.seam_frame(ctx["surfaces"][side])
        if frame is not None:
            return geometry.start_at_seam(V[chain.verts], frame)
    return None


def edge_points(chain, V, pos, projs, vertices, ctx, snap) -> tuple[np.ndarray, np.ndarray]:
    """Samples along a chain moved onto its surfaces (a closed chain restarted on a seam).

    Kept in ``ctx["point_cache"]`` by the chain, its ends' positions, its sides' surfaces, how
    far it may move and whether it may settle between surfaces: a rebuild moves again only the
    chains where one of them changed.

    Parameters
    ----------
    chain : Chain
        A boundary chain (mesh vertex ids, left and right segments, closed or not).
    V : (n, 3) float64
        Mesh vertices.
    pos : dict
        Corner positions (:func:`place_vertices`); a restarted closed chain moves its own.
    projs : list of Projector or None
        Per segment, its built surface.
    vertices : dict
        Corner vertex id -> TopoDS_Vertex.
    ctx : dict
        The build context.
    snap : (n, 3) float64
        Updated in place: the chain's mesh vertices at their samples' positions.

    Returns
    -------
    P : (q, 3) float64
        The samples, at least MIN_EDGE_SAMPLES + 1 of them, in chain order.
    at_vertex : (q,) bool
        True at the samples that are the chain's mesh vertices (the others subdivide its
        chords; a restarted closed chain's first and last sample is where it crosses the seam).
    """
    sides = (chain.left, chain.right)
    ps = [projs[s] for s in sides if s >= 0 and projs[s] is not None]
    a, b, limit = int(chain.verts[0]), int(chain.verts[-1]), _move_limit(ctx, sides)
    between = _between(ctx, sides)
    key = (chain.verts.tobytes(), sides, pos[a].tobytes(), pos[b].tobytes(), limit, between,
           *(projs[s] if s >= 0 else None for s in sides))
    cache = ctx.setdefault("point_cache", {})
    if key not in cache:
        R = _seam_polyline(chain, V, projs, ctx) if chain.closed else None
        P, orig = _samples(V[chain.verts] if R is None else R)
        if R is None:
            P[0], P[-1] = pos[a], pos[b]
        lo = 1 if R is None else 0  # a restarted closed chain also moves its vertex
        moved = np.zeros(0, dtype=bool)
        if ps and len(P) > 2:
            P[lo:len(P) - lo], _, moved = geometry.settle_on_surfaces(
                P[lo:len(P) - lo], ps, ctx["curve_tol"], limit, between)
        cache[key] = P, orig, R is not None, bool(moved.any())
    P, orig, restarted, between = cache[key]
    if between:
        ctx["between"].update(s for s in sides if s >= 0)
    P = P.copy()
    at_vertex = np.zeros(len(P), dtype=bool)
    at_vertex[orig] = True
    if not restarted:
        snap[chain.verts] = P[orig]
    else:
        P[-1] = P[0]
        at_vertex[[0, -1]] = False  # (the seam crossing, on a chord)
        move_vertex(a, P[0], pos, vertices, ctx)
    return P, at_vertex


def move_vertex(vid, X, pos, vertices, ctx) -> None:
    """Put corner ``vid`` at ``X`` (3,): in ``pos`` and on its TopoDS_Vertex."""
    pos[vid] = np.asarray(X, dtype=np.float64)
    ctx["builder"].UpdateVertex(vertices[vid], geometry._pnt(X), ctx["vertex_tol"])
