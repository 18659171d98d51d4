import igl
import numpy as np
import pytest
import scipy.sparse.linalg as sla
from meshes import cylinder, grid, sphere

from igl_heatseg.constants import TIE_RTOL
from igl_heatseg.heat.exact import HeatSolver, heat_fields
from igl_heatseg.segmentation.seeds import seed_groups, seed_mask


def _two_seed_grid():
    V, F = grid(10, 10)
    group = -np.ones(len(V), dtype=np.int64)
    group[np.isclose(V[:, 0], 0)] = 0
    group[np.isclose(V[:, 0], 1)] = 1
    return V, F, group


def test_linear_profile_between_two_walls():
    # Dirichlet 1 on x=0 and 0 on x=1, natural boundary elsewhere: u = 1 - x exactly.
    V, F, group = _two_seed_grid()
    U = heat_fields(V, F, group)
    np.testing.assert_allclose(U[:, 0], 1 - V[:, 0], atol=1e-12)
    np.testing.assert_allclose(U[:, 1], V[:, 0], atol=1e-12)


def test_fields_sum_to_one_are_harmonic_and_fixed_on_seeds():
    V, F = sphere(3)
    V = V * [1.0, 0.7, 0.5]
    mask = seed_mask(V, F, 0.1)
    rng = np.random.default_rng(1)
    mask &= rng.random(len(V)) < 0.3
    k, group = seed_groups(F, mask)
    assert k >= 3
    U = heat_fields(V, F, group)
    np.testing.assert_allclose(U.sum(axis=1), 1.0, atol=1e-10)
    seeds = group >= 0
    np.testing.assert_array_equal(U[seeds].argmax(axis=1), group[seeds])
    np.testing.assert_allclose(U[seeds].max(axis=1), 1.0)
    L = igl.cotmatrix(V, F)
    np.testing.assert_allclose((L @ U)[~seeds], 0.0, atol=1e-10)
    # maximum principle (this sphere is Delaunay: all cotangent weights are non-negative)
    assert U.min() >= -1e-12 and U.max() <= 1 + 1e-12


def test_matches_scipy_direct_solve():
    V, F = cylinder(32, 6)
    k, group = seed_groups(F, seed_mask(V, F))
    L = igl.cotmatrix(V, F).tocsr()
    free = np.flatnonzero(group < 0)
    known = np.flatnonzero(group >= 0)
    Y = (group[known][:, None] == np.arange(k)[None, :]).astype(float)
    Uf = sla.spsolve(L[free][:, free].tocsc(), -(L[free][:, known] @ Y))
    U = heat_fields(V, F, group)
    np.testing.assert_allclose(U[free], Uf, atol=1e-10)


def test_streaming_labels_equal_dense_argmax_with_low_id_ties():
    V, F, group = _two_seed_grid()
    solver = HeatSolver(V, F, group)
    hl = solver.labels()
    U = solver.temperatures([0, 1])

    def first_near_max(X):  # ties (within TIE_RTOL, i.e. round-off) to the lowest id
        top = X.max(axis=1, keepdims=True)
        return (X >= top - TIE_RTOL * np.abs(top)).argmax(axis=1)

    np.testing.assert_array_equal(hl.vertex_labels, first_near_max(U))
    Uf = U[F].mean(axis=1)
    np.testing.assert_array_equal(hl.face_labels, first_near_max(Uf))
    # the grid is symmetric: exact ties exist, and plain argmax decides them by round-off
    assert (np.abs(U[:, 0] - U[:, 1]) <= TIE_RTOL * U.max(axis=1)).any()
    assert hl.sum_error < 1e-12


def test_exact_ties_go_to_the_lowest_group_across_batches():
    from igl_heatseg.heat.exact import argmax_update

    best = np.full(3, -np.inf)
    arg = np.zeros(3, dtype=np.int64)
    argmax_update(np.array([[0.5, 0.5], [0.2, 0.8], [0.4, 0.1]]), 0, best, arg)
    argmax_update(np.array([[0.5, 0.1], [0.8, 0.0], [0.9, 0.0]]), 2, best, arg)
    assert arg.tolist() == [0, 1, 2]


def test_component_without_seed_is_rejected():
    V1, F1 = grid(3, 3)
    V = np.r_[V1, V1 + [5, 0, 0]]
    F = np.r_[F1, F1 + len(V1)]
    group = -np.ones(len(V), dtype=np.int64)
    group[0] = 0
    with pytest.raises(ValueError, match="hold no seed"):
        HeatSolver(V, F, group)


def test_partial_argmax_agrees_with_labels_and_dense_argmax():
    """HeatSolver.argmax (the fast solver's exact fallback) is the same streaming argmax as
    labels(): over all groups it gives labels() at the items asked; over a subset of groups
    (more than one batch) the dense argmax over those columns, ties to the lowest id."""
    V, F = sphere(3)
    k, group = seed_groups(F, np.random.default_rng(4).random(len(V)) < 0.3)
    assert k > 40  # more than one batch of SOLVE_BATCH fields
    solver = HeatSolver(V, F, group)
    hl = solver.labels()
    s = solver.system
    rng = np.random.default_rng(0)
    vs = np.sort(rng.choice(s.nf, 40, replace=False))
    fs = np.sort(rng.choice(len(F), 60, replace=False))
    r = solver.argmax(np.arange(k), vs, fs)
    np.testing.assert_array_equal(r.vertex_labels, hl.vertex_labels[s.free[vs]])
    np.testing.assert_array_equal(r.face_labels, hl.face_labels[fs])
    np.testing.assert_allclose(r.vertex_max, hl.vertex_max[s.free[vs]], atol=1e-12)
    assert r.error < 1e-10  # the solves' relative residual
    gs = np.arange(1, k, 2)
    r = solver.argmax(gs, vs, fs)
    U = solver.temperatures(gs)
    np.testing.assert_array_equal(r.vertex_labels, gs[U[s.free[vs]].argmax(axis=1)])
    np.testing.assert_array_equal(r.face_labels, gs[U[F[fs]].mean(axis=1).argmax(axis=1)])


def test_sparse_cholesky_solves_and_reports_backend():
    from igl_heatseg.heat.factor import SparseCholesky

    V, F = grid(8, 8)
    k, group = seed_groups(F, np.isclose(V[:, 0], 0) | np.isclose(V[:, 0], 1))
    s = HeatSolver(V, F, group).system
    fac = SparseCholesky(s.A, 1)
    assert fac.backend == "libigl"  # few right-hand sides: libigl's LLT
    B = s.B.toarray()
    X = fac.solve(B)
    np.testing.assert_allclose(s.A @ X, B, atol=1e-12)
    np.testing.assert_allclose(fac.solve(B[:, 0]), X[:, 0])
