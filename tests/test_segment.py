import numpy as np
import pytest
from meshes import cube, cylinder, disk, grid, sphere

from igl_heatseg import validate_mesh
from igl_heatseg.io.meshes import load_mesh
from igl_heatseg.segmentation import segment
from igl_heatseg.mesh.geometry import face_areas
from igl_heatseg.segmentation.paper import make_face_connected, segment_mesh
from igl_heatseg.mesh.topology import face_adjacency


def _seg(V, F, **kw):
    return segment_mesh(validate_mesh(V, F), **kw)


# ---------------------------------------------------------------- analytic cases


def test_cube_has_six_segments_one_per_side():
    V, F = cube(6)
    s = _seg(V, F)
    assert s.num_segments == 6 and s.initial_groups == 6
    N = np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]])
    side = np.argmax(np.abs(N), axis=1) * 2 + (N[np.arange(len(F)), np.argmax(np.abs(N), 1)] > 0)
    # every segment is exactly one side of the cube
    for k in range(6):
        assert len(np.unique(side[s.labels == k])) == 1
    np.testing.assert_allclose(s.segment_areas, 4.0)


def test_cylinder_with_fine_side_has_three_segments():
    V, F = cylinder(64, 8)
    s = _seg(V, F)
    assert s.num_segments == 3
    # the largest is the side (area 2*pi*r*h = 4*pi), the caps are pi each
    np.testing.assert_allclose(s.segment_areas, [4 * np.pi, np.pi, np.pi], rtol=0.01)


def test_flat_disk_is_one_segment():
    V, F = disk()
    s = _seg(V, F)
    assert s.num_segments == 1 and (s.labels == 0).all()


def test_fine_sphere_is_one_segment():
    s = _seg(*sphere(4))
    assert s.num_segments == 1 and s.seed_mask.all()


def test_coarse_cube_without_seeds_is_one_segment():
    s = _seg(*cube(1))
    assert s.seedless_components == 1 and s.num_segments == 1


def test_each_component_is_segmented_on_its_own():
    V1, F1 = cube(4)
    V2, F2 = cylinder(48, 6)
    V = np.r_[V1, V2 * 0.1 + [5, 0, 0]]  # a tiny cylinder next to a cube
    F = np.r_[F1, F2 + len(V1)]
    s = _seg(V, F)
    assert s.components == 2
    assert s.num_segments == 9  # eps is relative to each component's largest segment


def test_eps_drops_small_groups_and_resolves():
    # A flat grid with a small raised plateau (a mesa with steep walls): the plateau's inner
    # vertices are a seed group of their own, whose segment is far below 5 % of the plain.
    V, F = grid(30, 30)
    top = (np.abs(V[:, 0] - 0.5) < 2.5 / 30) & (np.abs(V[:, 1] - 0.5) < 2.5 / 30)
    V[top, 2] = 0.05
    s0 = _seg(V, F, eps=0.0)
    s1 = _seg(V, F, eps=0.05)
    assert s0.num_segments > 1
    assert s1.num_segments == 1
    assert len(s1.kept_groups) == 1


def test_parameters_are_checked():
    V, F = disk()
    m = validate_mesh(V, F)
    with pytest.raises(ValueError, match="theta"):
        segment_mesh(m, theta=0.0)
    with pytest.raises(ValueError, match="eps"):
        segment_mesh(m, eps=1.5)


def test_one_off_wrapper_validates():
    V, F = cube(3)
    assert segment(V, F).labels.max() == 5
    with pytest.raises(ValueError, match="outside"):
        segment(V, F + 1000)


def test_make_face_connected_merges_island_into_longest_neighbour():
    V, F = grid(6, 6)
    area = face_areas(V, F)
    labels = np.zeros(len(F), dtype=np.int64)
    C = V[F].mean(axis=1)
    labels[C[:, 0] > 0.5] = 1
    island = np.flatnonzero((np.abs(C[:, 0] - 0.25) < 0.09) & (np.abs(C[:, 1] - 0.5) < 0.09))
    labels[island] = 1  # a piece of label 1 inside label 0, with no seed of group 1
    group = -np.ones(len(V), dtype=np.int64)
    group[V[:, 0] > 0.9] = 1
    group[V[:, 0] < 0.1] = 0
    out, merged = make_face_connected(V, F, labels, group, area)
    assert merged == 1
    assert (out[island] == 0).all()
    assert np.array_equal(out[C[:, 0] > 0.5], np.ones((C[:, 0] > 0.5).sum()))


# ---------------------------------------------------------------- real meshes

REAL = ["fandisk.off", "block.ply", "psb_358_bearing.ply", "abc_00007974_5.ply"]


@pytest.fixture(scope="module", params=REAL)
def real(request, data_dir):
    m = load_mesh(data_dir / request.param)
    return request.param, m, segment_mesh(m)


def test_invariants_on_real_meshes(real):
    name, m, s = real
    k = s.num_segments
    # every face labelled, labels contiguous 0..k-1, sorted by area
    assert s.labels.shape == (len(m.F),) and s.labels.min() == 0
    assert np.array_equal(np.unique(s.labels), np.arange(k))
    assert np.all(np.diff(s.segment_areas) <= 0)
    np.testing.assert_allclose(np.bincount(s.labels, weights=face_areas(m.V, m.F)), s.segment_areas)
    # segments face-connected
    A = face_adjacency(m.F).tocoo()
    same = s.labels[A.row] == s.labels[A.col]
    import scipy.sparse as sp
    from scipy.sparse.csgraph import connected_components

    B = sp.csr_matrix((np.ones(same.sum()), (A.row[same], A.col[same])), shape=A.shape)
    assert connected_components(B, directed=False)[0] == k
    # heat fields sum to one (solve check)
    assert s.heat_sum_error < 1e-8
    # seeds keep their own label
    seeds = s.final_group >= 0
    final_of_group = np.empty(len(s.segment_group) + 1, dtype=np.int64)
    final_of_group[s.segment_group] = np.arange(k)
    assert np.array_equal(s.vertex_labels[seeds], final_of_group[s.final_group[seeds]])


def test_temperature_on_request_sums_to_one(real):
    name, m, s = real
    U = sum(s.temperature(i) for i in range(s.num_segments))
    np.testing.assert_allclose(U, 1.0, atol=1e-8)
    # (no [0, 1] bound here: cotangent weights of obtuse triangles are negative, so the
    # discrete maximum principle holds only on Delaunay meshes; see test_heat.py)


def test_deterministic(data_dir):
    m = load_mesh(data_dir / "psb_358_bearing.ply")
    a, b = segment_mesh(m), segment_mesh(m)
    assert np.array_equal(a.labels, b.labels)
    assert np.array_equal(a.vertex_labels, b.vertex_labels)


# Regression values (paper defaults), measured when the core landed.
REGRESSION = {
    "fandisk.off": (14454, 16, 15),
    "block.ply": (17550, 24, 11),
    "psb_358_bearing.ply": (28266, 283, 4),
    "abc_00007974_5.ply": (15702, 187, 2),
}


def test_regression_counts(real):
    name, m, s = real
    assert (len(m.F), s.initial_groups, s.num_segments) == REGRESSION[name]
