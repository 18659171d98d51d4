"""Spikes peeled off charts for packing (issue 13: atlas fill): analytic comb first, then
properties of the split on random spiky charts, then the pipeline and CAD around it."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from scipy.spatial import Delaunay

from igl_heatseg.mesh.geometry import uv_areas
from igl_heatseg.parameterization.chart import parameterize_chart
from igl_heatseg.parameterization.cut import chart_topology, cut_to_disk
from igl_heatseg.parameterization.spikes import packing_cost, split_spikes
from igl_heatseg.parameterization.split import PACKING_METHODS, peel_for_packing


def comb(n_spikes: int = 5, length: float = 8.0):
    """A 10 x 10 grid of unit squares with ``n_spikes`` one-triangle spikes of width 1 and
    the given length on its top side (a coarse export's slivers), as 2-D points and
    counter-clockwise faces; the spikes are the last ``n_spikes`` faces."""
    x, y = np.meshgrid(np.arange(11.0), np.arange(11.0))
    P = np.stack([x.ravel(), y.ravel()], 1)
    i = np.arange(121).reshape(11, 11)[:-1, :-1].ravel()
    F = np.concatenate([np.stack([i, i + 1, i + 12], 1), np.stack([i, i + 12, i + 11], 1)])
    tips, spikes = [], []
    for s in range(n_spikes):
        x0 = 1 + 2 * s
        tips.append([x0 + 0.5, 10 + length])
        spikes.append([110 + x0, 110 + x0 + 1, 121 + s])
    tips, spikes = np.reshape(tips, (-1, 2)), np.reshape(spikes, (-1, 3))
    return np.r_[P, tips], np.r_[F, spikes].astype(np.int64)


def test_comb_loses_its_spikes_and_keeps_its_body():
    P, F = comb()
    pieces = split_spikes(P, F, gap=0.2)
    assert pieces is not None and len(pieces) == 6
    assert np.array_equal(np.sort(np.concatenate(pieces)), np.arange(len(F)))
    body = max(pieces, key=len)
    assert np.array_equal(body, np.arange(200))  # every face of the square stays together
    assert sorted(len(p) for p in pieces)[:5] == [1] * 5
    cost = sum(packing_cost(P, F[p], 0.2) for p in pieces)
    assert cost < 0.8 * packing_cost(P, F, 0.2)  # 133 against 177: the hull over the spikes


def test_short_teeth_and_round_charts_are_left_whole():
    """Spikes shorter than two opening radii are a jagged outline's teeth; a disk has no
    spike at all."""
    P, F = comb(length=0.6)
    assert split_spikes(P, F, gap=0.2) is None
    t = np.linspace(0, 2 * np.pi, 40, endpoint=False)
    r = np.repeat([1.0, 2.0, 3.0], 40)
    D = np.r_[[[0.0, 0.0]], np.c_[r * np.tile(np.cos(t), 3), r * np.tile(np.sin(t), 3)]]
    assert split_spikes(D, Delaunay(D).simplices, gap=0.05) is None


def test_degenerate_charts_are_left_whole_and_long_strips_stay_cheap():
    """No face, one face: nothing to split.  A 1 x 5000 strip lying diagonally in its map:
    the raster is capped (a box of 5000^2 / 2 square units at 96 pixels per square root of
    70 would take 3.6e8 pixels)."""
    P, F = comb()
    assert split_spikes(P, F[:0], 0.1) is None and split_spikes(P, F[:1], 0.1) is None
    assert packing_cost(P, F[:0], 0.1) == 0.0
    n = 5000
    x = np.arange(n + 1.0)
    S = np.r_[np.c_[x, 0 * x], np.c_[x, 0 * x + 1]] @ np.array([[1, 1], [-1, 1]]) / np.sqrt(2)
    i = np.arange(n)
    T = np.r_[np.c_[i, i + 1, i + n + 2], np.c_[i, i + n + 2, i + n + 1]]
    assert split_spikes(S, T, 0.1) is None  # a strip has no spike


def test_packing_cost_is_the_hull_grown_by_half_the_gap():
    P, F = comb(0)
    assert packing_cost(P, F, 0.0) == pytest.approx(100.0)
    assert packing_cost(P, F, 0.4) == pytest.approx(100 + 40 * 0.2 + np.pi * 0.04)
    line = np.array([[0.0, 0.0], [1, 1], [2, 2]])  # no area: a segment of length 2 sqrt(2)
    assert packing_cost(line, np.array([[0, 1, 2]]), 0.1) == pytest.approx(
        2 * np.sqrt(2) * 0.1 + np.pi / 400)


@pytest.mark.parametrize("seed", range(6))
def test_split_pieces_are_disks_covering_every_face_once(seed):
    """Random spiky charts: a blob of Delaunay triangles with random long slivers glued to
    its outline.  Whatever the split, its pieces partition the faces, are disks, and cost
    less room than the chart."""
    rng = np.random.default_rng(seed)
    t = np.sort(rng.uniform(0, 2 * np.pi, 30))  # on a circle: every pair in order is on the hull
    rr = 4 * np.sqrt(rng.uniform(0, 1, 40))
    tt = rng.uniform(0, 2 * np.pi, 40)
    P = np.r_[5 * np.c_[np.cos(t), np.sin(t)], np.c_[rr * np.cos(tt), rr * np.sin(tt)]]
    F = Delaunay(P).simplices.astype(np.int64)
    F[uv_areas(P, F) < 0] = F[uv_areas(P, F) < 0][:, [0, 2, 1]]
    assert chart_topology(F).is_disk
    tips, spikes = [], []
    for k in rng.choice(30, int(rng.integers(1, 6)), replace=False):
        a, b = k, (k + 1) % 30
        mid = (P[a] + P[b]) / 2
        tips.append(mid * rng.uniform(1.8, 2.6))
        spikes.append([a, b, len(P) + len(tips) - 1])
    P2, F2 = np.r_[P, tips], np.r_[F, spikes].astype(np.int64)
    F2[uv_areas(P2, F2) < 0] = F2[uv_areas(P2, F2) < 0][:, [0, 2, 1]]
    assert chart_topology(F2).is_disk
    pieces = split_spikes(P2, F2, gap=0.1)
    assert pieces is not None  # slivers 0.8 to 1.6 times the blob's radius long
    assert np.array_equal(np.sort(np.concatenate(pieces)), np.arange(len(F2)))
    assert all(chart_topology(F2[p]).is_disk for p in pieces)
    assert sum(packing_cost(P2, F2[p], 0.1) for p in pieces) < packing_cost(P2, F2, 0.1)


def test_peeled_pieces_keep_the_map_whatever_its_scale():
    P, F = comb()
    V = np.c_[P, np.zeros(len(P))]
    res = cut_to_disk(V, F)
    param = parameterize_chart(res.V, res.F)
    big = dataclasses.replace(param, UV=param.UV * 1e3)
    sizes = []
    for q in (param, big):
        out = peel_for_packing(res, q, gap=0.2)
        sizes.append(sorted(len(faces) for faces, _, _ in out))
        for faces, sub, piece in out:
            assert piece.bijective and piece.certificate.bijective
            assert np.array_equal(piece.UV, q.UV[np.unique(res.F[faces])])
            assert piece.attempts[-1]["method"] == "spikes peeled for packing"
            assert len(sub.F) == len(faces)
    assert sizes[0] == sizes[1] == [1, 1, 1, 1, 1, 200]
    assert len(peel_for_packing(res, param, gap=0.2, name="comb")) == 6


def test_no_piece_is_peeled_off_more_stretched_than_the_bound_and_its_chart():
    """Spikes whose map is stretched 2.5 times along their length: alone (the scale
    normalised away), each has energy 5.8, above the per-chart bound (5), which the chart as
    a whole meets (4.6); the chart stays whole, unless the bound is raised."""
    from igl_heatseg.parameterization.distortion import distortion

    P, F = comb()
    V = np.c_[P, np.zeros(len(P))]
    res = cut_to_disk(V, F)
    param = parameterize_chart(res.V, res.F)
    UV = res.V[:, :2].copy()  # the flat comb's isometric map, then its tips at 30, not 18
    tips = np.flatnonzero(UV[:, 1] > 10.5)
    UV[tips, 1] = 10 + 2.5 * (UV[tips, 1] - 10)
    sd = distortion(res.V, res.F, UV)
    stretched = dataclasses.replace(param, UV=UV, distortion=sd)
    assert sd["sym_dirichlet"] == pytest.approx((100 * 4.1 + 20 * 7.25) / 120)
    spike = res.F[-1:]
    assert distortion(res.V, spike, UV)["sym_dirichlet"] == pytest.approx(5.8)
    assert len(peel_for_packing(res, stretched, gap=0.2)) == 1
    assert len(peel_for_packing(res, stretched, gap=0.2, sd_max=50.0)) == 6
    assert len(peel_for_packing(res, dataclasses.replace(param, bijective=False), 0.2)) == 1


def test_pipeline_peels_a_comb_only_when_the_atlas_packs_tighter(monkeypatch):
    """A flat comb is one chart, cut across for packing (it is long), then its spikes are
    peeled off: the atlas fills more of its square (both layouts packed).  The pieces keep
    one map, so CAD's freeform fit still gets the chart's map whole.  With the peel giving
    nothing back, only the cut across is left."""
    import igl_heatseg.pipeline.stages as stages
    from igl_heatseg.cad.segments import chart_uvs
    from igl_heatseg.mesh.checks import validate_mesh
    from igl_heatseg.pipeline import run_pipeline
    from igl_heatseg.surfaces.model import Surface

    P, F = comb(length=12.0)
    mesh = validate_mesh(np.c_[P, np.zeros(len(P))], F, "comb")
    res = run_pipeline(mesh)
    assert res.charts_cut_for_packing == 1
    assert all(c.param.bijective and c.split_from == 0 for c in res.charts)
    method = [c.param.attempts[-1]["method"] for c in res.charts]
    peeled = [c for c, m in zip(res.charts, method, strict=True) if m == PACKING_METHODS[1]]
    assert sorted(len(c.faces) for c in peeled)[:5] == [1] * 5  # the spikes
    labels = np.zeros(len(F), np.int64)
    free = [Surface("freeform", {"centroid": mesh.V.mean(axis=0)})]
    ids, UV = chart_uvs(labels, free, res.charts)[0]
    assert len(ids) == len(P) and np.isfinite(UV).all()
    # the pictures draw the pieces as the one map they come from: every vertex at one place
    from igl_heatseg.viz.layout import chart_layout, map_groups

    assert map_groups(res.charts) == [list(range(len(res.charts)))]
    placed = chart_layout(mesh.V, res.charts)
    at: dict = {}
    for c, uv in zip(res.charts, placed, strict=True):
        used = np.unique(c.cut.F)
        for v, xy in zip(c.cut.vertex_map[used], uv[used], strict=True):
            at.setdefault(int(v), []).append(xy)
    assert len(at) == len(P)
    assert max(float(np.ptp(np.array(xy), axis=0).max()) for xy in at.values()) < 1e-9

    monkeypatch.setattr(stages, "peel_for_packing", lambda res, param, gap, name, **kw: [
        (np.arange(len(res.F)), res, param)])
    whole = run_pipeline(mesh)
    assert len(whole.charts) == len(res.charts) - len(peeled) + 1
    assert res.atlas.fill > whole.atlas.fill + 0.1
