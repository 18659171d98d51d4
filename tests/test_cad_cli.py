"""``igl-heatseg cad`` and ``run --step``: STEP files that read back as the part, a cad section
in report.json, one-line errors with exit code 2 (also without OCP), the batch job kind."""

from __future__ import annotations

import json
import sys

import igl
import numpy as np
import pytest

pytest.importorskip("OCP")

from meshes import cube, cylinder  # noqa: E402

from igl_heatseg.batch.jobs import JOB_KINDS, cad_file  # noqa: E402
from igl_heatseg.cad import read_step  # noqa: E402
from igl_heatseg.cad.fidelity import brep_fidelity, faces_of  # noqa: E402
from igl_heatseg.cli import main  # noqa: E402
from igl_heatseg.cli.common import TIME_LIMIT_DEFAULT  # noqa: E402
from igl_heatseg.errors import MeshError  # noqa: E402


@pytest.fixture(scope="module")
def cube_obj(tmp_path_factory):
    V, F = cube(6)
    path = tmp_path_factory.mktemp("parts") / "cube.obj"
    igl.write_triangle_mesh(str(path), V, F)
    return path, V, F


@pytest.fixture(scope="module")
def cylinder_obj(tmp_path_factory):
    V, F = cylinder(48, 6, radius=1.0, height=2.0)
    path = tmp_path_factory.mktemp("parts") / "cylinder.obj"
    igl.write_triangle_mesh(str(path), V, F)
    return path, V, F


def _one_line_error(capsys) -> str:
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1, err
    assert err[0].startswith("igl-heatseg: error: ")
    return err[0]


def test_cad_cube_gives_a_valid_solid_of_six_planes(cube_obj, tmp_path, capsys):
    path, V, F = cube_obj
    out = tmp_path / "out"
    assert main(["cad", str(path), "-o", str(out), "--no-pictures"]) == 0
    assert "valid solid, 6 faces" in capsys.readouterr().err
    shape = read_step(out / "model.step")
    fid = brep_fidelity(shape, V, F)
    assert fid["valid"] and fid["solids"] == 1 and fid["free_edges"] == 0
    assert len(faces_of(shape)) == 6 and fid["faces_by_type"]["plane"]["count"] == 6
    assert fid["volume_rel_error"] < 1e-6
    rep = json.loads((out / "report.json").read_text())
    cad = rep["cad"]
    assert cad["step"] == "model.step" and cad["unit"] == "mm" and cad["segments"] == 6
    assert cad["not_built"] == [] and cad["fidelity"]["solids"] == 1
    for key in ("valid", "free_edges", "faces_by_type", "hausdorff", "rms", "volume_rel_error"):
        assert key in cad["fidelity"]
    assert {"surfaces", "edges", "faces", "sew", "check", "fidelity", "step"} <= set(cad["timings"])
    # everything `segment` writes is there too
    assert {"labels.txt", "vertex_labels.txt", "segmented.ply"} <= {p.name for p in out.iterdir()}
    assert not list(tmp_path.glob(".out.*"))  # atomic: no temporary folder left


def test_cad_paper_mode_fits_the_papers_segments(cylinder_obj, tmp_path):
    path, V, F = cylinder_obj
    job = cad_file(path, tmp_path / "out", mode="paper", pictures=False)
    cad = job.report["cad"]
    assert cad["surfaces_from"] == "fitted to the segments"
    assert len(cad["surfaces"]) == job.report["segments"] == len(cad["faces"])
    shape = read_step(tmp_path / "out" / "model.step")
    fid = brep_fidelity(shape, V, F)
    assert fid["valid"] and fid["solids"] == 1
    assert fid["faces_by_type"]["cylinder"]["count"] == 1
    assert fid["faces_by_type"]["plane"]["count"] == 2 and fid["faces"] == 3


def test_run_step_writes_the_step_file_and_cad_section(cube_obj, tmp_path):
    path, V, F = cube_obj
    out = tmp_path / "run"
    assert main(["run", str(path), "-o", str(out), "--step", "--mode", "robust",
                 "--no-pictures"]) == 0
    rep = json.loads((out / "report.json").read_text())
    assert "parameterization" in rep and rep["cad"]["fidelity"]["solids"] == 1
    assert len(faces_of(read_step(out / "model.step"))) == 6
    assert (out / "atlas.obj").exists()
    assert rep["cad"]["time_limit"]["seconds"] == TIME_LIMIT_DEFAULT  # the command's default


def test_time_limit_is_the_jobs_and_reported(cube_obj, tmp_path, capsys):
    """`--time-limit` counts from the start of the job: the report gives it and what the
    build had left of it; a bad value is one line, exit 2."""
    path, V, F = cube_obj
    for argv in (["cad", str(path), "-o", str(tmp_path / "c")],
                 ["run", str(path), "-o", str(tmp_path / "r"), "--step", "--mode", "robust"]):
        assert main(argv + ["--no-pictures", "--time-limit", "3600"]) == 0
        limit = json.loads((tmp_path / argv[3] / "report.json").read_text())["cad"]["time_limit"]
        assert limit["seconds"] == 3600.0 and 3000 < limit["build_seconds"] < 3600
        assert limit["reached"] is False and limit["skipped"] == []
    assert main(["cad", str(path), "-o", str(tmp_path / "n"), "--no-pictures",
                 "--time-limit", "0"]) == 0  # no limit
    assert json.loads((tmp_path / "n" / "report.json").read_text())["cad"]["time_limit"] is None
    for bad in ("-5", "inf", "soon"):
        with pytest.raises(SystemExit):
            main(["cad", str(path), "-o", str(tmp_path / "x"), "--time-limit", bad])
        assert "--time-limit" in capsys.readouterr().err
    with pytest.raises(MeshError, match="time_limit"):
        cad_file(path, tmp_path / "y", time_limit=float("nan"))
    assert not (tmp_path / "x").exists() and not (tmp_path / "y").exists()


def test_bad_input_is_one_line_and_exit_2(tmp_path, cube_obj, capsys):
    bad = tmp_path / "bad.obj"
    bad.write_text("v 0 0 0\nf 1 2 3\n")
    assert main(["cad", str(bad), "-o", str(tmp_path / "o1")]) == 2
    _one_line_error(capsys)
    assert main(["cad", str(tmp_path / "missing.obj"), "-o", str(tmp_path / "o2")]) == 2
    _one_line_error(capsys)
    assert main(["cad", str(cube_obj[0]), "-o", str(tmp_path / "o3"), "--tol", "-1"]) == 2
    assert "tol" in _one_line_error(capsys)
    assert not (tmp_path / "o1").exists() and not (tmp_path / "o3").exists()


def test_without_ocp_one_line_with_the_install_hint(monkeypatch, cube_obj, tmp_path, capsys):
    monkeypatch.setitem(sys.modules, "OCP", None)  # `import OCP` raises ImportError
    for argv in (["cad", str(cube_obj[0]), "-o", str(tmp_path / "a")],
                 ["run", str(cube_obj[0]), "-o", str(tmp_path / "b"), "--step"]):
        assert main(argv) == 2
        assert "pip install 'igl_heatseg[cad]'" in _one_line_error(capsys)
    assert not (tmp_path / "a").exists() and not (tmp_path / "b").exists()


def test_batch_has_the_cad_job_kind(cube_obj, tmp_path):
    kind = JOB_KINDS["cad"]
    assert kind.run is cad_file and "tol" in kind.options and kind.pictures == ("brep.png",)
    row = kind.summarize({"faces": 12, "segments": 6})  # a report without a cad section
    assert row["faces"] == 12 and row["segments"] == 6 and row["brep"] is None
    pytest.importorskip("dask")
    from igl_heatseg.batch import process_mesh

    out = tmp_path / "task-cad"
    rec = process_mesh({"mesh": "cube.obj", "input": str(cube_obj[0]), "output": str(out),
                        "kind": "cad", "options": {"pictures": False, "mode": "robust"},
                        "timeout": 300})
    assert rec["status"] == "done", rec
    assert rec["brep"] == "solid" and rec["faceted"] == 0 and rec["hausdorff_pct"] < 0.01
    assert len(faces_of(read_step(out / "model.step"))) == 6


def test_brep_picture_helpers():
    from OCP.BRepPrimAPI import BRepPrimAPI_MakeCylinder

    from igl_heatseg.cad import tessellate_by_type
    from igl_heatseg.viz.brep import brep_type_colors, face_border_edges

    TV, TF, tri_face, types = tessellate_by_type(BRepPrimAPI_MakeCylinder(1.0, 2.0).Shape(), 0.01)
    assert sorted(types) == ["cylinder", "plane", "plane"] and len(tri_face) == len(TF)
    assert np.allclose(brep_type_colors(["bspline"]), brep_type_colors(["freeform"]))
    E = face_border_edges(TF, tri_face)
    assert len(E) > 0 and E.max() < len(TV)


def test_summary_counts_faceted_segments_and_bspline_stand_ins():
    from igl_heatseg.cli.cad import cad_summary

    cad = {"segments": 3, "not_built": [2],
           "faces": [{"kind": "plane", "built_as": "bspline"},
                     {"kind": "freeform", "built_as": "bspline"},
                     {"kind": "cylinder", "built_as": None}],
           "fidelity": {"valid": True, "solids": 1, "faces": 9, "free_edges": 0,
                        "hausdorff_rel": 0.004, "volume_rel_error": 0.001}}
    assert cad_summary(cad) == (
        "B-Rep: valid solid, 9 faces from 3 segments (1 faceted, 1 analytic as B-splines), "
        "0 free edges, Hausdorff 0.40 % of the diagonal, volume error 0.10 %")


def test_summary_explains_the_chords_of_an_exact_tessellation():
    from igl_heatseg.cli.cad import cad_summary

    def line(exact, at_vertices):
        fid = {"valid": True, "solids": 1, "faces": 19, "free_edges": 0, "hausdorff_rel": 0.0101,
               "vertex_hausdorff_rel": at_vertices, "exact_tessellation": exact,
               "volume_rel_error": 0.0413}
        return cad_summary({"fidelity": fid, "segments": 19, "faces": [], "not_built": []})

    assert line(True, 0.0002).endswith(
        "Hausdorff 1.01 % of the diagonal (mesh vertices 0.02 %: the mesh is an exact "
        "tessellation, whose facets are chords of the curved faces), volume error 4.13 %")
    assert "chords" not in line(False, 0.0002)  # noise: no such claim
    assert "chords" not in line(True, 0.008)  # the vertices themselves are far
    assert "chords" not in line(True, None)  # a report of before


def test_summary_names_a_compound_of_parts():
    from igl_heatseg.cli.cad import cad_summary

    def line(solids, shells):
        fid = {"solids": solids, "shells": shells, "valid": True, "faces": 9, "free_edges": 0,
               "hausdorff_rel": 0.001}
        return cad_summary({"fidelity": fid, "segments": 9, "faces": [], "not_built": []})

    assert line(1, 1).startswith("B-Rep: valid solid, 9 faces")
    assert line(0, 1).startswith("B-Rep: valid shell, 9 faces")
    assert line(2, 2).startswith("B-Rep: valid solid x 2, 9 faces")
    assert line(6, 64).startswith("B-Rep: valid shell x 64 (6 of them closed solids), 9 faces")


def test_no_volume_for_a_solid_beside_an_open_shell():
    from OCP.BRep import BRep_Builder
    from OCP.BRepPrimAPI import BRepPrimAPI_MakeBox
    from OCP.TopoDS import TopoDS_Compound

    V, F = cube()
    solid = BRepPrimAPI_MakeBox(2.0, 2.0, 2.0).Shape()
    assert brep_fidelity(solid, V, F)["volume"] is not None
    builder, both = BRep_Builder(), TopoDS_Compound()
    builder.MakeCompound(both)
    builder.Add(both, solid)
    builder.Add(both, faces_of(BRepPrimAPI_MakeBox(1.0, 1.0, 1.0).Shape())[0])
    fid = brep_fidelity(both, V, F)
    assert fid["solids"] == 1 and fid["free_edges"] > 0
    assert fid["volume"] is None and fid["volume_rel_error"] is None
