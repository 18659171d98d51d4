"""The whole pipeline: segment, cut every chart to a disk, parameterize, pack.

:func:`run_pipeline` (behind ``igl-heatseg run MESH -o DIR``) is a short sequence of stages
(:mod:`.stages`), each working on the typed :class:`Chart` objects (:mod:`.results`):

1. :func:`igl_heatseg.segmentation.paper.segment_with_mode` (the paper's §3.1-3.4, or robust mode);
2. :func:`extract_charts`: one chart per face-connected piece of each segment;
3. :func:`cut_charts`: user cut paths (paper §3.5: the ends of a generatrix, vertex ids of the
   *input* mesh) are assigned to the chart holding both ends and cut with
   :func:`igl_heatseg.parameterization.cut.cut_along_paths`; with ``cut="auto"`` every chart
   that is still not a disk is cut by :func:`igl_heatseg.parameterization.cut.cut_to_disk`
   (:func:`cut_chart`, one chart);
4. :func:`parameterize_charts`: :func:`igl_heatseg.parameterization.chart.parameterize_chart`
   (Hessian eigenmap, certified, with fallback); charts too distorted or too long are split
   into charts of their own (:func:`map_chart`, one chart);
5. :func:`pack`: :func:`igl_heatseg.parameterization.atlas.pack_charts` (areas follow the 3D
   areas);

and returns a :class:`PipelineResult`, whose ``report`` (the pipeline's part of
``report.json``) is generated from the typed results (:meth:`PipelineResult.to_report`, each
chart's entry by :meth:`Chart.to_report`). Writing it is the caller's step:
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

import numbers
import time
from typing import Literal, Sequence

from ..errors import MeshError
from ..mesh.checks import CleanMesh
from ..mesh.geometry import face_areas
from ..parameterization.atlas import GUTTER_MAX
from ..parameterization.chart import HLLE_SKIP_CURVATURE
from ..parameterization.split import SPLIT_SD_MAX
from ..segmentation.api import segment_with_mode
from ..segmentation.params import resolve_params
from .results import Chart, PipelineResult
from .stages import (
    check_cut_paths,
    compose_cuts,
    cut_chart,
    cut_charts,
    extract_charts,
    map_chart,
    pack,
    parameterize_charts,
)

__all__ = [
    "Chart",
    "PipelineResult",
    "run_pipeline",
    "extract_charts",
    "cut_chart",
    "cut_charts",
    "map_chart",
    "parameterize_charts",
    "pack",
    "compose_cuts",
    "check_cut_paths",
]


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
        Gap between charts in the atlas, relative to its side (as for
        :func:`~igl_heatseg.parameterization.atlas.pack_charts`), from 0 to
        :data:`~igl_heatseg.parameterization.atlas.GUTTER_MAX` (default
        :data:`~igl_heatseg.parameterization.atlas.GUTTER_DEFAULT`, about 4 texels at 1024 px).
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
        or C-shaped charts (:func:`igl_heatseg.parameterization.split.cut_for_packing`: big
        ones always, any chart longer than ``PACK_MAX_LENGTH`` x the square root of the mesh's
        area, and C-shaped ones of any size, when the atlas then packs tighter) are cut
        across, keeping their maps, and counted in ``charts_cut_for_packing``.

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
    >>> res = ih.run(ih.validate_mesh(*igl.loop(V, F, 2)))  # a sphere: one segment, cut open
    >>> res.report["parameterization"]["charts_bijective"], res.segmentation.num_segments
    (6, 1)

    (Halved for distortion, then each half cut in three for packing: fill .56 -> .65.)
    >>> res.report["parameterization"]["charts_cut_for_distortion"]  # its mean energy was > 4.3
    1
    """
    if isinstance(hlle_skip_curvature, str) and hlle_skip_curvature == "default":
        hlle_skip_curvature = HLLE_SKIP_CURVATURE
    if cut not in ("auto", "none"):
        raise MeshError(f"`cut` must be 'auto' or 'none', got {cut!r}")
    if energy not in ("auto", "hlle", "curved"):
        raise MeshError(f"`energy` must be 'auto', 'hlle' or 'curved', got {energy!r}")
    if gutter is not None and (
        isinstance(gutter, bool) or not isinstance(gutter, numbers.Real)
        or not 0 <= gutter <= GUTTER_MAX
    ):
        raise MeshError(f"`gutter` must be a number in [0, {GUTTER_MAX}], got {gutter!r}")
    resolve_params(mode, theta, eps)  # before the (long) segmentation
    t0 = time.perf_counter()
    check_cut_paths(mesh, cut_paths)  # before the (long) segmentation
    seg = segment_with_mode(
        mesh,
        mode,
        theta,
        eps,
        progress=progress or (lambda stage, fraction=1.0: None),
        solver=solver,
    )
    areas = face_areas(mesh.V, mesh.F)
    timings: dict[str, float] = {}

    t = time.perf_counter()
    with_topology = bool(cut_paths) or cut != "auto"
    charts = extract_charts(mesh, seg.labels, with_topology=with_topology, areas=areas)
    timings["charts"] = time.perf_counter() - t

    cut_charts(mesh, charts, cut_paths, cut, progress=progress)
    timings["cut"] = sum(ch.cut_seconds for ch in charts)

    t = time.perf_counter()
    charts, n_split, n_pack = parameterize_charts(
        mesh,
        charts,
        energy=energy,
        fallback=fallback,
        hlle_skip_curvature=hlle_skip_curvature,
        split_sd_max=split_sd_max,
        areas=areas,
        progress=progress,
        gutter=gutter,
    )
    timings["param"] = time.perf_counter() - t

    t = time.perf_counter()
    corner_uv, atlas = pack(mesh, charts, gutter)
    timings["pack"] = time.perf_counter() - t
    timings["total"] = time.perf_counter() - t0
    return PipelineResult(
        mesh=mesh,
        segmentation=seg,
        charts=charts,
        corner_uv=corner_uv,
        atlas=atlas,
        energy=energy,
        cut=cut,
        cut_paths=list(cut_paths),
        charts_cut_for_distortion=n_split,
        charts_cut_for_packing=n_pack,
        timings=timings,
    )
