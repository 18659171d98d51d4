"""repair=True / --repair: each defect real exports have, repaired and counted, outputs in the
input's face and vertex order. The meshes are made here (a fresh clone has no shared data)."""

import json
from pathlib import Path

import numpy as np
import pytest
from meshes import cube

from igl_heatseg import MeshError, validate_mesh
from igl_heatseg.cli import main
from igl_heatseg.io import load_mesh
from igl_heatseg.mesh import face_areas
from igl_heatseg.mesh.repair import nonmanifold_vertices
from igl_heatseg.mesh.topology import edge_topology


def _off(V, F) -> bytes:
    return (
        f"OFF\n{len(V)} {len(F)} 0\n"
        + "".join(f"{x:.17g} {y:.17g} {z:.17g}\n" for x, y, z in V)
        + "".join(f"{len(f)} " + " ".join(map(str, f)) + "\n" for f in F)
    ).encode()


def _counts(mesh):
    return {k: v for k, v in mesh.repairs.items() if v and k != "weld_tolerance"}


def test_clean_mesh_is_unchanged_by_repair():
    V, F = cube(3)
    strict = validate_mesh(V, F)
    rep = validate_mesh(V, F, repair=True)
    np.testing.assert_array_equal(rep.F, strict.F)
    np.testing.assert_array_equal(rep.V, strict.V)
    assert rep.face_map is None and rep.face_source is None and _counts(rep) == {}
    assert rep.repairs["weld_tolerance"] > 0


def test_zero_area_faces_dropped_label_from_longest_edge():
    V, F = cube(3)
    V = V.copy()
    a, b, c = F[5]
    V[c] = (V[a] + V[b]) / 2  # face 5 collinear: its longest edge is (a, b)
    with pytest.raises(MeshError, match=r"zero area.*use --repair, or repair=True, to drop"):
        validate_mesh(V, F)
    m = validate_mesh(V, F, repair=True)
    assert m.repairs["zero_area_faces"] == 1 and m.F.shape[0] == len(F) - 1
    assert m.n_input_faces == len(F) and 5 not in m.face_map.tolist()
    # the face across (a, b): the other face holding both
    other = [f for f in range(len(F)) if f != 5 and {a, b} <= set(F[f].tolist())]
    labels = np.arange(m.F.shape[0])
    out = m.input_face_labels(labels)
    assert len(out) == len(F)
    assert out[5] == out[other[0]]
    keep = np.delete(np.arange(len(F)), 5)
    np.testing.assert_array_equal(out[keep], labels)


def test_collapsed_edge_faces_dropped():
    V, F = cube(4)
    V = V.copy()
    a, b, _ = F[10]
    V[b] = V[a]  # an edge collapsed by an exporter: both faces on it get a repeated corner
    with pytest.raises(MeshError, match="same vertex twice"):
        validate_mesh(V, F)
    m = validate_mesh(V, F, repair=True)
    assert m.repairs["zero_area_faces"] == 2
    assert (m.input_face_labels(np.zeros(m.F.shape[0], int)) == 0).all()


def test_duplicate_faces_dropped_take_their_twin_label():
    V, F = cube(2)
    F2 = np.concatenate([F, F[[3]][:, ::-1], F[[7]]])
    m = validate_mesh(V, F2, repair=True)
    assert m.repairs["duplicate_faces"] == 2 and m.F.shape[0] == len(F)
    out = m.input_face_labels(np.arange(len(F)))
    assert out[len(F)] == 3 and out[len(F) + 1] == 7


def test_nonmanifold_vertex_split():
    # two tetrahedra touching at one vertex
    V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [-1, 0, 0], [0, -1, 0], [0, 0, -1.0]])
    T = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    F = np.concatenate([T, np.where(T == 0, 0, T + 3)])
    with pytest.raises(MeshError, match=r"non-manifold vertex.*use --repair, or repair=True"):
        validate_mesh(V, F)
    m = validate_mesh(V, F, repair=True)
    assert m.repairs["nonmanifold_vertices"] == 1 and m.repairs["split_vertices"] == 1
    assert m.V.shape[0] == 8 and m.F.shape[0] == 8
    assert m.vertex_map[0] == 0 and m.input_vertex.tolist().count(0) == 2


def test_nonmanifold_edge_split_into_sheets():
    # three quads (6 triangles) sharing the edge (0, 1): a "book" of three pages
    V = np.array([[0, 0, 0], [0, 0, 1], [1, 0, 0], [1, 0, 1], [0, 1, 0], [0, 1, 1],
                  [-1, 0, 0], [-1, 0, 1.0]])  # fmt: skip
    F = np.array([[0, 2, 1], [1, 2, 3], [0, 1, 4], [1, 5, 4], [0, 6, 1], [1, 6, 7]])
    with pytest.raises(MeshError, match=r"non-manifold edge.*to split them into manifold sheets"):
        validate_mesh(V, F)
    m = validate_mesh(V, F, repair=True)
    assert m.repairs["nonmanifold_edges"] == 1 and m.repairs["split_vertices"] >= 2
    assert m.F.shape[0] == 6 and m.face_map is None


def test_orientation_made_consistent_and_outward():
    V, F = cube(2)
    F = F.copy()
    F[[1, 4, 9]] = F[[1, 4, 9]][:, ::-1]
    with pytest.raises(MeshError, match="to orient each component consistently"):
        validate_mesh(V, F)
    m = validate_mesh(V, F, repair=True)
    assert m.repairs["reoriented_faces"] == 3
    # outward: the signed volume is positive
    P = m.V[m.F]
    assert np.einsum("ij,ij->i", P[:, 0], np.cross(P[:, 1], P[:, 2])).sum() > 0
    # an inward closed surface is turned outward
    m = validate_mesh(V, cube(2)[1][:, ::-1], repair=True)
    assert m.repairs["reoriented_faces"] == len(F)


def test_near_duplicate_vertices_welded():
    V, F = cube(2)
    # split the mesh along vertex 0: a copy of it, 1e-9 away, used by one face
    f = int(np.flatnonzero((F == 0).any(1))[0])
    V2 = np.concatenate([V, V[[0]] + 1e-9])
    F2 = F.copy()
    F2[f][F2[f] == 0] = len(V)
    m = validate_mesh(V2, F2, repair=True)
    assert m.repairs["welded_vertices"] == 1 and m.V.shape[0] == len(V)
    assert m.vertex_map[len(V)] == m.vertex_map[0]
    m = validate_mesh(V2, F2, repair=True, weld_tol=0)  # not welded: a slit, still a surface
    assert m.repairs["welded_vertices"] == 0 and m.V.shape[0] == len(V) + 1


def test_everything_dropped_is_one_clear_error():
    V = np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0.0]])
    with pytest.raises(MeshError, match="nothing is left after repair"):
        validate_mesh(V, [[0, 1, 2]], repair=True)


def test_segment_and_run_with_repair_keep_input_order(tmp_path, capsys):
    """Two boxes touching at a corner (a non-manifold vertex) and a duplicated face."""
    V, F = cube(3)
    n = len(V)
    lo, corner = int(np.argmin(V.sum(1))), int(np.argmax(V.sum(1)))
    V2 = V + (V[lo] - V[corner])  # the second box's max corner sits on the first's min one
    F2 = np.where(F == corner, lo - n, F) + n  # ... and uses that vertex itself
    Vall = np.concatenate([V, V2])
    faces = np.concatenate([F, F2, F[[4]]])
    p = tmp_path / "two_boxes.off"
    p.write_bytes(_off(Vall, faces))
    assert main(["segment", str(p), "-o", str(tmp_path / "strict")]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "--repair" in err, err
    assert main(["segment", str(p), "-o", str(tmp_path / "s"), "--repair"]) == 0
    rep = json.loads((tmp_path / "s" / "report.json").read_text())
    assert rep["repairs"]["split_vertices"] == 1 and rep["repairs"]["nonmanifold_vertices"] == 1
    assert rep["repairs"]["duplicate_faces"] == 1
    assert rep["input_faces"] == len(faces) and rep["faces"] == len(faces) - 1
    labels = (tmp_path / "s" / "labels.txt").read_text().split()
    assert len(labels) == len(faces) and labels[-1] == labels[4]
    vlabels = (tmp_path / "s" / "vertex_labels.txt").read_text().split()
    assert len(vlabels) == len(Vall) and vlabels[n + corner] == "-1"  # unused copy
    assert main(["run", str(p), "-o", str(tmp_path / "r"), "--repair", "--no-pictures"]) == 0
    rep = json.loads((tmp_path / "r" / "report.json").read_text())
    assert rep["repairs"]["split_vertices"] == 1
    assert rep["parameterization"]["charts_bijective"] == rep["parameterization"]["charts_total"]
    assert (tmp_path / "r" / "labels.txt").read_text().split() == labels


def test_cli_polygons_labels_per_input_face(tmp_path):
    """A box of quads: labels.txt has one line per quad, the report counts the split."""
    import importlib.util
    from pathlib import Path

    spec = importlib.util.spec_from_file_location(
        "fuzz_readers", Path(__file__).resolve().parent.parent / "tools" / "fuzz_readers.py"
    )
    fz = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(fz)
    V, Q = fz._box(3, quads=True)
    p = tmp_path / "box.obj"
    p.write_bytes(fz.write_obj(V, Q))
    assert main(["segment", str(p), "-o", str(tmp_path / "s")]) == 0
    rep = json.loads((tmp_path / "s" / "report.json").read_text())
    assert rep["input_faces"] == len(Q) == 54 and rep["split_faces"] == 54
    assert rep["faces"] == 108 and rep["segments"] == 6 and "mixed_label_faces" in rep
    labels = np.array((tmp_path / "s" / "labels.txt").read_text().split(), dtype=int)
    assert len(labels) == 54 and set(labels.tolist()) == set(range(6))
    m = load_mesh(p)
    assert m.split_faces == 54 and m.n_input_faces == 54


def test_fandisk_with_a_few_zero_area_faces_segments_with_repair(tmp_path, data_dir, capsys):
    """A few zero-area faces among 14,454 (collapsed edges, collinear corners), as real CAD
    exports have: refused with the option named, segmented with --repair, every input face
    labelled."""
    from igl_heatseg.io import read_mesh_arrays

    V, F = read_mesh_arrays(data_dir / "fandisk.off")
    V = V.copy()
    faces = np.random.default_rng(3).choice(len(F), 7, replace=False)
    for f in faces[:5]:
        V[F[f, 1]] = V[F[f, 0]]  # edge collapse: the two faces on it lose their area
    for f in faces[5:]:
        V[F[f, 2]] = (V[F[f, 0]] + V[F[f, 1]]) / 2  # collinear corners
    p = tmp_path / "fandisk_zero.off"
    p.write_bytes(_off(V, F))
    assert main(["segment", str(p), "-o", str(tmp_path / "s")]) == 2
    assert "use --repair" in capsys.readouterr().err
    assert main(["segment", str(p), "-o", str(tmp_path / "s"), "--repair"]) == 0
    rep = json.loads((tmp_path / "s" / "report.json").read_text())
    assert rep["repairs"]["zero_area_faces"] == 12 and rep["faces"] == len(F) - 12
    assert rep["segments"] >= 10
    labels = np.array((tmp_path / "s" / "labels.txt").read_text().split(), dtype=int)
    assert len(labels) == len(F) and (labels >= 0).all()


SHARED_REPAIR = Path(__file__).resolve().parents[2] / "shared" / "data" / "repair"


@pytest.mark.skipif(not SHARED_REPAIR.is_dir(), reason="no ../shared/data/repair")
@pytest.mark.parametrize(
    "name", ["cylinder.obj", "halftunnel.off", "teapot.obj", "beetle.off", "truck.obj"]
)
def test_shared_repair_meshes_load_with_repair(name):
    """The public meshes a strict reader refused (see ../shared/data/MANIFEST.md)."""
    m = load_mesh(SHARED_REPAIR / name, repair=True)
    assert m.split_faces or any(v for k, v in m.repairs.items() if k != "weld_tolerance")
    assert len(m.input_face_labels(np.zeros(m.F.shape[0], int))) == m.n_input_faces


try:
    from hypothesis import given, settings
    from hypothesis import strategies as st
except ImportError:  # pragma: no cover
    given = None

if given is not None:

    @settings(max_examples=60, deadline=None)
    @given(
        flips=st.lists(st.integers(0, 53), max_size=10),
        dups=st.lists(st.integers(0, 53), max_size=5),
        collapses=st.lists(st.integers(0, 53), max_size=4),
        glue=st.booleans(),
    )
    def test_random_defects_repair_or_one_line(flips, dups, collapses, glue):
        """Flipped, duplicated and collapsed faces on one or two boxes (glued at a corner):
        repair gives a mesh the strict checks accept, or one MeshError line."""
        V, F = cube(3)
        V, F = V.copy(), F.copy()
        if glue:
            lo, hi = int(np.argmin(V.sum(1))), int(np.argmax(V.sum(1)))
            n = len(V)
            V = np.concatenate([V, V + (V[lo] - V[hi])])
            F = np.concatenate([F, np.where(F == hi, lo - n, F) + n])
        F[flips] = F[flips][:, ::-1]
        for f in collapses:
            V[F[f, 1]] = V[F[f, 0]]
        F = np.concatenate([F, F[dups]])
        try:
            m = validate_mesh(V, F, repair=True)
        except MeshError as exc:
            assert "\n" not in str(exc)
            return
        # what the strict checks ask (validate_mesh(m.V, m.F) would merge the split copies
        # again, they have equal coordinates): manifold, oriented, no zero-area face
        topo = edge_topology(m.F)
        assert topo.edge_face_count.max() <= 2 and len(nonmanifold_vertices(m.F)) == 0
        D = np.concatenate([m.F[:, [0, 1]], m.F[:, [1, 2]], m.F[:, [2, 0]]])
        assert len(np.unique(D, axis=0)) == len(D)  # each directed edge once: oriented
        assert (face_areas(m.V, m.F) > 0).all()
        out = m.input_face_labels(np.arange(m.F.shape[0]))
        assert len(out) == len(F) and out.max() < m.F.shape[0]
        assert m.repairs["duplicate_faces"] >= (len(set(dups)) if not collapses else 0)
