"""End-to-end tests for igl_heatseg.pipeline on a capped cylinder (a "can")."""

from __future__ import annotations

import argparse
import json

import igl
import numpy as np
import pytest

from igl_heatseg.cli.run import parse_cut_path, register, write_pictures
from igl_heatseg.errors import MeshError
from igl_heatseg.io import write_run
from igl_heatseg.mesh.checks import validate_mesh
from igl_heatseg.pipeline import run_pipeline

NU, NV, NR = 64, 8, 4
HEIGHT, RADIUS = 2.0, 1.0
#: Relative tolerance for the cut length against the cylinder height.
LENGTH_RTOL = 0.03


def can():
    """Closed cylinder: side (NV x NU quads) and two capped discs (NR rings + centre).

    Vertex ``k*NU + i`` is ring ``k`` (height ``k*HEIGHT/NV``), angle ``2*pi*i/NU``.
    """
    t = np.linspace(0, 2 * np.pi, NU, endpoint=False)
    ring = np.c_[np.cos(t), np.sin(t)] * RADIUS
    V = [np.c_[ring, np.full(NU, k * HEIGHT / NV)] for k in range(NV + 1)]
    F = []
    for k in range(NV):
        for i in range(NU):
            j = (i + 1) % NU
            a, b, c, d = k * NU + i, k * NU + j, (k + 1) * NU + j, (k + 1) * NU + i
            F += [[a, b, c], [a, c, d]]
    n = (NV + 1) * NU
    for z, outer, up in ((0.0, 0, False), (HEIGHT, NV * NU, True)):
        rings = [outer]
        for r in range(NR - 1, 0, -1):
            V.append(np.c_[ring * r / NR, np.full(NU, z)])
            rings.append(n)
            n += NU
        V.append(np.array([[0.0, 0.0, z]]))
        centre = n
        n += 1
        for a0, b0 in zip(rings[:-1], rings[1:], strict=True):
            for i in range(NU):
                j = (i + 1) % NU
                q = [[a0 + i, b0 + i, b0 + j], [a0 + i, b0 + j, a0 + j]]
                F += [f[::-1] for f in q] if up else q
        last = rings[-1]
        for i in range(NU):
            j = (i + 1) % NU
            f = [last + i, centre, last + j]
            F.append(f[::-1] if up else f)
    V = np.concatenate(V)
    F = np.array(F, dtype=np.int64)
    return V, F


@pytest.fixture(scope="module")
def can_mesh():
    V, F = can()
    return validate_mesh(V, F, "can")


def side_chart(res):
    """The side's chart (the only annulus), or one of its pieces when it was cut for
    packing."""
    return next(c for c in res.charts if c.report["topology"]["boundary_loops"] == 2)


def test_can_auto(can_mesh, tmp_path):
    res = run_pipeline(can_mesh)
    write_run(tmp_path, res)
    # the side and two caps; the side (2 pi x 2, longer than PACK_MAX_LENGTH x the square
    # root of the can's area) is then cut across for packing, its map kept
    assert len([c for c in res.charts if c.split_from is None]) == 2
    assert len({c.split_from for c in res.charts if c.split_from is not None}) == 1
    assert res.charts_cut_for_packing == 1
    side = side_chart(res)
    topo = side.report["topology"]
    assert (topo["components"], topo["euler"], topo["boundary_loops"]) == (1, 0, 2)
    assert side.report["cut_method"] == "annulus"
    assert side.report["cut_length"] == pytest.approx(HEIGHT, rel=LENGTH_RTOL)
    for ch in res.charts:
        assert ch.report["parameterized"] and ch.report["bijective"], ch.report
        assert ch.cut.topology_after.is_disk
    # the side unrolls into a rectangle 2*pi*R x H (up to the polygon's perimeter); its
    # pieces keep that map
    pieces = [c for c in res.charts if c.split_from == side.split_from]
    uv = np.vstack([c.param.UV[np.unique(c.cut.F)] for c in pieces])
    ext = np.sort(np.ptp(uv - uv.mean(0), axis=0))
    perimeter = NU * 2 * RADIUS * np.sin(np.pi / NU)
    assert all(c.param.distortion["sym_dirichlet"] < 4.05 for c in pieces)
    assert np.prod(ext) == pytest.approx(perimeter * HEIGHT, rel=0.05)

    # files
    rep = json.loads((tmp_path / "report.json").read_text())
    assert len(rep["charts"]) == len(res.charts)
    for key in (
        "id",
        "faces",
        "area",
        "topology",
        "cut_length",
        "method",
        "bijective",
        "flips",
        "overlaps",
        "distortion",
        "seconds",
    ):
        assert key in rep["charts"][0]
    assert rep["parameterization"]["charts_bijective"] == len(res.charts)
    assert rep["parameterization"]["charts_cut_for_packing"] == 1
    assert (tmp_path / "labels.txt").exists()
    V2, TC, _, F2, FTC, _ = igl.readOBJ(str(tmp_path / "atlas.obj"))
    np.testing.assert_array_equal(F2, can_mesh.F)
    assert TC.min() >= 0 and TC.max() <= 1
    from test_atlas import charts_overlap  # outlines may nest in each other's boxes

    assert not charts_overlap(res.atlas.uvs, [ch.cut.F for ch in res.charts])
    np.testing.assert_array_equal(TC[FTC], res.corner_uv)
    for ch in res.charts:
        Vc, TCc, _, Fc, FTCc, _ = igl.readOBJ(str(tmp_path / "charts" / f"chart_{ch.id:03d}.obj"))
        np.testing.assert_array_equal(Fc, ch.cut.F)
        np.testing.assert_array_equal(TCc, ch.param.UV)


def test_chart_topology_in_the_report_is_the_chart_s_own(can_mesh):
    """With cut="auto" and no paths the report takes cut_to_disk's topology_before: the same
    as chart_topology of the chart, whichever way it is computed."""
    from igl_heatseg.parameterization.cut import chart_topology

    auto = run_pipeline(can_mesh)
    first = run_pipeline(can_mesh, cut="none")  # computed before cutting (and not packed)
    assert len(first.charts) == 3 and len(auto.charts) > 3  # the side cut for packing
    for b in first.charts:  # a piece reports the topology of the chart it was cut from
        mine = [a for a in auto.charts if a.segment == b.segment]
        faces = np.sort(np.concatenate([a.faces for a in mine]))
        assert b.report["topology"] == chart_topology(can_mesh.F[faces]).as_dict()
        assert all(a.report["topology"] == b.report["topology"] for a in mine)


def test_hlle_skip_can_be_turned_off(can_mesh):
    res = run_pipeline(can_mesh, hlle_skip_curvature=0.0)  # every chart curved
    for ch in res.charts:
        first = ch.report["attempts"][0]
        assert first["method"] == "hessian-hlle"
        if first["total_abs_curvature"] > 0:
            assert first["skipped"] and "reason" in first
    res = run_pipeline(can_mesh, hlle_skip_curvature=None)
    assert all("skipped" not in ch.report["attempts"][0] for ch in res.charts)


def test_can_paper_mode_generatrix(can_mesh):
    v0, v1 = 5, NV * NU + 5  # bottom and top of the same generatrix (input ids)
    res = run_pipeline(can_mesh, cut="none", cut_paths=[(v0, v1)])
    side = side_chart(res)
    assert side.report["cut_method"] == "paths"
    assert side.report["cut_length"] == pytest.approx(HEIGHT, rel=1e-12)
    assert side.report["cut_paths"] == [[v0, v1]]
    assert all(ch.report["bijective"] for ch in res.charts)


def test_can_no_cut_reports_non_disk(can_mesh):
    res = run_pipeline(can_mesh, cut="none")
    side = side_chart(res)
    assert side.report["parameterized"] is False
    assert side.report["bijective"] is False
    assert "not a disk" in side.report["error"]
    assert np.all(res.corner_uv[side.faces] == 0)
    assert sum(ch.report["parameterized"] for ch in res.charts) == 2


def test_bad_cut_paths_raise(can_mesh):
    n = can_mesh.n_input_vertices
    with pytest.raises(MeshError, match=f"{n + 3} is outside"):
        run_pipeline(can_mesh, cut_paths=[(0, n + 3)])
    centre_bottom = (NV + 1) * NU + (NR - 1) * NU
    with pytest.raises(MeshError, match="no chart contains both"):
        run_pipeline(can_mesh, cut_paths=[(centre_bottom, centre_bottom + NU * (NR - 1) + 1)])
    with pytest.raises(MeshError, match="starts and ends at one vertex"):
        run_pipeline(can_mesh, cut_paths=[(5, 5)])
    with pytest.raises(MeshError, match="two vertex ids"):
        run_pipeline(can_mesh, cut_paths=[(5, 6, 7)])
    with pytest.raises(MeshError, match="cut"):
        run_pipeline(can_mesh, cut="sometimes")


def test_parse_cut_path():
    assert parse_cut_path("12:345") == (12, 345)
    with pytest.raises(argparse.ArgumentTypeError, match="V0:V1"):
        parse_cut_path("12-345")


def test_run_subcommand(tmp_path):
    V, F = can()
    mesh_path = tmp_path / "can.obj"
    igl.writeOBJ(str(mesh_path), V, F)
    parser = argparse.ArgumentParser()
    register(parser.add_subparsers())
    out = tmp_path / "out"
    args = parser.parse_args(
        ["run", str(mesh_path), "-o", str(out), "--energy", "curved", "--cut-path", "5:517"]
    )
    assert args.cut_path == [(5, 517)]
    assert args.func(args) == 0
    rep = json.loads((out / "report.json").read_text())
    assert rep["parameterization"]["energy"] == "curved"
    assert (out / "atlas.obj").exists() and (out / "charts" / "chart_000.obj").exists()


def test_run_gutter_option(tmp_path, capsys, can_mesh):
    """``--gutter``: the gap between charts relative to the atlas side; a wider gutter fills
    less; out of [0, 0.1] (the packer fails from about 0.2) or not a number, it is refused
    before any work (argparse's exit code 2; the library's MeshError)."""
    from igl_heatseg.cli import main

    V, F = can()
    mesh_path = tmp_path / "can.obj"
    igl.writeOBJ(str(mesh_path), V, F)
    reps = {}
    for g in ("0.001", "0.05"):
        assert main(["run", str(mesh_path), "-o", str(tmp_path / g), "--gutter", g,
                     "--no-pictures"]) == 0
        reps[g] = json.loads((tmp_path / g / "report.json").read_text())["parameterization"]
    assert reps["0.05"]["atlas_gutter"] > 10 * reps["0.001"]["atlas_gutter"] > 0
    assert reps["0.05"]["atlas_fill"] < reps["0.001"]["atlas_fill"]
    capsys.readouterr()
    with pytest.raises(SystemExit) as e:
        main(["run", str(mesh_path), "-o", str(tmp_path / "bad"), "--gutter", "0.2"])
    assert e.value.code == 2 and "must be in [0, 0.1]" in capsys.readouterr().err
    for bad in (float("nan"), 0.2, True, "0.01"):
        with pytest.raises(MeshError, match="gutter"):
            run_pipeline(can_mesh, gutter=bad)


def test_splitting_user_path_is_reported_not_fatal(can_mesh):
    # Both ends on the bottom loop: the path cuts the side in two pieces.
    res = run_pipeline(can_mesh, cut_paths=[(0, NU // 2)])
    side = side_chart(res)
    assert side.report["parameterized"] is False
    assert "2 edge-connected components" in side.report["error"]
    assert sum(ch.report["bijective"] for ch in res.charts) == 2  # the caps


def test_cli_main_run_and_bad_cut_path(tmp_path, capsys):
    from igl_heatseg.cli import main

    V, F = can()
    mesh_path = tmp_path / "can.off"
    igl.write_triangle_mesh(str(mesh_path), V, F)
    assert main(["run", str(mesh_path), "-o", str(tmp_path / "ok")]) == 0
    assert (tmp_path / "ok" / "atlas.obj").exists()
    capsys.readouterr()
    code = main(["run", str(mesh_path), "-o", str(tmp_path / "bad"), "--cut-path", "0:99999"])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2
    assert len(err) == 1 and "99999 is outside" in err[0]


def test_run_with_pictures(can_mesh, tmp_path):
    pytest.importorskip("polyscope")
    res = run_pipeline(can_mesh)
    report = write_run(tmp_path, res, pictures=write_pictures(tmp_path, res))
    # Rendering may be impossible here (no OpenGL): then it is skipped, never fatal.
    for name in report["pictures"]:
        assert (tmp_path / name).stat().st_size > 0


def test_degenerate_map_is_left_out_of_the_atlas(can_mesh, monkeypatch):
    import igl_heatseg.pipeline.stages as pipeline_mod

    real = pipeline_mod.parameterize_chart

    def collapse_side(V, F, *args, **kwargs):
        p = real(V, F, *args, **kwargs)
        if len(F) == 2 * NU * NV:  # the side: pretend its map collapsed
            p.UV = np.zeros_like(p.UV)
        return p

    monkeypatch.setattr(pipeline_mod, "parameterize_chart", collapse_side)
    res = run_pipeline(can_mesh)
    side = side_chart(res)
    assert "atlas_error" in side.report
    assert res.report["parameterization"]["charts_in_atlas"] == 2
    assert np.all(res.corner_uv[side.faces] == 0)


def test_compose_user_path_then_auto_cut():
    from test_cut import plate_with_holes

    from igl_heatseg.parameterization.cut import cut_along_paths, cut_to_disk
    from igl_heatseg.pipeline import compose_cuts

    V, F = plate_with_holes()  # 20 x 20 cells, holes at cells (4..6, 4..6) and (12..14, 10..12)
    first = cut_along_paths(V, F, [(4 * 21 + 0, 4 * 21 + 4)])  # border -> hole 1, 4 edges
    assert first.topology_after.boundary_loops == 2
    res = compose_cuts(first, cut_to_disk(first.V, first.F))
    assert res.topology_after.is_disk
    assert res.topology_before == first.topology_before
    np.testing.assert_array_equal(res.vertex_map[res.F], F)  # corners keep input vertices
    assert first.cut_length == pytest.approx(0.2)
    # total = both stages, and it is the length of the listed cut edges (input ids)
    E = res.cut_edges
    assert res.cut_length == pytest.approx(np.linalg.norm(V[E[:, 0]] - V[E[:, 1]], axis=1).sum())
    assert res.cut_length > first.cut_length
    assert len(res.cut_edges) == len(np.unique(np.sort(res.cut_edges, axis=1), axis=0))
    assert res.method == "paths+annulus"


def test_stages_by_hand_give_the_pipeline_s_report(can_mesh):
    """run_pipeline is its stages in order; the report is generated from the typed charts."""
    from igl_heatseg.pipeline import cut_charts, extract_charts, pack, parameterize_charts

    res = run_pipeline(can_mesh)
    charts = extract_charts(can_mesh, res.segmentation.labels, with_topology=False)
    charts, _, _ = parameterize_charts(can_mesh, cut_charts(can_mesh, charts))
    corner_uv, atlas = pack(can_mesh, charts)

    def untimed(r):  # attempts hold timings too
        if isinstance(r, list):
            return [untimed(x) for x in r]
        if isinstance(r, dict):
            return {k: untimed(v) for k, v in r.items() if not k.endswith("seconds")}
        return r

    assert [untimed(c.to_report()) for c in charts] == [untimed(r) for r in res.report["charts"]]
    assert np.array_equal(corner_uv, res.corner_uv) and atlas.fill == res.atlas.fill
    side = side_chart(res)
    assert side.report == side.to_report() and side.report["topology"]["genus"] == 0
    with pytest.raises(AttributeError):
        side.report = {}
    assert set(res.report) == {"charts", "parameterization", "timings"}


def test_mesh_mean_energy_is_brought_under_its_bound(monkeypatch):
    """A single chart below the per-chart split threshold (5) but above the per-mesh bound
    (4.3) is split by the mesh-level pass, so the mesh's mean energy meets the bound."""
    from test_param import sphere_cap

    import igl_heatseg.pipeline.stages as stages
    from igl_heatseg.parameterization.split import MESH_SD_MAX, SPLIT_SD_MAX

    V, F = sphere_cap(1.9)  # most of a hemisphere and a bit more: one chart of energy ~4.3-5
    mesh = validate_mesh(V, F)

    def mapped():
        charts = stages.cut_charts(mesh, stages.extract_charts(mesh, np.zeros(len(F), int)))
        out, _, _ = stages.parameterize_charts(mesh, charts)
        sd = np.array([c.param.distortion["sym_dirichlet"] for c in out])
        a = np.array([c.area for c in out])
        return out, float((sd * a).sum() / a.sum())

    monkeypatch.setattr(stages, "MESH_SD_MAX", 1e9)  # the pass off
    whole, sd_whole = mapped()
    monkeypatch.undo()
    assert len(whole) == 1 and MESH_SD_MAX < sd_whole <= SPLIT_SD_MAX
    pieces, sd_mesh = mapped()
    assert len(pieces) >= 2 and all(c.param.bijective for c in pieces)
    assert sd_mesh <= MESH_SD_MAX


def test_long_chart_is_cut_for_packing_only_when_the_atlas_packs_tighter():
    """A flat round disk alone is longer than the bound, but its quarters pack no tighter
    than the disk: it stays one chart; the can's side is cut (fill measured both ways)."""
    from igl_heatseg.parameterization.split import PACK_MAX_LENGTH, split_for_packing

    r, t = np.meshgrid(np.linspace(0, 1, 9)[1:], np.linspace(0, 2 * np.pi, 48, endpoint=False))
    P = np.r_[[[0.0, 0.0]], np.c_[(r * np.cos(t)).ravel(), (r * np.sin(t)).ravel()]]
    V = np.c_[P, np.zeros(len(P))]
    from scipy.spatial import Delaunay

    F = Delaunay(P).simplices.astype(np.int64)  # the disk's triangles, counter-clockwise
    disk = validate_mesh(V, F, "disk")
    area = 24 * np.sin(2 * np.pi / 48)  # the 48-gon's
    assert split_for_packing(P, F, big=False, max_length=PACK_MAX_LENGTH * np.sqrt(area))
    res = run_pipeline(disk)
    assert len(res.charts) == 1 and res.charts_cut_for_packing == 0
    assert res.atlas.fill > 0.7


def test_thread_flanks_cut_open_are_halved_into_arcs_when_the_atlas_packs_tighter():
    """A clean threaded rod (4 V ridges, 24 facets per turn): robust mode makes every flank
    and crest a ring, each cut open into a thin C that nests in nothing; halved into arcs
    (``PACK_HALVE_MIN_FACES``) the atlas fills 0.755 of its square instead of 0.706."""
    from meshes import revolved, thread_profile

    V, F, _ = revolved(thread_profile(4), n=24)
    res = run_pipeline(validate_mesh(V, F, "threaded rod"), mode="robust")
    assert res.charts_cut_for_packing > 0
    assert all(c.param.bijective for c in res.charts)
    assert res.atlas.fill > 0.74
