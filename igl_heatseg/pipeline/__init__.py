"""The whole pipeline: segment, cut every chart to a disk, parameterize, pack.

:func:`run_pipeline` (behind ``igl-heatseg run MESH -o DIR``) does

1. :func:`igl_heatseg.segmentation.paper.segment_with_mode` (the paper's §3.1-3.4, or robust mode);
2. one chart per face-connected piece of each segment; user cut paths (paper §3.5: the ends of
   a generatrix, vertex ids of the *input* mesh) are assigned to the chart holding both ends
   and cut with :func:`igl_heatseg.parameterization.cut.cut_along_paths`; with ``cut="auto"``
   every chart that is still not a disk is cut by
   :func:`igl_heatseg.parameterization.cut.cut_to_disk`;
3. :func:`igl_heatseg.parameterization.chart.parameterize_chart` (Hessian eigenmap, certified,
   with fallback);
4. :func:`igl_heatseg.parameterization.atlas.pack_charts` (areas follow the 3D areas);
and returns a :class:`PipelineResult`. Writing it is the caller's step:
:func:`igl_heatseg.io.results.write_run` writes everything ``segment`` writes plus
``charts/chart_000.obj`` ... (3D positions of the cut chart, ``vt`` = the chart's own UV in the
units of the mesh), ``atlas.obj`` (the cleaned input mesh in input face order with per-corner
UVs packed in ``[0, 1]^2``) and a ``charts`` list in ``report.json``; pictures come from
:func:`igl_heatseg.viz.write_run_pictures`.

A chart that is not a disk with ``cut="none"`` (and no user path making it one) is not
parameterized: its report entry says so (``"parameterized": false``) and its corners get UV
``(0, 0)`` in ``atlas.obj``.
"""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass, field
from typing import Literal, Sequence

import numpy as np

from .errors import MeshError
from .mesh.checks import CleanMesh
from .mesh.geometry import face_areas
from .mesh.topology import face_components
from .parameterization.atlas import atlas_corner_uv, pack_charts
from .parameterization.chart import HLLE_SKIP_CURVATURE, parameterize_chart
from .parameterization.cut import CutError, CutResult, chart_topology, cut_along_paths, cut_to_disk
from .parameterization.split import (
    PACK_MIN_AREA_FRACTION,
    SPLIT_SD_MAX,
    cut_for_packing,
    parameterize_pieces,
)
from .segmentation.api import segment_with_mode
from .segmentation.params import resolve_params

__all__ = ["Chart", "PipelineResult", "run_pipeline", "compose_cuts"]

log = logging.getLogger(__name__)


@dataclass
class Chart:
    """One chart of the pipeline.

    Attributes
    ----------
    id : int
    segment : int
        Segment label the chart comes from.
    faces : (m_i,) int64
        Faces of the whole (cleaned) mesh, ascending.
    cut : CutResult or None
        The cut chart (``cut.F`` row ``r`` is face ``faces[r]``); ``None`` if not cut/prepared.
    param : ChartParam or None
        The chart's map (``param.UV`` indexes ``cut.V``); ``None`` if not parameterized.
    uv : (n_i', 2) float64 or None
        Packed atlas UVs of ``cut.V``.
    report : dict
        The chart's entry of ``report.json``.
    """

    id: int
    segment: int
    faces: np.ndarray
    cut: CutResult | None = None
    param: object | None = None
    uv: np.ndarray | None = None
    report: dict = field(default_factory=dict)


@dataclass
class PipelineResult:
    """Result of :func:`run_pipeline`.

    Attributes
    ----------
    mesh : CleanMesh
    segmentation : Segmentation
    charts : list of Chart
    corner_uv : (m, 3, 2) float64
        Atlas UV of every corner of ``mesh.F`` (``(0, 0)`` for charts not parameterized).
    atlas : PackedAtlas or None
    report : dict
        What was (or would be) written to ``report.json``.
    """

    mesh: CleanMesh
    segmentation: object
    charts: list
    corner_uv: np.ndarray
    atlas: object | None
    report: dict


def _uv_area(UV: np.ndarray, F: np.ndarray) -> float:
    a = UV[F[:, 1]] - UV[F[:, 0]]
    b = UV[F[:, 2]] - UV[F[:, 0]]
    return float(np.abs(a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]).sum() / 2)


def _check_cut_paths(mesh: CleanMesh, cut_paths: Sequence[tuple[int, int]]) -> None:
    """Input-vertex ids of cut paths: pairs of integers, in range, used by a face, distinct."""
    n_in = mesh.n_input_vertices
    for pair in cut_paths:
        if len(pair) != 2:
            raise MeshError(f"{mesh.name}: a cut path needs two vertex ids, got {pair!r}")
        for v in pair:
            if not isinstance(v, (int, np.integer)) or isinstance(v, bool):
                raise MeshError(f"{mesh.name}: cut-path vertex {v!r} is not an integer")
            if not 0 <= int(v) < n_in:
                raise MeshError(
                    f"{mesh.name}: cut-path vertex {v} is outside 0..{n_in - 1} (input ids)"
                )
            if mesh.vertex_map[int(v)] < 0:
                raise MeshError(f"{mesh.name}: cut-path vertex {v} is not used by any face")
        v0, v1 = pair
        if mesh.vertex_map[int(v0)] == mesh.vertex_map[int(v1)]:
            raise MeshError(f"{mesh.name}: cut path {v0}:{v1} starts and ends at one vertex")


def _assign_paths(
    mesh: CleanMesh, charts: list[Chart], cut_paths: Sequence[tuple[int, int]]
) -> dict[int, list[tuple[int, int]]]:
    """Map input-vertex pairs to (chart id -> list of clean-vertex pairs)."""
    out: dict[int, list[tuple[int, int]]] = {}
    if not cut_paths:
        return out
    _check_cut_paths(mesh, cut_paths)
    vert_charts: dict[int, set[int]] = {}
    wanted = {int(mesh.vertex_map[int(v)]) for pair in cut_paths for v in pair}
    wanted_arr = np.array(sorted(wanted), dtype=np.int64)
    for ch in charts:
        used = np.unique(mesh.F[ch.faces])
        for v in used[np.isin(used, wanted_arr)].tolist():
            vert_charts.setdefault(v, set()).add(ch.id)
    for v0, v1 in cut_paths:
        c0, c1 = int(mesh.vertex_map[int(v0)]), int(mesh.vertex_map[int(v1)])
        common = sorted(vert_charts.get(c0, set()) & vert_charts.get(c1, set()))
        if not common:
            raise MeshError(
                f"{mesh.name}: cut path {v0}:{v1}: no chart contains both vertices "
                "(pick the two ends of a generatrix inside one segment)"
            )
        # Prefer a chart that is not a disk (the one that needs the cut), then the largest.
        common.sort(key=lambda c: (charts[c].report["topology"]["is_disk"], -len(charts[c].faces)))
        out.setdefault(common[0], []).append((c0, c1))
    return out


def _piece(ch: Chart, rows: np.ndarray, res: CutResult, areas: np.ndarray) -> Chart:
    """A piece of a chart cut for distortion or packing: a chart of its own (id set later)."""
    faces = ch.faces[rows]
    c = Chart(id=-1, segment=ch.segment, faces=faces, cut=res)
    c.report = {**ch.report, "faces": int(len(faces)), "area": float(areas[faces].sum())}
    c.report.update(split_from=ch.id, topology_after=res.topology_after.as_dict())
    return c


def compose_cuts(first: CutResult, second: CutResult) -> CutResult:
    """``second`` cut the output of ``first``: express it in ``first``'s input numbering.

    Parameters
    ----------
    first, second : CutResult
        ``second`` was computed on ``first.V, first.F``.

    Returns
    -------
    CutResult
        Vertex map, cut edges and paths in ``first``'s input numbering; lengths added.
    """
    vm = first.vertex_map
    return CutResult(
        V=second.V,
        F=second.F,
        vertex_map=vm[second.vertex_map],
        cut_edges=np.concatenate([first.cut_edges, np.sort(vm[second.cut_edges], axis=1)]),
        cut_length=first.cut_length + second.cut_length,
        topology_before=first.topology_before,
        topology_after=second.topology_after,
        method=f"{first.method}+{second.method}",
        paths=list(first.paths) + [vm[p] for p in second.paths],
    )


def run_pipeline(
    mesh: CleanMesh,
    theta: float | None = None,
    eps: float | None = None,
    energy: Literal["auto", "hlle", "curved"] = "auto",
    cut: Literal["auto", "none"] = "auto",
    cut_paths: Sequence[tuple[int, int]] = (),
    *,
    fallback: str = "tutte+slim",
    gutter: float | None = None,
    progress=None,
    solver: str = "fast",
    mode: str = "paper",
    hlle_skip_curvature: float | None | Literal["default"] = "default",
    split_sd_max: float = SPLIT_SD_MAX,
) -> PipelineResult:
    """Segment, cut, parameterize and pack a mesh (nothing is written; see the module docstring).

    Parameters
    ----------
    mesh : CleanMesh
        From :func:`igl_heatseg.io.load_mesh` or :func:`igl_heatseg.mesh.validate_mesh`.
    theta, eps : float, optional
        Segmentation parameters; ``None`` takes the mode's defaults (paper: Table 1).
    energy : {"auto", "hlle", "curved"}
        Hessian energy for :func:`igl_heatseg.parameterization.chart.parameterize_chart`: the
        paper's HLLE, libigl's curved Hessian, or ``"auto"`` (default): HLLE, and the curved
        Hessian for charts whose HLLE map is not bijective (measured: the fewest fallbacks on
        every mesh of the shared data set).
    cut : {"auto", "none"}
        Cut non-disk charts automatically, or only along ``cut_paths``.
    cut_paths : sequence of (int, int)
        Generatrix ends as vertex ids of the *input* mesh (before cleaning); each pair is
        assigned to the chart holding both (preferring a non-disk chart).
    fallback : str
        Passed to ``parameterize_chart``.
    gutter : float, optional
        Atlas gutter (default :data:`igl_heatseg.parameterization.atlas.GUTTER_DEFAULT`).
    progress : callable(stage, fraction), optional
    solver : {"fast", "exact"}
        Heat solver for the segmentation (see :func:`igl_heatseg.segmentation.paper.segment_mesh`).
    mode : {"paper", "robust"}
        Segmentation mode (:func:`igl_heatseg.segmentation.segment_with_mode`).
    hlle_skip_curvature : float, None or "default"
        With ``energy="auto"``, charts whose total absolute Gaussian curvature exceeds this
        skip HLLE (recorded in each chart's ``attempts``); ``"default"``:
        :data:`igl_heatseg.parameterization.chart.HLLE_SKIP_CURVATURE`; ``None`` always tries
        HLLE first.
    split_sd_max : float
        A chart whose best bijective map has a mean symmetric Dirichlet energy above this is
        split along a seam of highest stretch and mapped again
        (:func:`igl_heatseg.parameterization.split.parameterize_pieces`); its pieces are
        charts of their own (``split_from``), counted in ``charts_cut_for_distortion``.  Long
        charts (:func:`igl_heatseg.parameterization.split.cut_for_packing`) are cut across,
        keeping their maps, and counted in ``charts_cut_for_packing``.

    Returns
    -------
    PipelineResult

    Raises
    ------
    MeshError
        Bad parameters or cut-path vertex ids (named).

    Examples
    --------
    >>> import igl, igl_heatseg as ih
    >>> V, F = igl.icosahedron()
    >>> res = ih.run(ih.validate_mesh(*igl.loop(V, F, 2)))
    >>> res.report["parameterization"]["charts_bijective"], res.segmentation.num_segments
    (1, 1)
    """
    if isinstance(hlle_skip_curvature, str) and hlle_skip_curvature == "default":
        hlle_skip_curvature = HLLE_SKIP_CURVATURE

    if cut not in ("auto", "none"):
        raise MeshError(f"`cut` must be 'auto' or 'none', got {cut!r}")
    if energy not in ("auto", "hlle", "curved"):
        raise MeshError(f"`energy` must be 'auto', 'hlle' or 'curved', got {energy!r}")
    resolve_params(mode, theta, eps)  # before the (long) segmentation
    t0 = time.perf_counter()
    _check_cut_paths(mesh, cut_paths)  # before the (long) segmentation
    progress = progress or (lambda stage, fraction=1.0: None)
    seg = segment_with_mode(mesh, mode, theta, eps, progress=progress, solver=solver)
    V, F = mesh.V, mesh.F
    m = F.shape[0]
    areas = face_areas(V, F)

    # 1. charts: face-connected pieces of each segment.  Their topology is needed before
    # cutting only to place user cut paths or to skip non-disks (cut="none"); otherwise it is
    # cut_to_disk's topology_before (the same ChartTopology, checked on 179 charts of 8
    # meshes), which saves a second edge topology per chart (0.2 s on iron.ply).
    t = time.perf_counter()
    topology_first = bool(cut_paths) or cut != "auto"
    charts: list[Chart] = []
    for s in range(seg.num_segments):
        faces = np.flatnonzero(seg.labels == s)
        if len(faces) == 0:
            continue
        count, comp = face_components(F[faces])
        for c in range(count):
            fc = faces[comp == c]
            ch = Chart(id=len(charts), segment=s, faces=fc)
            topo = chart_topology(F[fc], name=f"chart {ch.id}") if topology_first else None
            ch.report = {
                "id": ch.id,
                "segment": s,
                "faces": int(len(fc)),
                "area": float(areas[fc].sum()),
                "topology": topo.as_dict() if topo is not None else None,
            }
            charts.append(ch)
    if any(seg_count > 1 for seg_count in np.bincount([c.segment for c in charts])):
        log.info("some segments are not face-connected; each piece is its own chart")
    assigned = _assign_paths(mesh, charts, cut_paths)
    t_charts = time.perf_counter() - t

    # 2. cut and parameterize (a chart cut for distortion becomes several)
    t_cut = t_param = 0.0
    n_split, n_pack, split_into = 0, 0, {}
    for ch in charts:
        name = f"chart {ch.id}"
        progress("cut+param", ch.id / max(len(charts), 1))
        t = time.perf_counter()
        Fc = F[ch.faces]
        res: CutResult | None = None
        error = "not a disk (use --cut auto or --cut-path)"
        try:
            if ch.id in assigned:
                res = cut_along_paths(V, Fc, assigned[ch.id], name=name)
            if cut == "auto":
                if res is None:
                    res = cut_to_disk(V, Fc, name=name)
                elif not res.topology_after.is_disk:
                    res = compose_cuts(res, cut_to_disk(res.V, res.F, name=name))
            elif res is None:
                # no cutting: only check (unpinching would change nothing for a disk)
                res = cut_to_disk(V, Fc, name=name) if ch.report["topology"]["is_disk"] else None
        except (MeshError, CutError) as exc:
            # e.g. a user path that splits the chart in two: report it, keep the other charts
            error = f"cutting failed: {exc}"
        if ch.report["topology"] is None:  # not computed in step 1
            if res is not None:
                ch.report["topology"] = res.topology_before.as_dict()
            else:  # raises MeshError for a chart that is not a valid surface, as step 1 did
                ch.report["topology"] = chart_topology(Fc, name=name).as_dict()
        secs_cut = time.perf_counter() - t
        t_cut += secs_cut
        ch.cut = res
        ch.report["cut_method"] = res.method if res is not None else "none"
        ch.report["cut_length"] = float(res.cut_length) if res is not None else 0.0
        ch.report["cut_edges"] = int(len(res.cut_edges)) if res is not None else 0
        ch.report["cut_seconds"] = secs_cut
        ch.report["cut_paths"] = [
            [int(mesh.input_vertex[v]) for v in (p[0], p[-1])] for p in (res.paths if res else [])
        ]
        if res is None or not res.topology_after.is_disk:
            after = res.topology_after.as_dict() if res is not None else ch.report["topology"]
            ch.report.update(
                parameterized=False,
                error=error,
                topology_after=after,
                method=None,
                bijective=False,
                seconds=secs_cut,
            )
            log.warning("%s: not a disk after cutting (%s); not parameterized", name, after)
            continue
        t = time.perf_counter()
        try:
            pieces = parameterize_pieces(
                res,
                lambda Vp, Fp, nm, start: parameterize_chart(
                    Vp,
                    Fp,
                    energy,
                    fallback=fallback,
                    hlle_skip_curvature=hlle_skip_curvature,
                    start_uv=start,
                    name=nm,
                ),
                name=name,
                sd_max=split_sd_max,
            )
        except (MeshError, RuntimeError, np.linalg.LinAlgError) as exc:
            # One chart failing must not lose the others: report it and go on.
            t_param += time.perf_counter() - t
            log.warning("%s: parameterization failed: %s", name, exc)
            ch.report.update(
                parameterized=False,
                error=f"parameterization failed: {exc}",
                topology_after=res.topology_after.as_dict(),
                method=None,
                bijective=False,
                seconds=secs_cut + time.perf_counter() - t,
            )
            continue
        n_dist = len(pieces)
        pieces = [  # long charts cut across for packing, their maps kept
            (rows[sub_rows], sub, q)
            for rows, r, p in pieces
            for sub_rows, sub, q in (
                cut_for_packing(r, p, name)
                if areas[ch.faces[rows]].sum() >= PACK_MIN_AREA_FRACTION * areas.sum()
                else [(np.arange(len(r.F)), r, p)]
            )
        ]
        t_param += time.perf_counter() - t
        if len(pieces) > 1:  # cut for distortion or packing: several charts (renumbered below)
            n_split += n_dist > 1
            n_pack += len(pieces) > n_dist
            split_into[ch.id] = [_piece(ch, rows, r, areas) for rows, r, _ in pieces]
        for c, (_, _, p) in zip(split_into.get(ch.id, [ch]), pieces, strict=True):
            c.param = p
            c.report.update(
                parameterized=True,
                method=p.method,
                bijective=bool(p.bijective),
                flips=int(p.flips),
                overlaps=int(p.overlaps),
                fallback_used=bool(p.fallback_used),
                distortion={k: float(v) for k, v in p.distortion.items()},
                seconds=secs_cut + p.seconds,
                attempts=p.attempts,
            )
    progress("cut+param", 1.0)
    charts = [c for ch in charts for c in split_into.get(ch.id, [ch])]
    for i, c in enumerate(charts):
        c.id = c.report["id"] = i

    # 3. pack
    t = time.perf_counter()
    done = []
    for ch in charts:
        if ch.param is None:
            continue
        UV = ch.param.UV
        if np.isfinite(UV).all() and _uv_area(UV, ch.cut.F) > 0:
            done.append(ch)
        else:  # a degenerate map (possible only when no fallback is used) cannot be packed
            ch.report["atlas_error"] = "degenerate or non-finite UVs; left out of the atlas"
            log.warning("chart %d: degenerate UVs, left out of the atlas", ch.id)
    corner_uv = np.zeros((m, 3, 2))
    atlas = None
    if done:
        kw = {} if gutter is None else {"gutter": gutter}
        atlas = pack_charts(
            [ch.param.UV for ch in done],
            [ch.cut.F for ch in done],
            areas=[ch.report["area"] for ch in done],
            **kw,
        )
        for ch, uv, box in zip(done, atlas.uvs, atlas.boxes, strict=True):
            ch.uv = uv
            ch.report["atlas_box"] = [float(b) for b in box]
        corner_uv = atlas_corner_uv(
            m,
            [ch.faces for ch in charts],
            [ch.cut.F if ch.uv is not None else np.zeros((len(ch.faces), 3), int) for ch in charts],
            [ch.uv if ch.uv is not None else np.zeros((1, 2)) for ch in charts],
        )
    t_pack = time.perf_counter() - t

    n_charts = len(charts)
    n_param = sum(ch.param is not None for ch in charts)
    summary = {
        "charts_total": n_charts,
        "charts_parameterized": n_param,
        "charts_in_atlas": len(done),
        "charts_bijective": int(sum(bool(ch.report.get("bijective")) for ch in charts)),
        "charts_fallback": int(sum(bool(ch.report.get("fallback_used")) for ch in charts)),
        "charts_cut": int(sum(ch.report["cut_length"] > 0 for ch in charts)),
        "charts_cut_for_distortion": n_split,
        "charts_cut_for_packing": n_pack,
        "energy": energy,
        "cut": cut,
        "cut_paths_input": [list(map(int, p)) for p in cut_paths],
        "atlas_fill": float(atlas.fill) if atlas is not None else 0.0,
    }
    report = {"charts": [ch.report for ch in charts], "parameterization": summary}
    report["timings"] = dict(
        charts=t_charts, cut=t_cut, param=t_param, pack=t_pack, total=time.perf_counter() - t0
    )
    return PipelineResult(
        mesh=mesh,
        segmentation=seg,
        charts=charts,
        corner_uv=corner_uv,
        atlas=atlas,
        report=report,
    )
