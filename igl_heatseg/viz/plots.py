"""matplotlib figures: the area distribution (paper Fig. 12), chart maps in 2D (Fig. 14), sweeps.

matplotlib is a soft dependency, imported inside the functions (Agg backend for files, so
no display is needed), with an install hint (``pip install igl_heatseg[viz]``).
"""

from __future__ import annotations

import logging
import math
import os
from collections.abc import Iterable, Sequence
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike

from ..segmentation.params import check_segment_params, eps_keep

if TYPE_CHECKING:
    from ..pipeline import Chart

__all__ = ["area_threshold", "plot_area_distribution", "plot_chart_maps", "plot_sweep"]

log = logging.getLogger(__name__)

#: Install hint shown when matplotlib is missing.
INSTALL_HINT: str = "pip install igl_heatseg[viz]"

#: Colours of kept and dropped groups (bars) and of the eps line.
KEPT_COLOR = "#1f77b4"
DROPPED_COLOR = "#bbbbbb"
EPS_LINE_COLOR = "#d62728"

#: Above this many groups the x axis (rank) is logarithmic, so the few large groups stay visible.
LOG_RANK_ABOVE: int = 200

#: Figure DPI for files.
DPI: int = 150


def _pyplot():
    """Import matplotlib.pyplot on the Agg backend (no display), or raise with the hint."""
    try:
        import matplotlib
    except ImportError as exc:
        raise ImportError(f"igl_heatseg.viz.plots needs matplotlib: {INSTALL_HINT}") from exc
    import matplotlib.pyplot as plt

    if plt.get_backend().lower() not in ("agg", "module://matplotlib_inline.backend_inline"):
        try:
            matplotlib.use("Agg")
        except Exception:  # noqa: BLE001 - keep whatever backend is active
            log.debug("could not switch matplotlib to Agg")
    return plt


def area_threshold(areas: ArrayLike, eps: float) -> float:
    """The eps round's threshold ``eps * max(areas)`` on one component (paper rule).

    Parameters
    ----------
    areas : (k,) array_like of float
        Initial segment areas (``Segmentation.initial_areas``).
    eps : float
        Area fraction in [0, 1].

    Returns
    -------
    float
        Groups with area strictly below this lose their seeds (for a one-component mesh;
        :func:`igl_heatseg.segmentation.paper.segment_mesh` applies it per connected component).

    Examples
    --------
    >>> area_threshold([4.0, 1.0, 0.1], 0.05)
    0.2
    """
    a = np.asarray(areas, dtype=np.float64)
    return float(eps * a.max()) if a.size else 0.0


def plot_area_distribution(
    areas: ArrayLike,
    eps: float,
    path: str | os.PathLike | None = None,
    *,
    log_scale: bool = True,
    title: str | None = None,
    ax=None,
    components: ArrayLike | None = None,
    reference: str = "largest",
):
    """Bar chart of the sorted initial segment areas with the line ``eps * A_largest`` (Fig. 12).

    Bars above the line (kept groups) are blue, bars below (dropped) grey; the legend gives
    how many of each.  With more than :data:`LOG_RANK_ABOVE` groups the rank axis is
    logarithmic too.  This is how a user chooses eps: the line should sit in the gap between
    the real faces of the part and the noise groups.

    Parameters
    ----------
    areas : (k,) array_like of float
        Area of every initial segment (``Segmentation.initial_areas``), any order.
    eps : float
        Area fraction in [0, 1].
    path : str or path-like, optional
        Write a PNG here (parent directory must exist).
    log_scale : bool
        Logarithmic area axis (default), needed when noise gives thousands of tiny groups.
    title : str, optional
    ax : matplotlib Axes, optional
        Draw into this Axes instead of a new figure.
    components : (k,) array_like of int, optional
        Connected component of each group (``Segmentation.group_component``): bars are marked
        kept or dropped by the segmentation's own rule
        (:func:`igl_heatseg.segmentation.params.eps_keep`), per component; the line is drawn
        for the component of the largest segment.
    reference : {"largest", "component"}
        What eps is a fraction of (the mode's rule: ``"component"`` in robust mode).

    Returns
    -------
    matplotlib.figure.Figure

    Raises
    ------
    ValueError
        ``areas`` is empty or holds negative or non-finite values, or ``eps`` is outside [0, 1].
    """
    a = np.asarray(areas, dtype=np.float64).ravel()
    if a.size == 0:
        raise ValueError("areas is empty: nothing to plot")
    if not np.all(np.isfinite(a)) or (a < 0).any():
        raise ValueError("areas must be finite and non-negative")
    check_segment_params(math.pi / 2, eps)
    plt = _pyplot()
    comp = np.zeros(a.size, dtype=np.int64) if components is None else np.asarray(components)
    if comp.shape != a.shape:
        raise ValueError(f"components should have shape {a.shape}, shape is {comp.shape}")
    order = np.argsort(-a, kind="stable")
    a, comp = a[order], comp[order]
    kept = eps_keep(a, comp, eps, reference)
    # the line: the threshold of the largest segment's component
    in_top = comp == comp[0]
    ref_area = a[in_top].sum() if reference == "component" else a[0]
    thr = eps * ref_area
    if ax is None:
        fig, ax = plt.subplots(figsize=(8, 4.5))
    else:
        fig = ax.figure
    eps_label = (
        f"eps * {'A_component' if reference == 'component' else 'A_largest'} = "
        f"{eps:g} * {ref_area:.3g} = {thr:.3g}"
        + (" (largest component)" if len(np.unique(comp)) > 1 else "")
    )
    _area_bars(ax, a, kept, thr, eps_label)
    _area_axes(ax, a, log_scale, title)
    fig.tight_layout()
    if path is not None:
        fig.savefig(Path(path), dpi=DPI)
        log.info("wrote %s", path)
    return fig


def _area_bars(ax, a: np.ndarray, kept: np.ndarray, thr: float, eps_label: str) -> None:
    """Bars of the sorted areas ``a`` (kept blue, dropped grey) and the dashed eps line."""
    x = np.arange(1, a.size + 1)
    width = 0.8 if a.size < 200 else 1.0
    ax.bar(x[kept], a[kept], width=width, color=KEPT_COLOR, label=f"kept: {int(kept.sum())} groups")
    ax.bar(
        x[~kept],
        a[~kept],
        width=width,
        color=DROPPED_COLOR,
        label=f"dropped: {int((~kept).sum())} groups",
    )
    ax.axhline(thr, color=EPS_LINE_COLOR, lw=1.5, ls="--", label=eps_label)


def _area_axes(ax, a: np.ndarray, log_scale: bool, title: str | None) -> None:
    """Scales, limits, labels, title and legend of the area plot (``a`` sorted, decreasing)."""
    if log_scale:
        pos = a[a > 0]
        ax.set_yscale("log")
        if pos.size:
            ax.set_ylim(pos.min() * 0.5, a[0] * 2)
    many = a.size > LOG_RANK_ABOVE
    if many:
        ax.set_xscale("log")
        ax.set_xlim(0.5, a.size * 1.1)
    else:
        ax.set_xlim(0.3, a.size + 0.7)
    ax.set_xlabel("initial segment, sorted by area" + (" (rank, log scale)" if many else ""))
    ax.set_ylabel("area" + (" (log scale)" if log_scale else ""))
    ax.set_title(title or "Initial segment areas")
    ax.legend(loc="upper right", fontsize=9)


def plot_chart_maps(
    charts: Iterable[Chart],
    V: ArrayLike,
    path: str | os.PathLike | None = None,
    *,
    max_charts: int = 24,
    ncols: int | None = None,
    edges: bool = True,
):
    """Each chart's 2D map in its own panel (paper Fig. 14); flipped triangles in red.

    Parameters
    ----------
    charts : iterable of igl_heatseg.pipeline.Chart
        Charts without a map are not drawn (:func:`igl_heatseg.viz.layout.drawable_charts`);
        panel titles number charts by ``Chart.id``.
    V : (n, 3) array_like of float
        Vertices of the whole mesh.
    path : str or path-like, optional
        Write a PNG here.
    max_charts : int
        Draw at most this many (the largest by face count).
    ncols : int, optional
        Panels per row (default about sqrt of the count).
    edges : bool
        Draw triangle edges.

    Returns
    -------
    matplotlib.figure.Figure

    Raises
    ------
    ValueError
        No chart has a map.
    """
    from matplotlib.collections import PolyCollection

    from ..io.results import label_colors
    from .layout import drawable_charts

    plt = _pyplot()
    ch = drawable_charts(charts)
    if not ch:
        raise ValueError("no charts to plot")
    order = sorted(range(len(ch)), key=lambda i: -len(ch[i].cut.F))[:max_charts]
    n = len(order)
    ncols = ncols or int(np.ceil(np.sqrt(n)))
    nrows = int(np.ceil(n / ncols))
    fig, axes = plt.subplots(nrows, ncols, figsize=(3.2 * ncols, 3.2 * nrows), squeeze=False)
    pal = label_colors(max(c.segment for c in ch) + 1) / 255.0
    for ax in axes.ravel():
        ax.set_axis_off()
    for ax, i in zip(axes.ravel(), order, strict=False):  # more panels than charts
        _chart_panel(ax, ch[i], pal, edges, PolyCollection)
    fig.tight_layout()
    if path is not None:
        fig.savefig(Path(path), dpi=DPI)
    return fig


def _chart_panel(ax, c: Chart, pal: np.ndarray, edges: bool, PolyCollection) -> None:
    """One chart's map in ``ax``: faces in the segment's colour, flipped ones red."""
    F = np.asarray(c.cut.F, dtype=np.int64)
    tri = np.asarray(c.param.UV, dtype=np.float64)[:, :2][F]
    col = np.tile(pal[c.segment], (len(F), 1))
    cert = c.param.certificate
    if cert is not None and len(cert.flipped_faces):
        col[np.asarray(cert.flipped_faces, dtype=np.int64)] = (1.0, 0.0, 0.0)
    pc = PolyCollection(
        tri, facecolors=col, edgecolors=(0, 0, 0, 0.35) if edges else "none", linewidths=0.15
    )
    ax.add_collection(pc)
    ax.set_xlim(tri[..., 0].min(), tri[..., 0].max())
    ax.set_ylim(tri[..., 1].min(), tri[..., 1].max())
    ax.set_aspect("equal")
    bij = c.param.bijective
    status = "" if bij is None else (" bijective" if bij else " NOT bijective")
    meth = f" {c.param.method}" if c.param.method else ""
    ax.set_title(f"chart {c.id} ({len(F)} tri){meth}{status}", fontsize=8)


def plot_sweep(
    values: Sequence[float],
    counts: Sequence[float],
    xlabel: str,
    path: str | os.PathLike | None = None,
    *,
    ylabel: str = "segments",
    extra: Sequence[float] | None = None,
    extra_label: str = "bijective charts (%)",
    ax=None,
):
    """Line plot of a parameter sweep (segment count vs theta or eps), optional second axis.

    Parameters
    ----------
    values : (s,) float
        Parameter values.
    counts : (s,) float
        Segment count (or any measure) per value.
    xlabel : str
    path : str or path-like, optional
    ylabel : str
    extra : (s,) float, optional
        Second series on a right axis (e.g. the share of bijective charts).
    extra_label : str
    ax : matplotlib Axes, optional

    Returns
    -------
    matplotlib.figure.Figure
    """
    plt = _pyplot()
    if ax is None:
        fig, ax = plt.subplots(figsize=(6, 3.5))
    else:
        fig = ax.figure
    ax.plot(values, counts, "o-", color=KEPT_COLOR)
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel, color=KEPT_COLOR)
    ax.grid(alpha=0.3)
    if extra is not None:
        ax2 = ax.twinx()
        ax2.plot(values, extra, "s--", color=EPS_LINE_COLOR)
        ax2.set_ylabel(extra_label, color=EPS_LINE_COLOR)
    fig.tight_layout()
    if path is not None:
        fig.savefig(Path(path), dpi=DPI)
    return fig
