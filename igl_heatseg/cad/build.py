"""From a segmented mesh with one fitted surface per segment to a sewn B-Rep.

Stages (timed in :attr:`~igl_heatseg.cad.result.CadResult.timings`): ``topology`` (chains,
loops, corners from the labels), ``surfaces`` (OCC surfaces; freeform B-splines over
charts; deviation check, a B-spline over the chart of an analytic segment that deviates),
``vertices`` and ``edges`` (Gauss-Newton onto the adjacent surfaces, exact lines and circles
or B-spline curves -- the chain's polyline where a spline would ring off it -- each edge
built once and shared by its two faces; two corners of one chain never share a point),
``faces`` (trimmed faces, ``ShapeFix_Face`` for pcurves and seams, per-face checks; failures
become faceted patches, and their neighbours are built again without their surfaces),
``sew`` (sewing, shape fix, same-domain unification, solid), ``check`` (BRepCheck in memory
and after a STEP round trip, for every sewn model) and ``fidelity``.
"""

from __future__ import annotations

import logging
import math
import time

import igl
import numpy as np

from igl_heatseg.errors import MeshError
from igl_heatseg.mesh.topology import edge_topology, face_components
from igl_heatseg.surfaces.model import Surface
from igl_heatseg.surfaces.tolerance import exact_tessellation

from ._ocp import require_ocp

require_ocp()

from OCP.BRep import BRep_Builder, BRep_Tool  # noqa: E402
from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeEdge, BRepBuilderAPI_MakeFace  # noqa: E402
from OCP.BRepCheck import BRepCheck_Analyzer  # noqa: E402
from OCP.ShapeFix import ShapeFix_Face, ShapeFix_Shape  # noqa: E402
from OCP.TopAbs import TopAbs_FACE  # noqa: E402
from OCP.TopoDS import TopoDS, TopoDS_Face, TopoDS_Vertex, TopoDS_Wire  # noqa: E402

from . import faceted, geometry, periodic, points, surface_choice  # noqa: E402
from .blame import invalid_segments as _invalid_segments  # noqa: E402
from .blame import open_segments as _open_segments  # noqa: E402
from .budget import TimeLimit  # noqa: E402
from .components import build_by_component  # noqa: E402
from .fidelity import brep_fidelity, face_area, face_samples  # noqa: E402
from .result import CadResult  # noqa: E402
from .segments import check_inputs, typical_rms  # noqa: E402
from .sew import assemble  # noqa: E402
from .topology import (  # noqa: E402
    boundary_graph,
    inner_vertices,
    segment_areas,
    segment_neighbours,
)

logger = logging.getLogger(__name__)

__all__ = ["CadResult", "build_brep"]

#: Default modelling tolerance as a fraction of the bbox diagonal: a segment whose mesh
#: vertices lie farther than this from its surface is not built (faceted instead).  Loose
#: enough for scan noise, tight enough to reject a wrong surface type.
DEFAULT_TOL_REL = 1e-2

#: An analytic segment whose vertex RMS distance is above this multiple of the part's typical
#: one (:func:`~igl_heatseg.cad.segments.typical_rms`) and above MISFIT_RMS_FLOOR tolerances
#: misses a shape the noise does not explain (a gear's involute flank as a plane: the lands
#: beside it were trimmed at its chord and failed the area check); it gets a B-spline face
#: when one fits it closer than its surface.
MISFIT_RMS_RATIO, MISFIT_RMS_FLOOR = 2.0, 0.05

#: Edge curves (B-splines) approximate their points to this fraction of the tolerance, so
#: curve error never dominates the fit error.
CURVE_TOL_FRACTION = 1e-2

#: A trimmed face whose area differs from its segment's mesh area by more than this fraction
#: was trimmed wrongly (complement chosen, loop lost) and is faceted instead.
FACE_AREA_SLACK = 0.2

#: A segment's boundary runs along mesh edges, the face's along the intersection of the
#: surfaces: up to about half a mesh edge apart on every side. A narrow segment (a chamfer two
#: triangles wide) may therefore differ from its face by more than FACE_AREA_SLACK: its slack
#: is BOUNDARY_SHIFT mean edges times its loops' length over its area, up to FACE_AREA_SLACK_MAX.
BOUNDARY_SHIFT, FACE_AREA_SLACK_MAX = 0.5, 0.5

#: A trimmed B-spline face reaching farther than this many tolerances from the mesh is not
#: built: within the tolerance of its segment and of the surfaces of its neighbours, it runs
#: on past its chart only through a wrong trim (seen: 5 units out of a coarse block's side),
#: or where it folds (a 0.016-wide fold in the parameters, 4.8 units out). Measured at
#: :func:`~.fidelity.face_samples` (a grid over the surface's parameters and points along the
#: edges): meshing the face took up to 10 s where it folds.
FREEFORM_OFF_MESH = 2.0

#: Sewing tolerance over the largest gap between a faceted patch's border chords and the
#: neighbouring face's edge curve (the sagitta of the chords plus margin).
FACET_GAP_FACTOR = 1.5

#: A face of revolution is built on a (u, v) rectangle when its loop edges stay within this
#: fraction of the sewing tolerance of their mean-v circle: those circles then replace the
#: loop edges, and sewing must close the gap (between two such neighbours, twice this).
REVOLVED_SEW_FRACTION = 0.45
#: ... read at the loop's mesh vertices alone on an exact tessellation when it has this many
#: (fewer leave too little of the turn around the axis: 4 of a square hole span 270 degrees).
LOOP_MIN_VERTICES = 6

#: Widest sewing tolerance tried when a closed part keeps free edges, in mean edge lengths
#: (wider would merge distinct mesh vertices).
SEW_MAX_EDGE = 0.5

#: Rebuilds with the segments whose sewn faces fail BRepCheck faceted, before the whole model
#: is faceted (an invalid face can hang OCC's mesher, and a CAD program reading the file);
#: the same rebuilds facet the built segments along the free edges of a closed mesh's shell
#: (when that does not give a valid solid, the first open shell is written). A build that
#: leaves out faceted triangles sewing closed up (:func:`~.blame.collapsed`) is one more.
#: Faceting a face can leave a neighbour invalid in turn: with 2, tuning
#: flange_s1025_coarse_n0.05 and tuning-3 bolt_s6029_frontal_n0.05 came out wholly faceted
#: (19 of 19 and 15 of 15 segments); with 4, valid solids with 9 and 3 faceted, in the same
#: time (the whole model's fallback had run every later build of :func:`build_brep` too).
MAX_REBUILDS = 4
#: Builds more (besides MAX_REBUILDS) with the edge points next to segments whose sewn faces
#: failed BRepCheck or kept free edges put back on the mesh
#: (:func:`~.geometry.settle_on_surfaces`), before those segments are faceted.
STRICT_REBUILDS = 2
#: The reason of a segment faceted because its trimmed face failed BRepCheck.
INVALID_TRIM = "trimmed face is not valid (BRepCheck)"

#: Smallest tolerance relative to the bbox diagonal (OCC's Precision::Confusion is 1e-7 on
#: ~1-unit parts; we keep a margin above it).
MIN_TOL_REL = 1e-7


def _vertex(builder, X, tol):
    v = TopoDS_Vertex()
    builder.MakeVertex(v, geometry._pnt(X), float(tol))
    return v


def _edge(chain, P, circle, pos, projs, vertices, ctx, snap):
    """The shared TopoDS_Edge of a chain through its samples P (or the given exact circle)."""
    if circle is None:
        curve, t0, t1 = geometry.edge_curve(P, ctx["curve_tol"], ctx["diag"])
    else:
        curve, t0, t1 = circle
    if any(s >= 0 and projs[s] is None for s in (chain.left, chain.right)):
        Q = snap[chain.verts]  # a faceted neighbour's border: chords against this curve
        gap = geometry.curve_distance(curve, 0.5 * (Q[1:] + Q[:-1])).max(initial=0.0)
        ctx["facet_gap"] = max(ctx.get("facet_gap", 0.0), float(gap))
    v0, v1 = vertices[int(chain.verts[0])], vertices[int(chain.verts[-1])]
    builder = ctx["builder"]
    for vid, t in ((int(chain.verts[0]), t0), (int(chain.verts[-1]), t1)):
        q = curve.Value(t)  # the vertex tolerance covers the curve's end
        gap = float(np.linalg.norm(pos[vid] - (q.X(), q.Y(), q.Z())))
        if 1.5 * gap > ctx["vtols"].get(vid, ctx["vertex_tol"]):
            ctx["vtols"][vid] = 1.5 * gap
            builder.UpdateVertex(vertices[vid], 1.5 * gap)
    mk = BRepBuilderAPI_MakeEdge(curve, v0, v1, t0, t1)
    if not mk.IsDone():
        raise RuntimeError(f"edge {chain.left}/{chain.right}: MakeEdge error {mk.Error()}")
    return mk.Edge()


def _circle_gap(curve, s, level, ctx) -> float:
    """Largest distance from samples of a neighbour's circle to this face's iso-v circle."""
    own, _ = periodic.iso_circle(s, level)
    t = np.linspace(0, 2 * np.pi, 32, endpoint=False)
    P = np.array([[q.X(), q.Y(), q.Z()] for q in (curve.Value(float(x)) for x in t)])
    return float(geometry.curve_distance(own, P).max())


def _revolved_plans(graph, surfaces, projs, seg_points, pos, vertices, ctx):
    """Faces of revolution bounded by closed edges around their axis (:mod:`.periodic`).

    Returns the faces built on a (u, v) rectangle (``plans``: their loops are circles at
    constant v, which become the shared edges), the other such faces with the seam angle
    ShapeFix_Face should use (``wraps``), and the exact circles by chain. Faces are visited
    breadth-first over shared closed edges: a face whose edge was started by a neighbour
    puts its seam through that edge's vertex and restarts its other closed edges there, so
    every closed edge's vertex lies on the seams of its faces (a closed edge cut next to its
    vertex leaves a sliver edge that sewing loses)."""
    plans, wraps = {}, {}
    for a, s in enumerate(surfaces):
        if projs[a] is None or s.kind not in periodic.REVOLVED_KINDS or not graph.loops[a]:
            continue
        lp = _loop_points(graph.loops[a], ctx)
        if not periodic.wraps_axis(s, lp):
            continue
        # an exact tessellation's vertices lie on its circles, its chords inside them: the
        # points that subdivide a chord are no evidence of where the loop runs
        plans[a] = periodic.revolved_plan(
            s, lp if ctx["noisy"] else _loop_points(graph.loops[a], ctx, vertices_only=True),
            seg_points(a), REVOLVED_SEW_FRACTION * ctx["sew_tol"])
    circles, done = {}, {}
    for root in plans:
        queue = [root]
        while queue:
            a = queue.pop(0)
            if a in done:
                continue
            done[a], planned = _plan_circles(a, surfaces[a], plans[a], graph, circles, pos,
                                             vertices, ctx)
            if not planned:
                plans[a] = None
            for loop in graph.loops[a]:
                ch = graph.chains[loop[0][0]]
                queue.extend(b for b in (ch.left, ch.right) if b in plans and b not in done)
    plans = {a: p for a, p in plans.items() if p is not None and done[a] is not None}
    wraps = {a: u0 for a, u0 in done.items() if a not in plans and u0 is not None}
    return plans, wraps, circles


def _plan_circles(a, s, plan, graph, circles, pos, vertices, ctx):
    """Seam start u0 of one face around its axis, starting its closed edges there (exact
    circles when it stays planned), and whether it stays planned; u0 is None when the face
    has no common seam with its neighbours (then ShapeFix_Face puts the seam away from the
    vertices)."""
    tol = REVOLVED_SEW_FRACTION * ctx["sew_tol"]
    cids = [lp[0][0] for lp in graph.loops[a]]
    if plan is not None and any(c in circles and (circles[c] is None or
                                                  _circle_gap(circles[c][0], s, lv, ctx) > tol)
                                for c, lv in zip(cids, plan["levels"], strict=True)):
        plan = None  # a neighbour's edge is no circle of this face: trim by ShapeFix
    given = [c for c in cids if c in circles]
    u0 = 0.0
    if given:
        u0 = float(periodic.surface_uv(s, pos[int(graph.chains[given[0]].verts[0])][None])[0][0])
    if len(given) > 1 and plan is None:
        return None, False  # both ends fixed by neighbours: no common seam
    levels = plan["levels"] if plan is not None else [None] * len(cids)
    for c, level in zip(cids, levels, strict=True):
        if c in circles:
            continue
        if level is not None:
            curve, start = periodic.iso_circle(s, level, ctx["chain_points"][c], u0)
            circles[c] = (curve, 0.0, 2 * np.pi)
        else:
            P = geometry.start_at_seam(ctx["chain_points"][c], periodic.seam_at(s, u0))
            if P is None:
                return None, False
            ctx["chain_points"][c], start, circles[c] = P, P[0], None
        points.move_vertex(int(graph.chains[c].verts[0]), start, pos, vertices, ctx)
    if plan is not None:
        plan["u0"] = u0
    return u0, plan is not None


def _loop_points(loops, ctx, vertices_only: bool = False):
    """Per loop, the points of its one closed edge (walked like the loop), or None; with
    ``vertices_only``, only its samples at the chain's mesh vertices (not those subdividing
    its chords) when it has LOOP_MIN_VERTICES of them."""
    out = []
    for loop in loops:
        if len(loop) != 1:
            out.append(None)
            continue
        P = ctx["chain_points"][loop[0][0]]
        at = ctx["chain_at_vertex"][loop[0][0]]
        if vertices_only and at.sum() >= LOOP_MIN_VERTICES:
            P = P[at]
        out.append(P if loop[0][1] else P[::-1])
    return out


def _face(a, geom, loops, edges, ctx, seg_area, seg_points):
    """Trimmed, fixed face of segment a, or (None, reason)."""
    builder = ctx["builder"]
    face = None
    if a in ctx["revolved"]:
        face = periodic.revolved_face(geom, ctx["revolved"][a])
    if face is not None:
        pass
    elif not loops:
        mk = BRepBuilderAPI_MakeFace(geom, ctx["vertex_tol"])
        if not mk.IsDone():
            return None, "closed segment on an unbounded surface"
        face = mk.Face()
    else:
        surf = ctx["surfaces"][a]
        if a in ctx["wraps"]:  # seam through the vertices of its closed edges
            u0 = ctx["wraps"][a]
            geom = geometry.occ_surface(surf, u0 if surf.outward else -u0)
        elif geometry.seam_frame(surf) is not None:  # seam away from the loops' vertices
            ends = [ctx["pos"][int(v)] for lp in loops for c, _ in lp
                    for v in (ctx["chains"][c].verts[0], ctx["chains"][c].verts[-1])]
            geom = geometry.occ_surface(surf, geometry.seam_away_from(surf, np.array(ends)))
        face = TopoDS_Face()
        builder.MakeFace(face, geom, ctx["vertex_tol"])
        for loop in loops:
            w = TopoDS_Wire()
            builder.MakeWire(w)
            for cid, fwd in loop:
                builder.Add(w, edges[cid] if fwd else edges[cid].Reversed())
            w.Closed(True)
            builder.Add(face, w)
        fix = ShapeFix_Face(face)
        fix.SetPrecision(ctx["curve_tol"])  # our edges are exact to it; finer splits slivers
        fix.SetMaxTolerance(ctx["sew_tol"])
        fix.Perform()
        face = fix.Face()
    if not BRepCheck_Analyzer(face).IsValid():
        fix = ShapeFix_Shape(face)  # same-parameter and tolerance fixes on the edges
        fix.SetPrecision(ctx["vertex_tol"])
        fix.SetMaxTolerance(ctx["sew_tol"])
        fix.Perform()
        fixed = fix.Shape()
        if fixed.ShapeType() != TopAbs_FACE or not BRepCheck_Analyzer(fixed).IsValid():
            return None, INVALID_TRIM
        face = TopoDS.Face(fixed)
    if ctx["surfaces"][a].kind == "freeform":  # a B-spline runs on past its chart
        if "mesh_tree" not in ctx:  # one tree for every B-spline face of every rebuild
            ctx["mesh_tree"] = igl.AABB()
            ctx["mesh_tree"].init(*ctx["mesh"])
        off = float(np.sqrt(ctx["mesh_tree"].squared_distance(
            *ctx["mesh"], face_samples(face, tol=ctx["vertex_tol"]))[0].max(initial=0.0)))
        if off > FREEFORM_OFF_MESH * ctx["tol"]:
            return None, f"trimmed B-spline face lies {off:.3g} from the mesh"
    area = face_area(face)
    area_gap = abs(area - seg_area)
    if not area_gap <= (_area_slack(loops, ctx, seg_area) if ctx["wide_area"] else
                        FACE_AREA_SLACK) * seg_area:
        return None, f"trimmed face area {area:.4g} differs from the segment's {seg_area:.4g}"
    if not area_gap <= FACE_AREA_SLACK * seg_area:
        ctx["widened"].add(a)  # built on the narrow segment's slack only
    return face, None


def _area_slack(loops, ctx, seg_area) -> float:
    """Relative area difference allowed between a trimmed face and its segment (see
    BOUNDARY_SHIFT): FACE_AREA_SLACK, more for a narrow segment, at most FACE_AREA_SLACK_MAX."""
    V = ctx["mesh"][0]
    length = sum(float(np.linalg.norm(np.diff(V[ctx["chains"][c].verts], axis=0), axis=1).sum())
                 for loop in loops for c, _ in loop)
    shift = BOUNDARY_SHIFT * ctx["mean_edge"] * length / max(seg_area, 1e-300)
    return min(FACE_AREA_SLACK_MAX, max(FACE_AREA_SLACK, shift))


def _tolerances(V, F, surfaces, tol):
    diag = float(np.linalg.norm(V.max(axis=0) - V.min(axis=0)))
    E = np.r_[F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]]
    mean_edge = float(np.linalg.norm(V[E[:, 0]] - V[E[:, 1]], axis=1).mean())
    if tol is None:
        tol = DEFAULT_TOL_REL * diag
    elif not (np.isfinite(tol) and tol > 0):
        raise MeshError(f"tol must be a positive number, got {tol!r}")
    tol = max(float(tol), MIN_TOL_REL * diag)
    curve_tol = max(CURVE_TOL_FRACTION * tol, MIN_TOL_REL * diag)
    return {"tol": tol, "curve_tol": curve_tol, "vertex_tol": max(MIN_TOL_REL * diag, 1e-7),
            "diag": diag, "mean_edge": mean_edge, "noisy": not exact_tessellation(V, F),
            "strict": set(), "between": set()}


def _sew_tolerance(ctx, devs) -> float:
    """Sewing closes gaps between built faces (curve error) and faceted patches (whose
    borders are the mesh polylines snapped onto the good neighbour's surface): a few curve
    tolerances or twice the deviation of the worst built surface, never above half an edge
    (raised later to cover the chords of faceted borders, :data:`FACET_GAP_FACTOR`)."""
    dev = max([d for d in devs if np.isfinite(d)], default=0.0)
    return float(min(max(4 * ctx["curve_tol"], 2.0 * dev), 0.5 * ctx["mean_edge"]))


def _faceted_result(V, F, ctx, closed, timings, message):
    t = time.perf_counter()
    faces = faceted.triangle_faces(V, F, ctx["vertex_tol"])
    shape, _ = assemble(faces, max(ctx["vertex_tol"], 1e-6 * ctx["diag"]), closed, unify=False,
                        connected=True)
    timings["faceted"] = time.perf_counter() - t
    return shape


def build_brep(V, F, labels, surfaces, uv=None, tol=None, progress=None,
               time_limit=None) -> CadResult:
    """Sewn B-Rep of a segmented mesh with one fitted surface per segment.

    Parameters
    ----------
    V : (n, 3) float64
        Vertex positions.
    F : (m, 3) int64
        Consistently oriented manifold triangles (outward when closed).
    labels : (m,) int64
        Segment of every face, ``0..k-1``, each segment face-connected.
    surfaces : list of Surface
        ``surfaces[a]`` fitted to segment ``a`` (``outward`` as in the fit).
    uv : list of (ids, UV) or None, optional
        Per segment, ``None`` or a bijective chart: vertex ids ``(p,)`` and ``UV (p, 2)``;
        used for freeform segments (a disk segment without one gets a harmonic chart).
    tol : float, optional
        Modelling tolerance (model units): a segment farther than this from its analytic
        surface (or misfit by it: MISFIT_RMS_RATIO) gets a B-spline face over its chart within
        it when one fits closer (else a far one is faceted). Default DEFAULT_TOL_REL x diag.
    progress : callable, optional
        ``progress(stage, fraction)``.
    time_limit : float, optional
        Seconds after which no further build is started: no rebuild, no second pass and no
        part-by-part build (the one running is finished, so the build can take longer). A
        model still invalid then is written faceted, a valid open shell kept as it is; the
        result's ``message`` and ``time_limit`` say what was skipped. None: no limit.

    Returns
    -------
    CadResult
        Never raises for geometry it cannot build: such faces are faceted and reported. A
        segment whose face fails BRepCheck once sewn (in memory, or read back from STEP) is
        faceted and the model rebuilt (up to MAX_REBUILDS times; a faceted triangle that
        sewing closed up is left out instead, the first time in one build more), as are the
        built segments along the free edges of a closed mesh's open shell (kept when that gives
        a valid solid, else the first open shell is returned); a failed build, or a model still
        invalid, returns the fully faceted model (``faceted_model=True``), unless the mesh has
        several edge-connected parts: they are then built one by one
        (:func:`~igl_heatseg.cad.components.build_by_component`; a compound).
        Before that, a model that came out fully faceted, or not a solid from a closed mesh,
        is built again without its B-spline stand-ins for analytic segments; one not a solid
        from a closed mesh also without the narrow faces that only BOUNDARY_SHIFT's area slack
        admitted; each kept when better.

    Raises
    ------
    MeshError
        Malformed input arrays.

    Examples
    --------
    >>> import numpy as np
    >>> from igl_heatseg.surfaces.model import Surface
    >>> V = np.array([[x, y, z] for x in (0., 1.) for y in (0., 1.) for z in (0., 1.)])
    >>> F = np.array([[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1],
    ...               [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]])
    >>> labels = np.repeat(np.arange(6), 2)
    >>> normals = [(-1, 0, 0), (1, 0, 0), (0, -1, 0), (0, 1, 0), (0, 0, -1), (0, 0, 1)]
    >>> surfs = [Surface("plane", {"point": V[F[2 * i, 0]], "normal": np.array(n, float)})
    ...          for i, n in enumerate(normals)]
    >>> res = build_brep(V, F, labels, surfs)
    >>> res.fidelity["valid"], res.fidelity["solids"], round(res.fidelity["volume"], 9)
    (True, 1, 1.0)
    """
    V, F, labels = check_inputs(V, F, labels, surfaces, uv)
    if time_limit is not None and not (np.isfinite(time_limit) and time_limit >= 0):
        raise MeshError(f"time_limit must be a number of seconds >= 0, got {time_limit!r}")
    progress = progress or (lambda stage, frac: None)
    surfaces = [geometry.sphere_poles_away(s, V[np.unique(F[labels == a])])
                for a, s in enumerate(surfaces)]
    ctx = _tolerances(V, F, surfaces, tol)
    limit = ctx["limit"] = TimeLimit(time_limit)
    ctx["builder"], ctx["vtols"], ctx["fitted"] = BRep_Builder(), {}, surfaces
    ctx["mesh"] = V, F
    closed = bool(edge_topology(F).interior.all())  # every edge has two faces
    ctx["notes"] = {}
    ctx["misfit_rms"] = max(MISFIT_RMS_RATIO * typical_rms(V, F, labels, surfaces),
                            MISFIT_RMS_FLOOR * ctx["tol"])
    timings: dict = {}
    ctx["bspline"], ctx["fallbacks"] = True, set()
    ctx["wide_area"], ctx["widened"] = True, set()
    ctx["touching"], ctx["narrowed"] = True, set()
    cache = ctx["surface_cache"] = {}  # (segment, B-splines allowed) -> its surface_for
    t = time.perf_counter()
    given, moved, touched = surface_choice.settle(V, F, labels, surfaces, uv, ctx["tol"],
                                                  ctx["misfit_rms"], cache, ctx["notes"])
    timings["surfaces"] = time.perf_counter() - t  # (the stand-ins fitted there are kept)
    shape, status, sew_tol, faceted_model, message, solid = _sewn_model(
        V, F, given, surfaces, uv, ctx, closed, timings, progress)
    if touched and (faceted_model or (closed and not solid)) and not limit.out_of_time(
            "the build with the segmentation's borders"):
        logger.warning("the model with border faces of segments %s moved is %s; building it "
                       "again with the segmentation's borders", sorted(touched),
                       "faceted" if faceted_model else "not a solid")
        _forget(ctx, touched)
        again = _sewn_model(V, F, labels, surfaces, uv, ctx, closed, timings, progress)
        if (not again[3], again[5]) > (not faceted_model, solid):
            shape, status, sew_tol, faceted_model, message, solid = again
            given, moved = labels, moved[:0]
        else:
            _forget(ctx, touched)
    labels = given
    # (built, allowed, what, how instead, also when fully faceted): the faces that may be what
    # broke the model; it is built again without them, and kept if better (a rebuild keeps the
    # earlier ones' choices). A fully faceted model is not built again for the narrow faces:
    # of the 4 seen, none came out better, at half the time again. The sewing defects of a
    # faceted patch's triangles are blamed on the built faces they touch; when that leaves no
    # solid, the model is built again blaming every built segment next to the patch.
    for key, allow, what, instead, if_faceted in (
            ("fallbacks", "bspline", "B-spline stand-ins", "without the B-spline stand-ins",
             True),
            ("widened", "wide_area", "narrow faces that only BOUNDARY_SHIFT's slack admitted",
             "without those narrow faces", False),
            ("narrowed", "touching", "the defects of their faceted triangles blamed on the "
             "built faces they touch", "blaming every built segment next to the faceted triangles",
             True)):
        if ctx[key] and ((faceted_model and if_faceted) or (closed and not solid)) and \
                not limit.out_of_time(f"the build {instead}"):
            logger.warning("the model with %s for segments %s is %s; building it again %s",
                           what, sorted(ctx[key]),
                           "faceted" if faceted_model else "not a solid", instead)
            ctx[allow] = False
            again = _sewn_model(V, F, labels, surfaces, uv, ctx, closed, timings, progress)
            if (not again[3], again[5]) > (not faceted_model, solid):
                shape, status, sew_tol, faceted_model, message, solid = again
    tols = {k: ctx[k] for k in ("tol", "curve_tol", "vertex_tol", "diag", "mean_edge")}
    # a part of the mesh that no rebuild mends need not facet the others
    if faceted_model and face_components(F)[0] > 1 and not limit.out_of_time(
            "the part-by-part build"):
        t = time.perf_counter()
        parts = build_by_component(V, F, labels, surfaces, uv, ctx["tol"],
                                   lambda *a, **k: build_brep(*a, time_limit=limit.left(), **k),
                                   progress)
        if parts is not None:
            timings["components"] = time.perf_counter() - t
        if parts is not None and not parts[3]:  # (each part was sewn with its own tolerance)
            return CadResult(*parts[:3], timings, {**tols, "sew_tol": None},
                             parts[3], limit.note(parts[4]), parts[5], limit.report())
    t = time.perf_counter()
    progress("fidelity", 0.0)
    fid = brep_fidelity(shape, V, F)
    timings["fidelity"] = time.perf_counter() - t
    tols["sew_tol"] = sew_tol
    progress("fidelity", 1.0)
    return CadResult(shape, status, fid, timings, tols, faceted_model, limit.note(message),
                     moved, limit.report())


def _forget(ctx, segments) -> None:
    """Drop what a build kept of the segments' faces (their surfaces, the inner vertices), for
    a build with other labels."""
    for a in segments:
        ctx["surface_cache"].pop((a, True), None)
        ctx["surface_cache"].pop((a, False), None)
    ctx.pop("inner", None)
    ctx.pop("dropped", None)


def _sewn_model(V, F, labels, surfaces, uv, ctx, closed, timings, progress):
    """Faces built, sewn and checked, with the rebuilds of :func:`build_brep`: (shape, status,
    sewing tolerance, fully faceted?, message, solid?)."""
    skip: dict = {}  # segments faceted after sewing: failed BRepCheck, or along free edges
    cache = ctx["surface_cache"]  # shared by the builds with and without B-splines
    neighbours = segment_neighbours(F, labels, len(surfaces))
    kept = None  # the first valid open shell, kept in case faceting does not close it
    dropped = ctx.setdefault("dropped", set())  # faceted triangles sewing closed up: left out
    extra = False  # whether a build went to leaving them out (besides MAX_REBUILDS)
    strict = 0  # builds that went to edge points on the mesh (besides MAX_REBUILDS)
    try:
        # (one more when triangles were left out, up to STRICT_REBUILDS for edge points on
        # the mesh)
        for attempt in range(MAX_REBUILDS + 2 + STRICT_REBUILDS):
            if attempt and ctx["limit"].out_of_time(f"rebuild {attempt} (segments "
                                                    f"{sorted(skip)} faceted)"):
                if kept is None:
                    raise _InvalidBRep("the sewn B-Rep is invalid (BRepCheck) and the time "
                                       "limit left no time to facet its invalid faces")
                shape, info, status, skip = kept
                break
            attempt -= extra + strict
            faces, status, sew_tol, owner = _build_faces(V, F, labels, surfaces, uv, ctx,
                                                         timings, progress, skip, cache)
            t = time.perf_counter()
            progress("sew", 0.0)
            shape, info = assemble(faces, sew_tol, closed,
                                   max_tol=SEW_MAX_EDGE * ctx["mean_edge"])
            timings["sew"] = timings.get("sew", 0.0) + time.perf_counter() - t
            t = time.perf_counter()
            # (the first build leaving triangles out is extra; later ones count as rebuilds,
            # and at the last one, closed-up triangles are blamed on their neighbours)
            closed_up = set() if not extra or attempt < MAX_REBUILDS else None
            bad = _invalid_segments(shape, faces, owner, status, neighbours, info["valid"],
                                    ctx["touching"], ctx["narrowed"], ctx["exempt"],
                                    ctx["triangles"].get, closed_up)
            timings["check"] = timings.get("check", 0.0) + time.perf_counter() - t
            if closed_up and bad is not None:
                logger.warning("sewing closed up %d faceted triangle(s); building again without"
                               " them (and segments %s faceted)", len(closed_up), sorted(bad))
                dropped |= closed_up
                extra = True
                skip.update({a: "invalid after sewing (BRepCheck)" for a in bad})
                continue
            # a sewn face invalid next to edge points between its surfaces and its
            # neighbours': built again with those points on the mesh before faceting it
            if strict < STRICT_REBUILDS and _through_the_mesh(ctx, bad or (), "sewn faces of "
                                                              "segments %s are invalid"):
                strict += 1
                continue
            if bad == [] and closed and info["free_edges_after_sewing"] and attempt < MAX_REBUILDS:
                gaps = _open_segments(shape, faces, owner, status, neighbours, ctx["touching"],
                                      ctx["narrowed"])
                if strict < STRICT_REBUILDS and _through_the_mesh(  # the same for free edges
                        ctx, gaps, "the shell keeps free edges along segments %s"):
                    kept = kept or (shape, info, status, dict(skip))
                    strict += 1
                    continue
                if gaps:
                    logger.warning("the shell keeps %d free edge(s) along segments %s; "
                                   "faceting them", info["free_edges_after_sewing"],
                                   sorted(gaps))
                    kept = kept or (shape, info, status, dict(skip))
                    skip.update({a: "free edges after sewing" for a in gaps})
                    continue
            invalid_at_last = bad is None or (bad != [] and attempt == MAX_REBUILDS)
            if kept is not None and (invalid_at_last or (bad == [] and not info["solid"])):
                logger.warning("faceting along the free edges did not make a valid solid; "
                               "keeping the open shell")
                shape, info, status, skip = kept
                break
            if bad == []:
                break
            if bad is None or attempt == MAX_REBUILDS:
                # an invalid face can hang OCC's mesher (and any CAD program reading it)
                raise _InvalidBRep("the sewn B-Rep is invalid (BRepCheck) and faceting the segments"
                                   " of its invalid faces did not mend it")
            logger.warning("sewn faces of segments %s are invalid (BRepCheck); faceting them",
                           sorted(bad))
            skip.update({a: "invalid after sewing (BRepCheck)" for a in bad})
        sew_tol = info["sew_tol"]
        message = "" if info["solid"] or not closed else (
            "closed mesh but the shell is open" if info["free_edges_after_sewing"] else
            "closed mesh and shell, but no valid solid")
        for why, what in (("invalid after sewing (BRepCheck)", "failing BRepCheck"),
                          ("free edges after sewing", "leaving free edges")):
            n = sum(r == why for r in skip.values())
            if n:
                message = (message + "; " if message else "") + (
                    f"{n} face(s) faceted after {what} in the sewn shell")
        n = sum(st["dropped"] for st in status)  # (of the segments faceted in this build)
        if n:
            message = (message + "; " if message else "") + (
                f"{n} faceted triangle(s) left out: sewing closed them up")
        if info.get("slivers_left_out"):
            message = (message + "; " if message else "") + (
                f"{info['slivers_left_out']} sliver face(s) that sewing split off, connected to "
                "nothing, left out")
        faceted_model, solid = False, info["solid"]
    except Exception as exc:  # OCC raises Standard_Failure subclasses of Exception
        if isinstance(exc, _InvalidBRep):
            logger.warning("%s; writing the faceted model", exc)
        else:
            logger.exception("B-Rep build failed; writing the faceted model")
        shape = _faceted_result(V, F, ctx, closed, timings, str(exc))
        status = [dict(index=a, kind=s.kind, status="faceted", reason=f"build failed: {exc}",
                       built_as=None, max_dev=None) for a, s in enumerate(surfaces)]
        sew_tol, faceted_model, message = None, True, f"build failed ({exc}); faceted model"
        solid = False
    return shape, status, sew_tol, faceted_model, message, solid


def _through_the_mesh(ctx, segments, what: str) -> bool:
    """Whether some of ``segments`` (failed faces) have edge points settled between their
    surfaces (``ctx["between"]``) and may go strict (``ctx["strict"]``: their edges through
    the mesh in the next build); those are added to ``ctx["strict"]``."""
    retry = set(segments) & ctx["between"] - ctx["strict"]
    if retry:
        logger.warning(what + "; building their edges again through the mesh", sorted(retry))
    ctx["strict"] |= retry
    return bool(retry)


class _InvalidBRep(RuntimeError):
    """The sewn shape stays invalid after the rebuilds."""


def _build_faces(V, F, labels, surfaces, uv, ctx, timings, progress, skip=None, cache=None):
    """Surfaces, vertices, edges and faces: (faces, per-segment status, sewing tolerance,
    the segment of each face). Segments in ``skip`` (index -> reason) are faceted; ``cache``
    keeps the surfaces between calls (key: segment, and whether an analytic one may become a
    B-spline); ``timings`` adds up over the calls."""
    k, given = len(surfaces), surfaces
    skip = {} if skip is None else skip
    cache = {} if cache is None else cache
    ctx["between"] = set()  # the segments with edge points between their surfaces
    t = time.perf_counter()
    graph = boundary_graph(V, F, labels, k)
    seg_faces = [np.flatnonzero(labels == a) for a in range(k)]
    timings["topology"] = timings.get("topology", 0.0) + time.perf_counter() - t
    t = time.perf_counter()
    geoms, projs, devs, reasons = [], [], [], []
    for a, s in enumerate(surfaces):
        progress("surfaces", a / k)
        key = (a, ctx.get("bspline", True) if s.is_analytic else None)
        first = cache.get((a, True), (None, None))[1]  # (the projector with B-splines allowed)
        if key == (a, False) and first is not None and first.surface is not None:
            cache[key] = cache[(a, True)]  # built on its analytic surface: no B-spline involved
        if key not in cache:
            try:
                cache[key] = surface_choice.surface_for(a, s, V, F, seg_faces[a], uv, ctx["tol"],
                                        bspline=ctx.get("bspline", True),
                                        misfit=ctx["misfit_rms"], notes=ctx["notes"])
            except Exception as exc:  # libigl, numpy and OCC (Standard_Failure) errors
                # one segment's fit failing facets that segment, not the whole model
                logger.warning("segment %d: surface not built (%s)", a, exc)
                cache[key] = None, None, math.nan, f"surface not built: {exc}"
        g, p, d, r = cache[key]
        if a in skip and r is None:
            g, p, r = None, None, skip[a]
        geoms.append(g), projs.append(p), devs.append(d), reasons.append(r)
    timings["surfaces"] = timings.get("surfaces", 0.0) + time.perf_counter() - t
    # an analytic segment built on a B-spline (its surface deviated) is freeform from here on
    built_as = [("bspline" if p.surface is None else s.kind) if p is not None else None
                for s, p in zip(surfaces, projs, strict=True)]
    surfaces = ctx["surfaces"] = [
        Surface("freeform", {"centroid": V[np.unique(F[seg_faces[a]])].mean(axis=0)},
                outward=s.outward) if s.is_analytic and b == "bspline" else s
        for a, (s, b) in enumerate(zip(ctx["fitted"], built_as, strict=True))]
    ctx["devs"] = devs
    ctx["fallbacks"] = {a for a, b in enumerate(built_as) if b == "bspline" and
                        ctx["fitted"][a].is_analytic}
    ctx["sew_tol"] = _sew_tolerance(ctx, [d for d, r in zip(devs, reasons, strict=True)
                                          if r is None])
    t = time.perf_counter()
    pos = points.place_vertices(V, graph, projs, ctx)
    ctx["pos"], ctx["chains"] = pos, graph.chains
    vertices = {v: _vertex(ctx["builder"], X, ctx["vertex_tol"]) for v, X in pos.items()}
    ctx["vtols"] = {}  # new vertices: the tolerances an earlier build raised are not theirs
    snap = V.copy()
    for v, X in pos.items():
        snap[v] = X
    sampled = [points.edge_points(ch, V, pos, projs, vertices, ctx, snap)
               for ch in graph.chains]
    ctx["chain_points"] = [P for P, _ in sampled]
    ctx["chain_at_vertex"] = [at for _, at in sampled]
    plans, wraps, circles = _revolved_plans(graph, surfaces, projs,
                                            lambda a: V[np.unique(F[seg_faces[a]])], pos,
                                            vertices, ctx)
    ctx["revolved"], ctx["wraps"] = plans, wraps
    edges = []
    for i, ch in enumerate(graph.chains):
        progress("edges", i / max(len(graph.chains), 1))
        edges.append(_edge(ch, ctx["chain_points"][i], circles.get(i), pos, projs, vertices,
                           ctx, snap))
    timings["edges"] = timings.get("edges", 0.0) + time.perf_counter() - t
    ctx["sew_tol"] = max(ctx["sew_tol"], FACET_GAP_FACTOR * ctx.get("facet_gap", 0.0))
    t = time.perf_counter()
    faces, status, owner = [], [], []
    ctx["exempt"] = {}  # faceted triangles left out of the STEP round trip, by surface
    ctx["triangles"] = {}  # faceted triangles along patch borders: surface -> mesh face
    gone = np.fromiter(ctx.get("dropped", ()), dtype=np.int64)  # those it closed up before
    areas = segment_areas(V, F, labels, k)
    for a in range(k):
        progress("faces", a / k)
        face, reason = (None, reasons[a]) if geoms[a] is None else _face(
            a, geoms[a], graph.loops[a], edges, ctx, areas[a], V[np.unique(F[seg_faces[a]])])
        if face is not None:
            faces.append(face)
            owner.append(a)
        else:
            logger.warning("face %d (%s) not built: %s", a, surfaces[a].kind, reason)
            mine = seg_faces[a][~np.isin(seg_faces[a], gone)]
            tri, rows = faceted.triangle_faces(snap, F[mine], ctx["vertex_tol"],
                                               return_index=True)
            if "inner" not in ctx:  # (the same for every build with these labels: _forget)
                ctx["inner"] = inner_vertices(F, labels)
            inside = ctx["inner"][F[mine[rows]]].all(axis=1)  # sewing does not touch these
            ctx["exempt"].update((BRep_Tool.Surface_s(tri[i]), tri[i])
                                 for i in np.flatnonzero(inside))
            ctx["triangles"].update((BRep_Tool.Surface_s(tri[i]), int(mine[rows[i]]))
                                    for i in np.flatnonzero(~inside))
            faces.extend(tri)
            owner.extend([a] * len(tri))
        status.append(dict(index=a, kind=ctx["fitted"][a].kind,
                           status="built" if face is not None else "faceted", reason=reason,
                           dropped=0 if face is not None else len(seg_faces[a]) - len(mine),
                           built_as=built_as[a] if face is not None else None,
                           max_dev=None if not np.isfinite(devs[a]) else float(devs[a]),
                           why_bspline=ctx["notes"].get(a) if built_as[a] == "bspline" and
                           face is not None and ctx["fitted"][a].is_analytic else None))
    timings["faces"] = timings.get("faces", 0.0) + time.perf_counter() - t
    if _through_the_mesh(ctx, [a for a, st in enumerate(status) if st["status"] == "faceted"
                               and str(st["reason"]).startswith(INVALID_TRIM)],
                         "trimmed faces of segments %s are invalid"):
        return _build_faces(V, F, labels, given, uv, ctx, timings, progress, skip, cache)
    # a segment faceted at its trim still lent its surface to its neighbours' edges and
    # corners, which its triangles do not follow (a noisy elbow's torus bulged the solid by
    # 2 % of its volume): built again without it, as a segment faceted after sewing
    trimmed = {a: st["reason"] for a, st in enumerate(status)
               if st["status"] == "faceted" and projs[a] is not None and a not in skip}
    if trimmed and not ctx["limit"].out_of_time(
            f"the build without the surfaces of segments {sorted(trimmed)} (faceted at their "
            "trim)"):
        logger.info("segments %s faceted at their trim; building their neighbours again "
                    "without their surfaces", sorted(trimmed))
        skip.update(trimmed)
        return _build_faces(V, F, labels, given, uv, ctx, timings, progress, skip, cache)
    return faces, status, ctx["sew_tol"], owner
