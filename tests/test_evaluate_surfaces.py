"""Tests for igl_heatseg.evaluation.surfaces: type accuracy, boundary length ratio, segment ratio.

Analytic cases on a cube [-1, 1]^3 with n x n cells per side (cell size h = 2/n): the true
labels are its six sides, their boundary the 12 edges of length 2 (total 24).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from meshes import cube

from igl_heatseg.errors import MeshError
from igl_heatseg.evaluation.metrics import evaluate_labels
from igl_heatseg.evaluation.surfaces import (
    boundary_length,
    boundary_length_ratio,
    face_kinds,
    read_surface_types,
    segment_ratio,
    surface_kind,
    type_accuracy,
)
from igl_heatseg.mesh.geometry import face_areas

N = 4
H = 2.0 / N


@pytest.fixture(scope="module")
def box():
    V, F = cube(N)
    C = V[F].mean(axis=1)
    axis = np.abs(C).argmax(axis=1)
    side = 2 * axis + (C[np.arange(len(F)), axis] > 0)  # -x 0, +x 1, -y 2, +y 3, -z 4, +z 5
    return V, F, C, side.astype(np.int64)


def test_cube_exact_labels_ratio_one(box):
    V, F, _, side = box
    assert boundary_length(V, F, side) == pytest.approx(24.0)
    assert boundary_length_ratio(V, F, side, side) == pytest.approx(1.0)
    assert boundary_length_ratio(V, F, 10 - 2 * side, side) == pytest.approx(1.0)  # renamed


def test_cube_staircase_is_longer(box):
    # teeth: the +z cells along the +x edge in rows 0 and 2 (of 4 along y) go to the +x side.
    # Row 0 (at the corner): -h of the old rim, +h inner side, +h lateral (its other lateral
    # side was already a rim against -y); row 2: -h, +h, +2h.  Net +3h.
    V, F, C, side = box
    row = np.floor((C[:, 1] + 1) / H).astype(int)
    tooth = (side == 5) & (C[:, 0] > 1 - H) & np.isin(row, [0, 2])
    pred = np.where(tooth, 1, side)
    assert boundary_length_ratio(V, F, pred, side) == pytest.approx((24 + 3 * H) / 24)
    assert boundary_length_ratio(V, F, pred, side) > 1


def test_cube_missed_boundary_is_shorter(box):
    V, F, _, side = box
    pred = np.where(side == 5, 1, side)  # +z merged into +x: the shared edge (length 2) is lost
    assert boundary_length_ratio(V, F, pred, side) == pytest.approx(22 / 24)
    assert boundary_length_ratio(V, F, np.zeros_like(side), side) == 0.0


def test_spurious_cut_and_no_true_boundary(box):
    V, F, C, side = box
    pred = np.where((side == 5) & (C[:, 0] > 0), 6, side)  # +z cut in half along x = 0
    assert boundary_length_ratio(V, F, pred, side) == pytest.approx(26 / 24)
    one = np.zeros_like(side)
    assert boundary_length_ratio(V, F, one, one) == 1.0
    assert boundary_length_ratio(V, F, side, one) == math.inf
    with pytest.raises(MeshError, match="labels for a mesh"):
        boundary_length_ratio(V, F, side[:-1], side)


def test_boundary_ignores_the_mesh_border():
    V = np.array([[0.0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]])
    F = np.array([[0, 1, 2], [0, 2, 3]])
    assert boundary_length(V, F, [0, 1]) == pytest.approx(math.sqrt(2))  # not the 4 sides


def test_surface_kind_maps_abc_names():
    for name, kind in [
        ("Plane", "plane"),
        ("Cylinder", "cylinder"),
        ("Cone", "cone"),
        ("Sphere", "sphere"),
        ("Torus", "torus"),
        (" torus ", "torus"),
    ]:
        assert surface_kind(name) == kind
    for other in ("BSpline", "Revolution", "Extrusion", "Other", "freeform", "", None):
        assert surface_kind(other) == "freeform"


def test_type_accuracy_right_and_wrong(box):
    V, F, _, side = box
    w = face_areas(V, F)
    true_types = ["Plane"] * 6
    truth = face_kinds(side, true_types)
    assert type_accuracy(face_kinds(side, ["plane"] * 6), truth, w) == 1.0
    # one side typed as a cylinder: 1/6 of the area wrong
    wrong = face_kinds(side, ["plane"] * 5 + ["cylinder"])
    assert type_accuracy(wrong, truth, w) == pytest.approx(5 / 6)
    # a merged segment typed plane keeps every face right; typed cone, none
    assert type_accuracy(face_kinds(np.zeros_like(side), ["plane"]), truth, w) == 1.0
    assert type_accuracy(face_kinds(np.zeros_like(side), ["cone"]), truth, w) == 0.0


def test_type_accuracy_weights_and_errors():
    pred = ["plane", "cylinder", "cone", "Other"]
    true = ["Plane", "Cylinder", "Torus", "BSpline"]  # third wrong; fourth both freeform
    assert type_accuracy(pred, true) == pytest.approx(0.75)
    assert type_accuracy(pred, true, [1.0, 1.0, 6.0, 2.0]) == pytest.approx(0.4)
    with pytest.raises(MeshError):
        type_accuracy(pred, true[:3])
    with pytest.raises(MeshError):
        type_accuracy(pred, true, [0, 0, 0, 0])
    with pytest.raises(MeshError):
        type_accuracy(pred, true, [1, -1, 1, 1])
    with pytest.raises(MeshError, match="types"):
        face_kinds([0, 2], ["Plane", "Cone"])


def test_segment_ratio():
    assert segment_ratio([0, 0, 1, 1], [3, 3, 4, 4]) == 1.0
    assert segment_ratio(np.arange(6), [0, 0, 0, 1, 1, 1]) == 3.0
    assert segment_ratio([5, 5, 5], [0, 1, 2]) == pytest.approx(1 / 3)


def test_read_surface_types(tmp_path):
    p = tmp_path / "part.surface_types.txt"
    p.write_text("# comment\n1 Cylinder\n0 Plane\n\n2 BSpline surface\n")
    assert read_surface_types(p) == ["Plane", "Cylinder", "BSpline surface"]
    assert read_surface_types(p, n_labels=3) == ["Plane", "Cylinder", "BSpline surface"]
    with pytest.raises(MeshError, match="3 surface types for 4 labels"):
        read_surface_types(p, n_labels=4)
    for text, msg in [
        ("0 Plane\n0 Cone\n", "twice"),
        ("0 Plane\n2 Cone\n", "missing"),
        ("Plane\n", "not 'id Type'"),
        ("x Plane\n", "not 'id Type'"),
    ]:
        p.write_text(text)
        with pytest.raises(MeshError, match=msg):
            read_surface_types(p)
    with pytest.raises(MeshError, match="cannot read"):
        read_surface_types(tmp_path / "missing.txt")


def test_evaluate_labels_reports_boundary_and_types(box):
    V, F, _, side = box
    pred = np.where(side == 5, 1, side)  # +z merged into +x
    _, pred = np.unique(pred, return_inverse=True)  # 0..4: -x, +x(+z), -y, +y, -z
    ev = evaluate_labels(V, F, pred, side, cut_metric=False)
    assert ev.boundary_ratio == pytest.approx(22 / 24)
    assert ev.segment_ratio == pytest.approx(5 / 6)
    assert ev.type_accuracy is None
    true_types = ["Plane"] * 5 + ["Cylinder"]
    ev = evaluate_labels(
        V, F, pred, side, pred_types=["plane"] * 5, truth_types=true_types, cut_metric=False
    )
    assert ev.type_accuracy == pytest.approx(5 / 6)
    d = ev.as_dict()
    assert d["boundary_ratio"] == pytest.approx(22 / 24) and d["type_accuracy"] == ev.type_accuracy
    with pytest.raises(MeshError, match="types"):
        evaluate_labels(V, F, pred, side, pred_types=["plane"] * 4, truth_types=true_types)


# --------------------------------------------------------------------------------------------
# igl-heatseg evaluate: --types, report.json beside --pred, robust mode's own surfaces
# --------------------------------------------------------------------------------------------


def _evaluate(argv, capsys):
    import json

    from igl_heatseg.cli import main

    code = main(["evaluate", *argv])
    out = capsys.readouterr()
    return code, (json.loads(out.out) if "--json" in argv and code == 0 else out.out + out.err)


@pytest.fixture()
def cube_files(tmp_path, box):
    import igl

    V, F, _, side = box
    mesh = tmp_path / "part.obj"
    igl.write_triangle_mesh(str(mesh), V, F)
    truth = tmp_path / "part.facelabels.txt"
    truth.write_text("\n".join(map(str, side)) + "\n")
    (tmp_path / "part.surface_types.txt").write_text(
        "".join(f"{k} {t}\n" for k, t in enumerate(["Plane"] * 5 + ["Cylinder"]))
    )
    return tmp_path, mesh, truth, side


def test_cli_types_from_report_beside_pred_and_default_types_file(cube_files, capsys):
    import json

    tmp, mesh, truth, side = cube_files
    pred = tmp / "seg"
    pred.mkdir()
    (pred / "labels.txt").write_text("\n".join(map(str, side)) + "\n")
    code, d = _evaluate([str(mesh), "--truth", str(truth), "--pred", str(pred), "--json"], capsys)
    assert code == 0 and d["type_accuracy"] is None and d["boundary_ratio"] == pytest.approx(1)
    assert d["types_file"] == str(tmp / "part.surface_types.txt")
    code, text = _evaluate([str(mesh), "--truth", str(truth), "--pred", str(pred)], capsys)
    assert "boundary length ratio" in text and "prediction has no surface types" in text
    report = {"surfaces": [{"segment": k, "type": "plane"} for k in range(6)]}
    (pred / "report.json").write_text(json.dumps(report))
    code, d = _evaluate([str(mesh), "--truth", str(truth), "--pred", str(pred), "--json"], capsys)
    assert code == 0 and d["type_accuracy"] == pytest.approx(5 / 6)  # +z is the cylinder
    # the labels file itself as --pred finds the report beside it; --types overrides
    planes = tmp / "planes.txt"
    planes.write_text("".join(f"{k} Plane\n" for k in range(6)))
    argv = [str(mesh), "--truth", str(truth), "--pred", str(pred / "labels.txt")]
    code, d = _evaluate([*argv, "--types", str(planes), "--json"], capsys)
    assert code == 0 and d["type_accuracy"] == pytest.approx(1.0)
    code, text = _evaluate([*argv, "--types", str(planes)], capsys)
    assert "surface type accuracy, area" in text and "1.0000" in text
    # too few types for the true labels, or a report without types: exit 2
    planes.write_text("0 Plane\n")
    code, text = _evaluate([*argv, "--types", str(planes)], capsys)
    assert code == 2 and "1 surface types for 6 labels" in text
    (pred / "report.json").write_text(json.dumps({"surfaces": [{"segment": 0}]}))
    code, text = _evaluate(argv, capsys)
    assert code == 2 and "'type'" in text


def test_cli_robust_mode_scores_its_own_surface_types(cube_files, capsys):
    tmp, mesh, truth, side = cube_files
    planes = tmp / "planes.txt"
    planes.write_text("".join(f"{k} Plane\n" for k in range(6)))
    argv = [str(mesh), "--truth", str(truth), "--mode", "robust", "--json"]
    code, d = _evaluate([*argv, "--types", str(planes)], capsys)
    assert code == 0 and d["n_segments"] == 6
    assert d["type_accuracy"] == pytest.approx(1.0) and d["boundary_ratio"] == pytest.approx(1.0)
    # the paper mode fits no surfaces: no type accuracy, the boundary ratio all the same
    code, d = _evaluate([str(mesh), "--truth", str(truth), "--mode", "paper", "--json"], capsys)
    assert code == 0 and d["type_accuracy"] is None and d["boundary_ratio"] == pytest.approx(1.0)
