"""Single-mesh jobs: what ``igl-heatseg segment`` and ``igl-heatseg run`` do to one file.

The command line (:mod:`igl_heatseg.cli.segment`, :mod:`igl_heatseg.cli.run`) and the batch
worker call the same functions here, so a batch writes into ``OUT/<mesh>/`` exactly what the
single-mesh command writes. Nothing here imports Dask.

:data:`JOB_KINDS` is the table of job kinds ``igl-heatseg batch --command`` accepts
(``segment``, ``run``, ``cad``: segment, fit surfaces, write a STEP file). A new kind is one
:class:`JobKind` entry: a
``run(mesh_path, out_dir, **options) -> report`` function writing through
:func:`~igl_heatseg.io.atomic_dir`, and a ``summarize(report) -> dict`` picking the summary
columns from its report.
"""

from __future__ import annotations

import logging
import os
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

import numpy as np

from ..errors import MeshError
from ..io import atomic_dir, load_mesh, write_labels, write_run, write_segmentation
from ..pipeline import run_pipeline
from ..segmentation import segment_with_mode

__all__ = [
    "segment_file",
    "run_file",
    "cad_file",
    "write_cad",
    "JobOutput",
    "write_pictures",
    "input_report",
    "write_input_labels",
    "named",
    "JobKind",
    "JOB_KINDS",
    "job_kind",
]

log = logging.getLogger(__name__)


def _sized(progress, n_faces: int):
    """Tell a :class:`~igl_heatseg.cli.Progress`-like display the mesh size (if it asks)."""
    sized = getattr(progress, "sized", None)
    return sized(n_faces) if sized is not None else progress


@dataclass
class JobOutput:
    """What a single-mesh job produced (its files are written already).

    Attributes
    ----------
    report : dict
        What ``report.json`` holds.
    mesh : CleanMesh
        The mesh as loaded (``split_faces`` and ``repairs`` tell what loading changed).
    result : Segmentation or PipelineResult
    """

    report: dict
    mesh: object
    result: object


def named(mesh, fn, *a, **kw):
    """Call ``fn``; a ``ValueError`` from inside the pipeline becomes a
    :class:`~igl_heatseg.MeshError` whose one-line message starts with the mesh's name."""
    try:
        return fn(*a, **kw)
    except ValueError as exc:
        msg = " ".join(str(exc).split())
        if not msg.startswith(f"{mesh.name}:"):
            msg = f"{mesh.name}: {msg}"
        raise MeshError(msg) from exc


def input_report(mesh, labels=None) -> dict:
    """Report entries about the input: faces as read, polygons split, repairs.

    ``labels`` (per face of ``mesh.F``) adds ``mixed_label_faces``: input polygons whose
    triangles got more than one label (labels.txt gives them the label covering most area).
    """
    rep: dict = {
        "input_faces": mesh.n_input_faces,
        "split_faces": mesh.split_faces,
        "labels_txt": "one label per input face, in the input's order",
    }
    if mesh.repairs:
        rep["repairs"] = dict(mesh.repairs)
    if labels is not None and mesh.face_map is not None:
        lab = np.asarray(labels)
        pairs = np.unique(np.stack([mesh.face_map, lab], axis=1), axis=0)
        rep["mixed_label_faces"] = int(len(pairs) - len(np.unique(pairs[:, 0])))
    return rep


def write_input_labels(out_dir, mesh, labels) -> None:
    """Rewrite ``labels.txt`` with one label per input face (polygons and faces dropped by
    repair included; see :meth:`~igl_heatseg.mesh.CleanMesh.input_face_labels`); a no-op when
    the faces are the input's."""
    if not mesh.same_faces:
        write_labels(Path(out_dir) / "labels.txt", mesh.input_face_labels(labels))


def segment_file(
    mesh_path: str | os.PathLike,
    out: str | os.PathLike,
    *,
    mode: str = "paper",
    theta: float | None = None,
    eps: float | None = None,
    solver: str = "fast",
    repair: bool = False,
    progress=None,
    refine: bool | None = None,
) -> JobOutput:
    """Load, segment and write one mesh: what ``igl-heatseg segment MESH -o OUT`` does.

    Parameters
    ----------
    mesh_path : str or path-like
        ``.obj``, ``.off``, ``.ply`` or ``.stl``.
    out : str or path-like
        Output folder, written atomically (:func:`~igl_heatseg.io.atomic_dir`): ``labels.txt``,
        ``vertex_labels.txt``, ``segmented.ply``, ``report.json`` (written last).
    mode, theta, eps, solver, refine
        As for :func:`~igl_heatseg.segmentation.segment_with_mode`.
    repair : bool
        ``load_mesh(mesh_path, repair=True)``.
    progress : callable(stage, fraction), optional

    Returns
    -------
    JobOutput

    Raises
    ------
    MeshError
        The file cannot be read or is not a valid mesh; nothing is written.
    """
    t0 = time.perf_counter()
    if progress is not None:
        progress("loading", 0.0)
    mesh = load_mesh(mesh_path, repair=repair)
    t_load = time.perf_counter() - t0
    if progress is not None:
        progress = _sized(progress, mesh.F.shape[0])
        progress("loading", 1.0)
    seg = named(mesh, segment_with_mode, mesh, mode, theta, eps, progress=progress, solver=solver,
                refine=refine)
    extra = {"input": str(Path(mesh_path).resolve()), "timings": {"load": t_load}}
    extra.update(input_report(mesh, seg.labels))
    with atomic_dir(out) as tmp:
        report = write_segmentation(tmp, mesh, seg, extra, t_start=t0)
        write_input_labels(tmp, mesh, seg.labels)
    if progress is not None:
        progress("done", 1.0)
    return JobOutput(report, mesh, seg)


def write_pictures(out: Path, res) -> dict:
    """Render ``segmentation.png`` and ``checker.png`` into ``out`` (needs the ``viz`` extra;
    skipped with a warning without it). Returns ``{"files": {...}, "seconds": float}``."""
    t = time.perf_counter()
    try:
        from ..viz import write_run_pictures

        out.mkdir(parents=True, exist_ok=True)
        written = write_run_pictures(out, res.mesh, res.segmentation, res.charts)
    except ImportError as exc:  # viz needs the `viz` extra
        log.warning("no pictures: %s", exc)
        written = {}
    return {"files": written, "seconds": time.perf_counter() - t}


def run_file(
    mesh_path: str | os.PathLike,
    out: str | os.PathLike,
    *,
    mode: str = "paper",
    theta: float | None = None,
    eps: float | None = None,
    solver: str = "fast",
    energy: str = "auto",
    cut: str = "auto",
    cut_paths=(),
    pictures: bool = True,
    repair: bool = False,
    step: bool = False,
    tol: float | None = None,
    progress=None,
    gutter: float | None = None,
    time_limit: float | None = None,
) -> JobOutput:
    """Load, run the pipeline and write one mesh: what ``igl-heatseg run MESH -o OUT`` does.

    Parameters
    ----------
    mesh_path, out, repair
        As for :func:`segment_file`; ``out`` also gets ``charts/chart_NNN.obj``, ``atlas.obj``
        and, with ``pictures``, ``segmentation.png`` and ``checker.png``.
    mode, theta, eps, solver, energy, cut, cut_paths, gutter
        As for :func:`~igl_heatseg.pipeline.run_pipeline`.
    pictures : bool
        Render the pictures (skipped with a warning without the ``viz`` extra).
    step, tol, time_limit
        Also build the B-Rep and write ``model.step`` (:func:`write_cad`, freeform faces over
        the certified chart maps; ``report["cad"]``), at modelling tolerance ``tol``, starting
        no further rebuild ``time_limit`` seconds after the start (as for :func:`cad_file`).
    progress : callable(stage, fraction), optional

    Returns
    -------
    JobOutput
        ``report["parameterization"]`` sums up the charts; ``result`` is the
        :class:`~igl_heatseg.pipeline.PipelineResult`.
    """
    if step:
        _check_cad(tol, time_limit)
    t0 = time.perf_counter()
    mesh = load_mesh(mesh_path, repair=repair)
    t_load = time.perf_counter() - t0
    if progress is not None:
        progress = _sized(progress, mesh.F.shape[0])
    res = named(
        mesh,
        run_pipeline,
        mesh,
        theta=theta,
        eps=eps,
        solver=solver,
        mode=mode,
        energy=energy,
        cut=cut,
        cut_paths=list(cut_paths or []),
        progress=progress,
        gutter=gutter,
    )
    extra = {"input": str(Path(mesh_path).resolve()), "timings": {"load": t_load}}
    extra.update(input_report(mesh, res.segmentation.labels))
    with atomic_dir(out) as tmp:
        pics = write_pictures(tmp, res) if pictures else None
        if step:
            extra["cad"] = write_cad(tmp, mesh, res.segmentation, res.charts, tol=tol,
                                     pictures=pictures, progress=progress,
                                     time_limit=_time_left(time_limit, t0))
            _job_time_limit(extra["cad"], time_limit)
        report = write_run(tmp, res, extra, t_start=t0, pictures=pics)
        write_input_labels(tmp, mesh, res.segmentation.labels)
    return JobOutput(report, mesh, res)


#: Tessellation deflection of ``brep.png``, as a fraction of the bounding-box diagonal.
PICTURE_DEFLECTION_REL = 1e-3


def _check_cad(tol, time_limit=None) -> None:
    """OCP importable (else ImportError with the install hint), ``tol`` and ``time_limit``
    positive."""
    from ..cad import build_brep  # noqa: F401  (the import checks OCP)

    if tol is not None and not (np.isfinite(tol) and tol > 0):
        raise MeshError(f"tol must be a positive number (model units), got {tol!r}")
    if time_limit is not None and not (np.isfinite(time_limit) and time_limit > 0):
        raise MeshError(f"time_limit must be a positive number of seconds, got {time_limit!r}")


def _time_left(time_limit, t0: float) -> float | None:
    """Seconds of ``time_limit`` (counted from ``t0``) left for the B-Rep build, >= 0."""
    return None if time_limit is None else max(time_limit - (time.perf_counter() - t0), 0.0)


def _job_time_limit(cad: dict, time_limit) -> None:
    """The ``cad`` section's ``time_limit``: the job's (``seconds``, counted from its start),
    and the part of it the build had (``build_seconds``)."""
    if time_limit is not None and cad.get("time_limit") is not None:
        left = cad["time_limit"]["seconds"]
        cad["time_limit"].update(seconds=float(time_limit), build_seconds=round(left, 3))


def write_cad(out, mesh, seg, charts=None, *, tol=None, pictures=True, progress=None,
              time_limit=None) -> dict:
    """Build the B-Rep of a segmentation, write ``out/model.step`` (AP214, mm) and, with
    ``pictures``, ``out/brep.png``; returns the ``cad`` section of ``report.json``.

    Segments keep their labels: robust mode's fitted surfaces are used as they are; a
    segmentation without surfaces (paper mode) gets one fitted per segment
    (:func:`~igl_heatseg.cad.fit_segment_surfaces`). With ``charts`` (the pipeline's),
    freeform segments are fitted over their certified chart maps
    (:func:`~igl_heatseg.cad.chart_uvs`). ``time_limit``: seconds after which the build starts
    no further rebuild (:func:`~igl_heatseg.cad.build_brep`).

    Returns
    -------
    dict
        :meth:`~igl_heatseg.cad.CadResult.to_report` plus ``step``, ``unit``, ``segments``,
        ``surfaces_from``, ``charts_used``, ``picture`` and timings of the fits, the STEP
        file and the picture.
    """
    from ..cad import build_brep, chart_uvs, fit_segment_surfaces, tessellate_by_type, write_step

    out = Path(out)
    t = time.perf_counter()
    surfaces = getattr(seg, "surfaces", None)
    fitted_here = surfaces is None
    if fitted_here:
        surfaces = fit_segment_surfaces(mesh.V, mesh.F, seg.labels)
    t_fit = time.perf_counter() - t
    uv = chart_uvs(seg.labels, surfaces, charts) if charts is not None else None
    res = build_brep(mesh.V, mesh.F, seg.labels, surfaces, uv=uv, tol=tol, progress=progress,
                     time_limit=time_limit)
    t = time.perf_counter()
    write_step(res.shape, out / "model.step", unit="mm")
    cad = res.to_report()
    cad["timings"].update(fit=t_fit, step=time.perf_counter() - t)
    cad.update(step="model.step", unit="mm", segments=len(surfaces),
               surfaces_from="fitted to the segments" if fitted_here else "segmentation",
               charts_used=sum(x is not None for x in (uv or [])), picture=None)
    if fitted_here:
        cad["surfaces"] = [dict(segment=i, **s.to_dict()) for i, s in enumerate(surfaces)]
    if pictures:
        t = time.perf_counter()
        try:
            from ..viz import render_brep

            TV, TF, tri_face, types = tessellate_by_type(
                res.shape, PICTURE_DEFLECTION_REL * res.tolerances["diag"])
            render_brep(out / "brep.png", mesh.V, mesh.F, seg.labels, TV, TF, tri_face, types)
            cad["picture"] = "brep.png"
        except (ImportError, RuntimeError) as exc:  # no polyscope or no EGL: no picture
            log.warning("no brep.png: %s", exc)
        cad["timings"]["picture"] = time.perf_counter() - t
    return cad


def cad_file(
    mesh_path: str | os.PathLike,
    out: str | os.PathLike,
    *,
    mode: str = "robust",
    theta: float | None = None,
    eps: float | None = None,
    solver: str = "fast",
    tol: float | None = None,
    repair: bool = False,
    pictures: bool = True,
    progress=None,
    time_limit: float | None = None,
) -> JobOutput:
    """Load, segment, build the B-Rep and write one mesh: what ``igl-heatseg cad MESH -o OUT``
    does.

    Parameters
    ----------
    mesh_path, out, mode, theta, eps, solver, repair
        As for :func:`segment_file` (``mode`` defaults to ``"robust"``, which fits the
        surfaces); ``out`` also gets ``model.step`` and, with ``pictures``, ``brep.png``.
    tol : float, optional
        Modelling tolerance (model units) of :func:`~igl_heatseg.cad.build_brep`.
    pictures : bool
    progress : callable(stage, fraction), optional
    time_limit : float, optional
        Seconds from the start after which the B-Rep build starts no further rebuild or
        second pass (:func:`~igl_heatseg.cad.build_brep`; what loading and segmenting took
        is counted). The build running then is finished, and the fidelity, STEP file and
        pictures follow, so the job takes longer than this.

    Returns
    -------
    JobOutput
        ``report["cad"]`` is :func:`write_cad`'s section.

    Raises
    ------
    ImportError
        OCP missing (the message says ``pip install 'igl_heatseg[cad]'``); nothing is done.
    MeshError
        Bad mesh or ``tol``; nothing is written.
    """
    _check_cad(tol, time_limit)
    t0 = time.perf_counter()
    mesh = load_mesh(mesh_path, repair=repair)
    t_load = time.perf_counter() - t0
    if progress is not None:
        progress = _sized(progress, mesh.F.shape[0])
    seg = named(mesh, segment_with_mode, mesh, mode, theta, eps, progress=progress, solver=solver)
    extra = {"input": str(Path(mesh_path).resolve()), "timings": {"load": t_load}}
    extra.update(input_report(mesh, seg.labels))
    with atomic_dir(out) as tmp:
        t = time.perf_counter()
        extra["cad"] = write_cad(tmp, mesh, seg, tol=tol, pictures=pictures, progress=progress,
                                 time_limit=_time_left(time_limit, t0))
        _job_time_limit(extra["cad"], time_limit)
        extra["timings"]["cad"] = time.perf_counter() - t
        report = write_segmentation(tmp, mesh, seg, extra, t_start=t0)
        write_input_labels(tmp, mesh, seg.labels)
    if progress is not None:
        progress("done", 1.0)
    return JobOutput(report, mesh, seg)


def _small_mesh():
    import igl

    from ..mesh import validate_mesh

    V, F = igl.icosahedron()
    V = V * [2.0, 1.0, 1.0]  # an ellipsoid: more than one segment, nothing degenerate
    return validate_mesh(*igl.loop(V, F, 2))


def _warm_segment() -> None:
    segment_with_mode(_small_mesh(), "paper")


def _warm_run() -> None:
    run_pipeline(_small_mesh())


def _summarize_segment(report: dict) -> dict:
    return {"faces": report.get("faces"), "segments": report.get("segments")}


def _summarize_cad(report: dict) -> dict:
    """Summary columns of a ``cad`` job: ``brep`` (``solid``, ``shell``, ``N solids``, ``N shells``
    or ``N shells (M solids)``, ``faceted`` before it when the whole model is, `` (invalid)``
    after it when it fails BRepCheck), ``faceted`` (segments not built), ``hausdorff_pct`` and
    ``volume_error_pct`` (per cent of the diagonal and of the mesh's volume), and as ``reason``
    the build's message (why no solid, what was faceted, what the time limit skipped).

    Examples
    --------
    >>> rep = {"faces": 12, "segments": 6, "cad": {"not_built": [2], "faceted_model": False,
    ...        "message": "1 face(s) faceted", "fidelity": {"valid": True, "solids": 1,
    ...        "shells": 1, "hausdorff_rel": 0.00123, "volume_rel_error": 2e-5}}}
    >>> row = _summarize_cad(rep)
    >>> row["brep"], row["faceted"], row["hausdorff_pct"], row["volume_error_pct"], row["reason"]
    ('solid', 1, 0.123, 0.002, '1 face(s) faceted')
    """
    cad = report.get("cad") or {}
    fid = cad.get("fidelity") or {}
    solids, shells = int(fid.get("solids") or 0), int(fid.get("shells") or 0)
    if solids and solids == shells:
        kind = "solid" if solids == 1 else f"{solids} solids"
    else:
        kind = ("shell" if shells <= 1 else f"{shells} shells") + (
            f" ({solids} solids)" if solids else "")
    brep = ("faceted " if cad.get("faceted_model") else "") + kind + (
        "" if fid.get("valid") else " (invalid)")
    h, v = fid.get("hausdorff_rel"), fid.get("volume_rel_error")
    return {
        "faces": report.get("faces"),
        "segments": report.get("segments"),
        "brep": brep if cad else None,
        "faceted": len(cad.get("not_built", [])) if cad else None,
        "hausdorff_pct": None if h is None else round(100 * float(h), 3),
        "volume_error_pct": None if v is None else round(100 * float(v), 3),
        "reason": cad.get("message") or "",
    }


def _summarize_run(report: dict) -> dict:
    s = report.get("parameterization", {})
    return {
        "faces": report.get("faces"),
        "segments": report.get("segments"),
        "charts": s.get("charts_total"),
        "bijective": s.get("charts_bijective"),
        "fallback": s.get("charts_fallback"),
    }


@dataclass(frozen=True)
class JobKind:
    """One kind of per-mesh job a batch can run.

    Attributes
    ----------
    name : str
        ``--command`` value.
    run : callable
        ``run(mesh_path, out_dir, **options) -> JobOutput`` (or the report dict); writes
        ``out_dir`` atomically (``report.json`` last) and raises
        :class:`~igl_heatseg.MeshError` on a bad mesh.
    summarize : callable
        ``summarize(report) -> dict`` with any of the summary columns ``faces``, ``segments``,
        ``charts``, ``bijective``, ``fallback``.
    options : tuple of str
        Keyword options ``run`` accepts (others given to a batch are dropped).
    pictures : tuple of str
        Picture files the gallery shows, when present.
    warm_up : callable, optional
        Run once in the job server before its first child (in memory, nothing written), so
        that lazy imports and first-call costs are paid once per worker, not once per mesh.
    """

    name: str
    run: Callable[..., dict]
    summarize: Callable[[dict], dict]
    options: tuple = ()
    pictures: tuple = field(default=())
    warm_up: Callable[[], None] | None = None


#: ``--command`` -> job kind.
JOB_KINDS: dict[str, JobKind] = {
    "segment": JobKind(
        "segment",
        segment_file,
        _summarize_segment,
        ("mode", "theta", "eps", "solver", "repair", "refine"),
        warm_up=_warm_segment,
    ),
    "run": JobKind(
        "run",
        run_file,
        _summarize_run,
        ("mode", "theta", "eps", "solver", "energy", "cut", "pictures", "repair"),
        ("segmentation.png", "checker.png"),
        warm_up=_warm_run,
    ),
    "cad": JobKind(
        "cad",
        cad_file,
        _summarize_cad,
        ("mode", "theta", "eps", "solver", "tol", "pictures", "repair", "time_limit"),
        ("brep.png",),
        warm_up=_warm_segment,
    ),
}


def job_kind(name: str) -> JobKind:
    """The :class:`JobKind` called ``name``.

    Raises
    ------
    ValueError
        Unknown name (the message lists the known ones).
    """
    try:
        return JOB_KINDS[name]
    except KeyError:
        raise ValueError(
            f"unknown batch command {name!r}; known: {', '.join(sorted(JOB_KINDS))}"
        ) from None
