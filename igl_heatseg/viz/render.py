"""Headless pictures: point polyscope's camera, take screenshots, render stages to PNG files.

Rendering goes through polyscope's EGL backend (:data:`~igl_heatseg.viz.scene.HEADLESS_BACKEND`),
which runs on Mesa's software rasterizer where no GPU is present.

Examples
--------
Headless, from the command line or Python::

    igl-heatseg render data/fandisk.off -o final.png --stage final --size 1200 900
    igl-heatseg render data/fandisk.off -o types.png --stage types --mode robust

>>> import igl_heatseg as ih                                          # doctest: +SKIP
>>> mesh = ih.load_mesh("data/fandisk.off")                           # doctest: +SKIP
>>> ih.viz.render_scene(mesh.V, mesh.F, ih.segment(mesh), "seeds.png", "seeds")  # doctest: +SKIP
"""

from __future__ import annotations

import logging
import os
import time
from collections.abc import Iterable, Sequence
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike

from .camera import DEFAULT_SIZE, three_quarter_camera, top_down_camera
from .layout import scene_points
from .scene import Stage, build_scene, import_polyscope, init_polyscope, show_checker

if TYPE_CHECKING:
    from ..pipeline import Chart

__all__ = ["set_camera", "screenshot", "render_scene", "write_run_pictures"]

log = logging.getLogger(__name__)


def _check_size(size: Sequence[int]) -> None:
    if len(size) != 2 or min(int(size[0]), int(size[1])) < 16:
        raise ValueError(f"size must be (width, height) with both >= 16 pixels, got {size}")


def set_camera(
    P: ArrayLike,
    size: tuple[int, int] = DEFAULT_SIZE,
    planar: bool = False,
    direction: Sequence[float] | None = None,
) -> None:
    """Point polyscope's camera at ``P`` (three-quarter view, or top-down when ``planar``).

    Parameters
    ----------
    P : (n, 3) array_like of float
        Points that must be in view.
    size : (width, height)
    planar : bool
        The scene lies in the plane z = 0 (chart layout): look straight down the z axis
        (:func:`~igl_heatseg.viz.camera.top_down_camera`), else
        :func:`~igl_heatseg.viz.camera.three_quarter_camera`.
    direction : (3,) float, optional
        World direction from the part to the camera
        (see :func:`~igl_heatseg.viz.camera.best_view_direction`).
    """
    ps = import_polyscope()
    aspect = size[0] / size[1]
    fov = ps.get_vertical_fov_degrees()
    if planar:
        eye, target, up = top_down_camera(P, aspect, fov)
    else:
        eye, target, up = three_quarter_camera(P, aspect, fov, direction=direction)
    ps.look_at_dir(eye, target, up)


def screenshot(png: str | os.PathLike, size: tuple[int, int] = DEFAULT_SIZE) -> float:
    """Write the current scene to ``png``; returns the seconds taken.

    Parameters
    ----------
    png : str or path-like
        Output file (``.png``).
    size : (width, height)
        Pixels.
    """
    ps = import_polyscope()
    t = time.perf_counter()
    ps.set_window_size(int(size[0]), int(size[1]))
    ps.screenshot(str(png), transparent_bg=False)
    return time.perf_counter() - t


def render_scene(
    V: ArrayLike,
    F: ArrayLike,
    seg,
    png: str | os.PathLike,
    stage: Stage = "final",
    charts: Iterable[Chart] | None = None,
    size: tuple[int, int] = DEFAULT_SIZE,
    segment: int | None = None,
    backend: str | None = None,
) -> dict:
    """Render one stage of an in-memory result to a PNG without a display.

    Parameters
    ----------
    V : (n, 3) float64
    F : (m, 3) int64
    seg : Segmentation
    png : str or path-like
    stage : str
        One of :data:`~igl_heatseg.viz.scene.STAGES`.
    charts : iterable of igl_heatseg.pipeline.Chart, optional
        For ``"charts"`` and ``"checker"``.
    size : (width, height)
        Pixels; each at least 16.
    segment : int, optional
        For ``"temperature"`` (default: the segment seen best).
    backend : str, optional
        Default: :data:`~igl_heatseg.viz.scene.BACKEND_ENV` or
        :data:`~igl_heatseg.viz.scene.HEADLESS_BACKEND`.

    Returns
    -------
    dict
        ``{"png": path, "seconds_scene": float, "seconds_screenshot": float}``.

    Raises
    ------
    ValueError
        Bad stage or size, or a stage the result cannot show (see
        :func:`~igl_heatseg.viz.scene.build_scene`).
    RuntimeError
        No headless OpenGL available.
    """
    _check_size(size)
    ps = init_polyscope(backend, headless=True)
    t = time.perf_counter()
    try:
        info = build_scene(V, F, seg, stage, charts=charts, segment=segment)
        set_camera(
            scene_points(V, charts, info["planar"]),
            size,
            planar=info["planar"],
            direction=info["direction"],
        )
        t_scene = time.perf_counter() - t
        t_shot = screenshot(png, size)
    finally:
        ps.remove_all_structures()
    log.info("rendered %s (%s) in %.2f s + %.2f s", png, stage, t_scene, t_shot)
    return {"png": Path(png), "seconds_scene": t_scene, "seconds_screenshot": t_shot}


def write_run_pictures(
    out_dir: str | os.PathLike,
    mesh,
    seg,
    charts: Iterable[Chart] | None = None,
    size: tuple[int, int] = DEFAULT_SIZE,
    backend: str | None = None,
) -> dict[str, Path]:
    """Write ``out_dir/segmentation.png`` (and ``out_dir/checker.png`` when charts are given).

    Called by ``igl-heatseg run`` (:mod:`igl_heatseg.cli.run`).  Failures to render (no EGL,
    no polyscope) are logged as warnings and the pictures skipped: pictures never make a run
    fail.

    Parameters
    ----------
    out_dir : str or path-like
        Existing directory.
    mesh : CleanMesh
        The mesh (``V``, ``F``).
    seg : Segmentation
    charts : iterable of igl_heatseg.pipeline.Chart, optional
        For the checkerboard picture.
    size : (width, height)
    backend : str, optional

    Returns
    -------
    dict of str to Path
        ``{"segmentation": path, "checker": path}`` for the files written.
    """
    out = Path(out_dir)
    written: dict[str, Path] = {}
    png = out / "segmentation.png"
    _check_size(size)
    try:
        ps = init_polyscope(backend, headless=True)
    except (ImportError, RuntimeError) as exc:
        log.warning("could not render %s: %s", png, exc)
        return written
    # One scene for both pictures (the same mesh, camera and window; measured on iron.ply:
    # the second render_scene spent 0.3 s registering the mesh again and choosing the same
    # view).  The checker picture is what render_scene(stage="checker") draws: the
    # segmentation colours and boundary curves are removed first.
    V = np.asarray(mesh.V, dtype=np.float64)
    F = np.asarray(mesh.F, dtype=np.int64)
    try:
        info = build_scene(V, F, seg, "final")
        set_camera(V, size, planar=False, direction=info["direction"])
        try:
            t = screenshot(png, size)
            written["segmentation"] = png
            log.info("rendered %s in %.2f s", png, t)
        except (ImportError, RuntimeError) as exc:
            log.warning("could not render %s: %s", png, exc)
        if charts is not None:
            png = out / "checker.png"
            info["mesh"].remove_quantity("final segmentation")
            ps.remove_curve_network("segment boundaries", error_if_absent=False)
            show_checker(V, F, charts)
            t = screenshot(png, size)
            written["checker"] = png
            log.info("rendered %s in %.2f s", png, t)
    except (ImportError, RuntimeError) as exc:
        log.warning("could not render %s: %s", png, exc)
    finally:
        ps.remove_all_structures()
    return written
