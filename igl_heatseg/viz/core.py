"""polyscope scenes and headless pictures of every pipeline stage (paper Figs. 6, 11, 13–15).

The scenes are built from results (:func:`build_scene`) and shown interactively
(``igl-heatseg view MESH --stage ...``) or rendered without a display (:func:`render_scene`,
``igl-heatseg render MESH -o PNG``) through polyscope's EGL backend, which runs on Mesa's
software rasterizer where no GPU is present. This module draws; it runs no algorithm (loading
a file and segmenting it is the command line's job, :mod:`igl_heatseg.cli.viz`).

Stages (:data:`STAGES`):

``seeds``
    Seed vertices coloured by seed group, non-seed vertices dark, sharp edges as curves
    (Fig. 6a).
``temperature``
    One temperature field ``u_i`` as a scalar map with isoline stripes (Fig. 6b).
``initial``
    The initial over-segmentation, one categorical colour per initial group (Fig. 11).
``final``
    The final segmentation (Fig. 13), segment boundaries as thin dark curves.
``checker``
    Every chart's UV map as a checkerboard on the 3D mesh, cut paths as curves (Fig. 15).
``charts``
    Every chart's 2D map on its own, laid out side by side in the plane (Fig. 14).

polyscope is a soft dependency: it is imported inside the functions that need it, with an
install hint (``pip install igl_heatseg[viz]``).  polyscope can be initialised only once per
process; :func:`init_polyscope` does it once and later calls just clear the scene.  The
backend comes from the argument, else the environment variable :data:`BACKEND_ENV`
(``IGL_HEATSEG_PS_BACKEND``, e.g. ``openGL_mock`` for tests and notebooks), else polyscope's
default (interactive) or :data:`HEADLESS_BACKEND` (rendering).

Charts (the ``checker``/``charts`` stages) are taken from the parameterization stage
(:func:`igl_heatseg.pipeline.run_pipeline`); any object with the attributes listed in
:func:`as_chart_maps` works.

Examples
--------
Headless, from the command line or Python::

    igl-heatseg render data/fandisk.off -o final.png --stage final --size 1200 900
    igl-heatseg plot-areas data/fandisk.off -o areas.png

    >>> import igl_heatseg as ih                                         # doctest: +SKIP
    >>> mesh = ih.load_mesh("data/fandisk.off")                          # doctest: +SKIP
    >>> ih.viz.render_scene(mesh.V, mesh.F, ih.segment(mesh), "seeds.png", "seeds")  # doctest: +SKIP
"""

from __future__ import annotations

import logging
import math
import os
import time
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal

import numpy as np
from numpy.typing import ArrayLike


__all__ = [
    "STAGES",
    "BACKEND_ENV",
    "HEADLESS_BACKEND",
    "ChartMap",
    "as_chart_maps",
    "init_polyscope",
    "build_scene",
    "add_mesh",
    "add_curves",
    "add_sharp_edges",
    "show_seeds",
    "show_temperature",
    "show_labels",
    "segment_boundary_edges",
    "show_checker",
    "show_chart_maps",
    "best_view_direction",
    "three_quarter_camera",
    "set_camera",
    "screenshot",
    "render_scene",
    "write_run_pictures",
    "scene_points",
    "CHART_STAGES",
    "DEFAULT_SIZE",
]

log = logging.getLogger(__name__)

Stage = Literal["seeds", "initial", "final", "temperature", "charts", "checker"]

#: Stages understood by :func:`build_scene` and :func:`render_scene`.
STAGES: tuple[str, ...] = ("seeds", "initial", "final", "temperature", "charts", "checker")

#: Stages that need the parameterization (charts).
CHART_STAGES: tuple[str, ...] = ("charts", "checker")

#: Environment variable naming the polyscope backend (``openGL_mock``, ``openGL3_egl``, ...).
BACKEND_ENV: str = "IGL_HEATSEG_PS_BACKEND"

#: Backend used for headless rendering when neither the argument nor the environment names one.
HEADLESS_BACKEND: str = "openGL3_egl"

#: polyscope backends (``"auto"`` lets polyscope choose).
BACKENDS: tuple[str, ...] = ("auto", "openGL3_glfw", "openGL3_egl", "openGL_mock")

#: What to install when EGL is missing (Debian/Ubuntu).
EGL_HINT: str = "apt-get install -y libegl1 libegl-mesa0 libgl1-mesa-dri libopengl0"

#: Default picture size in pixels (width, height).
DEFAULT_SIZE: tuple[int, int] = (1200, 900)

#: Install hint shown when polyscope is missing.
INSTALL_HINT: str = "pip install igl_heatseg[viz]"

#: Colours (RGB in [0, 1]).
BACKGROUND = (1.0, 1.0, 1.0)
MESH_COLOR = (0.82, 0.82, 0.80)
NONSEED_COLOR = (0.12, 0.12, 0.12)
SHARP_COLOR = (0.08, 0.08, 0.08)
CUT_COLOR = (0.85, 0.05, 0.05)
CHECKER_COLORS = ((0.97, 0.97, 0.97), (0.25, 0.25, 0.30))

#: Curve radii, relative to polyscope's scene length scale (the bounding-box diagonal).
SHARP_RADIUS: float = 0.0012
CUT_RADIUS: float = 0.003

#: Up to this many sharp edges are drawn at full radius; more get thinner curves.
SHARP_EDGES_FULL: int = 2000

#: Checker square size: the UV of every chart is rescaled to its 3D area, and the squares are
#: this fraction of polyscope's length scale (the scene's bounding-box diagonal).
CHECKER_FRACTION: float = 1.0 / 40.0

#: Isoline spacing of temperature fields (temperatures lie in [0, 1]).
ISOLINE_PERIOD: float = 0.05

#: Camera: the view direction in the mesh's principal frame (largest, middle, smallest axis)
#: for a three-quarter view; the margin around the part, as a fraction of the frame.
VIEW_DIRECTION: tuple[float, float, float] = (0.45, 0.50, 0.74)
CAMERA_MARGIN: float = 1.10

#: Gap between charts laid out side by side (fraction of the largest chart's size).
CHART_GAP: float = 0.15

#: Largest number of vertices used to fit the camera (a random-free, strided subsample).
_CAMERA_SAMPLES = 20000


# --------------------------------------------------------------------------------------------
# polyscope access


def _polyscope():
    """Import polyscope or raise ImportError with the install hint."""
    try:
        import polyscope as ps
    except ImportError as exc:
        raise ImportError(
            f"igl_heatseg.viz.core needs polyscope, which is not installed: {INSTALL_HINT}"
        ) from exc
    return ps


def init_polyscope(backend: str | None = None, *, headless: bool = False) -> Any:
    """Initialise polyscope once per process and clear the scene.

    Parameters
    ----------
    backend : str, optional
        polyscope backend name (``"openGL3_egl"``, ``"openGL_mock"``, ``"openGL3_glfw"``).
        Default: the environment variable :data:`BACKEND_ENV` if set, else
        :data:`HEADLESS_BACKEND` when ``headless``, else polyscope's own choice.
    headless : bool
        The caller only takes screenshots (no window).

    Returns
    -------
    module
        The ``polyscope`` module, initialised, with an empty scene, white background and no
        ground plane.

    Raises
    ------
    ImportError
        polyscope is not installed.
    ValueError
        Unknown backend name (argument or :data:`BACKEND_ENV`); see :data:`BACKENDS`.
    RuntimeError
        polyscope could not initialise the backend (e.g. no EGL library).

    Notes
    -----
    polyscope cannot be re-initialised with another backend in the same process; if it is
    already running, ``backend`` is ignored (logged at debug level).
    """
    ps = _polyscope()
    if backend is None:
        backend = os.environ.get(BACKEND_ENV) or (HEADLESS_BACKEND if headless else None)
    if backend and backend not in BACKENDS:
        raise ValueError(
            f"unknown polyscope backend {backend!r} (argument or ${BACKEND_ENV}); "
            f"use one of {BACKENDS}"
        )
    if not ps.is_initialized():
        ps.set_use_prefs_file(False)
        ps.set_program_name("igl-heatseg")
        ps.set_verbosity(0)
        ps.set_errors_throw_exceptions(True)
        ps.set_allow_headless_backends(True)
        t = time.perf_counter()
        try:
            ps.init(backend or "auto")
        except Exception as exc:  # polyscope raises RuntimeError (or a C++ exception type)
            raise RuntimeError(
                f"polyscope could not start the {backend or 'default'} backend: {exc}. "
                f"Headless rendering needs EGL with Mesa ({EGL_HINT})"
            ) from exc
        log.info(
            "polyscope initialised (%s) in %.2f s",
            ps.get_render_engine_backend_name(),
            time.perf_counter() - t,
        )
    elif backend and backend != ps.get_render_engine_backend_name():
        log.debug(
            "polyscope already runs %s; cannot switch to %s in this process",
            ps.get_render_engine_backend_name(),
            backend,
        )
    ps.remove_all_structures()
    ps.set_ground_plane_mode("none")
    ps.set_background_color(BACKGROUND)
    return ps


# --------------------------------------------------------------------------------------------
# charts


@dataclass
class ChartMap:
    """One chart's 2D map, in the form the scenes use.

    Attributes
    ----------
    faces : (mc,) int64
        Faces of the whole mesh that belong to the chart.
    F : (mc, 3) int64
        The chart's triangles indexing ``UV`` (same order as ``faces``).
    UV : (nc, 2) float64
        The chart's map to the plane.
    vertex_map : (nc,) int64
        Chart vertex -> vertex of the whole mesh (cut vertices appear several times).
    cut_edges : (k, 2) int64
        Edges the chart was cut along, as vertex pairs of the whole mesh (may be empty).
    label : int
        Segment id of the chart (for its colour).
    bijective : bool or None
        Certified bijective, if known.
    flipped_faces : (f,) int64
        Indices into ``F`` of flipped triangles (drawn red in 2D), may be empty.
    method : str
        How the map was made (``"hessian"``, ``"tutte"``, ...), for captions.
    """

    faces: np.ndarray
    F: np.ndarray
    UV: np.ndarray
    vertex_map: np.ndarray
    cut_edges: np.ndarray = field(default_factory=lambda: np.zeros((0, 2), dtype=np.int64))
    label: int = 0
    bijective: bool | None = None
    flipped_faces: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    method: str = ""


def _first_attr(obj: Any, names: Sequence[str], default: Any = None) -> Any:
    for nm in names:
        if isinstance(obj, dict) and nm in obj:
            return obj[nm]
        if hasattr(obj, nm):
            return getattr(obj, nm)
    return default


def as_chart_maps(charts: Iterable[Any] | None) -> list[ChartMap]:
    """Adapt the parameterization stage's per-chart results to :class:`ChartMap`.

    Accepts :class:`ChartMap` objects, :class:`igl_heatseg.pipeline.Chart` objects (``faces``,
    ``segment``, the cut chart in ``cut`` and its map in ``param``; charts without a map are
    skipped), or any object (or dict) with the faces of the chart
    (``faces`` / ``face_ids`` / ``face_index``), its triangles (``F``), its map (``UV``),
    the chart-vertex to mesh-vertex map (``vertex_map``), and optionally ``cut_edges``,
    ``label``, ``bijective`` (or ``certificate.bijective``), ``flipped_faces`` (or
    ``certificate.flipped_faces``) and ``method``.

    Parameters
    ----------
    charts : iterable or None

    Returns
    -------
    list of ChartMap
    """
    out: list[ChartMap] = []
    if charts is None:
        return out
    for i, c in enumerate(charts):
        if isinstance(c, ChartMap):
            out.append(c)
            continue
        param = _first_attr(c, ("param",))
        cut_res = _first_attr(c, ("cut",))
        if param is not None or cut_res is not None:
            # igl_heatseg.pipeline.Chart: the cut chart in ``cut``, its map in ``param``.
            if param is None or cut_res is None:
                continue  # not parameterized: nothing to draw
            cert = _first_attr(param, ("certificate",))
            flipped = None if cert is None else _first_attr(cert, ("flipped_faces",))
            out.append(
                ChartMap(
                    faces=np.asarray(c.faces, dtype=np.int64),
                    F=np.asarray(cut_res.F, dtype=np.int64),
                    UV=np.asarray(param.UV, dtype=np.float64)[:, :2],
                    vertex_map=np.asarray(cut_res.vertex_map, dtype=np.int64),
                    cut_edges=np.asarray(cut_res.cut_edges, dtype=np.int64).reshape(-1, 2),
                    label=int(_first_attr(c, ("segment",), i)),
                    bijective=_first_attr(param, ("bijective",)),
                    flipped_faces=np.zeros(0, np.int64)
                    if flipped is None
                    else np.asarray(flipped, dtype=np.int64),
                    method=str(_first_attr(param, ("method",), "")),
                )
            )
            continue
        cert = _first_attr(c, ("certificate", "cert"))
        faces = _first_attr(c, ("faces", "face_ids", "face_index"))
        F = _first_attr(c, ("F",))
        UV = _first_attr(c, ("UV", "uv"))
        vmap = _first_attr(c, ("vertex_map", "vertices"))
        cut = _first_attr(c, ("cut_edges",))
        if faces is None or F is None or UV is None or vmap is None:
            raise TypeError(f"chart {i}: need faces, F, UV and vertex_map, got {type(c)!r}")
        bij = _first_attr(c, ("bijective",))
        if bij is None and cert is not None:
            bij = _first_attr(cert, ("bijective",))
        flipped = _first_attr(c, ("flipped_faces",))
        if flipped is None and cert is not None:
            flipped = _first_attr(cert, ("flipped_faces",))
        out.append(
            ChartMap(
                faces=np.asarray(faces, dtype=np.int64),
                F=np.asarray(F, dtype=np.int64),
                UV=np.asarray(UV, dtype=np.float64)[:, :2],
                vertex_map=np.asarray(vmap, dtype=np.int64),
                cut_edges=np.zeros((0, 2), np.int64)
                if cut is None
                else np.asarray(cut, dtype=np.int64).reshape(-1, 2),
                label=int(_first_attr(c, ("label", "segment", "id"), i)),
                bijective=None if bij is None else bool(bij),
                flipped_faces=np.zeros(0, np.int64)
                if flipped is None
                else np.asarray(flipped, dtype=np.int64),
                method=str(_first_attr(c, ("method",), "")),
            )
        )
    return out


def _area(P: np.ndarray, F: np.ndarray) -> np.ndarray:
    if P.shape[1] == 2:
        a, b = P[F[:, 1]] - P[F[:, 0]], P[F[:, 2]] - P[F[:, 0]]
        return 0.5 * np.abs(a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0])
    return 0.5 * np.linalg.norm(np.cross(P[F[:, 1]] - P[F[:, 0]], P[F[:, 2]] - P[F[:, 0]]), axis=1)


def _normalised_uv(V: np.ndarray, c: ChartMap) -> np.ndarray:
    """The chart's UV centred at its centroid and scaled to the chart's 3D area, (nc, 2)."""
    a3 = _area(V[c.vertex_map], c.F).sum()
    a2 = _area(c.UV, c.F).sum()
    s = math.sqrt(a3 / a2) if a2 > 0 and a3 > 0 else 1.0
    used = np.unique(c.F)
    uv = (c.UV - c.UV[used].mean(axis=0)) * s
    return np.nan_to_num(uv, nan=0.0)  # rows of vertices F does not use


def corner_uv(V: np.ndarray, F: np.ndarray, charts: Sequence[ChartMap]) -> np.ndarray:
    """Per-corner UV of the whole mesh, every chart rescaled to its 3D area.

    Parameters
    ----------
    V : (n, 3) float64
    F : (m, 3) int64
    charts : sequence of ChartMap

    Returns
    -------
    UVc : (3m, 2) float64
        Corner ``j`` of face ``f`` at row ``3 f + j`` (polyscope's corner order); corners of
        faces no chart covers are NaN-free zeros.
    """
    UVc = np.zeros((F.shape[0], 3, 2))
    for c in charts:
        uv = _normalised_uv(V, c)
        UVc[c.faces] = uv[c.F]
    return UVc.reshape(-1, 2)


# --------------------------------------------------------------------------------------------
# scene pieces


def add_mesh(
    V: ArrayLike,
    F: ArrayLike,
    name: str = "mesh",
    color: tuple[float, float, float] = MESH_COLOR,
    smooth: bool = False,
):
    """Register a surface mesh with a neutral colour.

    Parameters
    ----------
    V : (n, 3) or (n, 2) array_like of float
    F : (m, 3) array_like of int
    name : str
    color : (3,) RGB in [0, 1]
    smooth : bool
        Smooth (vertex-normal) shading; default flat, which shows the facets of CAD parts.

    Returns
    -------
    polyscope.SurfaceMesh
    """
    ps = _polyscope()
    m = ps.register_surface_mesh(name, np.asarray(V), np.asarray(F), color=color)
    m.set_smooth_shade(smooth)
    return m


def add_curves(
    P: ArrayLike,
    E: ArrayLike,
    name: str,
    color: tuple[float, float, float] = SHARP_COLOR,
    radius: float = SHARP_RADIUS,
):
    """Register edges ``E`` between points ``P`` as a curve network.

    Parameters
    ----------
    P : (n, 3) array_like of float
    E : (k, 2) array_like of int
        Vertex pairs; only the vertices used are sent to polyscope.
    name : str
    color : (3,) RGB
    radius : float
        Relative to the scene's length scale.

    Returns
    -------
    polyscope.CurveNetwork or None
        ``None`` if ``E`` is empty.
    """
    ps = _polyscope()
    E = np.asarray(E, dtype=np.int64).reshape(-1, 2)
    if len(E) == 0:
        return None
    used, inv = np.unique(E, return_inverse=True)
    return ps.register_curve_network(
        name, np.asarray(P)[used], inv.reshape(-1, 2), color=color, radius=radius
    )


def add_sharp_edges(V: ArrayLike, sharp_edges: ArrayLike, name: str = "sharp edges", **kw):
    """Draw the sharp edges (``Segmentation.sharp_edges``, (s, 2)) as dark curves.

    On noisy meshes with many sharp edges the curves get thinner (radius scaled by
    ``sqrt(SHARP_EDGES_FULL / s)`` above :data:`SHARP_EDGES_FULL` edges) so that the seed
    colours stay visible.
    """
    s = len(np.asarray(sharp_edges).reshape(-1, 2))
    if "radius" not in kw and s > SHARP_EDGES_FULL:
        kw["radius"] = SHARP_RADIUS * math.sqrt(SHARP_EDGES_FULL / s)
    return add_curves(V, sharp_edges, name, **kw)


def segment_boundary_edges(F: ArrayLike, labels: ArrayLike) -> np.ndarray:
    """Interior edges whose two faces carry different labels.

    Parameters
    ----------
    F : (m, 3) array_like of int
    labels : (m,) array_like of int

    Returns
    -------
    E : (k, 2) int64
        Vertex pairs (smaller first).

    Examples
    --------
    >>> segment_boundary_edges([[0, 1, 2], [2, 1, 3]], [0, 1]).tolist()
    [[1, 2]]
    """
    F = np.asarray(F, dtype=np.int64)
    labels = np.asarray(labels, dtype=np.int64)
    if F.shape[0] == 0:
        return np.zeros((0, 2), dtype=np.int64)
    # Half-edges sorted by a 1D key: an interior edge is two consecutive equal keys (an
    # edge-manifold mesh).  Same edges in the same (lexicographic) order as from
    # topology.edge_topology, which costs 0.19 s instead of 0.05 s on iron.ply's 168k faces.
    he = F[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2)
    a, b = he.min(axis=1), he.max(axis=1)
    key = a * (int(F.max()) + 1) + b
    order = np.argsort(key, kind="stable")
    ks = key[order]
    pair = np.flatnonzero(ks[1:] == ks[:-1])
    i, j = order[pair], order[pair + 1]
    cross = labels[i // 3] != labels[j // 3]
    return np.stack([a[i[cross]], b[i[cross]]], axis=1)


def _rgb(labels: np.ndarray, k: int | None = None) -> np.ndarray:
    from ..io.results import label_colors

    k = int(labels.max()) + 1 if k is None else k
    return label_colors(k)[labels].astype(np.float64) / 255.0


def show_seeds(V, F, seg, mesh_name: str = "mesh", enabled: bool = True):
    """Seed vertices coloured by seed group, non-seeds dark, sharp edges as curves (Fig. 6a).

    Parameters
    ----------
    V : (n, 3) float64
    F : (m, 3) int64
    seg : Segmentation
        Uses ``seed_group`` (n,) (``-1`` = not a seed) and ``sharp_edges`` (s, 2).
    mesh_name : str
        Surface mesh to add the colour to (registered if missing).
    enabled : bool

    Returns
    -------
    polyscope.SurfaceMesh
    """
    ps = _polyscope()
    m = (
        ps.get_surface_mesh(mesh_name)
        if ps.has_surface_mesh(mesh_name)
        else add_mesh(V, F, mesh_name)
    )
    g = np.asarray(seg.seed_group)
    C = np.tile(np.asarray(NONSEED_COLOR), (len(g), 1))
    s = g >= 0
    if s.any():
        C[s] = _rgb(g[s], int(g.max()) + 1)
    m.add_color_quantity("seed groups", C, defined_on="vertices", enabled=enabled)
    if enabled:
        add_sharp_edges(V, seg.sharp_edges)
    return m


def show_temperature(
    V,
    F,
    seg,
    segment: int = 0,
    initial: bool = False,
    mesh_name: str = "mesh",
    enabled: bool = True,
):
    """Temperature field of one segment as a scalar map with isolines (Fig. 6b).

    Parameters
    ----------
    V : (n, 3) float64
    F : (m, 3) int64
    seg : Segmentation
        With solvers kept (``segment_mesh(..., keep_solvers=True)``, the default).
    segment : int
        Final segment id ``0..k-1`` (0 = largest), or initial group id if ``initial``.
    initial : bool
        Show a field of the initial round.
    mesh_name : str
    enabled : bool

    Returns
    -------
    u : (n,) float64
        The field shown, in [0, 1] (1 on the segment's seeds, 0 on other seeds).

    Raises
    ------
    ValueError
        ``segment`` is out of range.
    """
    ps = _polyscope()
    k = seg.initial_groups if initial else seg.num_segments
    if not 0 <= segment < k:
        raise ValueError(f"segment must be in 0..{k - 1}, got {segment}")
    u = np.asarray(seg.temperature(segment, initial=initial), dtype=np.float64)
    # Stripes change at multiples of the period; 0 and 1 (whole seed regions) would flicker
    # between two stripes.  Shift by half a period (colour range shifted alike).
    half = 0.5 * ISOLINE_PERIOD
    m = (
        ps.get_surface_mesh(mesh_name)
        if ps.has_surface_mesh(mesh_name)
        else add_mesh(V, F, mesh_name)
    )
    m.add_scalar_quantity(
        f"temperature u_{segment}",
        u + half,
        defined_on="vertices",
        enabled=enabled,
        cmap="viridis",
        vminmax=(half, 1.0 + half),
        isolines_enabled=True,
        isoline_style="stripe",
        isoline_period=ISOLINE_PERIOD,
        isoline_period_relative=False,
        isoline_darkness=0.75,
    )
    return u


def show_labels(V, F, labels: ArrayLike, name: str, mesh_name: str = "mesh", enabled: bool = True):
    """Face labels in categorical colours (Figs. 11, 13).

    Parameters
    ----------
    V : (n, 3) float64
    F : (m, 3) int64
    labels : (m,) int
        ``0..k-1``; colours from :func:`igl_heatseg.io.meshes.label_colors`.
    name : str
        Quantity name (``"initial segmentation"``, ``"final segmentation"``).
    mesh_name : str
    enabled : bool

    Returns
    -------
    polyscope.SurfaceMesh
    """
    ps = _polyscope()
    m = (
        ps.get_surface_mesh(mesh_name)
        if ps.has_surface_mesh(mesh_name)
        else add_mesh(V, F, mesh_name)
    )
    m.add_color_quantity(
        name, _rgb(np.asarray(labels, dtype=np.int64)), defined_on="faces", enabled=enabled
    )
    return m


def show_checker(V, F, charts, mesh_name: str = "mesh", enabled: bool = True, cuts: bool = True):
    """Every chart's UV as a checkerboard on the 3D mesh, cut paths as red curves (Fig. 15).

    Each chart's UV is rescaled to the chart's 3D area, so squares have about the same size
    everywhere; stretched or sheared squares show distortion.

    Parameters
    ----------
    V : (n, 3) float64
    F : (m, 3) int64
    charts : iterable
        Chart maps (see :func:`as_chart_maps`).
    mesh_name : str
    enabled : bool
    cuts : bool
        Draw the cut edges of all charts.

    Returns
    -------
    polyscope.SurfaceMesh
    """
    ps = _polyscope()
    V = np.asarray(V)
    charts = as_chart_maps(charts)
    m = (
        ps.get_surface_mesh(mesh_name)
        if ps.has_surface_mesh(mesh_name)
        else add_mesh(V, F, mesh_name)
    )
    m.add_parameterization_quantity(
        "chart UV",
        corner_uv(V, np.asarray(F), charts),
        defined_on="corners",
        coords_type="world",
        enabled=enabled,
        viz_style="checker",
        checker_colors=CHECKER_COLORS,
        checker_size=CHECKER_FRACTION,  # "world" coords: relative to polyscope's length scale
    )
    cut = [c.cut_edges for c in charts if len(c.cut_edges)]
    if cuts and cut:
        net = add_curves(V, np.concatenate(cut), "cut paths", color=CUT_COLOR, radius=CUT_RADIUS)
        net.set_enabled(enabled)
    return m


def chart_layout(V: np.ndarray, charts: Sequence[ChartMap]) -> list[np.ndarray]:
    """Place every chart's normalised UV side by side in rows (largest first).

    Parameters
    ----------
    V : (n, 3) float64
    charts : sequence of ChartMap

    Returns
    -------
    list of (nc, 2) float64
        Translated UV per chart (same order as ``charts``), not overlapping each other.
    """
    uvs = [_normalised_uv(V, c) for c in charts]
    if not uvs:
        return []
    ext = []
    for c, uv in zip(charts, uvs, strict=True):
        used = uv[np.unique(c.F)]
        ext.append((used.min(axis=0), used.max(axis=0)))
    sizes = np.array([hi - lo for lo, hi in ext])
    gap = CHART_GAP * float(sizes.max())
    total = float(((sizes[:, 0] + gap) * (sizes[:, 1] + gap)).sum())
    row_w = max(math.sqrt(total) * 1.3, float(sizes[:, 0].max()))
    order = np.argsort(-sizes[:, 1], kind="stable")
    out: list[np.ndarray] = [None] * len(uvs)  # type: ignore[list-item]
    x = y = row_h = 0.0
    for i in order:
        w, h = sizes[i]
        if x > 0 and x + w > row_w:
            x, y, row_h = 0.0, y - row_h - gap, 0.0
        lo, hi = ext[i]
        out[i] = uvs[i] - [lo[0], hi[1]] + [x, y]
        x += w + gap
        row_h = max(row_h, h)
    return out


def show_chart_maps(V, charts, enabled: bool = True, edges: bool = True):
    """Every chart's 2D map on its own, side by side in the plane z = 0 (Fig. 14).

    Charts are coloured like their segment; flipped triangles red.

    Parameters
    ----------
    V : (n, 3) float64
        Vertices of the whole mesh (for the area normalisation).
    charts : iterable
        Chart maps (see :func:`as_chart_maps`).
    enabled : bool
    edges : bool
        Draw triangle edges (thin) so that the map's triangles are visible.

    Returns
    -------
    list of polyscope.SurfaceMesh
    """
    charts = as_chart_maps(charts)
    V = np.asarray(V)
    placed = chart_layout(V, charts)
    k = max([c.label for c in charts], default=0) + 1
    from ..io.results import label_colors

    pal = label_colors(k).astype(np.float64) / 255.0
    out = []
    for i, (c, uv) in enumerate(zip(charts, placed, strict=True)):
        P = np.c_[uv, np.zeros(len(uv))]
        m = add_mesh(P, c.F, f"chart {i:03d}", color=tuple(pal[c.label]))
        m.set_enabled(enabled)
        if edges:
            m.set_edge_width(0.5)
            m.set_edge_color((0.2, 0.2, 0.2))
        if len(c.flipped_faces):
            C = np.tile(pal[c.label], (len(c.F), 1))
            C[c.flipped_faces] = (1.0, 0.0, 0.0)
            m.add_color_quantity("flipped", C, defined_on="faces", enabled=True)
        out.append(m)
    return out


def build_scene(
    V: ArrayLike,
    F: ArrayLike,
    seg,
    stage: Stage = "final",
    charts=None,
    segment: int | None = None,
    all_quantities: bool = False,
) -> dict:
    """Register the structures of one stage on polyscope's (initialised) scene.

    Parameters
    ----------
    V : (n, 3) float64
    F : (m, 3) int64
    seg : Segmentation
    stage : {"seeds", "initial", "final", "temperature", "charts", "checker"}
    charts : iterable, optional
        Chart maps; required for ``"charts"`` and ``"checker"``.
    segment : int, optional
        Segment whose temperature field the ``"temperature"`` stage shows; default the
        segment with the largest visible (projected) area from the camera.
    all_quantities : bool
        Also register (disabled) the quantities of the other stages, so an interactive user
        can switch between them in polyscope's UI.

    Returns
    -------
    dict
        ``{"mesh": SurfaceMesh or None, "stage": stage, "planar": bool, "direction": (3,)
        float64 or None, "segment": int or None}``; ``planar`` is true for the 2D chart
        layout, ``direction`` points from the part to the camera
        (:func:`best_view_direction`), ``segment`` is the temperature field's segment.

    Raises
    ------
    ValueError
        Unknown stage, or a chart stage without charts.
    """
    if stage not in STAGES:
        raise ValueError(f"stage must be one of {STAGES}, got {stage!r}")
    if stage in CHART_STAGES and charts is None:
        raise ValueError(f"stage {stage!r} needs the charts of the parameterization")
    V = np.asarray(V, dtype=np.float64)
    F = np.asarray(F, dtype=np.int64)
    if stage == "charts":
        show_chart_maps(V, charts)
        return {"mesh": None, "stage": stage, "planar": True, "direction": None, "segment": None}
    m = add_mesh(V, F)
    d = best_view_direction(V, F, seg.labels)
    if segment is None:  # the segment seen best from the camera
        N = np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]])
        seen = np.bincount(seg.labels, weights=np.maximum(N @ d, 0.0), minlength=seg.num_segments)
        segment = int(np.argmax(seen))
    on = {s: s == stage for s in STAGES}
    if stage == "seeds" or all_quantities:
        show_seeds(V, F, seg, enabled=on["seeds"])
    if stage == "temperature":
        show_temperature(V, F, seg, segment=segment)
    elif all_quantities:
        try:
            show_temperature(V, F, seg, segment=segment, enabled=False)
        except RuntimeError:  # fields not kept (segment_mesh(..., keep_solvers=False))
            log.debug("no temperature fields to show")
    if stage == "initial" or all_quantities:
        show_labels(V, F, seg.initial_labels, "initial segmentation", enabled=on["initial"])
    if stage == "final" or all_quantities:
        show_labels(V, F, seg.labels, "final segmentation", enabled=on["final"])
        if stage == "final":
            add_curves(V, segment_boundary_edges(F, seg.labels), "segment boundaries")
    if charts is not None and (stage == "checker" or all_quantities):
        show_checker(V, F, charts, enabled=on["checker"])
    return {"mesh": m, "stage": stage, "planar": False, "direction": d, "segment": segment}


# --------------------------------------------------------------------------------------------
# camera and pictures


def _principal_frame(P: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Bounding-box centre (3,) and principal axes (3, 3) (rows: largest spread first)."""
    c = 0.5 * (P.min(axis=0) + P.max(axis=0))
    Q = P - c
    axes = np.eye(3)
    if len(P) >= 3 and np.ptp(Q, axis=0).max() > 0:
        _, _, Vt = np.linalg.svd(Q - Q.mean(axis=0), full_matrices=False)
        if Vt.shape[0] == 3:
            axes = Vt
    # Deterministic signs: the largest component of each axis positive; right-handed frame.
    axes = axes * np.sign(axes[np.arange(3), np.abs(axes).argmax(axis=1)])[:, None]
    if np.linalg.det(axes) < 0:
        axes[2] *= -1
    return c, axes


def best_view_direction(
    V: ArrayLike,
    F: ArrayLike,
    labels: ArrayLike | None = None,
    direction: Sequence[float] = VIEW_DIRECTION,
) -> np.ndarray:
    """Choose among the 8 mirror images of a three-quarter direction the one showing most.

    A candidate ``d`` (``direction`` in the principal frame, with every sign combination)
    scores the effective number of visible labels ``exp(H)``, where ``H`` is the entropy of
    the labels' projected visible areas ``sum area_f * max(0, n_f . d)``; without labels, the
    projected visible area.  Ties keep the first candidate (all signs positive).

    Parameters
    ----------
    V : (n, 3) array_like of float
    F : (m, 3) array_like of int
        Outward-oriented triangles (for a closed part, front faces point to the camera).
    labels : (m,) array_like of int, optional
        Face labels (e.g. the final segmentation).
    direction : (3,) float
        In the principal frame (largest, middle, smallest spread).

    Returns
    -------
    d : (3,) float64
        Unit vector from the part towards the camera, in world coordinates.
    """
    V = np.asarray(V, dtype=np.float64)
    F = np.asarray(F, dtype=np.int64)
    _, axes = _principal_frame(V)
    N = np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]])  # 2 * area * unit normal
    lab = None if labels is None else np.asarray(labels, dtype=np.int64)
    best, best_d = -np.inf, None
    for sx in (1, -1):
        for sy in (1, -1):
            for sz in (1, -1):
                d = (np.asarray(direction, dtype=np.float64) * [sx, sy, sz]) @ axes
                d /= np.linalg.norm(d)
                w = np.maximum(N @ d, 0.0)
                if lab is None:
                    score = float(w.sum())
                else:
                    a = np.bincount(lab, weights=w)
                    p = a[a > 0] / a.sum() if a.sum() > 0 else np.ones(1)
                    score = float(np.exp(-(p * np.log(p)).sum()))
                if score > best * (1 + 1e-9) + 1e-12:
                    best, best_d = score, d
    return best_d


def _centre_offset(x: np.ndarray, depth_of, lo: float, hi: float) -> float:
    """Lateral camera offset ``c`` with ``max((x - c)/depth) = -min((x - c)/depth)`` (bisection)."""
    for _ in range(60):
        c = 0.5 * (lo + hi)
        r = (x - c) / depth_of
        if r.max() + r.min() > 0:
            lo = c
        else:
            hi = c
    return 0.5 * (lo + hi)


def _fit_frustum(x, y, z, tx, ty, margin, iterations: int = 4):
    """Camera distance along +z and lateral offsets so that every point is in view, centred.

    ``x, y, z``: point coordinates in the camera frame (z towards the camera); ``tx, ty``: the
    tangents of the half fields of view.  Returns ``(dist, cx, cy)``.
    """
    cx, cy = 0.5 * (x.max() + x.min()), 0.5 * (y.max() + y.min())
    dist = 0.0
    for _ in range(iterations):
        dist = float(np.max(np.maximum(z + np.abs(x - cx) / tx, z + np.abs(y - cy) / ty)))
        dist *= margin
        depth = dist - z
        cx = _centre_offset(x, depth, float(x.min()), float(x.max()))
        cy = _centre_offset(y, depth, float(y.min()), float(y.max()))
    # final distance for the final offsets
    dist = margin * float(np.max(np.maximum(z + np.abs(x - cx) / tx, z + np.abs(y - cy) / ty)))
    return dist, cx, cy


def three_quarter_camera(
    P: ArrayLike,
    aspect: float = DEFAULT_SIZE[0] / DEFAULT_SIZE[1],
    fov_deg: float = 45.0,
    direction: Sequence[float] | None = None,
    margin: float = CAMERA_MARGIN,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A perspective camera that sees all of ``P`` from a three-quarter angle.

    The view direction defaults to :data:`VIEW_DIRECTION` expressed in the principal frame of
    the points (largest, middle, smallest spread), so a flat part is not seen edge-on; the up
    vector is the middle principal axis made orthogonal to the view (pointing so that the
    camera looks down on the part).  The distance is the smallest at which every point lies
    inside the frustum (times ``margin``), and the target is shifted so that the part's image
    is centred.

    Parameters
    ----------
    P : (n, 3) array_like of float
    aspect : float
        Image width / height.
    fov_deg : float
        Vertical field of view (polyscope's default is 45 degrees).
    direction : (3,) float, optional
        Unit vector from the part towards the camera, in *world* coordinates (e.g. from
        :func:`best_view_direction`).
    margin : float
        > 1 leaves a border.

    Returns
    -------
    eye : (3,) float64
        Camera position.
    target : (3,) float64
        Point looked at.
    up : (3,) float64
        Unit up vector.
    """
    P = np.asarray(P, dtype=np.float64)
    if len(P) > _CAMERA_SAMPLES:
        P = P[:: int(math.ceil(len(P) / _CAMERA_SAMPLES))]
    c, axes = _principal_frame(P)
    Q = P - c
    if direction is None:
        d = np.asarray(VIEW_DIRECTION, dtype=np.float64) @ axes
    else:
        d = np.asarray(direction, dtype=np.float64)
    d = d / np.linalg.norm(d)
    # Up: a world axis (parts are usually modelled axis-aligned), made orthogonal to the view
    # and pointing so that the camera looks down on the part; of the two axes least aligned
    # with the view, the one that lets the part fill the frame best (smallest distance).
    ty = math.tan(math.radians(fov_deg) / 2)
    tx = ty * aspect
    best = None
    for w in np.argsort(np.abs(d))[:2]:
        up = np.eye(3)[w] - d[w] * d
        up /= np.linalg.norm(up)
        if d[w] < 0:
            up = -up
        right = np.cross(up, d)
        x, y, z = Q @ right, Q @ up, Q @ d
        dist, cx, cy = _fit_frustum(x, y, z, tx, ty, margin)
        dist = max(dist, 1e-12 + float(np.abs(Q).max()))
        if best is None or dist < best[0] * (1 - 1e-6):
            best = (dist, up, cx * right + cy * up)
    dist, up, shift = best
    target = c + shift
    return target + dist * d, target, up


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
        The scene lies in the plane z = 0 (chart layout): look straight down the z axis.
    direction : (3,) float, optional
        World direction from the part to the camera (see :func:`best_view_direction`).
    """
    ps = _polyscope()
    aspect = size[0] / size[1]
    fov = ps.get_vertical_fov_degrees()
    if planar:
        P = np.asarray(P)
        c = 0.5 * (P.min(axis=0) + P.max(axis=0))
        ext = P.max(axis=0) - P.min(axis=0)
        t = math.tan(math.radians(fov) / 2)
        dist = CAMERA_MARGIN * max(ext[1] / 2 / t, ext[0] / 2 / (t * aspect), 1e-9)
        target = np.array([c[0], c[1], 0.0])
        eye, up = target + [0.0, 0.0, dist], np.array([0.0, 1.0, 0.0])
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
    ps = _polyscope()
    t = time.perf_counter()
    ps.set_window_size(int(size[0]), int(size[1]))
    ps.screenshot(str(png), transparent_bg=False)
    return time.perf_counter() - t


def scene_points(V: ArrayLike, charts, planar: bool) -> np.ndarray:
    """Points the camera must see: the mesh, or the laid-out charts in the plane z = 0."""
    if not planar:
        return np.asarray(V)
    ch = as_chart_maps(charts)
    placed = chart_layout(np.asarray(V), ch)
    uv = np.concatenate([p[np.unique(c.F)] for c, p in zip(ch, placed, strict=True)])
    return np.c_[uv, np.zeros(len(uv))]


def render_scene(
    V: ArrayLike,
    F: ArrayLike,
    seg,
    png: str | os.PathLike,
    stage: Stage = "final",
    charts=None,
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
        One of :data:`STAGES`.
    charts : iterable, optional
        Chart maps, for ``"charts"`` and ``"checker"``.
    size : (width, height)
        Pixels; each at least 16.
    segment : int, optional
        For ``"temperature"`` (default: the segment seen best).
    backend : str, optional
        Default: :data:`BACKEND_ENV` or :data:`HEADLESS_BACKEND`.

    Returns
    -------
    dict
        ``{"png": path, "seconds_scene": float, "seconds_screenshot": float}``.

    Raises
    ------
    ValueError
        Bad stage or size.
    RuntimeError
        No headless OpenGL available.
    """
    if len(size) != 2 or min(int(size[0]), int(size[1])) < 16:
        raise ValueError(f"size must be (width, height) with both >= 16 pixels, got {size}")
    ps = init_polyscope(backend, headless=True)
    t = time.perf_counter()
    info = build_scene(V, F, seg, stage, charts=charts, segment=segment)
    set_camera(
        scene_points(V, charts, info["planar"]),
        size,
        planar=info["planar"],
        direction=info["direction"],
    )
    t_scene = time.perf_counter() - t
    t_shot = screenshot(png, size)
    log.info("rendered %s (%s) in %.2f s + %.2f s", png, stage, t_scene, t_shot)
    ps.remove_all_structures()
    return {"png": Path(png), "seconds_scene": t_scene, "seconds_screenshot": t_shot}


def write_run_pictures(
    out_dir: str | os.PathLike,
    mesh,
    seg,
    charts=None,
    size: tuple[int, int] = DEFAULT_SIZE,
    backend: str | None = None,
) -> dict[str, Path]:
    """Write ``out_dir/segmentation.png`` (and ``out_dir/checker.png`` when charts are given).

    Called by the ``run`` pipeline.  Failures to render (no EGL, no polyscope) are logged as
    warnings and the pictures skipped: pictures never make a run fail.

    Parameters
    ----------
    out_dir : str or path-like
        Existing directory.
    mesh : CleanMesh
        The mesh (``V``, ``F``).
    seg : Segmentation
    charts : iterable, optional
        Chart maps (see :func:`as_chart_maps`) for the checkerboard picture.
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
    if len(size) != 2 or min(int(size[0]), int(size[1])) < 16:
        raise ValueError(f"size must be (width, height) with both >= 16 pixels, got {size}")
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


# --------------------------------------------------------------------------------------------
# CLI
