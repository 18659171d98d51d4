"""Tests for igl_heatseg.evaluation.metrics: analytic cases first, then invariances, readers and the CLI."""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import numpy as np
import pytest

from igl_heatseg.errors import MeshError
from igl_heatseg.cli.evaluate import register
from igl_heatseg.evaluation.metrics import (
    consistency_errors,
    contingency_table,
    coverage,
    cut_discrepancy,
    cut_edges,
    directional_cut_discrepancy,
    evaluate_labels,
    face_areas,
    hamming_distance,
    mean_radius,
    psb_rand_index,
    purity,
    rand_index,
    read_labels,
    read_truth,
)

TOL = 1e-12
DATA = Path(__file__).resolve().parents[2] / "shared" / "data" / "mechanical"


def grid(nx: int, ny: int, lx: float, ly: float):
    """Triangulated rectangle [0,lx] x [0,ly], nx by ny cells, two triangles per cell."""
    xs, ys = np.linspace(0, lx, nx + 1), np.linspace(0, ly, ny + 1)
    X, Y = np.meshgrid(xs, ys, indexing="ij")
    V = np.stack([X.ravel(), Y.ravel(), np.zeros(X.size)], axis=1)
    idx = np.arange((nx + 1) * (ny + 1)).reshape(nx + 1, ny + 1)
    a, b = idx[:-1, :-1].ravel(), idx[1:, :-1].ravel()
    c, d = idx[1:, 1:].ravel(), idx[:-1, 1:].ravel()
    F = np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, d], 1)])
    return V, F


def four_triangles():
    """Four disjoint triangles with areas 1, 2, 3, 4."""
    V, F = [], []
    for k, w in enumerate([1.0, 2.0, 3.0, 4.0]):
        x0 = 10.0 * k
        V += [[x0, 0, 0], [x0 + 2 * w, 0, 0], [x0, 1, 0]]
        F.append([3 * k, 3 * k + 1, 3 * k + 2])
    return np.array(V), np.array(F)


# ---------------------------------------------------------------- hand-computed 4-face example
# weights 1,2,3,4; pred = [0,0,1,1]; truth = [0,1,1,1]  ->  N = [[1,2],[0,7]], A = 10.
W4 = np.array([1.0, 2.0, 3.0, 4.0])
P4 = np.array([0, 0, 1, 1])
T4 = np.array([0, 1, 1, 1])


def test_four_face_hand_computed():
    assert np.array_equal(contingency_table(P4, T4, W4), [[1.0, 2.0], [0.0, 7.0]])
    assert purity(P4, T4, W4) == pytest.approx(0.9, abs=TOL)  # (2 + 7) / 10
    assert coverage(P4, T4, W4) == pytest.approx(0.8, abs=TOL)  # (1 + 7) / 10
    # 1 - (.3^2 + .7^2) - (.1^2 + .9^2) + 2 (.1^2 + .2^2 + .7^2) = 0.68
    assert rand_index(P4, T4, W4) == pytest.approx(0.68, abs=TOL)
    # face pairs: (0,1), (1,2), (1,3) disagree out of 6
    assert psb_rand_index(P4, T4) == pytest.approx(0.5, abs=TOL)
    rm, rf, hd = hamming_distance(P4, T4, W4)
    assert (rm, rf, hd) == pytest.approx((0.2, 0.1, 0.15), abs=TOL)
    gce, lce = consistency_errors(P4, T4, W4)
    # sum N E12 = 1*2/3 + 2*1/3 = 4/3; sum N E21 = 2*7/9 + 7*2/9 = 28/9; LCE: 2 * 1/3
    assert gce == pytest.approx(4 / 30, abs=TOL)
    assert lce == pytest.approx(2 / 30, abs=TOL)


def test_four_face_mesh_evaluation_uses_areas():
    V, F = four_triangles()
    assert face_areas(V, F) == pytest.approx(W4)
    ev = evaluate_labels(V, F, P4, T4, cut_metric=False)
    assert (ev.n_segments, ev.n_true_segments, ev.n_truths) == (2, 2.0, 1)
    assert ev.purity == pytest.approx(0.9) and ev.coverage == pytest.approx(0.8)
    assert ev.rand_index == pytest.approx(0.68) and ev.psb_rand_index == pytest.approx(0.5)
    assert ev.gce == pytest.approx(4 / 30) and ev.lce == pytest.approx(2 / 30)
    counted = evaluate_labels(V, F, P4, T4, weighting="count", cut_metric=False)
    assert counted.purity == pytest.approx(0.75)  # faces: (1 + 2) / 4
    assert counted.coverage == pytest.approx(0.75)  # (1 + 2) / 4


# ---------------------------------------------------------------- invariances and properties
def random_case(seed: int, m: int = 200, k: int = 6):
    rng = np.random.default_rng(seed)
    return rng.integers(0, k, m), rng.integers(0, k, m), rng.uniform(0.1, 2.0, m)


@pytest.mark.parametrize("seed", range(5))
def test_identical_labelings_are_perfect(seed):
    _, t, w = random_case(seed)
    assert purity(t, t, w) == pytest.approx(1.0)
    assert coverage(t, t, w) == pytest.approx(1.0)
    assert rand_index(t, t, w) == pytest.approx(1.0)
    assert psb_rand_index(t, t) == pytest.approx(0.0, abs=TOL)
    assert hamming_distance(t, t, w) == pytest.approx((0, 0, 0), abs=TOL)
    assert consistency_errors(t, t, w) == pytest.approx((0, 0), abs=TOL)


@pytest.mark.parametrize("seed", range(5))
def test_relabelling_permutation_keeps_scores(seed):
    p, t, w = random_case(seed)
    rng = np.random.default_rng(100 + seed)
    perm = rng.permutation(50) + 7  # new ids, not contiguous, not starting at 0
    for f in (purity, coverage, rand_index):
        assert f(perm[p], t, w) == pytest.approx(f(p, t, w), abs=TOL)
        assert f(p, perm[t], w) == pytest.approx(f(p, t, w), abs=TOL)
    assert psb_rand_index(perm[p], t) == pytest.approx(psb_rand_index(p, t), abs=TOL)
    assert consistency_errors(perm[p], t, w) == pytest.approx(consistency_errors(p, t, w))


@pytest.mark.parametrize("seed", range(5))
def test_score_ranges_and_lce_below_gce(seed):
    p, t, w = random_case(seed)
    for f in (purity, coverage, rand_index):
        assert 0.0 <= f(p, t, w) <= 1.0
    gce, lce = consistency_errors(p, t, w)
    assert 0.0 <= lce <= gce + TOL
    rm, rf, _ = hamming_distance(p, t, w)
    assert rm == pytest.approx(1 - coverage(p, t, w)) and rf == pytest.approx(1 - purity(p, t, w))
    # symmetric scores
    assert rand_index(p, t, w) == pytest.approx(rand_index(t, p, w))
    assert psb_rand_index(p, t) == pytest.approx(psb_rand_index(t, p))


def test_merging_lowers_purity_not_coverage():
    truth = np.repeat([0, 1, 2], [30, 20, 50])
    merged = np.where(truth == 1, 0, truth)
    assert purity(merged, truth) == pytest.approx(0.8)  # segment {0,1} keeps 30 of 50
    assert coverage(merged, truth) == pytest.approx(1.0)
    # a coarsening is a refinement the other way: consistency errors are 0
    assert consistency_errors(merged, truth) == pytest.approx((0.0, 0.0), abs=TOL)


def test_splitting_lowers_coverage_not_purity():
    truth = np.repeat([0, 1, 2], [30, 20, 50])
    split = truth.copy()
    split[80:] = 3  # true segment 2 split 30 / 20
    assert purity(split, truth) == pytest.approx(1.0)
    assert coverage(split, truth) == pytest.approx(0.8)
    assert consistency_errors(split, truth) == pytest.approx((0.0, 0.0), abs=TOL)
    assert psb_rand_index(split, truth) > 0


# ---------------------------------------------------------------- cut discrepancy
def test_mean_radius_of_rectangle_matches_integral():
    V, F = grid(32, 8, 4.0, 1.0)
    # midpoint rule on a fine grid of the exact area integral
    xs = (np.arange(800) + 0.5) / 800 * 4.0
    ys = (np.arange(200) + 0.5) / 200 * 1.0
    X, Y = np.meshgrid(xs, ys)
    exact = np.hypot(X - 2.0, Y - 0.5).mean()
    assert mean_radius(V, F) == pytest.approx(exact, rel=2e-3)


def test_cut_discrepancy_between_parallel_cuts():
    V, F = grid(16, 4, 4.0, 1.0)
    cx = V[F].mean(axis=1)[:, 0]
    s1 = (cx < 1.0).astype(int)
    s2 = (cx < 2.0).astype(int)
    c1, c2 = cut_edges(F, s1), cut_edges(F, s2)
    assert len(c1) == 4 and np.allclose(V[c1][:, :, 0], 1.0)
    from igl_heatseg.mesh.topology import edge_topology

    E = edge_topology(F).E
    # every point of the line x=1 is exactly 1 away (along grid edges) from the line x=2
    assert directional_cut_discrepancy(V, c1, c2, E=E) == pytest.approx(1.0)
    assert directional_cut_discrepancy(V, c2, c1, E=E) == pytest.approx(1.0)
    assert cut_discrepancy(V, F, s1, s2) == pytest.approx(2.0 / mean_radius(V, F))
    assert cut_discrepancy(V, F, s1, s1) == pytest.approx(0.0, abs=TOL)
    none = np.zeros(len(F), dtype=int)
    assert cut_discrepancy(V, F, none, none) == 0.0
    assert math.isinf(cut_discrepancy(V, F, s1, none))


def test_several_truths_are_averaged():
    V, F = grid(8, 2, 4.0, 1.0)
    cx = V[F].mean(axis=1)[:, 0]
    t1, t2 = (cx < 2.0).astype(int), (cx < 1.0).astype(int)
    ev = evaluate_labels(V, F, t1, [t1, t2])
    one = evaluate_labels(V, F, t1, t2)
    assert ev.n_truths == 2
    assert ev.purity == pytest.approx(0.5 * (1.0 + one.purity))
    assert ev.cut_discrepancy == pytest.approx(0.5 * one.cut_discrepancy)
    assert ev.per_truth[0]["coverage"] == pytest.approx(1.0)
    stacked = evaluate_labels(V, F, t1, np.stack([t1, t2]))
    assert stacked.as_dict() == ev.as_dict()


# ---------------------------------------------------------------- input checks and readers
def test_bad_label_inputs_raise_mesherror():
    V, F = four_triangles()
    with pytest.raises(MeshError, match="3 labels for a mesh with 4 faces"):
        evaluate_labels(V, F, [0, 0, 1], T4)
    with pytest.raises(MeshError, match="truth 1: 5 labels"):
        evaluate_labels(V, F, P4, [T4, [0, 0, 0, 0, 0]])
    with pytest.raises(MeshError, match="non-integer"):
        evaluate_labels(V, F, [0.5, 0, 1, 1], T4)
    with pytest.raises(MeshError, match="shape"):
        evaluate_labels(V, F, np.zeros((4, 2), int), T4)
    with pytest.raises(MeshError, match="weighting"):
        evaluate_labels(V, F, P4, T4, weighting="volume")
    with pytest.raises(MeshError, match="no ground-truth"):
        evaluate_labels(V, F, P4, [])


def test_read_labels_and_truth_dir(tmp_path):
    f = tmp_path / "a.txt"
    f.write_text("# comment\n0\n1\n\n2\n")
    assert read_labels(f).tolist() == [0, 1, 2]
    with pytest.raises(MeshError, match="3 labels for a mesh with 4 faces"):
        read_labels(f, 4)
    (tmp_path / "bad.txt").write_text("0\nx1\n")
    with pytest.raises(MeshError, match="line 2"):
        read_labels(tmp_path / "bad.txt")
    with pytest.raises(MeshError, match="cannot read"):
        read_labels(tmp_path / "missing.txt")
    d = tmp_path / "segs"
    d.mkdir()
    with pytest.raises(MeshError, match="no .seg files"):
        read_truth(d)
    for k in (10, 2):
        (d / f"7_{k}.seg").write_text("\n".join([str(k)] * 3) + "\n")
    truths = read_truth(d, 3)
    assert [t[0] for t in truths] == [2, 10]  # natural order
    with pytest.raises(MeshError, match="no such"):
        read_truth(tmp_path / "nothing")


@pytest.mark.skipif(not DATA.exists(), reason="shared test meshes not present")
def test_psb_human_segmentations_agree_with_themselves():
    import igl

    V, F = igl.read_triangle_mesh(str(DATA / "psb_324_mech.off"))
    truths = read_truth(DATA / "psb_324_mech_seg", F.shape[0])
    assert len(truths) == 13
    ev = evaluate_labels(V, F, truths[0], truths[0])
    assert ev.purity == 1.0 and ev.cut_discrepancy == 0.0 and ev.gce == 0.0
    avg = evaluate_labels(V, F, truths[0], truths)
    assert 0.0 < avg.cut_discrepancy < 1.0 and avg.purity > 0.5


# ---------------------------------------------------------------- command line
def _parser():
    parser = argparse.ArgumentParser(prog="igl-heatseg")
    register(parser.add_subparsers(dest="command"))
    return parser


def test_cli_with_pred_dir(tmp_path, capsys):
    V, F = grid(4, 2, 4.0, 1.0)
    mesh = tmp_path / "g.obj"
    with mesh.open("w") as fh:
        fh.writelines(f"v {x} {y} {z}\n" for x, y, z in V)
        fh.writelines(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in F)
    cx = V[F].mean(axis=1)[:, 0]
    truth = tmp_path / "truth.txt"
    truth.write_text("\n".join(str(int(x < 2)) for x in cx) + "\n")
    pred = tmp_path / "out"
    pred.mkdir()
    split = np.digitize(cx, [1.0, 2.0])  # a refinement of the truth: pure, 3 of 4 covered
    (pred / "labels.txt").write_text("\n".join(str(k) for k in split) + "\n")
    args = _parser().parse_args(["evaluate", str(mesh), "--truth", str(truth), "--pred", str(pred)])
    assert args.func(args) == 0
    out = capsys.readouterr().out
    assert "purity" in out and "coverage" in out
    args = _parser().parse_args(
        ["evaluate", str(mesh), "--truth", str(truth), "--pred", str(pred), "--json"]
    )
    assert args.func(args) == 0
    import json

    d = json.loads(capsys.readouterr().out)
    assert d["purity"] == pytest.approx(1.0) and d["coverage"] == pytest.approx(0.75)
    (pred / "labels.txt").write_text("0\n1\n")
    assert args.func(args) == 2
    assert "2 labels for a mesh with 16 faces" in capsys.readouterr().err


@pytest.mark.parametrize("mode", ["paper", "robust"])
def test_cli_segments_when_no_pred_is_given(tmp_path, capsys, mode):
    import igl

    V, F = igl.upsample(
        np.array([[x, y, z] for x in (0.0, 1) for y in (0.0, 1) for z in (0.0, 1)]),
        np.array(
            [
                [0, 1, 3],
                [0, 3, 2],
                [4, 6, 7],
                [4, 7, 5],
                [0, 4, 5],
                [0, 5, 1],
                [2, 3, 7],
                [2, 7, 6],
                [0, 2, 6],
                [0, 6, 4],
                [1, 5, 7],
                [1, 7, 3],
            ]
        ),  # fmt: skip
        3,
    )
    mesh = tmp_path / "cube.obj"
    igl.write_triangle_mesh(str(mesh), V, F)
    truth = tmp_path / "sides.txt"
    truth.write_text("\n".join(str(s) for s in np.repeat(np.arange(6), 2 * 4**3)) + "\n")
    args = _parser().parse_args(
        ["evaluate", str(mesh), "--truth", str(truth), "--mode", mode, "--json"]
    )
    assert args.func(args) == 0
    import json

    d = json.loads(capsys.readouterr().out)
    assert d["n_segments"] == 6 and d["purity"] == pytest.approx(1.0)
