"""Scenes under polyscope's openGL_mock backend, the camera, and headless EGL renders.

polyscope can be initialised once per process: the scene tests share one mock backend in this
process; the EGL render tests run in subprocesses.
"""

from __future__ import annotations

import argparse
import copy
import ctypes
import dataclasses
import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

from igl_heatseg import validate_mesh
from igl_heatseg.errors import MeshError
from igl_heatseg.segmentation import segment_robust
from igl_heatseg.segmentation.paper import segment_mesh
from igl_heatseg.surfaces import SURFACE_KINDS, Surface

ps = pytest.importorskip("polyscope")
viz = pytest.importorskip("igl_heatseg.viz")
from igl_heatseg.cli.viz import register, view_file  # noqa: E402
from igl_heatseg.viz.layout import map_groups  # noqa: E402  (numpy only)

DATA = Path(__file__).resolve().parent.parent / "data"

#: A headless render must show at least this many distinct (quantized) colours.
MIN_COLOURS = 5
#: The part's pixel centroid must lie within this fraction of the image size from the centre.
CENTRE_TOL = 0.12
#: Share of the image the part must cover (not a speck, not overflowing).
COVER_RANGE = (0.08, 0.9)
#: Seconds a subprocess render may take before the test fails.
RENDER_TIMEOUT = 120


def box_mesh(n: int = 6, size=(2.0, 1.0, 0.5)):
    """A closed box made of 6 grid faces, outward oriented: V (k,3), F (12 n^2, 3)."""
    Vs, Fs, off = [], [], 0
    g = np.linspace(0.0, 1.0, n + 1)
    uu, vv = np.meshgrid(g, g, indexing="ij")
    uu, vv = uu.ravel(), vv.ravel()
    idx = np.arange((n + 1) ** 2).reshape(n + 1, n + 1)
    a, b, c, d = (
        idx[:-1, :-1].ravel(),
        idx[1:, :-1].ravel(),
        idx[1:, 1:].ravel(),
        idx[:-1, 1:].ravel(),
    )
    quad = np.r_[np.c_[a, b, c], np.c_[a, c, d]]
    for axis in range(3):
        for s in (0.0, 1.0):
            u_ax, v_ax = (axis + 1) % 3, (axis + 2) % 3  # e_u x e_v = +e_axis
            P = np.zeros((len(uu), 3))
            P[:, axis] = s
            P[:, u_ax], P[:, v_ax] = uu, vv
            f = quad if s == 1.0 else quad[:, ::-1]
            Vs.append(P)
            Fs.append(f + off)
            off += len(P)
    V = np.concatenate(Vs) * np.asarray(size)
    F = np.concatenate(Fs)
    Vu, inv = np.unique(np.round(V, 12), axis=0, return_inverse=True)
    return Vu, inv.ravel()[F]


@pytest.fixture(scope="module")
def box():
    mesh = validate_mesh(*box_mesh(), name="box")
    return mesh, segment_mesh(mesh)


@pytest.fixture(scope="module")
def box_charts(box):
    from igl_heatseg.pipeline import run_pipeline

    mesh, _ = box
    res = run_pipeline(mesh, None)
    return res.segmentation, res.charts


@pytest.fixture(scope="module")
def box_robust(box):
    mesh, _ = box
    return segment_robust(mesh, refine=True)


def surfaces_of_every_kind():
    """One Surface per kind, in SURFACE_KINDS order."""
    o, z = np.zeros(3), np.array([0.0, 0.0, 1.0])
    params = {
        "plane": {"point": o, "normal": z},
        "cylinder": {"point": o, "axis": z, "radius": 1.0},
        "cone": {"apex": o, "axis": z, "half_angle": 0.3},
        "sphere": {"center": o, "radius": 1.0},
        "torus": {"center": o, "axis": z, "major_radius": 2.0, "minor_radius": 0.5},
        "freeform": {"centroid": o},
    }
    return [Surface(k, params[k]) for k in SURFACE_KINDS]


@pytest.fixture(scope="module")
def mock_ps():
    return viz.init_polyscope("openGL_mock")


# ------------------------------------------------------------------------ pure numpy


def test_box_mesh_is_six_segments(box):
    mesh, seg = box
    assert seg.num_segments == 6
    assert len(seg.sharp_edges) == 12 * 6  # 12 box edges, 6 grid edges each


def test_camera_sees_every_point_and_centres_the_part():
    V, _ = box_mesh()
    V = V + [10.0, -3.0, 2.0]
    aspect, fov = 4 / 3, 45.0
    eye, target, up = viz.three_quarter_camera(V, aspect, fov)
    fwd = (target - eye) / np.linalg.norm(target - eye)
    assert abs(up @ fwd) < 1e-9 and abs(np.linalg.norm(up) - 1) < 1e-12
    right = np.cross(fwd, up)
    rel = V - eye
    depth = rel @ fwd
    assert (depth > 0).all()
    x = (rel @ right) / depth / (np.tan(np.radians(fov) / 2) * aspect)
    y = (rel @ up) / depth / np.tan(np.radians(fov) / 2)
    assert np.abs(x).max() <= 1 and np.abs(y).max() <= 1  # inside the frustum
    assert max(np.abs(x).max(), np.abs(y).max()) > 0.75  # and fills it
    assert abs(x.max() + x.min()) < 0.15 and abs(y.max() + y.min()) < 0.15  # centred
    # three-quarter: not along a principal axis of the box
    d = -fwd
    assert np.sort(np.abs(d))[0] > 0.2


def test_best_view_direction_prefers_more_visible_labels():
    V, F = box_mesh()
    N = np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]])
    labels = np.where(N[:, 2] > 0, 1, 0)  # the top face is label 1, everything else 0
    d = viz.best_view_direction(V, F, labels)
    assert abs(np.linalg.norm(d) - 1) < 1e-12
    assert d[2] > 0  # looks at the top face, so that two labels are visible


def test_segment_boundary_edges_of_box(box):
    mesh, _ = box
    V, F = mesh.V, mesh.F
    N = np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]])
    side = np.argmax(np.abs(N), axis=1) * 2 + (
        N[np.arange(len(F)), np.argmax(np.abs(N), axis=1)] > 0
    )
    E = viz.segment_boundary_edges(F, side)  # one label per box side: the 12 box edges
    assert len(E) == 12 * 6
    d = np.abs(V[E[:, 0]] - V[E[:, 1]])
    lo, hi = V.min(axis=0), V.max(axis=0)
    on_two_faces = (np.isclose(V[E[:, 0]], lo) | np.isclose(V[E[:, 0]], hi)).sum(axis=1) >= 2
    assert on_two_faces.all() and (np.count_nonzero(d > 1e-12, axis=1) == 1).all()
    assert len(viz.segment_boundary_edges(F, np.zeros(len(F), int))) == 0


def test_drawable_charts_skips_charts_without_a_map(box, box_charts):
    mesh, _ = box
    _, charts = box_charts
    bare = dataclasses.replace(charts[0], cut=None, param=None)  # a non-disk under cut="none"
    assert [c.id for c in viz.drawable_charts([bare, *charts[1:]])] == list(range(1, len(charts)))
    assert viz.drawable_charts(None) == []
    UVc = viz.corner_uv(mesh.V, mesh.F, [bare, *charts[1:]]).reshape(-1, 3, 2)
    assert not UVc[charts[0].faces].any() and UVc[charts[1].faces].any()  # no map: blank


def test_corner_uv_matches_3d_area_and_layout_does_not_overlap(box, box_charts):
    mesh, _ = box
    seg, charts = box_charts
    cm = viz.drawable_charts(charts)
    assert len(cm) == len(charts) >= 6 and all(c.param.bijective for c in cm)
    UVc = viz.corner_uv(mesh.V, mesh.F, cm).reshape(-1, 3, 2)
    a, b = UVc[:, 1] - UVc[:, 0], UVc[:, 2] - UVc[:, 0]
    a2 = 0.5 * np.abs(a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0])
    a3 = 0.5 * np.linalg.norm(
        np.cross(
            mesh.V[mesh.F[:, 1]] - mesh.V[mesh.F[:, 0]], mesh.V[mesh.F[:, 2]] - mesh.V[mesh.F[:, 0]]
        ),
        axis=1,
    )
    groups = map_groups(cm)  # pieces of one map (cut for packing): one scale
    assert sorted(i for g in groups for i in g) == list(range(len(cm)))
    for g in groups:
        faces = np.concatenate([cm[i].faces for i in g])
        assert a2[faces].sum() == pytest.approx(a3[faces].sum(), rel=1e-9)
    placed = viz.chart_layout(mesh.V, cm)
    boxes = []
    for g in groups:  # a map's pieces are drawn together, the maps apart
        used = np.concatenate([placed[i][np.unique(cm[i].cut.F)] for i in g])
        boxes.append((used.min(axis=0), used.max(axis=0)))
    for i in range(len(boxes)):
        for j in range(i + 1, len(boxes)):
            (lo1, hi1), (lo2, hi2) = boxes[i], boxes[j]
            overlap = np.all(np.minimum(hi1, hi2) - np.maximum(lo1, lo2) > 1e-9)
            assert not overlap, (i, j)


def test_surface_type_palette_is_fixed_and_covers_every_kind():
    pal = viz.SURFACE_TYPE_COLORS
    assert list(pal) == [*SURFACE_KINDS, "other"]
    rgb = np.array(list(pal.values()))
    assert rgb.shape == (7, 3) and (rgb >= 0).all() and (rgb <= 1).all()
    assert len({tuple(c) for c in rgb}) == 7
    assert pal["plane"] == pytest.approx((0x56 / 255, 0xB4 / 255, 0xE9 / 255))  # Okabe-Ito


def test_surface_types_from_surfaces_else_primitive_types(box, box_robust):
    _, paper = box
    # robust mode fits a surface per segment: the box is six planes
    assert viz.segment_surface_types(box_robust) == [s.kind for s in box_robust.surfaces]
    assert viz.segment_surface_types(box_robust) == ["plane"] * 6
    untyped = copy.copy(box_robust)  # without fitted surfaces: robust mode's primitive types
    untyped.surfaces = None
    expected = [t.lower() for t in box_robust.primitive_types]
    assert len(expected) == 6 and set(expected) <= {"plane", "cylinder", "sphere", "other"}
    assert viz.segment_surface_types(untyped) == expected
    with pytest.raises(ValueError, match="needs .* robust mode"):
        viz.segment_surface_types(paper)
    typed = copy.copy(box_robust)  # fitted surfaces win over robust mode's primitive types
    typed.surfaces = surfaces_of_every_kind()
    assert viz.segment_surface_types(typed) == list(SURFACE_KINDS)
    typed.surfaces = [None, *typed.surfaces[1:]]
    assert viz.segment_surface_types(typed)[0] == "other"
    typed.surfaces = typed.surfaces[:5]
    with pytest.raises(ValueError, match="5 surface types for 6 segments"):
        viz.segment_surface_types(typed)
    typed = copy.copy(untyped)
    typed.primitive_types = ["Plane"] * 5 + ["Blob"]
    with pytest.raises(ValueError, match="unknown surface types"):
        viz.segment_surface_types(typed)


# ------------------------------------------------------------------------ mock scenes


@pytest.mark.parametrize("stage", ["seeds", "initial", "final", "temperature"])
def test_scene_stages_under_mock(mock_ps, box, stage, tmp_path):
    mesh, seg = box
    viz.init_polyscope("openGL_mock")
    info = viz.build_scene(mesh.V, mesh.F, seg, stage)
    assert mock_ps.has_surface_mesh("mesh")
    assert info["stage"] == stage and not info["planar"]
    if stage == "seeds":
        assert mock_ps.has_curve_network("sharp edges")
    if stage == "final":
        assert mock_ps.has_curve_network("segment boundaries")
    if stage == "temperature":
        assert 0 <= info["segment"] < seg.num_segments


def test_types_stage_under_mock(mock_ps, box, box_robust):
    mesh, paper = box
    viz.init_polyscope("openGL_mock")
    info = viz.build_scene(mesh.V, mesh.F, box_robust, "types")
    assert info["stage"] == "types" and not info["planar"]
    # robust mode's trimming curves instead of the mesh edges (most of the box's edges on the
    # intersection of their two planes; a chain beside a face dealt to the wrong side smoothed)
    assert mock_ps.has_surface_mesh("mesh")
    assert mock_ps.has_curve_network("trimming curves (intersection)")
    assert not mock_ps.has_curve_network("segment boundaries")
    methods = [c.method for c in box_robust.boundary_curves]
    assert methods.count("intersection") > len(methods) / 2
    untrimmed = copy.copy(box_robust)
    untrimmed.boundary_curves = None
    viz.init_polyscope("openGL_mock")
    viz.build_scene(mesh.V, mesh.F, untrimmed, "types")
    assert mock_ps.has_curve_network("segment boundaries")
    typed = copy.copy(paper)
    typed.surfaces = surfaces_of_every_kind()
    viz.init_polyscope("openGL_mock")
    assert viz.show_surface_types(mesh.V, mesh.F, typed) == list(SURFACE_KINDS)
    viz.init_polyscope("openGL_mock")
    with pytest.raises(ValueError, match="robust mode"):
        viz.build_scene(mesh.V, mesh.F, paper, "types")
    assert not mock_ps.has_surface_mesh("mesh")  # failed before drawing anything
    # the viewer's other stages skip the types quietly in paper mode
    viz.build_scene(mesh.V, mesh.F, paper, "final", all_quantities=True)
    viz.build_scene(mesh.V, mesh.F, box_robust, "final", all_quantities=True)


def test_types_stage_from_the_command_line_under_mock(mock_ps, monkeypatch):
    monkeypatch.setenv(viz.BACKEND_ENV, "openGL_mock")
    p = _parser()
    args = p.parse_args(["view", str(DATA / "fandisk.off"), "--stage", "types", "--mode", "robust"])
    assert args.func(args) == 0
    assert mock_ps.has_surface_mesh("mesh")
    args = p.parse_args(["view", str(DATA / "fandisk.off"), "--stage", "types"])
    with pytest.raises(ValueError, match="robust mode"):
        args.func(args)


def test_temperature_segment_out_of_range(mock_ps, box):
    mesh, seg = box
    viz.init_polyscope("openGL_mock")
    with pytest.raises(ValueError, match="segment must be in 0..5"):
        viz.show_temperature(mesh.V, mesh.F, seg, segment=6)


def test_chart_stages_under_mock(mock_ps, box, box_charts):
    mesh, _ = box
    seg, charts = box_charts
    viz.init_polyscope("openGL_mock")
    viz.build_scene(mesh.V, mesh.F, seg, "checker", charts=charts)
    assert mock_ps.has_surface_mesh("mesh")
    viz.init_polyscope("openGL_mock")
    info = viz.build_scene(mesh.V, mesh.F, seg, "charts", charts=charts)
    assert info["planar"]
    assert all(mock_ps.has_surface_mesh(f"chart {i:03d}") for i in range(6))
    with pytest.raises(ValueError, match="needs the charts"):
        viz.build_scene(mesh.V, mesh.F, seg, "checker")
    with pytest.raises(ValueError, match="stage must be one of"):
        viz.build_scene(mesh.V, mesh.F, seg, "nope")


def test_init_rejects_unknown_backend(monkeypatch):
    with pytest.raises(ValueError, match="unknown polyscope backend"):
        viz.init_polyscope("bogus")
    monkeypatch.setenv(viz.BACKEND_ENV, "bogus")
    with pytest.raises(ValueError, match="IGL_HEATSEG_PS_BACKEND"):
        viz.init_polyscope()


def test_view_under_mock_returns(mock_ps, tmp_path, monkeypatch):
    monkeypatch.setenv(viz.BACKEND_ENV, "openGL_mock")
    view_file(DATA / "fandisk.off", "seeds")
    assert mock_ps.has_surface_mesh("mesh")


def test_write_run_pictures_under_mock(mock_ps, box, box_charts, tmp_path):
    mesh, _ = box
    seg, charts = box_charts
    out = viz.write_run_pictures(tmp_path, mesh, seg, charts, size=(64, 48), backend="openGL_mock")
    assert set(out) == {"segmentation", "checker"}
    assert all(p.exists() for p in out.values())


def _parser():
    p = argparse.ArgumentParser(prog="igl-heatseg")
    register(p.add_subparsers(dest="command"))
    return p


def test_cli_parses_and_bad_mesh_gives_mesh_error(tmp_path):
    p = _parser()
    args = p.parse_args(
        ["render", "m.off", "-o", "x.png", "--stage", "seeds", "--size", "320", "240"]
    )
    assert args.stage == "seeds" and args.size == [320, 240] and args.segment is None
    bad = tmp_path / "bad.off"
    bad.write_text("OFF\n3 1 0\n0 0 0\n1 0 0\n")
    for argv in (
        ["render", str(bad), "-o", str(tmp_path / "x.png")],
        ["plot-areas", str(bad), "-o", str(tmp_path / "a.png")],
        ["view", str(bad)],
    ):
        args = p.parse_args(argv)
        with pytest.raises(MeshError, match="bad.off"):
            args.func(args)
    args = p.parse_args(["render", str(DATA / "fandisk.off"), "-o", "x.png", "--theta", "7"])
    with pytest.raises(MeshError, match="theta must be in"):
        args.func(args)
    with pytest.raises(SystemExit):
        p.parse_args(["render", "m.off", "-o", "x.png", "--stage", "nope"])


def test_cli_plot_areas_writes_png(tmp_path):
    p = _parser()
    out = tmp_path / "areas.png"
    args = p.parse_args(["plot-areas", str(DATA / "fandisk.off"), "-o", str(out), "--eps", "0.1"])
    assert args.func(args) == 0
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


# ------------------------------------------------------------------------ EGL renders


def _egl_loadable() -> bool:
    for name in ("libEGL.so.1", "libEGL.so"):
        try:
            ctypes.CDLL(name)
            return True
        except OSError:
            continue
    return False


needs_egl = pytest.mark.skipif(
    not _egl_loadable(), reason=f"no EGL library can be loaded ({viz.EGL_HINT})"
)


def _render_subprocess(code: str, tmp_path: Path) -> dict:
    env = {k: v for k, v in os.environ.items() if k != viz.BACKEND_ENV}
    script = tmp_path / "render.py"
    script.write_text(textwrap.dedent(code))
    r = subprocess.run(
        [sys.executable, str(script)],
        capture_output=True,
        text=True,
        env=env,
        timeout=RENDER_TIMEOUT,
        cwd=tmp_path,
    )
    assert r.returncode == 0, r.stderr[-2000:]
    return json.loads(r.stdout.strip().splitlines()[-1])


def _check_picture(png: Path, size):
    import matplotlib.image as mpimg

    img = mpimg.imread(png)[..., :3]
    assert img.shape[:2] == (size[1], size[0])
    bg = np.all(img > 0.98, axis=2)  # white background
    cover = 1 - bg.mean()
    assert COVER_RANGE[0] < cover < COVER_RANGE[1], cover
    ys, xs = np.nonzero(~bg)
    cx, cy = xs.mean() / size[0], ys.mean() / size[1]
    assert abs(cx - 0.5) < CENTRE_TOL and abs(cy - 0.5) < CENTRE_TOL, (cx, cy)
    q = np.unique((img[~bg] * 15).round().astype(int), axis=0)
    assert len(q) >= MIN_COLOURS, len(q)
    return img


@needs_egl
def test_headless_render_of_every_segmentation_stage(tmp_path):
    size = (400, 300)
    out = _render_subprocess(
        f"""
        import json, time
        from igl_heatseg.cli.viz import render_file
        res = {{}}
        for st in ("seeds", "initial", "final", "temperature"):
            t = time.perf_counter()
            r = render_file({str(DATA / "fandisk.off")!r}, st + ".png", st, size={size})
            res[st] = time.perf_counter() - t
        print(json.dumps(res))
        """,
        tmp_path,
    )
    imgs = {st: _check_picture(tmp_path / f"{st}.png", size) for st in out}
    # the stages differ from one another
    assert not np.allclose(imgs["final"], imgs["temperature"], atol=0.05)
    assert not np.allclose(imgs["seeds"], imgs["initial"], atol=0.05)


def _render_box_run(tmp_path: Path, size, stages) -> None:
    """``run_pipeline`` on the box, then ``write_run_pictures`` and ``render_scene`` for each
    of ``stages`` (written as ``STAGE.png``), in a headless subprocess."""
    V, F = box_mesh()
    np.save(tmp_path / "V.npy", V)
    np.save(tmp_path / "F.npy", F)
    _render_subprocess(
        f"""
        import json
        import numpy as np
        from igl_heatseg import validate_mesh, viz
        from igl_heatseg.pipeline import run_pipeline
        mesh = validate_mesh(np.load("V.npy"), np.load("F.npy"))
        res = run_pipeline(mesh, None)
        out = viz.write_run_pictures(".", mesh, res.segmentation, res.charts, size={size})
        for stage in {list(stages)!r}:
            viz.render_scene(mesh.V, mesh.F, res.segmentation, stage + ".png", stage,
                             charts=res.charts, size={size})
        print(json.dumps(sorted(out)))
        """,
        tmp_path,
    )


@needs_egl
def test_headless_render_of_surface_types(tmp_path):
    """fandisk in robust mode: planes sky blue, cylinders orange (hues survive the shading)."""
    from matplotlib.colors import rgb_to_hsv

    size = (400, 300)
    _render_subprocess(
        f"""
        import json
        from igl_heatseg.cli.viz import render_file
        render_file({str(DATA / "fandisk.off")!r}, "types.png", "types", size={size},
                    mode="robust")
        print(json.dumps(0))
        """,
        tmp_path,
    )
    img = _check_picture(tmp_path / "types.png", size)
    part = img[~np.all(img > 0.98, axis=2)]
    hsv = rgb_to_hsv(part)
    for kind, least in (("plane", 0.2), ("cylinder", 0.05)):
        h = rgb_to_hsv(np.array(viz.SURFACE_TYPE_COLORS[kind]))[0]
        near = (np.abs((hsv[:, 0] - h + 0.5) % 1.0 - 0.5) < 0.03) & (hsv[:, 1] > 0.3)
        assert near.mean() > least, (kind, near.mean())


@needs_egl
def test_headless_render_of_chart_stages(tmp_path):
    size = (320, 240)
    _render_box_run(tmp_path, size, ["charts"])
    for name in ("segmentation", "checker", "charts"):
        _check_picture(tmp_path / f"{name}.png", size)


@needs_egl
def test_run_pictures_equal_the_single_stage_renders(tmp_path):
    """write_run_pictures draws both pictures from one scene: pixel for pixel what
    render_scene draws for the "final" and "checker" stages."""
    size = (320, 240)
    _render_box_run(tmp_path, size, ["final", "checker"])
    import matplotlib.image as mpimg

    for run, single in (("segmentation", "final"), ("checker", "checker")):
        a = mpimg.imread(tmp_path / f"{run}.png")
        b = mpimg.imread(tmp_path / f"{single}.png")
        np.testing.assert_array_equal(a, b)


def test_missing_polyscope_gives_install_hint(monkeypatch):
    monkeypatch.setitem(sys.modules, "polyscope", None)  # `import polyscope` now fails
    with pytest.raises(ImportError, match=r"pip install igl_heatseg\[viz\]"):
        viz.init_polyscope("openGL_mock")
