"""Tests for benchmarks/surface_metrics_draft.py (type accuracy, boundary-length ratio)."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))
import surface_metrics_draft as sm  # noqa: E402


def grid(n: int) -> tuple[np.ndarray, np.ndarray]:
    """Unit square split into n x n cells of two triangles; face 2*(i*n+j)+{0,1} in cell (i,j)."""
    x = np.linspace(0.0, 1.0, n + 1)
    X, Y = np.meshgrid(x, x, indexing="ij")
    V = np.stack([X.ravel(), Y.ravel(), np.zeros(X.size)], axis=1)
    F = []
    for i in range(n):
        for j in range(n):
            a, b = i * (n + 1) + j, (i + 1) * (n + 1) + j
            F += [[a, b, a + 1], [b, b + 1, a + 1]]
    return V, np.array(F, dtype=np.int64)


def cell_labels(n: int, f) -> np.ndarray:
    """Label of each face from ``f(i, j)`` of its cell."""
    return np.repeat([f(i, j) for i in range(n) for j in range(n)], 2)


def test_kind_of_maps_abc_names_and_everything_else_to_freeform():
    for abc, kind in [
        ("Plane", "plane"),
        ("Cylinder", "cylinder"),
        ("Cone", "cone"),
        ("Sphere", "sphere"),
        ("Torus", "torus"),
        ("torus", "torus"),
    ]:
        assert sm.kind_of(abc) == kind
    for other in ("BSpline", "Extrusion", "Revolution", "Other", "freeform", "", None):
        assert sm.kind_of(other) == "freeform"


def test_face_kinds_expands_segment_types():
    k = sm.face_kinds(np.array([1, 0, 1]), ["Plane", "BSpline"])
    assert list(k) == ["freeform", "plane", "freeform"]
    with pytest.raises(ValueError, match="labels"):
        sm.face_kinds(np.array([0, 2]), ["Plane", "Cone"])


def test_type_accuracy_is_area_weighted():
    pred = ["plane", "cylinder", "cone", "Other"]
    true = ["Plane", "Cylinder", "Torus", "BSpline"]  # third wrong; fourth: both freeform
    assert sm.type_accuracy(pred, true) == pytest.approx(0.75)
    assert sm.type_accuracy(pred, true, [1.0, 1.0, 6.0, 2.0]) == pytest.approx(0.4)
    assert sm.type_accuracy(true, true) == 1.0
    with pytest.raises(ValueError):
        sm.type_accuracy(pred, true[:3])
    with pytest.raises(ValueError):
        sm.type_accuracy(pred, true, [0, 0, 0, 0])


def test_boundary_length_on_a_grid():
    n = 4
    V, F = grid(n)
    assert sm.boundary_length(V, F, np.zeros(len(F), dtype=int)) == 0.0
    halves = cell_labels(n, lambda i, j: int(i >= n // 2))  # cut along x = 0.5: length 1
    assert sm.boundary_length(V, F, halves) == pytest.approx(1.0)
    quarters = cell_labels(n, lambda i, j: 2 * int(i >= 2) + int(j >= 2))  # a cross: length 2
    assert sm.boundary_length(V, F, quarters) == pytest.approx(2.0)
    # every triangle its own label: all interior edges (axis-parallel and diagonals)
    every = np.arange(len(F))
    interior = 2 * (n - 1) * n * (1.0 / n) + n * n * np.sqrt(2) / n
    assert sm.boundary_length(V, F, every) == pytest.approx(interior)
    assert len(sm.boundary_edges(F, quarters)) == 2 * n


def test_boundary_length_ratio():
    n = 4
    V, F = grid(n)
    truth = cell_labels(n, lambda i, j: int(i >= n // 2))
    assert sm.boundary_length_ratio(V, F, truth, truth) == 1.0
    # label permutations do not matter
    assert sm.boundary_length_ratio(V, F, 5 - truth, truth) == 1.0
    over = cell_labels(n, lambda i, j: 2 * int(i >= 2) + int(j >= 2))
    assert sm.boundary_length_ratio(V, F, over, truth) == pytest.approx(2.0)
    assert sm.boundary_length_ratio(V, F, np.zeros(len(F), dtype=int), truth) == 0.0
    one = np.zeros(len(F), dtype=int)
    assert sm.boundary_length_ratio(V, F, one, one) == 1.0
    assert sm.boundary_length_ratio(V, F, truth, one) == float("inf")


def test_boundary_ignores_mesh_border_and_closed_mesh_counts_each_edge_once():
    # a tetrahedron: two labels, 2 faces each -> the boundary is a 4-edge cycle
    V = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]])
    F = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    lab = np.array([0, 0, 1, 1])
    E = sm.boundary_edges(F, lab)
    assert len(E) == 4
    L = sm.boundary_length(V, F, lab)
    shared = {tuple(sorted(e)) for e in E.tolist()}
    assert (0, 1) not in shared and (2, 3) not in shared  # inside label 0 and label 1
    assert L == pytest.approx(sum(np.linalg.norm(V[a] - V[b]) for a, b in shared))
    # the open grid's border edges never count
    V2, F2 = grid(2)
    assert sm.boundary_length(V2, F2, np.arange(len(F2))) > 0
    assert len(sm.boundary_edges(F2, np.arange(len(F2)))) == 2 * 2 + 4  # interior edges only


# --------------------------------------------------------------------------------------------
# The CGAL peer (benchmarks/peers.py) that feeds these metrics its per-segment types
# --------------------------------------------------------------------------------------------


def cube(n: int) -> tuple[np.ndarray, np.ndarray]:
    """A closed, outward unit cube with every side an n x n grid of triangle pairs."""
    Vs, Fs, off = [], [], 0
    V0, F0 = grid(n)
    for axis in range(3):
        for side in (0.0, 1.0):
            W = np.roll(V0, axis + 1, axis=1)  # the grid in the plane normal to ``axis``
            W[:, axis] = side
            Fk = F0 if (side == 1.0) == (axis != 1) else F0[:, ::-1]
            Vs.append(W)
            Fs.append(Fk + off)
            off += len(W)
    V, F = np.concatenate(Vs), np.concatenate(Fs)
    key = np.round(V, 9)
    _, first, inv = np.unique(key, axis=0, return_index=True, return_inverse=True)
    V = V[first]
    F = inv.reshape(-1)[F]
    P = V[F]
    vol = np.einsum("ij,ij->i", P[:, 0], np.cross(P[:, 1], P[:, 2])).sum() / 6
    return V, (F if vol > 0 else F[:, ::-1])


def test_peer_face_adjacency_and_growth():
    import peers

    V, F = cube(3)
    a, b = peers.face_adjacency(F)
    assert len(a) == 3 * len(F) // 2  # closed: every edge has two faces
    nbr = peers._neighbours(len(F), a, b)
    lab = np.full(len(F), -1)
    lab[0], lab[len(F) - 1] = 0, 1
    grown = peers._grow(lab, nbr)
    assert (grown >= 0).all() and set(grown.tolist()) == {0, 1}
    assert peers.ransac_type("Type: cylinder center: (0, 0, 0) axis: (0, 0, 1)") == "cylinder"
    assert peers.ransac_type("something else") == "freeform"


def test_cgal_peer_labels_every_face_of_a_cube_with_planes():
    pytest.importorskip("CGAL.CGAL_Shape_detection", reason="the cgal wheel is not installed")
    import peers

    V, F = cube(12)
    # CGAL's default cluster_epsilon (1 % of the diagonal) connects none of these centroids
    # (spacing 1/12): whatever it finds, every face gets a label and a kind
    for ce in (None, peers.spacing_cluster_epsilon(V, F)):
        # in a child process: the wheel's RANSAC occasionally segfaults (then retried)
        r = peers.cgal_ransac_isolated(V, F, cluster_epsilon=ce)
        assert r.labels.shape == (len(F),) and r.labels.min() == 0
        assert np.array_equal(np.unique(r.labels), np.arange(len(r.types)))
        assert set(r.types) <= set(sm.KINDS)
    # with the spacing-based epsilon the six sides come out as planes covering most faces
    lab_kind = sm.face_kinds(r.labels, r.types)
    assert (lab_kind == "plane").mean() > 0.5
    with pytest.raises(ValueError, match="unassigned"):
        peers.cgal_ransac(V, F, unassigned="drop")  # checked before CGAL runs
    with pytest.raises(RuntimeError, match="unassigned"):
        peers.cgal_ransac_isolated(V, F, unassigned="drop")


# --------------------------------------------------------------------------------------------
# benchmarks/surface_table.py: scoring, aggregation and report (no CLI, no CGAL)
# --------------------------------------------------------------------------------------------


def test_surface_table_scores_aggregates_and_reports():
    import surface_table as st

    n = 4
    V, F = grid(n)
    truth = cell_labels(n, lambda i, j: int(i >= n // 2))
    P = V[F]
    part = dict(
        V=V,
        F=F,
        labels=truth,
        kinds=sm.face_kinds(truth, ["Plane", "Cylinder"]),
        area=0.5 * np.linalg.norm(np.cross(P[:, 1] - P[:, 0], P[:, 2] - P[:, 0]), axis=1),
        true_boundary=sm.boundary_length(V, F, truth),
    )
    perfect = st.score(part, 1 - truth, ["cylinder", "plane"])
    assert perfect["purity"] == perfect["coverage"] == perfect["type_acc"] == 1.0
    assert perfect["seg_ratio"] == 1.0 and perfect["bnd_ratio"] == 1.0
    merged = st.score(part, np.zeros(len(F), dtype=int), None)
    assert merged["purity"] == 0.5 and merged["coverage"] == 1.0 and merged["type_acc"] is None
    assert merged["bnd_ratio"] == 0.0
    base = dict(name="p", family="f", seed=1, tessellation="frontal", noise=0.0, faces=len(F))
    rows = [
        dict(base, method="a", true_faces=2, **perfect, seconds=1.0, error=None),
        dict(base, method="b", true_faces=2, **merged, seconds=2.0, error=None),
        dict(base, method="a", true_faces=2, seconds=None, error="exit 1: boom", noise=0.1),
    ]
    agg = st.aggregate(rows, ["a", "b"])
    assert agg["a"]["passed"] == 1 and agg["a"]["failed"] == 1 and agg["b"]["passed"] == 0
    assert agg["a"]["passed_by_noise"] == {"0.0": "1/1", "0.1": "0/1"}
    meta = dict(set="t", date="d", machine="m", command="c", cli="x", igl_heatseg="y", parts=1)
    md = st.markdown(meta, rows, agg, ["a", "b"])
    assert "| a | 2 | 1 |" in md and "failed: exit 1: boom" in md
    assert st._report_types({"surfaces": [{"type": "plane"}]}, 1) == (["plane"], "surfaces")
    assert st._report_types({"primitive_types": ["Plane", "Other"]}, 2)[1] == "primitive_types"
    assert st._report_types({"primitive_types": ["Plane"]}, 2) == (None, None)
