"""_fast_utils: identical output to np.unique(axis=0) and topology.edge_topology."""

import numpy as np
import pytest
from meshes import cube, cylinder, sphere

from igl_heatseg._fast_utils import edge_topology as fast_edge_topology
from igl_heatseg._fast_utils import unique_rows
from igl_heatseg.topology import edge_topology


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
def test_edge_topology_identical(mesh):
    _, F = mesh
    a, b = edge_topology(F), fast_edge_topology(F)
    for name in ("E", "EMAP", "edge_face_count", "EF"):
        np.testing.assert_array_equal(getattr(b, name), getattr(a, name))
        assert getattr(b, name).dtype == getattr(a, name).dtype
