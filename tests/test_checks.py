"""Every rejection of validate_mesh has a test asserting the error and its message."""

import numpy as np
import pytest
from meshes import cube, grid

from igl_heatseg import MeshError, validate_mesh

TRI = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0]])


def test_clean_mesh_passes_unchanged():
    V, F = cube(3)
    m = validate_mesh(V, F)
    np.testing.assert_array_equal(m.V, V)
    np.testing.assert_array_equal(m.F, F)
    assert m.merged_vertices == 0 and m.unreferenced_vertices == 0
    assert m.V.flags.c_contiguous and m.V.dtype == np.float64 and m.F.dtype == np.int64


def test_meshError_is_a_valueerror():
    assert issubclass(MeshError, ValueError)


@pytest.mark.parametrize(
    "V,F,match",
    [
        (np.zeros((3, 2)), [[0, 1, 2]], r"`V` should have shape \(n,3\), shape is \(3, 2\)"),
        (TRI, [[0, 1]], r"`F` should have shape \(m,3\)"),
        (TRI, [[0.0, 1.5, 2.0]], "integer vertex indices"),
        (TRI, np.array([["a", "b", "c"]]), "integer vertex indices"),
        (np.array([["x", "y", "z"]]), [[0, 0, 0]], "must hold numbers"),
    ],
)
def test_shapes_and_dtypes(V, F, match):
    with pytest.raises(MeshError, match=match):
        validate_mesh(V, F)


def test_empty_mesh():
    with pytest.raises(MeshError, match=r"empty mesh \(3 vertices, 0 faces\)"):
        validate_mesh(TRI, np.zeros((0, 3), dtype=int))
    with pytest.raises(MeshError, match="empty mesh"):
        validate_mesh(np.zeros((0, 3)), np.zeros((0, 3), dtype=int))


def test_out_of_range_and_negative_indices_name_the_faces():
    V, F = grid(2, 2)
    F = F.copy()
    F[1, 2] = 99
    F[3, 0] = -1
    with pytest.raises(MeshError) as e:
        validate_mesh(V, F, name="part.obj")
    msg = str(e.value)
    assert msg.startswith("part.obj: 2 face(s) have vertex indices outside 0..8")
    assert "face 1 = " in msg and "99" in msg and "face 3 = [-1" in msg


@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_nonfinite_coordinates_name_the_vertex(bad):
    V, F = grid(2, 2)
    V[4, 1] = bad
    with pytest.raises(
        MeshError, match=r"1 vertex\(es\) have NaN or infinite coordinates: vertex 4"
    ):
        validate_mesh(V, F)


def test_nonfinite_unreferenced_vertex_is_just_dropped():
    V, F = grid(2, 2)
    V = np.r_[V, [[np.nan, 0, 0]]]
    m = validate_mesh(V, F)
    assert m.unreferenced_vertices == 1 and m.vertex_map[-1] == -1


def test_zero_area_faces_collinear_and_repeated_corner():
    V = np.array([[0.0, 0, 0], [1, 0, 0], [2, 0, 0], [0, 1, 0]])
    with pytest.raises(MeshError, match=r"1 face\(s\) have zero area .*face 1"):
        validate_mesh(V, [[0, 1, 3], [0, 1, 2]])
    with pytest.raises(MeshError, match=r"use the same vertex twice.*face 0 = \[0, 0, 3\]"):
        validate_mesh(V, [[0, 0, 3]])


def test_tiny_but_well_shaped_faces_are_accepted():
    V = TRI * 1e-7  # the iron scan has faces of area 1e-14 that are fine triangles
    assert validate_mesh(V, [[0, 1, 2]]).F.shape == (1, 3)


def test_nonmanifold_edge_reports_count_and_edge():
    V = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1]])
    F = [[0, 1, 2], [1, 0, 3], [0, 1, 4]]
    with pytest.raises(MeshError, match=r"1 non-manifold edge\(s\).*edge \(0, 1\) in 3 faces"):
        validate_mesh(V, F)


def test_nonmanifold_vertex_two_fans():
    V = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [-1, 0, 0], [0, -1, 0]])
    F = [[0, 1, 2], [0, 3, 4]]  # two triangles touching at vertex 0 only
    with pytest.raises(MeshError, match=r"1 non-manifold vertex\(es\).*vertex 0"):
        validate_mesh(V, F)


def test_inconsistent_orientation_names_edge_and_faces():
    V, F = grid(2, 1)
    F = F.copy()
    F[0] = F[0, ::-1]
    with pytest.raises(
        MeshError, match=r"inconsistent orientation on 2 edge\(s\).*between faces 0 and"
    ):
        validate_mesh(V, F)
    assert validate_mesh(V, F, check_orientation=False).F.shape == F.shape


def test_duplicate_vertices_are_merged_with_map_kept():
    V, F = grid(2, 2)
    soup = V[F.ravel()]  # STL style: three vertices per face
    Fs = np.arange(len(soup)).reshape(-1, 3)
    m = validate_mesh(soup, Fs)
    assert m.V.shape == V.shape and m.merged_vertices == len(soup) - len(V)
    np.testing.assert_array_equal(m.V[m.F], soup[Fs])
    np.testing.assert_array_equal(m.V[m.vertex_map], soup)
    np.testing.assert_array_equal(soup[m.input_vertex], m.V)


def test_listing_is_truncated_after_five():
    V, F = grid(4, 4)
    F = F.copy()
    F[:, 0] = 1000
    with pytest.raises(MeshError, match=r"32 face\(s\).*\(27 more\)"):
        validate_mesh(V, F)
