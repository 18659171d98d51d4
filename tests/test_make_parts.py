"""Tests for tools/make_parts.py (machined parts with exact B-Rep face labels)."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("gmsh", reason="gmsh (pip install gmsh) is needed to build the parts")

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tools"))
import make_parts as mp  # noqa: E402

from igl_heatseg.checks import validate_mesh  # noqa: E402
from igl_heatseg.topology import edge_topology, face_components  # noqa: E402

#: Small parts keep the test fast; the default target is checked once.
SMALL = 4000

#: Planar B-Rep faces must be flat to this fraction of the part's bounding-box diagonal.
PLANE_TOL = 1e-6


@pytest.fixture(scope="module")
def parts():
    return {kind: mp.make_part(7, kind, target_faces=SMALL) for kind in mp.KINDS}


@pytest.mark.parametrize("kind", mp.KINDS)
def test_part_is_closed_manifold_oriented_and_fully_labelled(parts, kind):
    p = parts[kind]
    m = len(p.F)
    mesh = validate_mesh(p.V, p.F, name=kind)  # raises on non-manifold or flipped faces
    assert mesh.merged_vertices == 0 and mesh.unreferenced_vertices == 0
    assert edge_topology(mesh.F).boundary.sum() == 0  # closed solid boundary
    P = p.V[p.F]
    volume = np.einsum("ij,ij->i", P[:, 0], np.cross(P[:, 1], P[:, 2])).sum() / 6
    assert volume > 0  # outward normals
    assert p.labels.shape == (m,) and p.labels.dtype == np.int64
    k = len(p.surface_types)
    assert np.array_equal(np.unique(p.labels), np.arange(k))  # every face labelled, none empty
    assert SMALL / mp.FACE_COUNT_SLACK**2 < m < SMALL * mp.FACE_COUNT_SLACK**3


@pytest.mark.parametrize("kind", mp.KINDS)
def test_labels_are_connected_and_planes_are_flat(parts, kind):
    p = parts[kind]
    diag = np.linalg.norm(p.V.max(0) - p.V.min(0))
    for k, t in enumerate(p.surface_types):
        sel = np.flatnonzero(p.labels == k)
        sub = p.F[sel]
        assert face_components(sub)[0] == 1, f"B-Rep face {k} ({t}) is not connected"
        if t == "Plane":
            X = p.V[np.unique(sub)]
            s = np.linalg.svd(X - X.mean(0), compute_uv=False)
            assert s[-1] / np.sqrt(len(X)) < PLANE_TOL * diag


def test_expected_face_counts_and_types(parts):
    # a box with all 12 edges filleted: 6 planes, 12 cylinders, 8 sphere corners
    rb = parts["rounded_box"]
    assert sorted(rb.surface_types).count("Plane") == 6
    assert rb.surface_types.count("Cylinder") == 12 and rb.surface_types.count("Sphere") == 8
    assert "Torus" in parts["flange"].surface_types  # hub fillet
    assert "Cone" in parts["block"].surface_types  # drill tips and chamfers
    for p in parts.values():
        assert "Other" not in p.surface_types


def test_same_seed_same_mesh_different_seed_different():
    a = mp.make_part(3, "plate", target_faces=SMALL)
    b = mp.make_part(3, "plate", target_faces=SMALL)
    c = mp.make_part(4, "plate", target_faces=SMALL)
    assert np.array_equal(a.V, b.V) and np.array_equal(a.F, b.F)
    assert np.array_equal(a.labels, b.labels) and a.params == b.params
    assert a.params["L"] != c.params["L"]


def test_default_target_is_in_range():
    p = mp.make_part(1)
    assert 5000 <= len(p.F) <= 40000
    assert p.kind == mp.KINDS[1]


def test_noise_is_along_normals_with_requested_size():
    clean = mp.make_part(2, "bracket", target_faces=SMALL)
    noisy = mp.make_part(2, "bracket", target_faces=SMALL, noise=0.1)
    assert np.array_equal(clean.F, noisy.F) and np.array_equal(clean.labels, noisy.labels)
    d = np.linalg.norm(noisy.V - clean.V, axis=1)
    sigma = 0.1 * mp.mean_edge_length(clean.V, clean.F)
    assert np.sqrt((d**2).mean()) == pytest.approx(sigma, rel=0.1)
    # on a flat plate interior the displacement is normal to the plane
    V, F = (
        np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]]),
        np.array([[0, 1, 2], [1, 3, 2]]),
    )
    W = mp.add_normal_noise(V, F, 0.5, 1)
    assert np.allclose(W[:, :2], V[:, :2]) and np.abs(W[:, 2]).max() > 0
    validate_mesh(noisy.V, noisy.F)


def test_irregular_varies_triangle_size():
    reg = mp.make_part(5, "rounded_box", target_faces=SMALL)
    irr = mp.make_part(5, "rounded_box", target_faces=SMALL, irregular=0.6)
    validate_mesh(irr.V, irr.F)

    def cv(p):
        area = np.linalg.norm(
            np.cross(*(p.V[p.F[:, 1:]] - p.V[p.F[:, :1]]).transpose(1, 0, 2)), axis=1
        )
        return area.std() / area.mean()

    assert cv(irr) > 1.2 * cv(reg)


def test_bad_options_raise():
    with pytest.raises(ValueError, match="kind"):
        mp.make_part(0, "teapot")
    with pytest.raises(ValueError, match="irregular"):
        mp.make_part(0, irregular=1.5)
    with pytest.raises(ValueError, match="noise"):
        mp.make_part(0, noise=-1)


def test_write_read_roundtrip_and_main(tmp_path, parts):
    p = parts["flange"]
    obj = mp.write_part(p, tmp_path)
    V, F, labels, types = mp.read_part(obj)
    assert np.allclose(V, p.V, rtol=1e-8, atol=1e-6) and np.array_equal(F, p.F)
    assert np.array_equal(labels, p.labels) and types == p.surface_types
    assert mp.main(["--out", str(tmp_path / "cli"), "--seeds", "0", "--target-faces", "2000"]) == 0
    assert (tmp_path / "cli" / "part_000_rounded_box.facelabels.txt").exists()
