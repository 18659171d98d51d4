"""Compare parameterization methods on the charts of a segmented mesh.

``igl-heatseg compare-param MESH`` segments MESH (paper defaults), cuts every chart to a disk
(:func:`igl_heatseg.parameterization.cut.cut_to_disk`) and maps each chart with every method in ``--methods``
(default: Hessian HLLE, Hessian curved, libigl harmonic, libigl LSCM), without fallbacks, all
through the same bijectivity certificate and distortion code
(:func:`igl_heatseg.parameterization.methods.compare_methods`).  It prints one table: chart, faces, method,
bijective, flips, overlaps, distortions, seconds, and a per-method summary.  The pseudo-methods
``param-hlle``, ``param-curved`` and ``param-auto`` run the full chart parameterization
(:func:`igl_heatseg.parameterization.chart.parameterize_chart`: Hessian map, local repair, certified fallbacks)
and report the map each chart got and the share of charts that needed a fallback.
"""

from __future__ import annotations

import logging
from typing import Sequence

import numpy as np

from ..errors import MeshError
from ..mesh.checks import CleanMesh
from ..parameterization.methods import METHODS, PIPELINE_METHODS, compare_methods
from ..segmentation import segment_with_mode

__all__ = ["chart_disks", "compare_param", "format_table", "DEFAULT_METHODS"]

log = logging.getLogger(__name__)

#: Methods compared by default (the issue's four).
DEFAULT_METHODS: tuple[str, ...] = ("hessian-hlle", "hessian-curved", "harmonic", "lscm")

#: Table columns: (key, header, format).
_COLUMNS = (
    ("chart", "chart", "{}"),
    ("faces", "faces", "{}"),
    ("method", "method", "{}"),
    ("result", "result", "{}"),
    ("bijective", "bij", "{}"),
    ("flips", "flips", "{}"),
    ("overlaps", "overl", "{}"),
    ("conformal_mean", "conf_mean", "{:.4f}"),
    ("conformal_max", "conf_max", "{:.3f}"),
    ("area_mean", "area_mean", "{:.4f}"),
    ("area_max", "area_max", "{:.3f}"),
    ("sym_dirichlet", "symDir", "{:.4f}"),
    ("seconds", "sec", "{:.2f}"),
)


def chart_disks(
    mesh: CleanMesh, labels: np.ndarray, min_faces: int = 1
) -> list[tuple[str, np.ndarray, np.ndarray]]:
    """Face-connected pieces of every segment, each cut to a topological disk.

    Parameters
    ----------
    mesh : CleanMesh
        The segmented mesh.
    labels : (m,) int64
        Face labels ``0..k-1``.
    min_faces : int
        Skip pieces with fewer faces.

    Returns
    -------
    charts : list of (name, V, F)
        ``name`` is ``"<segment>.<piece>"``; ``V`` (n', 3), ``F`` (m', 3) the cut disk.  Pieces
        the cutter cannot turn into a disk are skipped with a warning.
    """
    from ..mesh.topology import face_components
    from ..parameterization.cut import cut_to_disk

    out = []
    for s in range(int(labels.max()) + 1 if len(labels) else 0):
        faces = np.flatnonzero(labels == s)
        if len(faces) == 0:
            continue
        count, comp = face_components(mesh.F[faces])
        for c in range(count):
            fc = faces[comp == c]
            if len(fc) < min_faces:
                continue
            name = f"{s}.{c}"
            try:
                res = cut_to_disk(mesh.V, mesh.F[fc], name=f"chart {name}")
            except (MeshError, RuntimeError) as exc:
                log.warning("chart %s: could not cut to a disk: %s", name, exc)
                continue
            if not res.topology_after.is_disk:
                log.warning("chart %s: not a disk after cutting; skipped", name)
                continue
            out.append((name, res.V, res.F))
    return out


def compare_param(
    mesh: CleanMesh,
    theta: float | None = None,
    eps: float | None = None,
    methods: Sequence[str] = DEFAULT_METHODS,
    min_faces: int = 1,
    mode: str = "paper",
) -> list[dict]:
    """Segment, cut to disks and run every method on every chart.

    Parameters
    ----------
    mesh : CleanMesh
        A validated mesh.
    theta, eps : float, optional
        Segmentation parameters (paper defaults when ``None``).
    methods : sequence of str
        Names from :data:`igl_heatseg.parameterization.methods.METHODS` (one map, no fallback) or
        :data:`igl_heatseg.parameterization.methods.PIPELINE_METHODS` (``param-hlle`` ...: the full chart
        parameterization with repair and fallbacks; the row's ``result`` says which map).
    min_faces : int
        Skip charts with fewer faces.
    mode : {"paper", "robust"}
        Segmentation mode; ``theta``/``eps`` ``None`` take its defaults.

    Returns
    -------
    rows : list of dict
        One per (chart, method), see :func:`igl_heatseg.parameterization.methods.compare_methods`.

    Raises
    ------
    MeshError
        Unknown method names.
    """
    known = METHODS + PIPELINE_METHODS
    bad = [m for m in methods if m not in known]
    if bad:
        raise MeshError(f"unknown method(s) {', '.join(bad)}; known: {', '.join(known)}")
    seg = segment_with_mode(mesh, mode, theta, eps)
    charts = chart_disks(mesh, seg.labels, min_faces)
    return compare_methods(charts, methods)


def _fmt(row: dict, key: str, fmt: str) -> str:
    if key not in row:
        return "-"
    v = row[key]
    if isinstance(v, float) and not np.isfinite(v):
        return "inf"
    return fmt.format(v)


def format_table(rows: list[dict]) -> str:
    """Fixed-width text table of :func:`compare_param` rows (one line per row, plus a
    per-method summary: bijective charts, total flips and overlaps, face-weighted mean
    distortions over the charts mapped bijectively, total time).
    """
    cells = [[h for _, h, _ in _COLUMNS]]
    for r in rows:
        line = [_fmt(r, k, f) for k, _, f in _COLUMNS]
        if "error" in r:
            line[3] = "ERR"
        cells.append(line)
    widths = [max(len(c[i]) for c in cells) for i in range(len(_COLUMNS))]
    lines = ["  ".join(c[i].rjust(widths[i]) for i in range(len(c))) for c in cells]
    lines.insert(1, "  ".join("-" * w for w in widths))
    # Summary per method (distortion averaged over the charts the method maps bijectively).
    lines.append("")
    lines.append(
        "method            bijective  flips  overlaps  conf_mean  area_mean  symDir  seconds"
        "   (means: face-weighted over bijective charts)"
    )
    for m in dict.fromkeys(r["method"] for r in rows):
        rs = [r for r in rows if r["method"] == m]
        ok = [r for r in rs if r.get("bijective")]
        w = sum(r["faces"] for r in ok)

        def mean(key, ok=ok, w=w):
            return sum(r["faces"] * r[key] for r in ok) / w if w else float("nan")

        line = (
            f"{m:16s}  {len(ok):4d}/{len(rs):<4d}  {sum(r.get('flips', 0) for r in rs):5d}  "
            f"{sum(r.get('overlaps', 0) for r in rs):8d}  {mean('conformal_mean'):9.4f}  "
            f"{mean('area_mean'):9.4f}  {mean('sym_dirichlet'):6.4f}  "
            f"{sum(r.get('seconds', 0.0) for r in rs):7.2f}"
        )
        if any("result" in r for r in rs):
            results = [r.get("result", "error") for r in rs]
            nfb = sum(bool(r.get("fallback_used")) for r in rs)
            counts = ", ".join(f"{k} {results.count(k)}" for k in dict.fromkeys(results))
            line += f"   fallback {nfb}/{len(rs)} ({counts})"
        lines.append(line)
    return "\n".join(lines)
