"""Result writers: labels, segmented PLY, report JSON, chart and atlas OBJ files.

Everything a command writes goes through here. Outputs are in the input mesh's own face and
vertex order (a :class:`~igl_heatseg.mesh.CleanMesh` keeps the map back).
"""

from __future__ import annotations

import contextlib
import json
import os
import shutil
import tempfile
import time
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike

from ..errors import MeshError
from ..version import __version__

__all__ = [
    "label_colors",
    "write_labels",
    "write_segmented_ply",
    "write_report",
    "write_segmentation",
    "write_boundary_curves",
    "write_run",
    "atomic_dir",
    "is_complete",
    "COMPLETE_MARKER",
    "write_chart_obj",
    "write_atlas_obj",
]


def label_colors(k: int) -> np.ndarray:
    """A categorical palette, distinct neighbours, deterministic.

    Parameters
    ----------
    k : int
        Number of labels.

    Returns
    -------
    C : (k, 3) uint8
        RGB colours; the first 20 are Tableau-like, then golden-ratio hues.
    """
    base = np.array(
        [
            [31, 119, 180], [255, 127, 14], [44, 160, 44], [214, 39, 40], [148, 103, 189],
            [140, 86, 75], [227, 119, 194], [127, 127, 127], [188, 189, 34], [23, 190, 207],
            [174, 199, 232], [255, 187, 120], [152, 223, 138], [255, 152, 150], [197, 176, 213],
            [196, 156, 148], [247, 182, 210], [199, 199, 199], [219, 219, 141], [158, 218, 229],
        ],
        dtype=np.uint8,
    )  # fmt: skip
    if k <= len(base):
        return base[:k].copy()
    i = np.arange(k - len(base))
    h = (i * 0.618033988749895) % 1.0
    s = 0.55 + 0.35 * ((i * 7) % 3) / 2
    v = 0.95 - 0.25 * ((i * 5) % 2)
    hi = np.floor(h * 6).astype(int) % 6
    f = h * 6 - np.floor(h * 6)
    p, q, t = v * (1 - s), v * (1 - f * s), v * (1 - (1 - f) * s)
    table = [(v, t, p), (q, v, p), (p, v, t), (p, q, v), (t, p, v), (v, p, q)]
    rgb = np.stack([np.choose(hi, [tb[c] for tb in table]) for c in range(3)], axis=1)
    return np.concatenate([base, (rgb * 255).round().astype(np.uint8)])


def write_labels(path: str | os.PathLike, labels: np.ndarray) -> None:
    """Write one integer per line.

    Parameters
    ----------
    path : str or path-like
    labels : (k,) int array
    """
    values = np.asarray(labels, dtype=np.int64).ravel().tolist()
    text = "\n".join(map(str, values))  # 10x faster than np.savetxt on 168k labels
    Path(path).write_text(text + "\n" if values else "")


def write_segmented_ply(
    path: str | os.PathLike,
    V: np.ndarray,
    F: np.ndarray,
    labels: np.ndarray,
    surface_kinds: list | None = None,
) -> None:
    """Write a binary PLY with a per-face ``label`` and per-face ``red green blue`` colour.

    With ``surface_kinds`` (one kind per label), each face also gets ``uchar surface_type``:
    its segment's index in :data:`igl_heatseg.surfaces.SURFACE_KINDS` (0 plane, 1 cylinder,
    2 cone, 3 sphere, 4 torus, 5 freeform); the header's comment lists the codes.

    Parameters
    ----------
    path : str or path-like
    V : (n, 3) float64
        Written as ``double`` x, y, z.
    F : (m, 3) int64
    labels : (m,) int64
        Face labels ``0..k-1``; colours from :func:`label_colors`.
    surface_kinds : list of str, optional
        Surface kind of every label.
    """
    from ..surfaces.model import SURFACE_KINDS

    labels = np.asarray(labels, dtype=np.int64)
    C = label_colors(int(labels.max()) + 1 if len(labels) else 0)[labels]
    fields = [("n", "u1"), ("v", "<i4", (3,)), ("label", "<i4"), ("r", "u1"), ("g", "u1"),
              ("b", "u1")]
    extra = ""
    if surface_kinds is not None:
        fields.append(("surface_type", "u1"))
        codes = " ".join(f"{i}={k}" for i, k in enumerate(SURFACE_KINDS))
        extra = "property uchar surface_type\n"
    header = (
        "ply\nformat binary_little_endian 1.0\ncomment igl_heatseg segmentation\n"
        + (f"comment surface_type {codes}\n" if surface_kinds is not None else "")
        + f"element vertex {len(V)}\nproperty double x\nproperty double y\nproperty double z\n"
        f"element face {len(F)}\nproperty list uchar int vertex_indices\nproperty int label\n"
        "property uchar red\nproperty uchar green\nproperty uchar blue\n" + extra
        + "end_header\n"
    )
    fdt = np.dtype(fields)
    fa = np.zeros(len(F), dtype=fdt)
    fa["n"] = 3
    fa["v"] = F
    fa["label"] = labels
    fa["r"], fa["g"], fa["b"] = C[:, 0], C[:, 1], C[:, 2]
    if surface_kinds is not None:
        code = np.array([SURFACE_KINDS.index(k) for k in surface_kinds], dtype=np.uint8)
        fa["surface_type"] = code[labels]
    with open(path, "wb") as fh:
        fh.write(header.encode("ascii"))
        fh.write(np.ascontiguousarray(V, dtype="<f8").tobytes())
        fh.write(fa.tobytes())


def write_report(path: str | os.PathLike, report: dict) -> None:
    """Write a JSON report (numpy scalars and arrays converted), indented."""

    def conv(o):
        if isinstance(o, np.integer):
            return int(o)
        if isinstance(o, np.floating):
            return float(o)
        if isinstance(o, np.ndarray):
            return o.tolist()
        if isinstance(o, Path):
            return str(o)
        raise TypeError(f"not JSON serialisable: {type(o)}")

    Path(path).write_text(json.dumps(report, indent=2, default=conv) + "\n")


def write_segmentation(
    out_dir: Path, mesh, seg, extra: dict | None = None, t_start: float | None = None
) -> dict:
    """Write ``labels.txt``, ``vertex_labels.txt``, ``segmented.ply`` and ``report.json``.

    Parameters
    ----------
    out_dir : Path
        Created if missing.
    mesh : CleanMesh
    seg : Segmentation
    extra : dict, optional
        More report entries (e.g. ``input``, ``timings`` of loading).
    t_start : float, optional
        ``time.perf_counter()`` at the start of the job; sets ``timings["total"]``.

    Returns
    -------
    report : dict
        What was written to ``report.json``.

    Notes
    -----
    ``labels.txt`` has one line per input face, in the input's face order.
    ``vertex_labels.txt`` has one line per input vertex; ``-1`` marks a vertex no face uses.
    ``segmented.ply`` holds the cleaned mesh (duplicate vertices merged) in the input's face
    order, with per-face ``label`` and ``red green blue``.
    With trimming curves (robust mode), ``boundaries.obj`` holds them
    (:func:`write_boundary_curves`) and ``report.json`` a ``boundary_curves`` list.
    """
    t = time.perf_counter()
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    write_labels(out_dir / "labels.txt", seg.labels)
    vlab = np.full(mesh.n_input_vertices, -1, dtype=np.int64)
    ref = mesh.vertex_map >= 0
    vlab[ref] = seg.vertex_labels[mesh.vertex_map[ref]]
    write_labels(out_dir / "vertex_labels.txt", vlab)
    kinds = None
    if getattr(seg, "surfaces", None) is not None:
        kinds = [s.kind for s in seg.surfaces]
    write_segmented_ply(out_dir / "segmented.ply", mesh.V, mesh.F, seg.labels, kinds)
    report = {
        "igl_heatseg": __version__,
        "faces": int(mesh.F.shape[0]),
        "vertices": int(mesh.n_input_vertices),
        "vertices_used": int(mesh.V.shape[0]),
        "merged_vertices": mesh.merged_vertices,
        "unreferenced_vertices": mesh.unreferenced_vertices,
        "components": seg.components,
        "seedless_components": seg.seedless_components,
        "theta": seg.theta,
        "eps": seg.eps,
        "sharp_edges": int(seg.sharp_edges.shape[0]),
        "seed_vertices": int(seg.seed_mask.sum()),
        "initial_groups": seg.initial_groups,
        "dropped_groups": int(seg.initial_groups - len(seg.kept_groups)),
        "segments": seg.num_segments,
        "segment_areas": seg.segment_areas,
        "segment_faces": np.bincount(seg.labels, minlength=seg.num_segments),
        "initial_segment_areas": np.sort(seg.initial_areas)[::-1],
        "merged_islands": seg.merged_islands,
        "merged_islands_initial": seg.merged_islands_initial,
        "heat_sum_error": seg.heat_sum_error,
    }
    types = getattr(seg, "primitive_types", None)
    report["mode"] = "robust" if types is not None else "paper"
    if types is not None:
        report["primitive_types"] = list(types)
        report["primitive_rms"] = seg.primitive_rms
        report["subdivided"] = int(getattr(seg, "subdivided", 0))
        report["refinement"] = str(getattr(seg, "refinement", "off"))
    surfaces = getattr(seg, "surfaces", None)
    if surfaces is not None:
        report["surfaces"] = [dict(segment=i, **s.to_dict()) for i, s in enumerate(surfaces)]
    curves = getattr(seg, "boundary_curves", None)
    if curves is not None:
        write_boundary_curves(out_dir / "boundaries.obj", curves)
        report["boundary_curves"] = [dict(curve=i, **c.to_dict()) for i, c in enumerate(curves)]
    report.update(extra or {})
    timings = dict(report.pop("timings", {}))
    timings.update(seg.timings)
    timings["write"] = time.perf_counter() - t
    if t_start is not None:
        timings["total"] = time.perf_counter() - t_start
    report["timings"] = timings
    write_report(out_dir / "report.json", report)
    return report


def write_boundary_curves(path: str | os.PathLike, curves: list) -> None:
    """Trimming curves as OBJ polylines: one object ``curve_<i>_<left>_<right>_<method>`` per
    curve (``left``/``right``: the segment labels on either side, ``-1`` for the mesh border),
    its points as ``v`` lines and one ``l`` element through them (a closed curve ends on its
    first point).

    Parameters
    ----------
    path : path-like
    curves : list of BoundaryCurve
        :func:`igl_heatseg.surfaces.boundaries.boundary_curves` (``points (q, 3)``, ``left``,
        ``right``, ``method``, ``closed``).

    Examples
    --------
    >>> import tempfile, numpy as np
    >>> from types import SimpleNamespace as C
    >>> c = C(left=0, right=1, method="intersection", closed=False,
    ...       points=np.array([[0.0, 0, 0], [1, 0, 0]]))
    >>> with tempfile.TemporaryDirectory() as d:
    ...     write_boundary_curves(f"{d}/b.obj", [c])
    ...     print(open(f"{d}/b.obj").read().splitlines()[1:])
    ['o curve_0_0_1_intersection', 'v 0 0 0', 'v 1 0 0', 'l 1 2']
    """
    lines = ["# igl_heatseg trimming curves: o curve_<i>_<left>_<right>_<method>"]
    base = 1
    for i, c in enumerate(curves):
        P = np.asarray(c.points, dtype=np.float64)
        q = len(P) - 1 if c.closed else len(P)
        lines.append(f"o curve_{i}_{c.left}_{c.right}_{c.method}")
        lines += ["v " + " ".join(f"{x:.17g}" for x in p) for p in P[:q]]
        idx = list(range(base, base + q)) + ([base] if c.closed else [])
        lines.append("l " + " ".join(map(str, idx)))
        base += q
    Path(path).write_text("\n".join(lines) + "\n")


def _check_write(V, F, n_name: str) -> tuple[np.ndarray, np.ndarray]:
    V = np.asarray(V, dtype=np.float64)
    F = np.asarray(F)
    if V.ndim != 2 or V.shape[1] != 3:
        raise MeshError(f"`V` should have shape (n,3), shape is {V.shape}")
    if F.ndim != 2 or F.shape[1] != 3 or F.dtype.kind not in "iu":
        raise MeshError(f"`F` should be (m,3) integers, got shape {F.shape} dtype {F.dtype}")
    if F.size and (F.min() < 0 or F.max() >= len(V)):
        raise MeshError(f"`F` has indices outside 0..{len(V) - 1} ({n_name})")
    return V, F.astype(np.int64)


#: Rows formatted per ``%`` call in :func:`_write`.
_WRITE_ROWS = 65536


def _write_rows(fh, fmt: str, A: np.ndarray) -> None:
    """Write ``fmt % row`` for every row of ``A``: one ``%`` per block of rows (one format
    string repeated), 1.8-2.4x faster than one per row, same text."""
    for s in range(0, len(A), _WRITE_ROWS):
        B = A[s : s + _WRITE_ROWS]
        fh.write((fmt * len(B)) % tuple(B.ravel().tolist()))


def _write(path, header: str, V: np.ndarray, VT: np.ndarray, F: np.ndarray, FT: np.ndarray):
    I = np.stack([F + 1, FT + 1], axis=2).reshape(-1, 6)
    with open(os.fspath(path), "w", encoding="ascii") as fh:
        fh.write(header + "\n")
        _write_rows(fh, "v %.17g %.17g %.17g\n", V)
        _write_rows(fh, "vt %.17g %.17g\n", VT)
        _write_rows(fh, "f %d/%d %d/%d %d/%d\n", I)


def write_chart_obj(path: str | os.PathLike, V: ArrayLike, F: ArrayLike, UV: ArrayLike) -> None:
    """Write one chart as OBJ: ``v`` (3D positions), ``vt`` (its UV), ``f v/vt v/vt v/vt``.

    Parameters
    ----------
    path : str or path-like
    V : (n, 3) array_like of float
        The chart's (cut) vertex positions.
    F : (m, 3) array_like of int
        Triangles, 0-based (written 1-based).
    UV : (n, 2) array_like of float
        One UV per vertex (``vt`` index = ``v`` index).

    Raises
    ------
    MeshError
        Mismatched shapes or out-of-range indices.
    """
    V, F = _check_write(V, F, "chart")
    UV = np.asarray(UV, dtype=np.float64)
    if UV.shape != (V.shape[0], 2):
        raise MeshError(f"`UV` should have shape ({V.shape[0]},2), shape is {UV.shape}")
    _write(path, "# igl_heatseg chart: v = 3D position, vt = chart UV", V, UV, F, F)


def _unique_rows(P: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``np.unique(P, axis=0, return_inverse=True)`` for (k, 2) floats, via one lexsort."""
    order = np.lexsort((P[:, 1], P[:, 0]))
    S = P[order]
    new = np.ones(len(S), dtype=bool)
    new[1:] = (S[1:] != S[:-1]).any(axis=1)
    inv = np.empty(len(P), dtype=np.int64)
    inv[order] = np.cumsum(new) - 1
    return S[new], inv


def write_atlas_obj(
    path: str | os.PathLike, V_input: ArrayLike, F_input: ArrayLike, corner_uv: ArrayLike
) -> None:
    """Write the whole mesh with per-corner UVs (one ``vt`` per distinct corner UV).

    Vertices and faces are written in the input's order, so the OBJ's faces line up with
    ``F_input`` (and per-face label files).

    Parameters
    ----------
    path : str or path-like
    V_input : (n, 3) array_like of float
    F_input : (m, 3) array_like of int
    corner_uv : (m, 3, 2) array_like of float
        UV of corner ``j`` of face ``f`` (e.g. from :func:`atlas_corner_uv`).

    Raises
    ------
    MeshError
        Mismatched shapes, out-of-range indices or non-finite UVs.
    """
    V, F = _check_write(V_input, F_input, "mesh")
    C = np.asarray(corner_uv, dtype=np.float64)
    if C.shape != (F.shape[0], 3, 2):
        raise MeshError(f"`corner_uv` should have shape ({F.shape[0]},3,2), shape is {C.shape}")
    if not np.isfinite(C).all():
        bad = np.flatnonzero(~np.isfinite(C).all(axis=(1, 2)))
        raise MeshError(f"`corner_uv` is not finite on {len(bad)} face(s), e.g. {bad[:5].tolist()}")
    VT, inv = _unique_rows(C.reshape(-1, 2))
    FT = inv.reshape(-1, 3)
    _write(path, "# igl_heatseg atlas: per-corner UVs in [0,1]^2", V, VT, F, FT)


def write_run(
    out_dir: str | os.PathLike,
    result,
    extra: dict | None = None,
    t_start: float | None = None,
    pictures: dict | None = None,
) -> dict:
    """Write a :class:`~igl_heatseg.pipeline.PipelineResult`: what ``segment`` writes, the charts
    and the atlas.

    Parameters
    ----------
    out_dir : str or path-like
        Created if missing.
    result : PipelineResult
    extra : dict, optional
        More report entries (e.g. ``input``, ``timings`` of loading).
    t_start : float, optional
        ``time.perf_counter()`` at the start of the job; sets ``timings["total"]``.
    pictures : dict, optional
        ``{"files": {name: Path}, "seconds": float}`` of pictures already written into
        ``out_dir`` (listed in the report).

    Returns
    -------
    report : dict
        What was written to ``report.json``.
    """
    out = Path(out_dir)
    t = time.perf_counter()
    (out / "charts").mkdir(parents=True, exist_ok=True)
    for ch in result.charts:
        if ch.param is not None:
            write_chart_obj(
                out / "charts" / f"chart_{ch.id:03d}.obj", ch.cut.V, ch.cut.F, ch.param.UV
            )
    write_atlas_obj(out / "atlas.obj", result.mesh.V, result.mesh.F, result.corner_uv)
    report = {k: v for k, v in result.report.items() if k != "timings"}
    report.update(extra or {})
    timings = dict(report.pop("timings", {}))
    timings.update({k: v for k, v in result.report["timings"].items() if k != "total"})
    timings["write_charts"] = time.perf_counter() - t
    if pictures is not None:
        report["pictures"] = sorted(Path(p).name for p in pictures["files"].values())
        timings["pictures"] = pictures["seconds"]
    report["timings"] = timings
    return write_segmentation(out, result.mesh, result.segmentation, report, t_start=t_start)


#: Written last into an output folder by :func:`atomic_dir`: its presence means "complete".
COMPLETE_MARKER = "report.json"


def is_complete(out_dir: str | os.PathLike) -> bool:
    """True when ``out_dir`` holds a finished result (written through :func:`atomic_dir`)."""
    return (Path(out_dir) / COMPLETE_MARKER).is_file()


@contextlib.contextmanager
def atomic_dir(out_dir: str | os.PathLike):
    """Write a result folder atomically: into a temporary sibling, renamed when complete.

    An interrupted or failed job leaves no folder that looks finished: the temporary folder is
    removed on an exception, and ``out_dir`` appears (replacing an older one) only after the
    block ends without one.

    Parameters
    ----------
    out_dir : str or path-like
        The final folder. Its parent is created; it must not be an existing file.

    Yields
    ------
    tmp : pathlib.Path
        The folder to write into.

    Raises
    ------
    MeshError
        ``out_dir`` is an existing file, or its parent cannot be written.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> root = pathlib.Path(tempfile.mkdtemp())
    >>> with atomic_dir(root / "out") as tmp:
    ...     _ = (tmp / "report.json").write_text("{}")
    >>> sorted(p.name for p in (root / "out").iterdir())
    ['report.json']
    """
    out = Path(out_dir)
    if out.exists() and not out.is_dir():
        raise MeshError(f"{out}: output path is a file, not a folder")
    try:
        out.parent.mkdir(parents=True, exist_ok=True)
        tmp = Path(tempfile.mkdtemp(prefix=f".{out.name}.", suffix=".tmp", dir=out.parent))
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o777 & ~umask)  # mkdtemp makes 0700; the result gets the usual mode
    except OSError as exc:
        raise MeshError(f"{out}: cannot write the output folder ({exc.strerror or exc})") from None
    try:
        yield tmp
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    old = None
    if out.exists():
        old = out.parent / f".{out.name}.{os.getpid()}.old"
        shutil.rmtree(old, ignore_errors=True)
        os.replace(out, old)
    os.replace(tmp, out)
    if old is not None:
        shutil.rmtree(old, ignore_errors=True)
