"""The area distribution plot (Fig. 12), chart maps in 2D (Fig. 14) and sweep plots."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("matplotlib")

from igl_heatseg.viz import plots  # noqa: E402

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"
FANDISK = Path(__file__).resolve().parent.parent / "data" / "fandisk.off"


@pytest.fixture(scope="module")
def fandisk_run():
    from igl_heatseg.io import load_mesh
    from igl_heatseg.pipeline import run_pipeline

    return run_pipeline(load_mesh(FANDISK))


def test_area_threshold_is_eps_times_largest():
    assert plots.area_threshold([4.0, 1.0, 0.1], 0.05) == pytest.approx(0.2)
    assert plots.area_threshold([3.0, 9.0], 0.5) == pytest.approx(4.5)
    assert plots.area_threshold([], 0.5) == 0.0


def test_area_plot_bars_line_and_legend(tmp_path):
    areas = np.array([0.5, 10.0, 0.01, 2.0, 0.3])  # threshold 0.05 * 10 = 0.5: 3 kept, 2 dropped
    out = tmp_path / "areas.png"
    fig = plots.plot_area_distribution(areas, 0.05, out, title="t")
    assert out.read_bytes()[:8] == PNG_MAGIC
    ax = fig.axes[0]
    heights = [p.get_height() for p in ax.patches]
    assert sorted(heights, reverse=True) == heights  # sorted, decreasing
    assert heights == sorted(areas.tolist(), reverse=True)
    kept = [
        p
        for p in ax.patches
        if np.allclose(p.get_facecolor()[:3], (0x1F / 255, 0x77 / 255, 0xB4 / 255))
    ]
    assert len(kept) == 3  # 10, 2 and 0.5 (equal to the threshold is kept, as in segment_mesh)
    line = [ln for ln in ax.get_lines() if np.allclose(ln.get_ydata(), 0.5)]
    assert len(line) == 1
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert "kept: 3 groups" in labels and "dropped: 2 groups" in labels
    assert ax.get_yscale() == "log"
    fig2 = plots.plot_area_distribution(areas, 0.05, log_scale=False)
    assert fig2.axes[0].get_yscale() == "linear"


def test_area_plot_matches_segmentation_eps_round():
    from igl_heatseg.io.meshes import load_mesh
    from igl_heatseg.segmentation.paper import segment_mesh

    seg = segment_mesh(load_mesh(FANDISK))
    fig = plots.plot_area_distribution(seg.initial_areas, seg.eps)
    labels = [t.get_text() for t in fig.axes[0].get_legend().get_texts()]
    assert f"kept: {len(seg.kept_groups)} groups" in labels


@pytest.mark.parametrize(
    "areas, eps, msg",
    [
        ([], 0.05, "empty"),
        ([1.0, -1.0], 0.05, "non-negative"),
        ([1.0, np.nan], 0.05, "finite"),
        ([1.0], 1.5, "eps"),
    ],
)
def test_area_plot_rejects_bad_input(areas, eps, msg):
    with pytest.raises(ValueError, match=msg):
        plots.plot_area_distribution(areas, eps)


def _with_flips(chart, flipped):
    """The chart with its map marked not bijective, ``flipped`` (rows of ``cut.F``) flipped."""
    p = chart.param
    cert = dataclasses.replace(p.certificate, flipped_faces=np.asarray(flipped, dtype=np.int64))
    return dataclasses.replace(
        chart, param=dataclasses.replace(p, bijective=False, certificate=cert)
    )


def test_chart_maps_one_panel_per_chart_and_flips_red(fandisk_run, tmp_path):
    V = fandisk_run.mesh.V
    a, b = fandisk_run.charts[:2]
    unmapped = dataclasses.replace(fandisk_run.charts[2], cut=None, param=None)
    out = tmp_path / "charts.png"
    fig = plots.plot_chart_maps([a, _with_flips(b, [1]), unmapped], V, out)
    assert out.read_bytes()[:8] == PNG_MAGIC
    drawn = {ax.get_title().split(" (")[0]: ax for ax in fig.axes if ax.collections}
    assert set(drawn) == {f"chart {a.id}", f"chart {b.id}"}  # the chart without a map skipped
    ax = drawn[f"chart {b.id}"]
    cols = ax.collections[0].get_facecolors()
    assert len(cols) == len(b.cut.F)
    assert np.allclose(cols[1][:3], (1, 0, 0)) and not np.allclose(cols[0][:3], (1, 0, 0))
    assert "NOT bijective" in ax.get_title() and b.param.method in ax.get_title()
    assert " bijective" in drawn[f"chart {a.id}"].get_title()
    with pytest.raises(ValueError, match="no charts"):
        plots.plot_chart_maps([], V)
    with pytest.raises(ValueError, match="no charts"):
        plots.plot_chart_maps([unmapped], V)


def test_sweep_plot(tmp_path):
    out = tmp_path / "sweep.png"
    fig = plots.plot_sweep([0.1, 0.2, 0.3], [30, 15, 8], "theta", out, extra=[100, 100, 90])
    assert out.read_bytes()[:8] == PNG_MAGIC
    assert len(fig.axes) == 2
    assert list(fig.axes[0].get_lines()[0].get_ydata()) == [30, 15, 8]


def test_area_plot_rank_axis_log_for_many_groups():
    few = plots.plot_area_distribution(np.geomspace(1, 1e-3, plots.LOG_RANK_ABOVE), 0.05)
    many = plots.plot_area_distribution(np.geomspace(1, 1e-3, plots.LOG_RANK_ABOVE + 1), 0.05)
    assert few.axes[0].get_xscale() == "linear" and many.axes[0].get_xscale() == "log"


def test_missing_matplotlib_gives_install_hint(monkeypatch):
    import sys

    monkeypatch.setitem(sys.modules, "matplotlib", None)
    with pytest.raises(ImportError, match=r"pip install igl_heatseg\[viz\]"):
        plots.plot_area_distribution([1.0, 0.5], 0.05)
