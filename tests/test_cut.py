"""Tests for igl_heatseg.parameterization.cut: chart topology and cutting charts into disks."""

from __future__ import annotations

import igl
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from igl_heatseg.errors import MeshError
from igl_heatseg.mesh.topology import boundary_loops, face_components
from igl_heatseg.parameterization.cut import (
    chart_topology,
    cut_along_path,
    cut_along_paths,
    cut_mesh_along_edges,
    cut_to_disk,
)

#: Relative tolerance for a cut length against its analytic value on a regular mesh.
LENGTH_RTOL = 0.03


# ------------------------------------------------------------------------------------------
# test meshes


def cylinder(nu=32, nv=10, r=1.0, h=2.0, twist=0.0):
    """Open cylinder (annulus) around z; ``twist`` rotates ring k by ``k*twist`` radians."""
    t = np.linspace(0, 2 * np.pi, nu, endpoint=False)
    z = np.linspace(0, h, nv + 1)
    V = np.concatenate(
        [
            np.c_[r * np.cos(t + k * twist), r * np.sin(t + k * twist), np.full(nu, z[k])]
            for k in range(nv + 1)
        ]
    )
    F = []
    for k in range(nv):
        for i in range(nu):
            j = (i + 1) % nu
            a, b, c, d = k * nu + i, k * nu + j, (k + 1) * nu + j, (k + 1) * nu + i
            F += [[a, b, c], [a, c, d]]
    return V, np.array(F, dtype=np.int64)


def flat_annulus(nu=40, nr=6, r0=1.0, r1=2.0):
    t = np.linspace(0, 2 * np.pi, nu, endpoint=False)
    rad = np.linspace(r0, r1, nr + 1)
    V = np.concatenate([np.c_[r * np.cos(t), r * np.sin(t), np.zeros(nu)] for r in rad])
    _, F = cylinder(nu, nr)
    return V, F


def torus(nu=24, nv=12, R=2.0, r=0.6):
    V, F = [], []
    for k in range(nv):
        p = 2 * np.pi * k / nv
        for i in range(nu):
            t = 2 * np.pi * i / nu
            V.append(
                [(R + r * np.cos(p)) * np.cos(t), (R + r * np.cos(p)) * np.sin(t), r * np.sin(p)]
            )
    for k in range(nv):
        for i in range(nu):
            j, kk = (i + 1) % nu, (k + 1) % nv
            a, b, c, d = k * nu + i, k * nu + j, kk * nu + j, kk * nu + i
            F += [[a, b, c], [a, c, d]]
    return np.array(V), np.array(F, dtype=np.int64)


def grid(n=20):
    """Unit square, n x n cells, two triangles per cell (cell c has faces 2c, 2c+1)."""
    x = np.linspace(0, 1, n + 1)
    X, Y = np.meshgrid(x, x)
    V = np.c_[X.ravel(), Y.ravel(), np.zeros(X.size)]
    F = []
    for k in range(n):
        for i in range(n):
            a = k * (n + 1) + i
            F += [[a, a + 1, a + n + 2], [a, a + n + 2, a + n + 1]]
    return V, np.array(F, dtype=np.int64)


def plate_with_holes(n=20, holes=((4, 4), (12, 10)), size=3):
    """Grid with square holes of ``size`` x ``size`` cells whose lower-left cell is given."""
    V, F = grid(n)
    keep = np.ones(len(F), dtype=bool)
    for ci, ck in holes:
        for k in range(ck, ck + size):
            for i in range(ci, ci + size):
                c = k * n + i
                keep[[2 * c, 2 * c + 1]] = False
    return V, F[keep]


def icosphere(level=2):
    p = (1 + 5**0.5) / 2
    V = np.array(
        [
            [-1, p, 0],
            [1, p, 0],
            [-1, -p, 0],
            [1, -p, 0],
            [0, -1, p],
            [0, 1, p],
            [0, -1, -p],
            [0, 1, -p],
            [p, 0, -1],
            [p, 0, 1],
            [-p, 0, -1],
            [-p, 0, 1],
        ],
        dtype=float,
    )
    F = np.array(
        [
            [0, 11, 5],
            [0, 5, 1],
            [0, 1, 7],
            [0, 7, 10],
            [0, 10, 11],
            [1, 5, 9],
            [5, 11, 4],
            [11, 10, 2],
            [10, 7, 6],
            [7, 1, 8],
            [3, 9, 4],
            [3, 4, 2],
            [3, 2, 6],
            [3, 6, 8],
            [3, 8, 9],
            [4, 9, 5],
            [2, 4, 11],
            [6, 2, 10],
            [8, 6, 7],
            [9, 8, 1],
        ]
    )
    for _ in range(level):
        E = np.sort(np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]]), axis=1)
        uE, inv = np.unique(E, axis=0, return_inverse=True)
        mid = len(V) + inv.reshape(3, -1).T  # (m,3): midpoints of edges 01, 12, 20
        V = np.r_[V, (V[uE[:, 0]] + V[uE[:, 1]]) / 2]
        a, b, c = F.T
        ab, bc, ca = mid.T
        F = np.concatenate(
            [np.c_[a, ab, ca], np.c_[b, bc, ab], np.c_[c, ca, bc], np.c_[ab, bc, ca]]
        )
    V /= np.linalg.norm(V, axis=1, keepdims=True)
    return V, F


def assert_manifold(F):
    """Edge- and vertex-manifold, consistently oriented (checked with libigl, not our code).

    ``validate_mesh`` cannot be used: it merges the coincident copies a cut creates.
    """
    assert igl.is_edge_manifold(F)
    assert igl.is_vertex_manifold(F)[np.unique(F)].all()
    D = np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]])
    assert len(np.unique(D, axis=0)) == len(D)  # every directed edge once: oriented


def assert_manifold_disk(res, m):
    """The cut chart is a manifold single disk with the same faces, counted independently."""
    assert res.F.shape == (m, 3)
    assert res.topology_after.is_disk, res.topology_after
    assert_manifold(res.F)
    assert np.array_equal(np.unique(res.F), np.arange(len(res.V)))
    ne = len(
        np.unique(
            np.sort(np.concatenate([res.F[:, [0, 1]], res.F[:, [1, 2]], res.F[:, [2, 0]]]), axis=1),
            axis=0,
        )
    )
    assert len(res.V) - ne + m == 1
    assert len(igl.boundary_loop_all(res.F)) == 1
    assert face_components(res.F)[0] == 1


# ------------------------------------------------------------------------------------------
# chart_topology


def test_topology_of_analytic_charts():
    t = chart_topology(grid(4)[1])
    assert (t.components, t.euler, t.boundary_loops, t.genus, t.is_disk) == (1, 1, 1, 0, True)
    t = chart_topology(cylinder()[1])
    assert (t.components, t.euler, t.boundary_loops, t.genus, t.is_disk) == (1, 0, 2, 0, False)
    t = chart_topology(plate_with_holes()[1])
    assert (t.euler, t.boundary_loops, t.genus, t.is_disk) == (-1, 3, 0, False)
    t = chart_topology(icosphere(1)[1])
    assert (t.euler, t.boundary_loops, t.genus, t.is_disk) == (2, 0, 0, False)
    t = chart_topology(torus()[1])
    assert (t.euler, t.boundary_loops, t.genus, t.is_disk) == (0, 0, 1, False)


def test_topology_two_components_and_pinch():
    _, F = grid(3)
    two = np.r_[F, F + F.max() + 1]
    t = chart_topology(two)
    assert t.components == 2 and not t.is_disk
    # Two cells removed diagonally: the chart touches itself at their shared corner.
    Fp = plate_with_holes(n=6, holes=((1, 1), (2, 2)), size=1)[1]
    t = chart_topology(Fp)
    assert t.pinched_vertices == 1 and not t.is_disk
    assert (t.components, t.boundary_loops, t.genus) == (1, 2, 0)


def test_topology_rejects_bad_faces():
    with pytest.raises(MeshError, match="shape"):
        chart_topology(np.zeros((3, 4), dtype=int))
    with pytest.raises(MeshError, match="negative"):
        chart_topology([[0, 1, -2]])
    with pytest.raises(MeshError, match="non-manifold"):
        chart_topology([[0, 1, 2], [1, 0, 3], [0, 1, 4]])
    with pytest.raises(MeshError, match="orientation"):
        chart_topology([[0, 1, 2], [0, 1, 3]])


# ------------------------------------------------------------------------------------------
# automatic mode


def test_disk_is_returned_unchanged():
    V, F = grid(5)
    res = cut_to_disk(V, F)
    assert res.method == "none" and res.cut_length == 0.0 and len(res.cut_edges) == 0
    np.testing.assert_array_equal(res.F, F)
    np.testing.assert_array_equal(res.V, V)
    np.testing.assert_array_equal(res.vertex_map, np.arange(len(V)))


def test_cylinder_cut_is_a_generatrix():
    h = 2.0
    V, F = cylinder(nu=32, nv=10, h=h)
    res = cut_to_disk(V, F)
    assert not res.topology_before.is_disk
    assert res.topology_before.boundary_loops == 2
    assert res.method == "annulus"
    assert_manifold_disk(res, len(F))
    assert res.cut_length == pytest.approx(h, rel=LENGTH_RTOL)
    # All cut vertices share one angle: a straight vertical line.
    cut_vertices = np.unique(res.cut_edges)
    ang = np.arctan2(V[cut_vertices, 1], V[cut_vertices, 0])
    assert np.ptp(ang) < 1e-9
    # The cut duplicates exactly the path's vertices: 11 vertices on the generatrix.
    assert res.V.shape[0] == V.shape[0] + 11
    np.testing.assert_allclose(res.V, V[res.vertex_map])


def test_twisted_cylinder_cut_stays_short():
    # Rings rotated by half a cell each: no straight vertical edges, the cut must zig-zag
    # minimally (length of a geodesic-like path, not around the cylinder).
    V, F = cylinder(nu=32, nv=10, h=2.0, twist=np.pi / 32)
    res = cut_to_disk(V, F)
    assert_manifold_disk(res, len(F))
    step = np.linalg.norm(V[32] - V[0])  # one ring-to-ring edge
    assert res.cut_length == pytest.approx(10 * step, rel=LENGTH_RTOL)


def test_flat_annulus_cut_is_radial():
    V, F = flat_annulus(r0=1.0, r1=2.0)
    res = cut_to_disk(V, F)
    assert_manifold_disk(res, len(F))
    assert res.cut_length == pytest.approx(1.0, rel=LENGTH_RTOL)


def test_plate_with_two_holes_becomes_disk():
    V, F = plate_with_holes()
    res = cut_to_disk(V, F)
    assert res.topology_before.boundary_loops == 3
    assert res.method == "boundary-tree"
    assert len(res.paths) == 2  # h = 2 holes -> 2 joining paths
    assert_manifold_disk(res, len(F))
    # hole 1 (cells 4..6) is 4 cells (0.2) from the border, hole 2 (rows 10..12, cols
    # 12..14) is 5 cells from hole 1 diagonally/4 from the border: short cuts only.
    assert res.cut_length <= 0.5


def test_sphere_is_cut_to_disk():
    V, F = icosphere(3)
    res = cut_to_disk(V, F)
    assert res.method == "sphere-path"
    assert res.topology_before.boundary_loops == 0
    assert_manifold_disk(res, len(F))
    # Cut between two (nearly) antipodal vertices: about half a great circle.
    assert np.pi * 0.95 < res.cut_length < np.pi * 1.25


def test_torus_is_cut_to_disk():
    V, F = torus()
    res = cut_to_disk(V, F)
    assert res.method == "tree-cotree"
    assert res.topology_before.genus == 1
    assert len(res.paths) == 2  # two generator loops
    assert_manifold_disk(res, len(F))
    # The shortest system: a meridian and the inner equator (polygons of the mesh).
    meridian = 12 * 2 * 0.6 * np.sin(np.pi / 12)
    inner = 24 * 2 * (2.0 - 0.6) * np.sin(np.pi / 24)
    assert res.cut_length == pytest.approx(meridian + inner, rel=LENGTH_RTOL)


def test_torus_with_hole_is_cut_to_disk():
    V, F = torus()
    F = F[2:]  # remove one quad: genus 1, one boundary loop
    res = cut_to_disk(V, F)
    assert res.topology_before.genus == 1 and res.topology_before.boundary_loops == 1
    assert_manifold_disk(res, len(F))


def test_pinched_chart_is_split_and_cut():
    V, F = plate_with_holes(n=6, holes=((1, 1), (2, 2)), size=1)
    res = cut_to_disk(V, F)
    assert res.topology_before.pinched_vertices == 1
    assert_manifold_disk(res, len(F))


def test_pinched_disk_is_unpinched_without_cut():
    # Remove the cells along a staircase up to the border: the remaining chart is a disk
    # touching itself at one vertex.
    V, F = plate_with_holes(n=4, holes=((0, 0), (1, 1)), size=1)
    t = chart_topology(F)
    assert t.pinched_vertices == 1
    res = cut_to_disk(V, F)
    assert res.method == "unpinch" and res.cut_length == 0.0
    assert_manifold_disk(res, len(F))


def test_unused_vertices_are_dropped_and_mapped():
    V, F = cylinder()
    Vbig = np.r_[np.full((5, 3), 9.0), V]
    res = cut_to_disk(Vbig, F + 5)
    assert_manifold_disk(res, len(F))
    assert res.vertex_map.min() >= 5
    np.testing.assert_allclose(res.V, Vbig[res.vertex_map])


def test_several_components_raise():
    V, F = grid(3)
    V2 = np.r_[V, V + [5, 0, 0]]
    with pytest.raises(MeshError, match="2 edge-connected components"):
        cut_to_disk(V2, np.r_[F, F + len(V)])


def test_cut_to_disk_rejects_bad_input():
    V, F = grid(2)
    with pytest.raises(MeshError, match="outside"):
        cut_to_disk(V, np.r_[F, [[0, 1, 99]]])
    with pytest.raises(MeshError, match="shape"):
        cut_to_disk(V[:, :2], F)
    with pytest.raises(MeshError, match="empty"):
        cut_to_disk(V, np.zeros((0, 3), dtype=int))


# ------------------------------------------------------------------------------------------
# paper mode


def test_generatrix_path_joins_the_two_vertices():
    V, F = cylinder(nu=32, nv=10, h=2.0)
    v0, v1 = 3, 10 * 32 + 3
    res = cut_along_path(V, F, v0, v1)
    assert res.method == "paths"
    path = res.paths[0]
    assert path[0] == v0 and path[-1] == v1
    assert_manifold_disk(res, len(F))
    assert res.cut_length == pytest.approx(2.0, rel=1e-12)
    assert {v0, v1} <= set(np.unique(res.cut_edges).tolist())


def test_generatrix_path_avoids_the_boundary():
    # Ends half way around: the shortest path could run along the bottom loop; it must not
    # touch the boundary except at its ends, so the result is still one disk.
    V, F = cylinder(nu=32, nv=10, h=2.0)
    v0, v1 = 0, 10 * 32 + 16
    res = cut_along_path(V, F, v0, v1)
    onb = np.zeros(len(V), dtype=bool)
    for loop in boundary_loops(F):
        onb[loop] = True
    assert not onb[res.paths[0][1:-1]].any()
    assert_manifold_disk(res, len(F))


def test_two_paths_on_a_plate():
    V, F = plate_with_holes(n=10, holes=((3, 3),), size=2)
    # outer border vertex (0,5) -> hole corner (3,5); hole corner (5,5) -> border (10,5)
    row = 5 * 11
    res = cut_along_paths(V, F, [(row + 0, row + 3), (row + 5, row + 10)])
    count, _ = face_components(res.F)
    assert count == 2  # the plate falls apart into two halves
    assert res.cut_length == pytest.approx(0.3 + 0.5, rel=1e-12)
    assert_manifold(res.F)


def test_bad_vertex_ids_raise_naming_them():
    V, F = cylinder()
    with pytest.raises(MeshError, match=r"-1 \(outside.*5000 \(outside"):
        cut_along_path(V, F, -1, 5000)
    Vx = np.r_[V, [[7.0, 7, 7]]]  # vertex 352 is not used by any face
    with pytest.raises(MeshError, match="352 .no face"):
        cut_along_path(Vx, F, 0, 352)
    with pytest.raises(MeshError, match="same vertex"):
        cut_along_path(V, F, 4, 4)
    with pytest.raises(MeshError, match="not an integer"):
        cut_along_path(V, F, 0, 1.5)


def test_disconnected_ends_raise():
    V, F = grid(3)
    V2 = np.r_[V, V + [5, 0, 0]]
    with pytest.raises(MeshError, match="not connected"):
        cut_along_path(V2, np.r_[F, F + len(V)], 0, len(V) + 3)


# ------------------------------------------------------------------------------------------
# opening along arbitrary edges (the non-manifold traps)


def test_cut_through_boundary_vertex_stays_manifold():
    # A cut from the bottom border straight up through a hole (touching the hole's boundary
    # at two vertices) and on to the top: each vertex copy must be a single fan.
    V, F = plate_with_holes(n=8, holes=((3, 3),), size=2)
    col = 4
    path = [k * 9 + col for k in range(9)]  # vertical line x = 0.5 through the hole
    edges = [
        (a, b)
        for a, b in zip(path[:-1], path[1:], strict=False)
        if not (3 * 9 + col <= a and b <= 5 * 9 + col)
    ]  # skip the removed part
    res = cut_mesh_along_edges(V, F, edges)
    assert_manifold(res.F)
    count, _ = face_components(res.F)
    assert count == 2 and res.topology_after.components == 2


def test_chord_between_boundary_vertices_stays_manifold():
    # A single interior edge joining two boundary vertices of the same loop cuts a corner
    # off: two components, every vertex manifold.
    V = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0.5, -1, 0]], dtype=float)
    F = np.array([[0, 1, 2], [0, 2, 3], [0, 4, 1]])
    res = cut_mesh_along_edges(V, F, [(0, 2), (0, 1)])
    assert_manifold(res.F)
    assert res.topology_after.components == 3
    assert res.V.shape[0] == 9


def test_cut_mesh_along_edges_rejects_non_edges():
    V, F = grid(2)
    with pytest.raises(MeshError, match="not edges"):
        cut_mesh_along_edges(V, F, [(0, 8)])


def test_interior_slit_opens_only_inner_vertices():
    V, F = grid(6)
    # a horizontal slit of 2 edges in the middle: only its middle vertex is duplicated
    mid = 3 * 7
    res = cut_mesh_along_edges(V, F, [(mid + 2, mid + 3), (mid + 3, mid + 4)])
    assert res.V.shape[0] == V.shape[0] + 1
    assert res.topology_after.boundary_loops == 2  # the slit is a second boundary loop
    assert_manifold(res.F)


# ------------------------------------------------------------------------------------------
# real meshes (data/)

#: A cut between the two loops of a machined bore/boss is generatrix-like: its length is
#: within this factor of the straight distance between its ends.
GENERATRIX_STRAIGHTNESS = 1.06


@pytest.mark.parametrize(
    ("name", "genus"), [("block.ply", 3), ("psb_358_bearing.ply", 4), ("abc_00007974_5.ply", 4)]
)
def test_real_closed_meshes_of_higher_genus(data_dir, name, genus):
    from igl_heatseg.io.meshes import load_mesh

    mesh = load_mesh(data_dir / name)
    res = cut_to_disk(mesh.V, mesh.F)
    assert res.topology_before.genus == genus
    assert res.method in ("tree-cotree", "igl-cut-to-disk")
    if res.method == "tree-cotree":
        assert len(res.paths) == 2 * genus  # a system of loops through one root
    assert_manifold_disk(res, len(mesh.F))
    # never longer than libigl's own cut graph
    cuts = igl.cut_to_disk(mesh.F)
    ref = cut_mesh_along_edges(
        mesh.V, mesh.F, [(c[i], c[i + 1]) for c in cuts for i in range(len(c) - 1)]
    )
    assert ref.topology_after.is_disk
    assert res.cut_length <= ref.cut_length * (1 + 1e-12)


def test_real_block_segments_become_disks(data_dir):
    from igl_heatseg.io.meshes import load_mesh
    from igl_heatseg.segmentation.paper import segment_mesh

    mesh = load_mesh(data_dir / "block.ply")
    seg = segment_mesh(mesh, keep_solvers=False)
    annuli = 0
    for s in range(seg.num_segments):
        F = mesh.F[seg.labels == s]
        res = cut_to_disk(mesh.V, F)
        assert_manifold_disk(res, len(F))
        if res.method == "annulus":
            annuli += 1
            p = res.paths[0]
            length = np.linalg.norm(np.diff(mesh.V[p], axis=0), axis=1).sum()
            chord = np.linalg.norm(mesh.V[p[-1]] - mesh.V[p[0]])
            assert length == pytest.approx(res.cut_length)
            assert length <= GENERATRIX_STRAIGHTNESS * chord
    assert annuli >= 6  # the block's bores and rounded edges


def _igl_cut_mask(F, edges):
    """Per-face-edge mask for igl.cut_mesh: its edge j of face f is (F[f,j], F[f,(j+1)%3])."""
    pe = {tuple(sorted(e)) for e in np.asarray(edges).tolist()}
    return np.array(
        [
            [tuple(sorted((F[f, j], F[f, (j + 1) % 3]))) in pe for j in range(3)]
            for f in range(len(F))
        ]
    )


def test_opening_matches_igl_cut_mesh_on_a_generatrix():
    V, F = cylinder(nu=32, nv=10, h=2.0)
    res = cut_along_path(V, F, 3, 10 * 32 + 19)  # a zig-zag path across the side
    Vn, Fn, I = igl.cut_mesh(V, F, _igl_cut_mask(F, res.cut_edges))
    assert len(Vn) == len(res.V)
    np.testing.assert_array_equal(np.sort(I), np.sort(res.vertex_map))
    # same faces up to vertex naming: corner -> input vertex agrees
    np.testing.assert_array_equal(I[Fn], res.vertex_map[res.F])
    assert chart_topology(Fn).is_disk


def test_tetrahedron_is_cut_to_disk():
    # Every pair of vertices is adjacent: a one-edge cut would open nothing.
    V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1.0]])
    F = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    res = cut_to_disk(V, F)
    assert res.method == "sphere-path"
    assert len(res.cut_edges) == 2
    assert_manifold_disk(res, 4)


@settings(max_examples=60, deadline=None)
@given(
    seed=st.integers(0, 2**31 - 1),
    drop=st.floats(0.0, 0.45),
    surface=st.sampled_from(["torus", "sphere", "plate"]),
)
def test_any_random_chart_becomes_a_manifold_disk(seed, drop, surface):
    # Random face subsets: many holes, pinched vertices, handles kept or broken.
    V, F = {"torus": torus, "sphere": lambda: icosphere(2), "plate": lambda: grid(12)}[surface]()
    rng = np.random.default_rng(seed)
    Fk = F[rng.random(len(F)) >= drop]
    if len(Fk) == 0:
        return
    _, C = face_components(Fk)
    Fc = Fk[C == np.bincount(C).argmax()]
    res = cut_to_disk(V, Fc)
    assert_manifold_disk(res, len(Fc))
    np.testing.assert_allclose(res.V, V[res.vertex_map])
    # corners keep their input vertex: same faces up to the duplication
    np.testing.assert_array_equal(res.vertex_map[res.F], Fc)
    # the sort-free topology update agrees with edge_topology, corner by corner
    from igl_heatseg.mesh.topology import edge_topology
    from igl_heatseg.parameterization.cut import open_wedges, split_topology

    topo = edge_topology(Fc)
    cut = rng.random(len(topo.E)) < 0.2
    Fn, _ = open_wedges(Fc, topo, cut)
    fast, ref = split_topology(topo, Fn), edge_topology(Fn)
    np.testing.assert_array_equal(fast.E[fast.EMAP], ref.E[ref.EMAP])
    np.testing.assert_array_equal(fast.edge_face_count[fast.EMAP], ref.edge_face_count[ref.EMAP])
    np.testing.assert_array_equal(
        np.sort(fast.EF[fast.EMAP], axis=1), np.sort(ref.EF[ref.EMAP], axis=1)
    )


def test_annulus_cut_is_the_shortest_loop_to_loop_path():
    # Irregular annulus (jittered rings): the cut equals the multi-source Dijkstra minimum
    # from one loop to the other.
    import scipy.sparse as sp
    from scipy.sparse.csgraph import dijkstra

    rng = np.random.default_rng(7)
    V, F = flat_annulus(nu=48, nr=9, r0=1.0, r1=3.0)
    inner = np.arange(48, len(V) - 48)
    V[inner, :2] += rng.uniform(-0.04, 0.04, (len(inner), 2))
    res = cut_to_disk(V, F)
    assert res.method == "annulus"
    assert_manifold_disk(res, len(F))
    E = np.unique(np.sort(np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]]), 1), axis=0)
    w = np.linalg.norm(V[E[:, 0]] - V[E[:, 1]], axis=1)
    G = sp.csr_matrix((w, (E[:, 0], E[:, 1])), shape=(len(V), len(V)))
    d = dijkstra(G, directed=False, indices=np.arange(48), min_only=True)
    assert res.cut_length == pytest.approx(d[-48:].min(), rel=1e-12)
