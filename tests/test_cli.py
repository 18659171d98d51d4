import json
import subprocess
import sys

import numpy as np
import pytest

from igl_heatseg.cli import Progress, main
from igl_heatseg.errors import MeshError
from igl_heatseg.io.meshes import load_mesh


def test_segment_writes_all_outputs(tmp_path, data_dir, capsys):
    out = tmp_path / "out"
    assert main(["segment", str(data_dir / "fandisk.off"), "-o", str(out)]) == 0
    labels = np.loadtxt(out / "labels.txt", dtype=int)
    vlabels = np.loadtxt(out / "vertex_labels.txt", dtype=int)
    rep = json.loads((out / "report.json").read_text())
    for key in (
        "faces",
        "vertices",
        "components",
        "theta",
        "eps",
        "seed_vertices",
        "initial_groups",
        "segments",
        "segment_areas",
        "merged_islands",
        "timings",
    ):
        assert key in rep, key
    assert rep["faces"] == len(labels) == 14454 and rep["vertices"] == len(vlabels) == 7229
    assert rep["segments"] == labels.max() + 1 == len(rep["segment_areas"])
    assert set(rep["timings"]) >= {"load", "seeds", "factor_initial", "solve_initial", "total"}
    # labels: largest first
    assert rep["segment_areas"] == sorted(rep["segment_areas"], reverse=True)
    ply = load_mesh(out / "segmented.ply")
    assert ply.F.shape == (14454, 3)
    assert "15 segments" in capsys.readouterr().err


def test_labels_follow_input_order_with_unreferenced_and_duplicate_vertices(tmp_path):
    # An OBJ with an unused vertex first and every vertex duplicated (soup).
    from meshes import cube

    V, F = cube(3)
    soup = V[F.ravel()]
    lines = ["v 9 9 9"] + [f"v {x:.17g} {y:.17g} {z:.17g}" for x, y, z in soup]
    lines += [f"f {3 * i + 2} {3 * i + 3} {3 * i + 4}" for i in range(len(F))]
    p = tmp_path / "soup.obj"
    p.write_text("\n".join(lines) + "\n")
    assert main(["segment", str(p), "-o", str(tmp_path / "o")]) == 0
    labels = np.loadtxt(tmp_path / "o" / "labels.txt", dtype=int)
    vl = np.loadtxt(tmp_path / "o" / "vertex_labels.txt", dtype=int)
    assert len(labels) == len(F) and labels.max() == 5
    assert len(vl) == 1 + len(soup) and vl[0] == -1
    rep = json.loads((tmp_path / "o" / "report.json").read_text())
    assert rep["unreferenced_vertices"] == 1 and rep["merged_vertices"] == len(soup) - len(V)
    # copies of one vertex carry one label
    m = load_mesh(p)
    for c in range(len(m.V)):
        copies = np.flatnonzero(m.vertex_map == c)
        assert len(set(vl[copies])) == 1


@pytest.mark.parametrize(
    "content,name,needle",
    [
        (None, "missing.off", "no such file"),
        (b"1 2 3", "x.xyz", "unknown mesh file extension"),
        (b"", "e.obj", "empty file"),
        (b"OFF\n99999999 1 0\n0 0 0\n", "h.off", "declares 99999999 vertices"),
        (b"\x00\x01garbage" * 5, "g.ply", "not a PLY file"),
        (
            b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n",
            "r.obj",
            "line 4: face vertex index 7 refers to no vertex",
        ),
        (b"v 0 0 0\nv 1 0 0\nv 0 inf 0\nf 1 2 3\n", "i.obj", "NaN or infinite"),
        (b"v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n", "z.obj", "zero area"),
        (
            b"v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 -1 0\nv 0 0 1\nf 1 2 3\nf 2 1 4\nf 1 2 5\n",
            "nm.obj",
            "non-manifold edge",
        ),
        (
            b"v 0 0 0\nv 1 0 0\nv 0 1 0\nv -1 0 0\nv 0 -1 0\nf 1 2 3\nf 1 4 5\n",
            "nv.obj",
            "non-manifold vertex",
        ),
        (
            b"v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3\nf 1 4 3\n",
            "o.obj",
            "inconsistent orientation",
        ),
    ],
)
def test_bad_input_is_one_line_and_exit_2(tmp_path, content, name, needle):
    p = tmp_path / name
    if content is not None:
        p.write_bytes(content)
    r = subprocess.run(
        [sys.executable, "-m", "igl_heatseg", "segment", str(p), "-o", str(tmp_path / "o")],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert r.returncode == 2, r.stderr
    err = r.stderr.strip()
    assert "\n" not in err and "Traceback" not in err
    assert err.startswith("igl-heatseg: error: ") and needle in err, err


def test_bad_parameter_is_exit_2(tmp_path, data_dir, capsys):
    assert main(["segment", str(data_dir / "fandisk.off"), "-o", str(tmp_path), "--eps", "2"]) == 2
    assert "eps must be in [0, 1]" in capsys.readouterr().err


def test_progress_lines_when_not_a_tty():
    import io

    s = io.StringIO()
    p = Progress(True, s)
    for f in np.linspace(0, 1, 101):
        p("heat initial", f)
    lines = s.getvalue().splitlines()
    assert len(lines) == 5 and lines[-1].endswith("heat initial: 100%")
    q = Progress(False, s)
    q("x", 1.0)
    assert len(s.getvalue().splitlines()) == 5


def test_progress_appears_for_large_meshes(tmp_path, data_dir):
    r = subprocess.run(
        [
            sys.executable,
            "-m",
            "igl_heatseg",
            "segment",
            str(data_dir / "fandisk.off"),
            "-o",
            str(tmp_path / "o"),
            "--progress",
            "always",
        ],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert r.returncode == 0
    assert "heat initial: 100%" in r.stderr


def test_help_lists_segment():
    r = subprocess.run(
        [sys.executable, "-m", "igl_heatseg", "--help"], capture_output=True, text=True, timeout=60
    )
    assert r.returncode == 0 and "segment" in r.stdout


def test_segment_robust_mode_reports_primitives_and_scores_better(tmp_path, data_dir):
    from igl_heatseg.evaluation.metrics import coverage, purity, read_labels

    mesh = data_dir / "abc_00007974_5.ply"
    truth = read_labels(data_dir / "abc_00007974_5.facelabels.txt")
    area = load_mesh(mesh)
    from igl_heatseg.mesh.geometry import face_areas

    w = face_areas(area.V, area.F)
    scores = {}
    for mode in ("paper", "robust"):
        out = tmp_path / mode
        assert main(["segment", str(mesh), "-o", str(out), "--mode", mode]) == 0
        rep = json.loads((out / "report.json").read_text())
        assert rep["mode"] == mode
        labels = np.loadtxt(out / "labels.txt", dtype=int)
        scores[mode] = (purity(labels, truth, w), coverage(labels, truth, w))
        if mode == "robust":
            assert len(rep["primitive_types"]) == rep["segments"]
            assert set(rep["primitive_types"]) <= {"Plane", "Cylinder", "Sphere", "Other"}
            assert rep["theta"] == 0.7
            # one OBJ polyline per trimming curve, between segments that exist
            curves = rep["boundary_curves"]
            obj = (out / "boundaries.obj").read_text().splitlines()
            assert sum(ln.startswith("l ") for ln in obj) == len(curves) > 0
            assert all(-1 <= c["left"] < rep["segments"] and c["right"] < rep["segments"]
                       for c in curves)
            assert {c["method"] for c in curves} <= {"intersection", "smoothed", "chain"}
        else:
            assert not (out / "boundaries.obj").exists()
    # the paper's mode merges this thin frame into 2 segments (24 true faces)
    assert scores["paper"][0] < 0.8
    assert scores["robust"][0] >= 0.9 and scores["robust"][1] >= 0.85


def test_unknown_mode_is_rejected():
    from meshes import cube

    from igl_heatseg import validate_mesh
    from igl_heatseg.segmentation import segment_with_mode

    with pytest.raises(ValueError, match="mode must be one of"):
        segment_with_mode(validate_mesh(*cube(2)), "fancy")


def _zero_area_cube(tmp_path):
    from meshes import cube

    V, F = cube(4)
    V = V.copy()
    for f in (3, 40, 77):  # collapse one edge of three faces: 6 zero-area faces
        V[F[f, 1]] = V[F[f, 0]]
    p = tmp_path / "zero.off"
    p.write_text(
        f"OFF\n{len(V)} {len(F)} 0\n"
        + "".join(f"{float(x)!r} {float(y)!r} {float(z)!r}\n" for x, y, z in V)
        + "".join(f"3 {a} {b} {c}\n" for a, b, c in F)
    )
    return p, len(F)


def test_zero_area_faces_refused_with_the_option_then_repaired(tmp_path, capsys):
    p, m = _zero_area_cube(tmp_path)
    assert main(["segment", str(p), "-o", str(tmp_path / "a")]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "zero area" in err and "use --repair" in err
    assert main(["segment", str(p), "-o", str(tmp_path / "a"), "--repair"]) == 0
    err = capsys.readouterr().err
    assert "repaired: 6 zero area faces" in err
    rep = json.loads((tmp_path / "a" / "report.json").read_text())
    assert rep["repairs"]["zero_area_faces"] == 6 and rep["repairs"]["dropped_faces_unlabelled"] == 0
    labels = (tmp_path / "a" / "labels.txt").read_text().split()
    assert len(labels) == m and "-1" not in labels


def test_evaluate_pred_needs_no_geometric_checks(tmp_path, capsys):
    p, m = _zero_area_cube(tmp_path)
    labels = tmp_path / "labels.txt"
    labels.write_text("".join(f"{i % 3}\n" for i in range(m)))
    assert main(["evaluate", str(p), "--truth", str(labels), "--pred", str(labels), "--json"]) == 0
    ev = json.loads(capsys.readouterr().out)
    assert ev["purity"] == pytest.approx(1.0) and ev["n_faces"] == m
    short = tmp_path / "short.txt"
    short.write_text("0\n" * (m - 1))
    assert main(["evaluate", str(p), "--truth", str(labels), "--pred", str(short)]) == 2
    assert "labels" in capsys.readouterr().err


def test_evaluate_pred_on_polygon_mesh_counts_input_faces(tmp_path, capsys):
    p = tmp_path / "q.off"
    p.write_text("OFF\n5 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n2 0.5 0\n4 0 1 2 3\n3 1 4 2\n")
    t = tmp_path / "t.txt"
    t.write_text("0\n1\n")
    assert main(["evaluate", str(p), "--truth", str(t), "--pred", str(t), "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["purity"] == pytest.approx(1.0)


@pytest.mark.parametrize("where", ["file", "parent_file"])
def test_output_path_that_cannot_be_a_folder_is_one_line(tmp_path, data_dir, capsys, where):
    f = tmp_path / "taken"
    f.write_text("x")
    out = f if where == "file" else f / "sub"
    rc = main(["segment", str(data_dir / "block.ply"), "-o", str(out), "--progress", "never"])
    err = capsys.readouterr().err.strip()
    assert rc == 2 and "\n" not in err and str(out) in err, err
    assert f.read_text() == "x"


def test_unwritable_output_parent_is_one_line(tmp_path, data_dir, capsys):
    import os

    ro = tmp_path / "ro"
    ro.mkdir()
    ro.chmod(0o500)
    try:
        if os.access(ro, os.W_OK):
            pytest.skip("running as root: permissions are not enforced")
        rc = main(["segment", str(data_dir / "block.ply"), "-o", str(ro / "out")])
        err = capsys.readouterr().err.strip()
        assert rc == 2 and "\n" not in err and "cannot write the output folder" in err, err
    finally:
        ro.chmod(0o700)


def test_output_on_a_read_only_file_system_is_one_line(tmp_path, data_dir, capsys):
    import os

    if not os.path.isdir("/proc/self"):
        pytest.skip("no /proc")
    out = "/proc/self/igl_heatseg_out"  # /proc refuses new folders, even to root
    rc = main(["segment", str(data_dir / "block.ply"), "-o", out, "--progress", "never"])
    err = capsys.readouterr().err.strip()
    assert rc == 2 and "\n" not in err and "cannot write the output folder" in err, err


def test_warnings_before_an_error_fold_into_its_one_line(tmp_path, capsys, monkeypatch):
    """A fuzzed STL made the heat solver warn, then fail: two lines on stderr. Now one."""
    import logging

    import igl_heatseg.cli.segment as seg_cmd

    def warn_then_fail(args):
        log = logging.getLogger("igl_heatseg.heat.exact")
        log.warning("heat fields sum to 1 only within 2e-06")
        raise MeshError("case.stl: factorization of the heat system failed")

    monkeypatch.setattr(seg_cmd, "run", warn_then_fail)
    code = main(["segment", "case.stl", "-o", str(tmp_path / "o")])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1
    assert "factorization" in err[0] and "after the warning: heat fields sum" in err[0]


@pytest.mark.parametrize("command, default", [("run", "paper"), ("segment", "paper"),
                                              ("cad", "robust")])
def test_help_names_each_commands_own_default_mode(command, default):
    from igl_heatseg.cli import build_parser

    sub = build_parser()._subparsers._group_actions[0].choices[command]
    assert sub.get_default("mode") == default
    text = " ".join(sub.format_help().split())
    marks = {"paper": "paper: the paper's method, faithful (default)", "robust": "robust (default)"}
    assert marks[default] in text
    assert marks["robust" if default == "paper" else "paper"] not in text
