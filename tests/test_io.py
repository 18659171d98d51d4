"""Readers: every format round-trips; every malformed file gives MeshError naming it."""

import json
import subprocess
import sys

import numpy as np
import pytest
from meshes import cube

from igl_heatseg import MeshError, validate_mesh
from igl_heatseg.io import label_colors, load_mesh, read_mesh_arrays, write_segmented_ply


def _obj(V, F):
    return "".join(f"v {x:.17g} {y:.17g} {z:.17g}\n" for x, y, z in V) + "".join(
        f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in F
    )


def _off(V, F):
    return (
        f"OFF\n# comment\n{len(V)} {len(F)} 0\n"
        + "".join(f"{x:.17g} {y:.17g} {z:.17g}\n" for x, y, z in V)
        + "".join(f"3 {a} {b} {c}\n" for a, b, c in F)
    )


def _ply(V, F, fmt):
    head = (
        f"ply\nformat {fmt} 1.0\nelement vertex {len(V)}\nproperty double x\nproperty double y\n"
        f"property double z\nproperty uchar red\nelement face {len(F)}\n"
        "property list uchar int vertex_indices\nproperty float quality\nend_header\n"
    ).encode()
    if fmt == "ascii":
        body = "".join(f"{x:.17g} {y:.17g} {z:.17g} 7\n" for x, y, z in V)
        body += "".join(f"3 {a} {b} {c} 0.5\n" for a, b, c in F)
        return head + body.encode()
    e = "<" if fmt == "binary_little_endian" else ">"
    vdt = np.dtype([("p", e + "f8", 3), ("r", "u1")])
    fdt = np.dtype([("n", "u1"), ("v", e + "i4", 3), ("q", e + "f4")])
    va = np.zeros(len(V), vdt)
    va["p"] = V
    fa = np.zeros(len(F), fdt)
    fa["n"], fa["v"] = 3, F
    return head + va.tobytes() + fa.tobytes()


def _stl_ascii(V, F):
    s = "solid test\n"
    for f in F:
        s += "facet normal 0 0 0\nouter loop\n"
        s += (
            "".join(f"vertex {x:.17g} {y:.17g} {z:.17g}\n" for x, y, z in V[f])
            + "endloop\nendfacet\n"
        )
    return s + "endsolid test\n"


def _stl_binary(V, F):
    rec = np.dtype([("n", "<f4", 3), ("v", "<f4", (3, 3)), ("a", "<u2")])
    a = np.zeros(len(F), rec)
    a["v"] = V[F]
    return b"\0" * 80 + np.uint32(len(F)).tobytes() + a.tobytes()


@pytest.mark.parametrize(
    "ext,make",
    [
        (".obj", lambda V, F: _obj(V, F).encode()),
        (".off", lambda V, F: _off(V, F).encode()),
        (".ply", lambda V, F: _ply(V, F, "ascii")),
        (".ply", lambda V, F: _ply(V, F, "binary_little_endian")),
        (".ply", lambda V, F: _ply(V, F, "binary_big_endian")),
        (".stl", lambda V, F: _stl_ascii(V, F).encode()),
        (".stl", lambda V, F: _stl_binary(V, F)),
    ],
)
def test_formats_round_trip(tmp_path, ext, make):
    V, F = cube(2)
    p = tmp_path / f"cube{ext}"
    p.write_bytes(make(V, F))
    m = load_mesh(p)
    assert m.F.shape == F.shape
    # STL stores float32 soups: compare the geometry of each face.
    np.testing.assert_allclose(m.V[m.F], V[F], atol=1e-6)
    if ext == ".stl":
        assert m.V.shape == V.shape and m.merged_vertices == 3 * len(F) - len(V)
    else:
        np.testing.assert_array_equal(m.F, F)


def test_obj_with_texture_normal_indices_and_negative_indices(tmp_path):
    p = tmp_path / "t.obj"
    p.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvn 0 0 1\nf 1/1/1 2/1/1 -1/1/1\n")
    V, F = read_mesh_arrays(p)
    assert F.tolist() == [[0, 1, 2]]


def _err(tmp_path, name, content: bytes | None):
    p = tmp_path / name
    if content is not None:
        p.write_bytes(content)
    with pytest.raises(MeshError) as e:
        load_mesh(p)
    return str(e.value)


def test_missing_file(tmp_path):
    assert "no such file" in _err(tmp_path, "nope.off", None)


def test_directory_is_not_a_mesh(tmp_path):
    (tmp_path / "d.obj").mkdir()
    with pytest.raises(MeshError, match="is a directory"):
        load_mesh(tmp_path / "d.obj")


def test_unknown_extension(tmp_path):
    assert "unknown mesh file extension '.xyz'" in _err(tmp_path, "a.xyz", b"1 2 3")


@pytest.mark.parametrize("ext", [".obj", ".off", ".ply", ".stl"])
def test_empty_file(tmp_path, ext):
    assert "empty file" in _err(tmp_path, "e" + ext, b"")


def test_off_header_larger_than_file_fails_fast(tmp_path):
    msg = _err(tmp_path, "huge.off", b"OFF\n99999999 1 0\n0 0 0\n")
    assert "declares 99999999 vertices" in msg and "truncated" in msg


def test_off_truncated_and_garbage(tmp_path):
    V, F = cube(1)
    text = _off(V, F)
    assert "truncated" in _err(tmp_path, "t.off", text[: len(text) // 2].encode())
    assert "not an OFF file" in _err(tmp_path, "g.off", b"hello world\n1 2 3\n")
    assert "'x' is not a number" in _err(
        tmp_path, "n.off", b"OFF\n3 1 0\n0 0 0\n1 0 x\n0 1 0\n3 0 1 2\n"
    )


def test_polygon_faces_are_triangulated_in_face_order(tmp_path):
    quad = b"OFF\n5 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n2 0.5 0\n4 0 1 2 3\n3 1 4 2\n"
    (tmp_path / "q.off").write_bytes(quad)
    m = load_mesh(tmp_path / "q.off")
    assert m.F.tolist() == [[0, 1, 2], [0, 2, 3], [1, 4, 2]]
    assert m.face_map.tolist() == [0, 0, 1] and m.n_input_faces == 2 and m.split_faces == 1
    assert m.input_face_labels([5, 5, 7]).tolist() == [5, 7]
    obj = b"v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n"
    (tmp_path / "q.obj").write_bytes(obj)
    assert load_mesh(tmp_path / "q.obj").F.tolist() == [[0, 1, 2], [0, 2, 3]]
    V, F = read_mesh_arrays(tmp_path / "q.off")
    assert [list(f) for f in F] == [[0, 1, 2, 3], [1, 4, 2]]


def test_polygon_majority_label_by_area(tmp_path):
    # a pentagon fan: 3 triangles; the label covering most area wins
    V = np.array([[0, 0, 0], [4, 0, 0], [4, 1, 0], [2, 3, 0], [0, 1, 0.0]])
    m = validate_mesh(V, [[0, 1, 2, 3, 4]])
    areas = 0.5 * np.linalg.norm(
        np.cross(V[m.F[:, 1]] - V[m.F[:, 0]], V[m.F[:, 2]] - V[m.F[:, 0]]), axis=1
    )
    big = int(np.argmax(areas))
    labels = np.zeros(3, dtype=int)
    labels[big] = 9
    assert m.input_face_labels(labels).tolist() == [9 if areas[big] > areas.sum() / 2 else 0]


def test_ply_polygons_binary_mixed_sizes(tmp_path):
    head = (
        b"ply\nformat binary_little_endian 1.0\nelement vertex 5\nproperty float x\n"
        b"property float y\nproperty float z\nelement face 2\n"
        b"property list uchar int vertex_indices\nend_header\n"
    )
    V = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [2, 0.5, 0]], "<f4")
    body = V.tobytes() + bytes([4]) + np.array([0, 1, 2, 3], "<i4").tobytes()
    body += bytes([3]) + np.array([1, 4, 2], "<i4").tobytes()
    (tmp_path / "p.ply").write_bytes(head + body)
    m = load_mesh(tmp_path / "p.ply")
    assert m.F.tolist() == [[0, 1, 2], [0, 2, 3], [1, 4, 2]] and m.n_input_faces == 2


def test_obj_index_zero_and_out_of_range(tmp_path):
    assert "index 0" in _err(tmp_path, "z.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n")
    msg = _err(tmp_path, "r.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n")
    assert msg == "r.obj: line 4: face vertex index 9 refers to no vertex (the file has 3)"
    # a vertex after the face using it is fine (positive indices count in the whole file)
    (tmp_path / "fwd.obj").write_bytes(b"v 0 0 0\nv 1 0 0\nf 1 2 3\nv 0 1 0\n")
    assert load_mesh(tmp_path / "fwd.obj").F.tolist() == [[0, 1, 2]]
    msg = _err(tmp_path, "r.off", b"OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 8\n")
    assert "r.off: 1 face(s) have vertex indices outside 0..2: face 0 = [0, 1, 8]" in msg


def test_ply_truncated_binary_and_bad_header(tmp_path):
    V, F = cube(1)
    data = _ply(V, F, "binary_little_endian")
    msg = _err(tmp_path, "t.ply", data[:-10])
    assert "face row 11 of 12" in msg and "truncated" in msg
    assert "not a PLY file" in _err(tmp_path, "g.ply", b"garbage garbage")
    assert "format 'binary_weird'" in _err(
        tmp_path, "f.ply", b"ply\nformat binary_weird 1.0\nelement vertex 0\nend_header\n"
    )


def test_stl_truncated_binary(tmp_path):
    V, F = cube(1)
    data = _stl_binary(V, F)
    msg = _err(tmp_path, "t.stl", data[:-7])
    assert "declares 12 triangles" in msg


def test_nan_in_file_names_vertex(tmp_path):
    msg = _err(tmp_path, "nan.obj", b"v 0 0 0\nv 1 nan 0\nv 0 1 0\nf 1 2 3\n")
    assert msg.startswith("nan.obj: 1 vertex(es) have NaN") and "vertex 1" in msg


def test_segmented_ply_is_readable_and_holds_labels(tmp_path):
    V, F = cube(2)
    labels = np.arange(len(F)) % 5
    p = tmp_path / "s.ply"
    write_segmented_ply(p, V, F, labels)
    m = load_mesh(p)
    np.testing.assert_array_equal(m.F, F)
    np.testing.assert_allclose(m.V, V)
    raw = p.read_bytes()
    body = raw[raw.index(b"end_header\n") + 11 :]
    fdt = np.dtype([("n", "u1"), ("v", "<i4", 3), ("l", "<i4"), ("rgb", "u1", 3)])
    fa = np.frombuffer(body[len(V) * 24 :], dtype=fdt)
    np.testing.assert_array_equal(fa["l"], labels)
    np.testing.assert_array_equal(fa["rgb"], label_colors(5)[labels])


def test_label_colors_distinct():
    C = label_colors(300)
    assert C.shape == (300, 3) and C.dtype == np.uint8
    assert len({tuple(c) for c in C[:20]}) == 20


def test_cli_hang_case_returns_quickly(tmp_path):
    # libigl's reader hangs on this file; the CLI must answer with one line and exit 2.
    p = tmp_path / "huge.off"
    p.write_bytes(b"OFF\n99999999 1 0\n0 0 0\n")
    r = subprocess.run(
        [sys.executable, "-m", "igl_heatseg", "segment", str(p), "-o", str(tmp_path / "o")],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert r.returncode == 2
    assert r.stderr.strip().count("\n") == 0 and "Traceback" not in r.stderr
    assert "declares 99999999 vertices" in r.stderr
    assert not (tmp_path / "o" / "report.json").exists()
    json.dumps(r.stderr)


# --------------------------------------------------------------------------------------------
# Hardened readers: one root cause each (found by tools/fuzz_readers.py), with its minimal file.

TRI_OBJ = b"v 0 0 0\nv 1 0 0\nv 0 1 0\n"


@pytest.mark.parametrize(
    "name,content,needle",
    [
        # OverflowError: counts and indices beyond int64
        ("big.off", b"OFF\n99999999999999999999 1 0\n", "line 2: OFF vertex count: 99999999999999999999 is out of range"),
        ("big.obj", TRI_OBJ + b"f 1 2 99999999999999999999\n", "line 4: face vertex index: 99999999999999999999 is out of range"),
        ("bigf.off", b"OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 99999999999999999999\n", "line 6: face vertex index"),
        ("bigk.off", b"OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n99999999999999999999 0 1 2\n", "line 6: face vertex count"),
        ("big.ply", b"ply\nformat ascii 1.0\nelement vertex 99999999999999999999\nproperty float x\nend_header\n", "line 3: PLY element vertex count"),
        # StopIteration: a token str.isdigit() accepts but int() does not
        ("sup.obj", TRI_OBJ + "f 1 2 \u00b3\n".encode(), "line 4: face vertex index: '\u00b3' is not an integer"),
        ("sup.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 \u00b2\n".encode(), "line 6: face vertex index"),
        # IndexError: a short 'property' line
        ("short.ply", b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float\nend_header\n", "line 4: expected 'property TYPE NAME'"),
        ("short2.ply", b"ply\nformat ascii 1.0\nelement vertex 3\nproperty\nend_header\n", "line 4: expected 'property TYPE NAME'"),
        # KeyError/ValueError: an unknown type, a float list count, a list as vertex x
        ("type.ply", b"ply\nformat ascii 1.0\nelement vertex 3\nproperty flaot x\nend_header\n", "line 4: unknown PLY type 'flaot'"),
        ("flist.ply", b"ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\nproperty float z\nelement face 0\nproperty list float int vertex_indices\nend_header\n", "list count must be an integer type"),
        # binary PLY: a face list longer than the file
        ("list.ply", b"ply\nformat binary_little_endian 1.0\nelement vertex 0\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n\xff", "truncated"),
        # warnings on stderr (a multi-line error): coordinates whose squares overflow
        ("huge.obj", b"v 1e200 0 0\nv 0 1e200 0\nv 0 0 0\nf 1 2 3\n", "too large coordinates"),
        # OBJ face lines with too few vertices, empty indices
        ("two.obj", TRI_OBJ + b"f 1 2\n", "line 4: a face needs at least 3 vertices, this one has 2"),
        ("slash.obj", TRI_OBJ + b"f //1 2 3\n", "line 4: face vertex index: '' is not an integer"),
        ("rel.obj", TRI_OBJ + b"f -1 -2 -4\n", "line 4: face vertex index -4 refers to no vertex"),
        # OFF: a face row shorter than its count; NUL bytes in a text file
        ("shortf.off", b"OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n4 0 1 2\n", "line 6: a face of 4 vertices lists only 3"),
        ("nul.off", b"OFF\n3 1 0\n0 0\x00 0\n", "byte 13: binary content"),
        # ASCII STL: a bad number names its line
        ("bad.stl", b"solid s\nfacet normal 0 0 0\nouter loop\nvertex 0 0 0\nvertex 1 0 x\nvertex 0 1 0\nendloop\nendfacet\nendsolid\n", "line 5: vertex coordinate: 'x' is not a number"),
    ],
)  # fmt: skip
def test_reader_root_causes_give_one_line(tmp_path, name, content, needle):
    msg = _err(tmp_path, name, content)
    assert "\n" not in msg and msg.startswith(name + ":"), msg
    assert needle in msg, msg


def _fuzz_module():
    import importlib.util
    from pathlib import Path

    path = Path(__file__).resolve().parent.parent / "tools" / "fuzz_readers.py"
    spec = importlib.util.spec_from_file_location("fuzz_readers", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_fuzzed_files_raise_only_one_line_mesh_errors(tmp_path):
    """A seeded mutation fuzzer over the six formats (1,800 files, a few seconds): every
    file loads or raises MeshError, one line naming the file; no warning is printed."""
    import warnings

    fz = _fuzz_module()
    kinds = {"ok": 0, "error": 0}
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        for i in range(1800):
            fmt, data, names = fz.make_case(1414, i)
            p = tmp_path / f"f{i}{fz.EXT[fmt]}"
            p.write_bytes(data)
            try:
                load_mesh(p)
                kinds["ok"] += 1
            except MeshError as exc:
                msg = str(exc)
                assert "\n" not in msg and p.name in msg, (i, fmt, names, msg)
                kinds["error"] += 1
            p.unlink()
    assert kinds["ok"] > 100 and kinds["error"] > 1000


def test_fuzzed_files_through_the_cli(tmp_path):
    """The tool's own runner: segment in-process, stderr captured (as tools/fuzz_readers.py)."""
    fz = _fuzz_module()
    seen = set()
    for i in range(120):
        fmt, data, names = fz.make_case(2718, i)
        p = tmp_path / f"c{i}{fz.EXT[fmt]}"
        p.write_bytes(data)
        kind, detail = fz.run_case(p, tmp_path / "out", timeout=60)
        assert kind in ("success", "clean"), (i, fmt, names, detail)
        seen.add(kind)
    assert seen == {"success", "clean"}


try:
    from hypothesis import HealthCheck, given, settings
    from hypothesis import strategies as st
except ImportError:  # pragma: no cover
    given = None

if given is not None:
    _MAGIC = {
        ".off": [b"OFF\n", b"OFF 3 1 0\n", b""],
        ".obj": [b"v 0 0 0\n", b"f ", b""],
        ".ply": [b"ply\nformat ascii 1.0\n", b"ply\nformat binary_little_endian 1.0\nelement vertex 3\n", b"ply\n"],
        ".stl": [b"solid x\n", b"\x00" * 80, b""],
    }  # fmt: skip

    @settings(max_examples=150, deadline=None, suppress_health_check=list(HealthCheck))
    @given(
        ext=st.sampled_from(sorted(_MAGIC)),
        k=st.integers(0, 2),
        body=st.binary(max_size=300)
        | st.lists(
            st.sampled_from(
                ["v", "f", "3", "1", "-1", "0", "1e400", "nan", "end_header", "property",
                 "element", "face", "vertex", "list", "uchar", "int", "float", "\n", " ", "/",
                 "99999999999999999999", "OFF", "solid", "facet", "loop"]
            ),
            max_size=60,
        ).map(lambda t: " ".join(t).encode()),
    )  # fmt: skip
    def test_any_bytes_load_or_raise_one_line(tmp_path_factory, ext, k, body):
        p = tmp_path_factory.mktemp("h") / ("m" + ext)
        p.write_bytes(_MAGIC[ext][k] + body)
        try:
            load_mesh(p)
        except MeshError as exc:
            assert "\n" not in str(exc) and "m" + ext in str(exc)

    @settings(max_examples=40, deadline=None)
    @given(
        sizes=st.lists(st.integers(3, 9), min_size=1, max_size=6),
        fmt=st.sampled_from(["obj", "off", "ply_ascii", "ply_binary"]),
    )
    def test_convex_polygons_round_trip(tmp_path_factory, sizes, fmt):
        """Separate convex polygons in any format: triangles in face order, one input face each."""
        fz = _fuzz_module()
        V, F = [], []
        for j, k in enumerate(sizes):
            a = np.linspace(0, 2 * np.pi, k, endpoint=False)
            F.append(list(range(len(V), len(V) + k)))
            V.extend(np.stack([np.cos(a) + 3 * j, np.sin(a), np.zeros(k)], 1).tolist())
        write = {
            "obj": lambda: fz.write_obj(V, F),
            "off": lambda: fz.write_off(V, F),
            "ply_ascii": lambda: fz.write_ply(V, F, False),
            "ply_binary": lambda: fz.write_ply(V, F, True),
        }[fmt]
        p = tmp_path_factory.mktemp("p") / ("m" + fz.EXT[fmt])
        p.write_bytes(write())
        m = load_mesh(p)
        assert m.F.shape[0] == sum(k - 2 for k in sizes)
        assert m.n_input_faces == len(sizes) and m.split_faces == sum(k > 3 for k in sizes)
        fm = np.arange(len(sizes)) if m.face_map is None else m.face_map
        assert np.bincount(fm).tolist() == [k - 2 for k in sizes]
        assert m.input_face_labels(fm * 10).tolist() == [10 * j for j in range(len(sizes))]
