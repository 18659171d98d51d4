"""polyscope scenes of every pipeline stage (paper Figs. 6, 11, 13–15) and of the fitted types.

The scenes are built from results (:func:`build_scene`) and shown interactively
(``igl-heatseg view MESH --stage ...``) or rendered without a display
(:func:`igl_heatseg.viz.render.render_scene`, ``igl-heatseg render MESH -o PNG``).  This module
draws; it runs no algorithm (loading a file and segmenting it is the command line's job,
:mod:`igl_heatseg.cli.viz`).

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
``types``
    Every face in the colour of its segment's fitted surface type
    (:data:`SURFACE_TYPE_COLORS`); needs typed segments (:func:`segment_surface_types`: robust
    mode today). The trimming curves (``seg.boundary_curves``) are drawn where the segmentation
    has them: black on the intersection of two surfaces, red along the mesh (smoothed, or the
    chain of an exact tessellation) (:func:`show_boundary_curves`); else the segment boundaries
    along the mesh edges.
``checker``
    Every chart's UV map as a checkerboard on the 3D mesh, cut paths as curves (Fig. 15).
``charts``
    Every chart's 2D map on its own, laid out side by side in the plane (Fig. 14).

Charts are :class:`igl_heatseg.pipeline.Chart` objects (``faces``, ``segment``, the cut chart
``cut.F``/``cut.vertex_map``/``cut.cut_edges``, the map ``param.UV``); charts without a map
are not drawn (:func:`igl_heatseg.viz.layout.drawable_charts`).

polyscope is a soft dependency: it is imported inside the functions that need it, with an
install hint (``pip install igl_heatseg[viz]``).  polyscope can be initialised only once per
process; :func:`init_polyscope` does it once and later calls just clear the scene.  The
backend comes from the argument, else the environment variable :data:`BACKEND_ENV`
(``IGL_HEATSEG_PS_BACKEND``, e.g. ``openGL_mock`` for tests and notebooks), else polyscope's
default (interactive) or :data:`HEADLESS_BACKEND` (rendering).

Examples
--------
>>> import igl_heatseg as ih                                          # doctest: +SKIP
>>> mesh = ih.load_mesh("data/fandisk.off")                           # doctest: +SKIP
>>> ps = ih.viz.init_polyscope()                                      # doctest: +SKIP
>>> info = ih.viz.build_scene(mesh.V, mesh.F, ih.segment(mesh), "final")  # doctest: +SKIP
>>> ps.show()                                                         # doctest: +SKIP
"""

from __future__ import annotations

import logging
import math
import os
import time
from collections.abc import Iterable
from typing import TYPE_CHECKING, Any, Literal

import numpy as np
from numpy.typing import ArrayLike

from ..mesh.geometry import face_areas, face_normals
from .camera import best_view_direction
from .layout import chart_layout, corner_uv, drawable_charts, flipped_faces

if TYPE_CHECKING:
    from ..pipeline import Chart

__all__ = [
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
]

log = logging.getLogger(__name__)

Stage = Literal["seeds", "initial", "final", "types", "temperature", "charts", "checker"]

#: Stages understood by :func:`build_scene` and :func:`igl_heatseg.viz.render.render_scene`.
STAGES: tuple[str, ...] = ("seeds", "initial", "final", "types", "temperature", "charts", "checker")

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

#: Install hint shown when polyscope is missing.
INSTALL_HINT: str = "pip install igl_heatseg[viz]"

#: Colours (RGB in [0, 1]).
BACKGROUND = (1.0, 1.0, 1.0)
MESH_COLOR = (0.82, 0.82, 0.80)
NONSEED_COLOR = (0.12, 0.12, 0.12)
SHARP_COLOR = (0.08, 0.08, 0.08)
CUT_COLOR = (0.85, 0.05, 0.05)
#: Trimming curves on the intersection of two surfaces, and smoothed along the mesh.
CURVE_COLORS = {"intersection": (0.0, 0.0, 0.0), "smoothed": (0.80, 0.10, 0.10),
                "chain": (0.80, 0.10, 0.10)}
CHECKER_COLORS = ((0.97, 0.97, 0.97), (0.25, 0.25, 0.30))


def _hex(code: str) -> tuple[float, float, float]:
    return tuple(int(code[i : i + 2], 16) / 255.0 for i in (1, 3, 5))  # type: ignore[return-value]


#: Colour of each fitted surface type (RGB in [0, 1]), for the ``types`` stage and its legend.
#: The six kinds take six colours of the Okabe–Ito palette (Okabe & Ito 2008, "Color Universal
#: Design"), which stay distinguishable under protanopia, deuteranopia and tritanopia; its black
#: is left out (the boundary curves are dark) and so is its blue, which has the hue of the sky
#: blue of planes and would differ from it only in lightness, which shading changes.
#: ``"other"``, neutral grey, is a segment whose type is not known precisely: robust mode's
#: ``"Other"`` (a cone, torus or freeform surface, not told apart) or a segment without a fit.
SURFACE_TYPE_COLORS: dict[str, tuple[float, float, float]] = {
    "plane": _hex("#56B4E9"),  # sky blue
    "cylinder": _hex("#E69F00"),  # orange
    "cone": _hex("#009E73"),  # bluish green
    "sphere": _hex("#CC79A7"),  # reddish purple
    "torus": _hex("#F0E442"),  # yellow
    "freeform": _hex("#D55E00"),  # vermillion
    "other": _hex("#999999"),  # grey
}

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


# --------------------------------------------------------------------------------------------
# polyscope access


def import_polyscope():
    """The ``polyscope`` module (not initialised: see :func:`init_polyscope`).

    Raises
    ------
    ImportError
        polyscope is not installed; the message says what to install.
    """
    try:
        import polyscope as ps
    except ImportError as exc:
        raise ImportError(
            f"igl_heatseg.viz needs polyscope, which is not installed: {INSTALL_HINT}"
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
    ps = import_polyscope()
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


def _mesh(V, F, mesh_name: str):
    """The registered surface mesh ``mesh_name``, registered from ``V, F`` if missing."""
    ps = import_polyscope()
    return (
        ps.get_surface_mesh(mesh_name)
        if ps.has_surface_mesh(mesh_name)
        else add_mesh(V, F, mesh_name)
    )


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
    ps = import_polyscope()
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
    ps = import_polyscope()
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
    m = _mesh(V, F, mesh_name)
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
    k = seg.initial_groups if initial else seg.num_segments
    if not 0 <= segment < k:
        raise ValueError(f"segment must be in 0..{k - 1}, got {segment}")
    u = np.asarray(seg.temperature(segment, initial=initial), dtype=np.float64)
    # Stripes change at multiples of the period; 0 and 1 (whole seed regions) would flicker
    # between two stripes.  Shift by half a period (colour range shifted alike).
    half = 0.5 * ISOLINE_PERIOD
    _mesh(V, F, mesh_name).add_scalar_quantity(
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
        ``0..k-1``; colours from :func:`igl_heatseg.io.results.label_colors`.
    name : str
        Quantity name (``"initial segmentation"``, ``"final segmentation"``).
    mesh_name : str
    enabled : bool

    Returns
    -------
    polyscope.SurfaceMesh
    """
    m = _mesh(V, F, mesh_name)
    m.add_color_quantity(
        name, _rgb(np.asarray(labels, dtype=np.int64)), defined_on="faces", enabled=enabled
    )
    return m


def segment_surface_types(seg) -> list[str]:
    """The fitted surface type of every final segment, as keys of :data:`SURFACE_TYPE_COLORS`.

    Taken from ``seg.surfaces`` (a list of :class:`igl_heatseg.surfaces.Surface`, one per
    segment, ``None`` for a segment without a fit) when the segmentation has it, else from
    ``seg.primitive_types`` (robust mode: ``"Plane"``, ``"Cylinder"``, ``"Sphere"``,
    ``"Other"``), lower-cased; ``None`` and ``"Other"`` become ``"other"``.

    Parameters
    ----------
    seg : Segmentation

    Returns
    -------
    list of str, length ``seg.num_segments``

    Raises
    ------
    ValueError
        The segmentation has no types (paper mode: segment with ``mode="robust"``), their
        count is not the number of segments, or a type is unknown.

    Examples
    --------
    >>> from types import SimpleNamespace as NS
    >>> segment_surface_types(NS(num_segments=2, primitive_types=["Plane", "Other"]))
    ['plane', 'other']
    """
    surfaces = getattr(seg, "surfaces", None)
    if surfaces is not None:
        kinds = [None if s is None else s.kind for s in surfaces]
    elif getattr(seg, "primitive_types", None):
        kinds = list(seg.primitive_types)
    else:
        raise ValueError(
            "stage 'types' needs the fitted surface type of every segment: segment in robust "
            "mode (--mode robust, or mode='robust'), which types its segments"
        )
    out = ["other" if k is None else str(k).lower() for k in kinds]
    if len(out) != seg.num_segments:
        raise ValueError(f"{len(out)} surface types for {seg.num_segments} segments")
    unknown = sorted(set(out) - set(SURFACE_TYPE_COLORS))
    if unknown:
        raise ValueError(f"unknown surface types {unknown}; known: {list(SURFACE_TYPE_COLORS)}")
    return out


def show_surface_types(V, F, seg, mesh_name: str = "mesh", enabled: bool = True) -> list[str]:
    """Every face in the colour of its segment's fitted surface type (:data:`SURFACE_TYPE_COLORS`).

    Parameters
    ----------
    V : (n, 3) float64
    F : (m, 3) int64
    seg : Segmentation
        With types (see :func:`segment_surface_types`) and ``labels``.
    mesh_name : str
    enabled : bool

    Returns
    -------
    list of str
        The type of every segment (for a legend).

    Raises
    ------
    ValueError
        As :func:`segment_surface_types`.
    """
    kinds = segment_surface_types(seg)
    pal = np.array([SURFACE_TYPE_COLORS[k] for k in kinds], dtype=np.float64).reshape(-1, 3)
    C = pal[np.asarray(seg.labels, dtype=np.int64)]
    _mesh(V, F, mesh_name).add_color_quantity(
        "surface types", C, defined_on="faces", enabled=enabled
    )
    return kinds


def show_boundary_curves(curves, radius: float = 2 * SHARP_RADIUS) -> dict:
    """Trimming curves as one curve network per method, ``trimming curves (intersection)``,
    ``... (smoothed)``, ``... (chain)`` (:data:`CURVE_COLORS`).

    Parameters
    ----------
    curves : list of BoundaryCurve
        ``points (q, 3)`` polylines with a ``method`` each
        (:func:`igl_heatseg.surfaces.boundaries.boundary_curves`).
    radius : float
        Relative to the scene's length scale.

    Returns
    -------
    dict
        Method -> the registered network (methods without curves are left out).
    """
    out = {}
    for method, color in CURVE_COLORS.items():
        P, E, n = [], [], 0
        for c in curves:
            if c.method != method or len(c.points) < 2:
                continue
            P.append(np.asarray(c.points, dtype=np.float64))
            E.append(n + np.c_[np.arange(len(c.points) - 1), np.arange(1, len(c.points))])
            n += len(c.points)
        if P:
            out[method] = add_curves(np.vstack(P), np.vstack(E), f"trimming curves ({method})",
                                     color=color, radius=radius)
    return out


def show_checker(V, F, charts, mesh_name: str = "mesh", enabled: bool = True, cuts: bool = True):
    """Every chart's UV as a checkerboard on the 3D mesh, cut paths as red curves (Fig. 15).

    Each chart's UV is rescaled to the chart's 3D area, so squares have about the same size
    everywhere; stretched or sheared squares show distortion.

    Parameters
    ----------
    V : (n, 3) float64
    F : (m, 3) int64
    charts : iterable of igl_heatseg.pipeline.Chart
        Charts without a map are left blank.
    mesh_name : str
    enabled : bool
    cuts : bool
        Draw the cut edges of all charts.

    Returns
    -------
    polyscope.SurfaceMesh
    """
    V = np.asarray(V)
    charts = drawable_charts(charts)
    m = _mesh(V, F, mesh_name)
    m.add_parameterization_quantity(
        "chart UV",
        corner_uv(V, F, charts),
        defined_on="corners",
        coords_type="world",
        enabled=enabled,
        viz_style="checker",
        checker_colors=CHECKER_COLORS,
        checker_size=CHECKER_FRACTION,  # "world" coords: relative to polyscope's length scale
    )
    cut = [np.asarray(c.cut.cut_edges).reshape(-1, 2) for c in charts]
    cut = [e for e in cut if len(e)]
    if cuts and cut:
        net = add_curves(V, np.concatenate(cut), "cut paths", color=CUT_COLOR, radius=CUT_RADIUS)
        net.set_enabled(enabled)
    return m


def show_chart_maps(V, charts, enabled: bool = True, edges: bool = True):
    """Every chart's 2D map on its own, side by side in the plane z = 0 (Fig. 14).

    Charts are coloured like their segment; flipped triangles red.

    Parameters
    ----------
    V : (n, 3) float64
        Vertices of the whole mesh (for the area normalisation).
    charts : iterable of igl_heatseg.pipeline.Chart
        Charts without a map are not drawn.
    enabled : bool
    edges : bool
        Draw triangle edges (thin) so that the map's triangles are visible.

    Returns
    -------
    list of polyscope.SurfaceMesh
    """
    from ..io.results import label_colors

    charts = drawable_charts(charts)
    placed = chart_layout(V, charts)
    k = max([c.segment for c in charts], default=0) + 1
    pal = label_colors(k).astype(np.float64) / 255.0
    out = []
    for i, (c, uv) in enumerate(zip(charts, placed, strict=True)):
        P = np.c_[uv, np.zeros(len(uv))]
        m = add_mesh(P, c.cut.F, f"chart {i:03d}", color=tuple(pal[c.segment]))
        m.set_enabled(enabled)
        if edges:
            m.set_edge_width(0.5)
            m.set_edge_color((0.2, 0.2, 0.2))
        flipped = flipped_faces(c)
        if len(flipped):
            C = np.tile(pal[c.segment], (len(c.cut.F), 1))
            C[flipped] = (1.0, 0.0, 0.0)
            m.add_color_quantity("flipped", C, defined_on="faces", enabled=True)
        out.append(m)
    return out


# --------------------------------------------------------------------------------------------
# whole scenes


def build_scene(
    V: ArrayLike,
    F: ArrayLike,
    seg,
    stage: Stage = "final",
    charts: Iterable[Chart] | None = None,
    segment: int | None = None,
    all_quantities: bool = False,
) -> dict:
    """Register the structures of one stage on polyscope's (initialised) scene.

    Parameters
    ----------
    V : (n, 3) float64
    F : (m, 3) int64
    seg : Segmentation
    stage : str
        One of :data:`STAGES`.
    charts : iterable of igl_heatseg.pipeline.Chart, optional
        Required for ``"charts"`` and ``"checker"``.
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
        (:func:`igl_heatseg.viz.camera.best_view_direction`), ``segment`` is the temperature
        field's segment.

    Raises
    ------
    ValueError
        Unknown stage, a chart stage without charts, or ``"types"`` without surface types
        (:func:`segment_surface_types`).
    """
    if stage not in STAGES:
        raise ValueError(f"stage must be one of {STAGES}, got {stage!r}")
    if stage in CHART_STAGES and charts is None:
        raise ValueError(f"stage {stage!r} needs the charts of the parameterization")
    V = np.asarray(V, dtype=np.float64)
    F = np.asarray(F, dtype=np.int64)
    if stage == "types":
        segment_surface_types(seg)  # fail before registering anything
    if stage == "charts":
        show_chart_maps(V, charts)
        return {"mesh": None, "stage": stage, "planar": True, "direction": None, "segment": None}
    m = add_mesh(V, F)
    d = best_view_direction(V, F, seg.labels)
    if segment is None:  # the segment seen best from the camera
        seen = np.maximum((face_areas(V, F)[:, None] * face_normals(V, F)) @ d, 0.0)
        segment = int(np.argmax(np.bincount(seg.labels, weights=seen, minlength=seg.num_segments)))
    _add_stage_quantities(V, F, seg, stage, segment, all_quantities)
    if charts is not None and (stage == "checker" or all_quantities):
        show_checker(V, F, charts, enabled=stage == "checker")
    return {"mesh": m, "stage": stage, "planar": False, "direction": d, "segment": segment}


def _add_stage_quantities(V, F, seg, stage: str, segment: int, all_quantities: bool) -> None:
    """The segmentation's quantities on the mesh: ``stage``'s enabled, the others (when
    ``all_quantities``) disabled, skipping those the segmentation cannot provide."""
    if stage == "seeds" or all_quantities:
        show_seeds(V, F, seg, enabled=stage == "seeds")
    if stage == "temperature":
        show_temperature(V, F, seg, segment=segment)
    elif all_quantities:
        try:
            show_temperature(V, F, seg, segment=segment, enabled=False)
        except RuntimeError:  # fields not kept (segment_mesh(..., keep_solvers=False))
            log.debug("no temperature fields to show")
    if stage == "initial" or all_quantities:
        show_labels(V, F, seg.initial_labels, "initial segmentation", enabled=stage == "initial")
    if stage == "final" or all_quantities:
        show_labels(V, F, seg.labels, "final segmentation", enabled=stage == "final")
    if stage == "types":
        show_surface_types(V, F, seg)
    elif all_quantities:
        try:
            show_surface_types(V, F, seg, enabled=False)
        except ValueError:  # paper mode: no fitted types
            log.debug("no surface types to show")
    curves = getattr(seg, "boundary_curves", None) if stage == "types" else None
    if curves:
        show_boundary_curves(curves)
    elif stage in ("final", "types"):
        add_curves(V, segment_boundary_edges(F, seg.labels), "segment boundaries")
