"""The pipeline's stages, each on the typed :class:`~.results.Chart` objects.

:func:`extract_charts` -> :func:`cut_charts` (:func:`cut_chart` per chart) ->
:func:`parameterize_charts` (:func:`map_chart` per chart) -> :func:`pack`; put together by
:func:`igl_heatseg.pipeline.run_pipeline`.
"""

from __future__ import annotations

import copy
import hashlib
import logging
import time
from collections import OrderedDict
from dataclasses import replace
from typing import Literal, Sequence

import numpy as np

from ..errors import MeshError
from ..mesh.checks import CleanMesh
from ..mesh.geometry import face_areas, uv_areas
from ..mesh.topology import face_components
from ..parameterization.atlas import GUTTER_DEFAULT, PackedAtlas, atlas_corner_uv, pack_charts
from ..parameterization.chart import HLLE_SKIP_CURVATURE, parameterize_chart
from ..parameterization.cut import (
    CutError,
    CutResult,
    chart_topology,
    cut_along_paths,
    cut_to_disk,
)
from ..parameterization.split import (
    MESH_SD_MAX,
    PACK_HALVE_MIN_FACES,
    PACK_LONG_GAIN,
    PACK_MAX_LENGTH,
    PACK_MIN_AREA_FRACTION,
    SPLIT_SD_MAX,
    cut_for_packing,
    parameterize_pieces,
    peel_for_packing,
)
from .results import Chart

__all__ = [
    "check_cut_paths",
    "compose_cuts",
    "extract_charts",
    "cut_chart",
    "cut_charts",
    "map_chart",
    "parameterize_charts",
    "pack",
]

log = logging.getLogger(__name__)

#: Fill of the square atlas assumed when the gutter is turned into model units for peeling
#: spikes (the gutter is a fraction of the atlas side, unknown before packing).
PEEL_FILL_GUESS: float = 0.65


def check_cut_paths(mesh: CleanMesh, cut_paths: Sequence[tuple[int, int]]) -> None:
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
    check_cut_paths(mesh, cut_paths)
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
        common.sort(key=lambda c: (charts[c].topology.is_disk, -len(charts[c].faces)))
        out.setdefault(common[0], []).append((c0, c1))
    return out


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


def extract_charts(
    mesh: CleanMesh,
    labels: np.ndarray,
    *,
    with_topology: bool = True,
    areas: np.ndarray | None = None,
) -> list[Chart]:
    """Stage 1: one chart per face-connected piece of each segment.

    Parameters
    ----------
    mesh : CleanMesh
    labels : (m,) int
        Segment of every face (``Segmentation.labels``).
    with_topology : bool
        Compute each chart's topology now. It is needed before cutting only to place user cut
        paths or to skip non-disks (``cut="none"``); otherwise :func:`cut_chart` takes
        ``cut_to_disk``'s ``topology_before`` (the same ``ChartTopology``, checked on 179
        charts of 8 meshes), which saves a second edge topology per chart (0.2 s on iron.ply).
    areas : (m,) float64, optional
        Face areas (computed if not given).

    Returns
    -------
    list of Chart
        Numbered in order of segment, then piece; ``area`` set.

    Raises
    ------
    MeshError
        A chart that is not a valid surface (with ``with_topology``).

    Examples
    --------
    >>> import igl, igl_heatseg as ih
    >>> V, F = igl.icosahedron()
    >>> mesh = ih.validate_mesh(V, F)
    >>> labels = (np.arange(len(F)) >= 10).astype(int)
    >>> [(c.segment, len(c.faces)) for c in extract_charts(mesh, labels)]
    [(0, 10), (1, 10)]
    """
    F = mesh.F
    areas = face_areas(mesh.V, F) if areas is None else areas
    labels = np.asarray(labels)
    charts: list[Chart] = []
    for s in range(int(labels.max()) + 1 if len(labels) else 0):
        faces = np.flatnonzero(labels == s)
        if len(faces) == 0:
            continue
        count, comp = face_components(F[faces])
        for c in range(count):
            fc = faces[comp == c]
            ch = Chart(id=len(charts), segment=s, faces=fc, area=float(areas[fc].sum()))
            if with_topology:
                ch.topology = chart_topology(F[fc], name=f"chart {ch.id}")
            charts.append(ch)
    if any(seg_count > 1 for seg_count in np.bincount([c.segment for c in charts])):
        log.info("some segments are not face-connected; each piece is its own chart")
    return charts


def cut_chart(
    mesh: CleanMesh,
    ch: Chart,
    paths: Sequence[tuple[int, int]] = (),
    cut: Literal["auto", "none"] = "auto",
) -> Chart:
    """Stage 2, one chart: cut it along ``paths``, then (``cut="auto"``) to a disk.

    Sets ``ch.cut`` (``None`` when cutting failed, or for a non-disk with ``cut="none"``),
    ``ch.topology`` (if not known yet), ``ch.cut_paths``, ``ch.cut_seconds`` and, for a chart
    that is not a disk afterwards, ``ch.error``.  A cut that fails (e.g. a user path that
    splits the chart in two) is recorded in ``ch.error``, not raised, so the other charts go on.

    Parameters
    ----------
    mesh : CleanMesh
    ch : Chart
        From :func:`extract_charts`.
    paths : sequence of (int, int)
        Cut paths as *clean* vertex ids (see :func:`cut_charts` for input ids).
    cut : {"auto", "none"}
        With ``"none"`` a chart is only checked (unpinching would change nothing for a disk).

    Returns
    -------
    Chart
        ``ch``.

    Raises
    ------
    MeshError
        The chart is not a valid surface.

    Examples
    --------
    >>> import igl, igl_heatseg as ih
    >>> V, F = igl.icosahedron()
    >>> mesh = ih.validate_mesh(V, F)
    >>> ch = cut_chart(mesh, extract_charts(mesh, np.zeros(len(F), int), with_topology=False)[0])
    >>> ch.topology.is_disk, ch.cut.topology_after.is_disk, ch.error is None
    (False, True, True)
    """
    V, F = mesh.V, mesh.F
    name = f"chart {ch.id}"
    t = time.perf_counter()
    Fc = F[ch.faces]
    res: CutResult | None = None
    error = "not a disk (use --cut auto or --cut-path)"
    try:
        if paths:
            res = cut_along_paths(V, Fc, list(paths), name=name)
        if cut == "auto":
            if res is None:
                res = cut_to_disk(V, Fc, name=name)
            elif not res.topology_after.is_disk:
                res = compose_cuts(res, cut_to_disk(res.V, res.F, name=name))
        elif res is None:
            # no cutting: only check (unpinching would change nothing for a disk)
            res = cut_to_disk(V, Fc, name=name) if ch.topology.is_disk else None
    except (MeshError, CutError) as exc:
        # e.g. a user path that splits the chart in two: report it, keep the other charts
        error = f"cutting failed: {exc}"
    if ch.topology is None:  # not computed by extract_charts
        if res is not None:
            ch.topology = res.topology_before
        else:  # raises MeshError for a chart that is not a valid surface, as extraction would
            ch.topology = chart_topology(Fc, name=name)
    ch.cut = res
    ch.cut_seconds = time.perf_counter() - t
    ch.cut_paths = [
        (int(mesh.input_vertex[p[0]]), int(mesh.input_vertex[p[-1]]))
        for p in (res.paths if res else [])
    ]
    ch.error = None
    if res is None or not res.topology_after.is_disk:
        ch.error = error
        after = res.topology_after.as_dict() if res is not None else ch.topology.as_dict()
        log.warning("%s: not a disk after cutting (%s); not parameterized", name, after)
    return ch


def cut_charts(
    mesh: CleanMesh,
    charts: list[Chart],
    cut_paths: Sequence[tuple[int, int]] = (),
    cut: Literal["auto", "none"] = "auto",
    progress=None,
) -> list[Chart]:
    """Stage 2: assign user cut paths to charts, then :func:`cut_chart` every chart.

    Parameters
    ----------
    mesh : CleanMesh
    charts : list of Chart
        From :func:`extract_charts` (with topology if ``cut_paths`` is given).
    cut_paths : sequence of (int, int)
        Generatrix ends as vertex ids of the *input* mesh (paper §3.5); each pair goes to the
        chart holding both ends, preferring a chart that is not a disk, then the largest.
    cut : {"auto", "none"}
    progress : callable(stage, fraction), optional
        Called with stage ``"cut"``.

    Returns
    -------
    list of Chart
        ``charts``, cut.

    Raises
    ------
    MeshError
        Bad cut-path vertex ids, or a pair no chart holds (named).
    """
    progress = progress or (lambda stage, fraction=1.0: None)
    assigned = _assign_paths(mesh, charts, cut_paths)
    for ch in charts:
        progress("cut", ch.id / max(len(charts), 1))
        cut_chart(mesh, ch, assigned.get(ch.id, ()), cut)
    progress("cut", 1.0)
    return charts


def map_chart(
    ch: Chart,
    mesh: CleanMesh,
    areas: np.ndarray,
    *,
    energy: Literal["auto", "hlle", "curved"] = "auto",
    fallback: str = "tutte+slim",
    hlle_skip_curvature: float | None = HLLE_SKIP_CURVATURE,
    split_sd_max: float = SPLIT_SD_MAX,
) -> tuple[list[Chart], bool, bool]:
    """Stage 3, one chart: map a cut chart (a disk), splitting it if needed.

    The chart is mapped by :func:`igl_heatseg.parameterization.chart.parameterize_chart`
    through :func:`igl_heatseg.parameterization.split.parameterize_pieces` (split along a seam
    of highest stretch while the best bijective map's mean symmetric Dirichlet energy is above
    ``split_sd_max``); a piece of at least ``PACK_MIN_AREA_FRACTION`` of the mesh's area is cut
    for packing when it is long or C-shaped
    (:func:`igl_heatseg.parameterization.split.cut_for_packing`), keeping its map (a piece
    more stretched than ``split_sd_max`` and the chart joins its neighbour).  A failure is
    recorded in ``ch.error``, not raised.

    Parameters
    ----------
    ch : Chart
        After :func:`cut_chart`; a chart with ``error`` set is returned as it is.
    mesh : CleanMesh
    areas : (m,) float64
        Face areas of ``mesh``.
    energy, fallback, hlle_skip_curvature, split_sd_max
        As for :func:`run_pipeline` (``hlle_skip_curvature`` resolved: a float or ``None``).

    Returns
    -------
    charts : list of Chart
        ``[ch]`` with ``param`` set, or its pieces (new charts, ``id=-1``, ``split_from=ch.id``).
    cut_for_distortion, cut_for_packing : bool
        Whether the chart was split for either reason.

    Examples
    --------
    >>> import igl, igl_heatseg as ih
    >>> V, F = igl.loop(*igl.icosahedron(), 1)
    >>> mesh = ih.validate_mesh(V, F)
    >>> ch = extract_charts(mesh, (V[F].mean(axis=1)[:, 2] > 0).astype(int))[0]
    >>> out, dist, pack = map_chart(cut_chart(mesh, ch), mesh, igl.doublearea(V, F) / 2)
    >>> len(out), out[0].param.bijective, dist, pack
    (1, True, False, False)
    """
    if ch.error is not None:
        return [ch], False, False
    name = f"chart {ch.id}"
    res = ch.cut
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
            split_unmapped=fallback != "none",
        )
    except (MeshError, RuntimeError, np.linalg.LinAlgError) as exc:
        # One chart failing must not lose the others: report it and go on.
        ch.param_seconds = time.perf_counter() - t
        log.warning("%s: parameterization failed: %s", name, exc)
        ch.error = f"parameterization failed: {exc}"
        return [ch], False, False
    n_dist = len(pieces)
    pieces = [  # long or C-shaped big charts cut for packing, their maps kept
        (rows[sub_rows], sub, q)
        for rows, r, p in pieces
        for sub_rows, sub, q in (
            cut_for_packing(r, p, name, sd_max=split_sd_max)
            if areas[ch.faces[rows]].sum() >= PACK_MIN_AREA_FRACTION * areas.sum()
            else [(np.arange(len(r.F)), r, p)]
        )
    ]
    if len(pieces) == 1:
        ch.param = pieces[0][2]
        return [ch], False, False
    out = []
    for rows, r, p in pieces:  # cut for distortion or packing: charts of their own
        faces = ch.faces[rows]
        out.append(
            replace(
                ch,
                id=-1,
                faces=faces,
                area=float(areas[faces].sum()),
                cut=r,
                param=p,
                split_from=ch.id,
                chart_cut=res,
            )
        )
    return out, n_dist > 1, len(pieces) > n_dist


def parameterize_charts(
    mesh: CleanMesh,
    charts: list[Chart],
    *,
    energy: Literal["auto", "hlle", "curved"] = "auto",
    fallback: str = "tutte+slim",
    hlle_skip_curvature: float | None = HLLE_SKIP_CURVATURE,
    split_sd_max: float = SPLIT_SD_MAX,
    areas: np.ndarray | None = None,
    progress=None,
    gutter: float | None = None,
) -> tuple[list[Chart], int, int]:
    """Stage 3: :func:`map_chart` every chart; pieces of a split chart replace it.

    Parameters
    ----------
    mesh : CleanMesh
    charts : list of Chart
        After :func:`cut_charts`.
    energy, fallback, hlle_skip_curvature, split_sd_max
        As for :func:`map_chart`.
    areas : (m,) float64, optional
        Face areas (computed if not given).
    progress : callable(stage, fraction), optional
        Called with stage ``"param"``.
    gutter : float, optional
        The atlas gutter :func:`pack` will use (default
        :data:`igl_heatseg.parameterization.atlas.GUTTER_DEFAULT`): cuts for packing are
        judged by layouts with it.

    Returns
    -------
    charts : list of Chart
        In order, pieces in place of the chart they come from, renumbered ``0, 1, ...``.
    cut_for_distortion, cut_for_packing : int
        How many charts were split for either reason.

    Notes
    -----
    Charts longer than ``PACK_MAX_LENGTH`` times the square root of the mesh's area are then
    cut across, their maps kept, when the atlas packs tighter that way (both layouts are
    packed: a long chart sets the side of a square atlas, but a mesh of one round chart gains
    nothing from quarters); then the spikes of charts are peeled off the same way (a coarse
    export's slivers fanning out of a chart keep the other charts away).
    """
    progress = progress or (lambda stage, fraction=1.0: None)
    areas = face_areas(mesh.V, mesh.F) if areas is None else areas
    opts = dict(energy=energy, fallback=fallback, hlle_skip_curvature=hlle_skip_curvature)
    done = []
    for ch in charts:
        progress("param", ch.id / max(len(charts), 1))
        orig = replace(ch)  # map_chart sets param on its chart
        done.append((orig, *map_chart(ch, mesh, areas, split_sd_max=split_sd_max, **opts)))
    progress("param", 1.0)
    if split_sd_max > MESH_SD_MAX:
        _lower_mesh_energy(done, mesh, areas, opts)
    gutter = GUTTER_DEFAULT if gutter is None else gutter
    _cut_for_packing(done, areas, split_sd_max, gutter)
    out = [c for _, pieces, _, _ in done for c in pieces]
    for i, c in enumerate(out):
        c.id = i
    return out, sum(d for *_, d, _ in done), sum(p for *_, p in done)


def _packable(ch: Chart) -> bool:
    """Whether :func:`pack` packs a mapped chart (finite UVs of positive area)."""
    UV = ch.param.UV
    return bool(np.isfinite(UV).all() and np.abs(uv_areas(UV, ch.cut.F)).sum() > 0)


def _fill(charts: list, gutter: float) -> float:
    """Atlas fill of :func:`pack`'s layout of ``charts`` with ``gutter`` (0 when none can be
    packed)."""
    done = [ch for ch in charts if ch.param is not None and _packable(ch)]
    if not done:
        return 0.0
    return _pack_once(done, gutter).fill


#: The last layouts packed (a trial layout of :func:`_trial_cut` is usually the one
#: :func:`pack` packs next: packing it again would cost one more packing, ~1-2 s).
_PACKED: OrderedDict = OrderedDict()


def _pack_once(done: list, gutter: float) -> PackedAtlas:
    """:func:`pack_charts` of the charts' maps (UV area = 3D area), the layout of an identical
    call reused (the inputs' bytes are the key; the two last layouts are kept)."""
    uvs, faces = [ch.param.UV for ch in done], [ch.cut.F for ch in done]
    areas = np.array([ch.area for ch in done], dtype=np.float64)
    h = hashlib.blake2b(np.float64(gutter).tobytes() + areas.tobytes(), digest_size=16)
    for UV, F in zip(uvs, faces, strict=True):  # shapes too: the bytes alone do not split
        h.update(np.array([*np.shape(UV), *np.shape(F)], dtype=np.int64).tobytes())
        h.update(np.ascontiguousarray(UV, dtype=np.float64).tobytes())
        h.update(np.ascontiguousarray(F, dtype=np.int64).tobytes())
    key = h.hexdigest()
    if key not in _PACKED:
        _PACKED[key] = pack_charts(uvs, faces, areas=areas, gutter=gutter)
        while len(_PACKED) > 2:
            _PACKED.popitem(last=False)
    _PACKED.move_to_end(key)
    return _PACKED[key]


def _cut_for_packing(done: list, areas: np.ndarray, sd_max: float, gutter: float) -> None:
    """Cut charts for packing, in place in ``done`` (``(orig, pieces, cut_for_distortion,
    cut_for_packing)`` per chart), keeping each kind of cut only when the atlas then fills
    at least ``PACK_LONG_GAIN`` more of its square (both layouts are packed):

    1. charts longer than ``PACK_MAX_LENGTH`` x the square root of the mesh's area, cut
       across (:func:`~igl_heatseg.parameterization.split.cut_for_packing`); then, in a trial
       of its own, those whose equal slices are not disks, cut through their holes (``shift``:
       a dimpled knob's side). Moved into the first trial, such cuts made it fail as a whole
       on fresh f21 saddle_boss_s21020 (paper), and since the later trials start from the
       layout kept, its atlas ended at 0.627 instead of 0.710;
    2. then C-shaped charts of any size (filling less than ``PACK_MIN_BOX_FILL`` of their
       rectangle, down to ``PACK_HALVE_MIN_FACES`` faces) halved while that helps them: the
       thin rings of a bolt's thread flanks, cut open, nest in nothing (a coarse clean bolt's
       37 charts filled 0.466 of the square);
    3. then the spikes peeled off every chart whose pieces cost less room than it
       (:func:`~igl_heatseg.parameterization.split.peel_for_packing`; the gutter is
       estimated for a square filled to :data:`PEEL_FILL_GUESS`);

    in both, a piece whose energy is above ``sd_max`` and its chart's joins the piece next to
    it, or the chart stays whole.

    The maps are kept (restricted to the pieces)."""
    bound = PACK_MAX_LENGTH * float(np.sqrt(areas.sum()))
    fill = _trial_cut(done, areas, gutter, "long charts cut", lambda c, name: cut_for_packing(
        c.cut, c.param, name, max_length=bound, big=False, sd_max=sd_max))
    fill = _trial_cut(done, areas, gutter, "long charts cut through their holes", (
        lambda c, name: cut_for_packing(c.cut, c.param, name, max_length=bound, big=False,
                                        sd_max=sd_max, shift=True)), fill)
    fill = _trial_cut(done, areas, gutter, "C-shaped charts halved", lambda c, name: (
        cut_for_packing(c.cut, c.param, name, big=True, sd_max=sd_max, max_aspect=np.inf,
                        min_faces=PACK_HALVE_MIN_FACES)), fill)
    total = sum(c.area for d in done for c in d[1] if c.param is not None)
    gap = gutter * float(np.sqrt(total / PEEL_FILL_GUESS))
    _trial_cut(done, areas, gutter, "spikes peeled", lambda c, name: peel_for_packing(
        c.cut, c.param, gap, name, sd_max=sd_max), fill)


def _trial_cut(
    done: list, areas: np.ndarray, gutter: float, what: str, cut, fill: float | None = None
):
    """Cut every bijectively mapped piece of ``done`` by ``cut(chart, name)`` (a list of
    ``(faces, CutResult, ChartParam)``), and keep the cuts when the atlas fills at least
    ``PACK_LONG_GAIN`` more; ``fill``: the fill of ``done`` as it is, when known.  Returns
    the fill of the layout kept (``fill`` when nothing was cut)."""
    new = []
    for orig, pieces, _, _ in done:
        out = []
        for c in pieces:
            mapped = c.param is not None and c.param.bijective
            got = cut(c, f"chart {orig.id}") if mapped else []
            out += [c] if len(got) <= 1 else [
                replace(c, id=-1, faces=c.faces[rows], area=float(areas[c.faces[rows]].sum()),
                        cut=sub, param=q, split_from=orig.id,
                        chart_cut=c.chart_cut if c.split_from is not None else c.cut)
                for rows, sub, q in got]
        new.append(out)
    if all(len(out) == len(d[1]) for out, d in zip(new, done, strict=True)):
        return fill
    before = _fill([c for d in done for c in d[1]], gutter) if fill is None else fill
    after = _fill([c for out in new for c in out], gutter)
    kept = after >= before + PACK_LONG_GAIN
    log.info("%s for packing: fill %.3f -> %.3f%s", what, before, after,
             "" if kept else " (not kept)")
    if not kept:
        return before
    for i, out in enumerate(new):
        if len(out) != len(done[i][1]):
            done[i] = (done[i][0], out, done[i][2], True)
    return after


def _excess(pieces: list, signed: bool = False) -> float:
    """Area times symmetric Dirichlet energy above :data:`MESH_SD_MAX`, summed over the
    mapped pieces (``signed``: below it counts negatively, as in the mesh's mean)."""
    total = 0.0
    for c in pieces:
        if c.param is None or not c.param.bijective:
            continue
        d = c.param.distortion.get("sym_dirichlet", np.inf) - MESH_SD_MAX
        if np.isfinite(d):
            total += c.area * (d if signed else max(d, 0.0))
    return total


def _lower_mesh_energy(done: list, mesh: CleanMesh, areas: np.ndarray, opts: dict) -> None:
    """While the mesh's area-weighted mean energy is above :data:`MESH_SD_MAX` (issue 13:
    4.3 per mesh), map its charts again with that bound as the split threshold, the chart
    farthest above it first, keeping a new mapping only when it lowers the excess: a coarse
    part's few charts, each below :data:`SPLIT_SD_MAX`, can still leave the mesh above the
    bound (paper mode on coarse tuning parts: 4.4-4.8 per mesh, with 1-3 charts)."""
    mapped = [c for _, pieces, _, _ in done for c in pieces if c.param is not None]
    sd = np.array([c.param.distortion.get("sym_dirichlet", np.inf) for c in mapped])
    a = np.array([c.area for c in mapped])
    ok = np.isfinite(sd)
    if not ok.any() or a[ok].sum() <= 0:
        return
    total, excess = a[ok].sum(), float((a[ok] * (sd[ok] - MESH_SD_MAX)).sum())
    order = sorted(range(len(done)), key=lambda i: -_excess(done[i][1]))
    for i in order:
        old = _excess(done[i][1])
        if excess <= 0 or old <= 0:
            break
        orig, pieces, dist, pack = done[i]
        again = map_chart(replace(orig), mesh, areas, split_sd_max=MESH_SD_MAX, **opts)
        new = _excess(again[0])
        if new < old and all(c.param is not None and c.param.bijective for c in again[0]):
            excess += _excess(again[0], signed=True) - _excess(pieces, signed=True)
            done[i] = (orig, *again)
            log.info("chart %d mapped again for the mesh's mean energy: excess %.3g -> %.3g "
                     "(%d piece(s))", orig.id, old / total, new / total, len(again[0]))


def pack(
    mesh: CleanMesh, charts: list[Chart], gutter: float | None = None
) -> tuple[np.ndarray, PackedAtlas | None]:
    """Stage 4: pack the mapped charts into ``[0, 1]^2`` (areas follow the 3D areas).

    Sets ``uv`` and ``atlas_box`` of every packed chart, and ``atlas_error`` of a mapped chart
    whose map is degenerate or not finite (possible only without fallback), which is left out.

    Parameters
    ----------
    mesh : CleanMesh
    charts : list of Chart
        After :func:`parameterize_charts`.
    gutter : float, optional
        Atlas gutter (default :data:`igl_heatseg.parameterization.atlas.GUTTER_DEFAULT`).

    Returns
    -------
    corner_uv : (m, 3, 2) float64
        Atlas UV of every corner of ``mesh.F`` (``(0, 0)`` for charts not packed).
    atlas : PackedAtlas or None
        ``None`` when no chart could be packed.
    """
    m = mesh.F.shape[0]
    done = []
    for ch in charts:
        if ch.param is None:
            continue
        if _packable(ch):
            done.append(ch)
        else:  # a degenerate map (possible only when no fallback is used) cannot be packed
            ch.atlas_error = "degenerate or non-finite UVs; left out of the atlas"
            log.warning("chart %d: degenerate UVs, left out of the atlas", ch.id)
    if not done:
        return np.zeros((m, 3, 2)), None
    # a copy: the layout kept for reuse is not shared with the charts of this run
    atlas = copy.deepcopy(_pack_once(done, GUTTER_DEFAULT if gutter is None else gutter))
    for ch, uv, box in zip(done, atlas.uvs, atlas.boxes, strict=True):
        ch.uv = uv
        ch.atlas_box = np.asarray(box, dtype=np.float64)
    corner_uv = atlas_corner_uv(
        m,
        [ch.faces for ch in charts],
        [ch.cut.F if ch.uv is not None else np.zeros((len(ch.faces), 3), int) for ch in charts],
        [ch.uv if ch.uv is not None else np.zeros((1, 2)) for ch in charts],
    )
    return corner_uv, atlas
