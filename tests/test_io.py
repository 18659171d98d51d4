"""Readers: every format round-trips; every malformed file gives MeshError naming it."""

import json
import subprocess
import sys

import numpy as np
import pytest
from meshes import cube

from igl_heatseg import MeshError
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


def test_non_triangles_are_refused(tmp_path):
    msg = _err(tmp_path, "q.off", b"OFF\n4 1 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n")
    assert "not triangles" in msg and "triangulate" in msg
    msg = _err(tmp_path, "q.obj", b"v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n")
    assert "line 5" in msg and "only triangles" in msg


def test_obj_index_zero_and_out_of_range(tmp_path):
    assert "index 0" in _err(tmp_path, "z.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n")
    msg = _err(tmp_path, "r.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n")
    assert "r.obj: 1 face(s) have vertex indices outside 0..2: face 0 = [0, 1, 8]" in msg


def test_ply_truncated_binary_and_bad_header(tmp_path):
    V, F = cube(1)
    data = _ply(V, F, "binary_little_endian")
    msg = _err(tmp_path, "t.ply", data[:-10])
    assert "declares 12 face rows" in msg and "truncated" in msg
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
