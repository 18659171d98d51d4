"""Pictures of results: polyscope scenes, headless renders, matplotlib plots.

Contract: draws results (a mesh, a :class:`~igl_heatseg.segmentation.Segmentation`,
:class:`~igl_heatseg.pipeline.Chart` objects); never runs an algorithm. polyscope and
matplotlib are the ``viz`` extra, imported inside the functions that use them, so importing
this package loads neither.

Modules:

``scene``   polyscope initialisation and backends; the scene of every stage (:func:`build_scene`)
``camera``  the three-quarter and top-down cameras (numpy and libigl only)
``layout``  chart geometry: which charts to draw, area-normalised UVs, the 2D layout
``render``  screenshots, :func:`render_scene` (one stage to a PNG), :func:`write_run_pictures`
``plots``   matplotlib figures: area distribution, chart maps, sweeps
``brep``    the B-Rep picture: mesh by segment next to B-Rep faces by type (arrays from ``cad``)
"""

from . import brep, camera, layout, plots, render, scene
from .brep import render_brep
from .camera import (
    CAMERA_MARGIN,
    DEFAULT_SIZE,
    VIEW_DIRECTION,
    best_view_direction,
    three_quarter_camera,
    top_down_camera,
)
from .layout import CHART_GAP, chart_layout, corner_uv, drawable_charts, flipped_faces, scene_points
from .plots import area_threshold, plot_area_distribution, plot_chart_maps, plot_sweep
from .render import render_scene, screenshot, set_camera, write_run_pictures
from .scene import (
    BACKEND_ENV,
    CHART_STAGES,
    EGL_HINT,
    HEADLESS_BACKEND,
    STAGES,
    SURFACE_TYPE_COLORS,
    Stage,
    add_curves,
    add_mesh,
    add_sharp_edges,
    build_scene,
    import_polyscope,
    init_polyscope,
    segment_boundary_edges,
    segment_surface_types,
    show_boundary_curves,
    show_chart_maps,
    show_checker,
    show_labels,
    show_seeds,
    show_surface_types,
    show_temperature,
)

__all__ = [
    "camera",
    "layout",
    "plots",
    "render",
    "scene",
    "brep",
    "render_brep",
    "STAGES",
    "CHART_STAGES",
    "BACKEND_ENV",
    "HEADLESS_BACKEND",
    "EGL_HINT",
    "SURFACE_TYPE_COLORS",
    "Stage",
    "import_polyscope",
    "init_polyscope",
    "build_scene",
    "add_mesh",
    "add_curves",
    "add_sharp_edges",
    "show_seeds",
    "show_temperature",
    "show_labels",
    "show_surface_types",
    "segment_surface_types",
    "segment_boundary_edges",
    "show_boundary_curves",
    "show_checker",
    "show_chart_maps",
    "DEFAULT_SIZE",
    "VIEW_DIRECTION",
    "CAMERA_MARGIN",
    "best_view_direction",
    "three_quarter_camera",
    "top_down_camera",
    "CHART_GAP",
    "drawable_charts",
    "flipped_faces",
    "corner_uv",
    "chart_layout",
    "scene_points",
    "set_camera",
    "screenshot",
    "render_scene",
    "write_run_pictures",
    "area_threshold",
    "plot_area_distribution",
    "plot_chart_maps",
    "plot_sweep",
]
