"""``igl-heatseg view | render | plot-areas MESH``: load, segment (or run the pipeline), show.

The viewer (:mod:`igl_heatseg.viz`) only draws; loading and running the algorithms happens here.
"""

from __future__ import annotations

import logging
import os
import sys
import time
from pathlib import Path

from ..io import load_mesh
from ..pipeline import run_pipeline
from ..segmentation import segment_with_mode
from ..segmentation.params import MODE_DEFAULTS
from ..viz.camera import DEFAULT_SIZE
from ..viz.layout import scene_points
from ..viz.render import render_scene, set_camera
from ..viz.scene import CHART_STAGES, STAGES, Stage, build_scene, init_polyscope
from .common import add_segment_arguments

__all__ = ["register", "render_file", "view_file", "load_and_run"]

log = logging.getLogger(__name__)


def load_and_run(mesh_path, mode: str, theta, eps, need_charts: bool):
    """Load a mesh file and segment it (``need_charts``: run the whole pipeline, no files).

    Returns ``(mesh, segmentation, charts or None)``.
    """
    mesh = load_mesh(mesh_path)
    if need_charts:
        res = run_pipeline(mesh, theta, eps, mode=mode)
        return mesh, res.segmentation, res.charts
    return mesh, segment_with_mode(mesh, mode, theta, eps, keep_solvers=True), None


def render_file(
    mesh_path: str | os.PathLike,
    png: str | os.PathLike,
    stage: Stage = "final",
    size: tuple[int, int] = DEFAULT_SIZE,
    theta: float | None = None,
    eps: float | None = None,
    segment: int | None = None,
    backend: str | None = None,
    mode: str = "paper",
) -> dict:
    """Segment a mesh file and render one stage to a PNG, headless.

    Parameters
    ----------
    mesh_path : str or path-like
        ``.obj``/``.off``/``.ply``/``.stl``.
    png : str or path-like
    stage : str
        One of :data:`STAGES`.
    size : (width, height)
    theta, eps : float, optional
        Segmentation parameters (``None``: the mode's defaults).
    segment : int, optional
        For ``"temperature"`` (default: the segment seen best).
    backend : str, optional
    mode : {"paper", "robust"}

    Returns
    -------
    dict
        As :func:`render_scene`, plus ``"seconds_pipeline"`` (load, segment, parameterize).

    Raises
    ------
    MeshError
        The file is not a valid mesh.
    """
    if stage not in STAGES:
        raise ValueError(f"stage must be one of {STAGES}, got {stage!r}")
    t = time.perf_counter()
    mesh, seg, charts = load_and_run(mesh_path, mode, theta, eps, stage in CHART_STAGES)
    t_pipe = time.perf_counter() - t
    out = render_scene(
        mesh.V, mesh.F, seg, png, stage, charts=charts, size=size, segment=segment, backend=backend
    )
    out["seconds_pipeline"] = t_pipe
    return out


def view_file(
    mesh_path: str | os.PathLike,
    stage: Stage = "final",
    theta: float | None = None,
    eps: float | None = None,
    segment: int | None = None,
    backend: str | None = None,
    charts: bool | None = None,
    mode: str = "paper",
) -> None:
    """Open polyscope's viewer on a mesh file, one stage enabled, the others a click away.

    Under a headless backend (``openGL_mock``, EGL) the scene is built and one frame drawn,
    then the function returns.

    Parameters
    ----------
    mesh_path : str or path-like
    stage : str
        One of :data:`STAGES`.
    theta, eps : float, optional
        Segmentation parameters (``None``: the mode's defaults).
    segment : int, optional
        Temperature field shown (default: the segment seen best).
    backend : str, optional
    charts : bool, optional
        Parameterize to offer the chart stages; default only when ``stage`` needs it.
    mode : {"paper", "robust"}

    Raises
    ------
    MeshError
        The file is not a valid mesh.
    """
    if stage not in STAGES:
        raise ValueError(f"stage must be one of {STAGES}, got {stage!r}")
    want_charts = stage in CHART_STAGES if charts is None else charts
    mesh, seg, ch = load_and_run(mesh_path, mode, theta, eps, want_charts)
    ps = init_polyscope(backend)
    info = build_scene(
        mesh.V,
        mesh.F,
        seg,
        stage,
        charts=ch,
        segment=segment,
        all_quantities=not (stage == "charts"),
    )
    if info["planar"]:
        ps.set_navigation_style("planar")
    set_camera(
        scene_points(mesh.V, ch, info["planar"]),
        ps.get_window_size(),
        planar=info["planar"],
        direction=info["direction"],
    )
    if ps.is_headless():
        ps.show(forFrames=1)
    else:  # pragma: no cover - needs a display
        ps.show()


def register(subparsers) -> None:
    """Add the ``view``, ``render`` and ``plot-areas`` subcommands.

    Parameters
    ----------
    subparsers : argparse._SubParsersAction
        From ``parser.add_subparsers()``; each subcommand sets ``func`` (``args -> int``).
    """

    def common(p, with_stage=True):
        p.add_argument("mesh", help="mesh file (.obj, .off, .ply, .stl)")
        if with_stage:
            p.add_argument(
                "--stage",
                choices=STAGES,
                default="final",
                help="what to show (default: final segmentation); 'types' colours every "
                "segment by its fitted surface type (plane, cylinder, ...) and needs --mode robust",
            )
            p.add_argument(
                "--segment",
                type=int,
                default=None,
                help="segment whose temperature field --stage temperature shows "
                "(0 = largest; default: the one seen best)",
            )
        add_segment_arguments(p)

    p = subparsers.add_parser(
        "view",
        help="open the polyscope viewer on one stage",
        description="Segment MESH and show a stage in polyscope.",
    )
    common(p)
    p.set_defaults(func=_cli_view, _parser=p)

    p = subparsers.add_parser(
        "render",
        help="render a stage to a PNG without a display",
        description="Segment MESH and render one stage headless (polyscope EGL backend).",
    )
    common(p)
    p.add_argument("-o", "--output", required=True, help="PNG file to write")
    p.add_argument(
        "--size",
        type=int,
        nargs=2,
        metavar=("W", "H"),
        default=list(DEFAULT_SIZE),
        help=f"picture size in pixels (default {DEFAULT_SIZE[0]} {DEFAULT_SIZE[1]})",
    )
    p.set_defaults(func=_cli_render, _parser=p)

    p = subparsers.add_parser(
        "plot-areas",
        help="plot the initial segment areas with the eps line (paper Fig. 12)",
        description="Segment MESH and plot the sorted areas of the initial segments with the "
        "line eps * A_largest: groups below it are dropped. Use it to choose eps.",
    )
    common(p, with_stage=False)
    p.add_argument("-o", "--output", required=True, help="PNG file to write")
    p.add_argument("--linear", action="store_true", help="linear area axis (default log)")
    p.set_defaults(func=_cli_plot_areas, _parser=p)


def _check_params(args) -> None:
    """Reject a bad ``--size`` the argparse way (theta/eps are checked by the segmentation)."""
    if min(getattr(args, "size", (16, 16))) < 16:
        args._parser.error(f"--size must be at least 16 16 pixels, got {args.size}")


def _cli_view(args) -> int:
    _check_params(args)
    view_file(args.mesh, args.stage, args.theta, args.eps, segment=args.segment, mode=args.mode)
    return 0


def _cli_render(args) -> int:
    _check_params(args)
    try:
        out = render_file(
            args.mesh,
            args.output,
            args.stage,
            tuple(args.size),
            args.theta,
            args.eps,
            segment=args.segment,
            mode=args.mode,
        )
    except RuntimeError as exc:  # no EGL: one line, not a traceback
        sys.stderr.write(f"igl-heatseg: error: {exc}\n")
        return 1
    log.info("wrote %s", out["png"])
    return 0


def _cli_plot_areas(args) -> int:
    from ..viz.plots import plot_area_distribution

    _check_params(args)
    mesh, seg, _ = load_and_run(args.mesh, args.mode, args.theta, args.eps, False)
    plot_area_distribution(
        seg.initial_areas,
        seg.eps,
        args.output,
        components=seg.group_component,
        reference=MODE_DEFAULTS[seg.mode][2],
        log_scale=not args.linear,
        title=f"{Path(args.mesh).name}: initial segment areas",
    )
    return 0
