import numpy as np
import pytest
from meshes import cube, cylinder, disk, grid, sphere

from igl_heatseg.constants import THETA_DEFAULT
from igl_heatseg.mesh.geometry import face_normals
from igl_heatseg.segmentation.seeds import dihedral_deviation, seed_groups, seed_mask, sharp_edges
from igl_heatseg.mesh.topology import edge_topology


def test_coarse_cube_has_exactly_12_sharp_edges_at_right_angles():
    V, F = cube(1)
    E, phi = dihedral_deviation(V, F)
    sharp = sharp_edges(phi, THETA_DEFAULT)
    assert sharp.sum() == 12
    np.testing.assert_allclose(phi[sharp], np.pi / 2, atol=1e-12)
    np.testing.assert_allclose(phi[~sharp], 0.0, atol=1e-12)  # the face diagonals
    assert not seed_mask(V, F).any()  # every cube vertex is a corner


def test_fine_cube_seeds_form_six_groups_of_face_interiors():
    n = 6
    V, F = cube(n)
    mask = seed_mask(V, F)
    on_edge = (np.abs(V) > 1 - 1e-12).sum(axis=1) >= 2
    assert np.array_equal(mask, ~on_edge)
    k, group = seed_groups(F, mask)
    assert k == 6
    assert np.bincount(group[group >= 0]).tolist() == [(n - 1) ** 2] * 6


def test_boundary_edges_are_never_sharp_and_have_nan_deviation():
    V, F = disk()
    topo = edge_topology(F)
    _, phi = dihedral_deviation(V, F, topo)
    assert np.isnan(phi[topo.boundary]).all()
    assert np.isfinite(phi[topo.interior]).all()
    assert seed_mask(V, F).all()


def test_fold_deviation_matches_bend_angle():
    V, F = grid(4, 4)
    bend = 0.3
    right = V[:, 0] > 0.5
    x = V[right, 0] - 0.5
    V[right, 0] = 0.5 + x * np.cos(bend)
    V[right, 2] = x * np.sin(bend)
    E, phi = dihedral_deviation(V, F)
    on_fold = np.isclose(V[E[:, 0], 0], 0.5) & np.isclose(V[E[:, 1], 0], 0.5)
    np.testing.assert_allclose(phi[on_fold], bend, atol=1e-12)
    np.testing.assert_allclose(phi[np.isfinite(phi) & ~on_fold], 0.0, atol=1e-12)
    assert sharp_edges(phi, 0.2).sum() == on_fold.sum()
    assert sharp_edges(phi, 0.4).sum() == 0


def test_threshold_is_strict_and_monotone():
    V, F = sphere(3)
    _, phi = dihedral_deviation(V, F)
    top = np.nanmax(phi)
    assert sharp_edges(phi, top).sum() == 0  # phi > theta, strictly
    counts = [seed_mask(V, F, t).sum() for t in (0.01, 0.05, 0.1, 0.2)]
    assert counts == sorted(counts)


def test_cylinder_side_is_one_group_caps_are_two():
    V, F = cylinder()
    k, group = seed_groups(F, seed_mask(V, F))
    assert k == 3


def test_face_normals_point_outward_on_sphere():
    V, F = sphere(2)
    N = face_normals(V, F)
    C = V[F].mean(axis=1)
    assert ((N * C).sum(axis=1) > 0).all()
    np.testing.assert_allclose(np.linalg.norm(N, axis=1), 1.0)


@pytest.mark.parametrize("theta", [0.05, THETA_DEFAULT, 0.5])
def test_seed_groups_are_edge_connected_and_numbered_by_first_vertex(theta):
    V, F = cylinder(24, 4)
    mask = seed_mask(V, F, theta)
    k, group = seed_groups(F, mask)
    assert (group >= 0).sum() == mask.sum()
    firsts = [np.flatnonzero(group == g)[0] for g in range(k)]
    assert firsts == sorted(firsts)
