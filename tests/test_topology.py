"""topology: unique_rows equals np.unique(axis=0); edge topology, loops and Euler counts."""

import numpy as np
import pytest
from meshes import cube, cylinder, sphere

from igl_heatseg.mesh.topology import (
    boundary_loops,
    corner_edges,
    edge_topology,
    euler_characteristic,
    face_components,
    unique_rows,
)


def _same_unique(A):
    U0, i0, c0 = np.unique(A, axis=0, return_inverse=True, return_counts=True)
    U1, i1, c1 = unique_rows(A, return_inverse=True, return_counts=True)
    np.testing.assert_array_equal(U1, U0)
    np.testing.assert_array_equal(i1, i0.reshape(-1))
    np.testing.assert_array_equal(c1, c0)
    assert U1.dtype == U0.dtype
    np.testing.assert_array_equal(unique_rows(A), U0)


@pytest.mark.parametrize("seed", range(5))
def test_unique_rows_matches_numpy(seed):
    rng = np.random.default_rng(seed)
    _same_unique(rng.integers(0, 7, size=(300, 2)))  # packed-key path
    _same_unique(rng.integers(-3, 4, size=(300, 2)))  # negative: lexsort path
    _same_unique(rng.integers(0, 5, size=(300, 3)))
    V = rng.integers(0, 4, size=(400, 3)).astype(np.float64) * 0.25  # many exact duplicates
    _same_unique(V)
    _same_unique(rng.random((50, 3)))  # no duplicates
    _same_unique(np.zeros((0, 3)))


def test_unique_rows_negative_zero_equals_zero():
    A = np.array([[0.0, 1.0], [-0.0, 1.0], [1.0, 0.0]])
    U, inv = unique_rows(A, return_inverse=True)
    assert len(U) == 2 and inv[0] == inv[1]


@pytest.mark.parametrize("mesh", [cube(5), cylinder(16, 4), sphere(2)])
def test_edge_topology_matches_numpy_reference(mesh):
    _, F = mesh
    t = edge_topology(F)
    S = np.sort(corner_edges(F), axis=1)
    E, EMAP, counts = np.unique(S, axis=0, return_inverse=True, return_counts=True)
    np.testing.assert_array_equal(t.E, E)
    np.testing.assert_array_equal(t.EMAP, EMAP.reshape(-1))
    np.testing.assert_array_equal(t.edge_face_count, counts)
    assert t.E.dtype == t.EMAP.dtype == t.EF.dtype == np.int64
    # EF lists the faces of each edge: every face holds its edge
    m = len(F)
    for e in range(0, len(t.E), 7):
        for f in t.EF[e][t.EF[e] >= 0]:
            assert set(t.E[e]) <= set(F[f])
    assert (t.edge_face_count == 2).all()  # closed meshes
    assert np.bincount(t.EMAP, minlength=len(t.E)).tolist() == [2] * len(t.E)
    assert m * 3 == 2 * len(t.E)


def test_boundary_loops_euler_and_components():
    V, F = cylinder(16, 4, caps=False)
    loops = boundary_loops(F)
    assert [len(lp) for lp in loops] == [16, 16]
    assert euler_characteristic(F) == 0
    assert face_components(F)[0] == 1
    V2, F2 = sphere(1)
    assert euler_characteristic(F2) == 2 and boundary_loops(F2) == []
    assert face_components(np.r_[F2, F2 + len(V2)])[0] == 2
