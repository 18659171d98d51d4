"""Trimming curves: on the intersection of two fitted surfaces where it is well conditioned,
else the smoothed mesh chain; never onto a surface that does not fit the faces along it."""

from __future__ import annotations

import igl
import numpy as np
import pytest
from meshes import plane_into_cylinder

from igl_heatseg.mesh.topology import boundary_graph
from igl_heatseg.surfaces.boundaries import boundary_curves, move_limit, onto_surfaces
from igl_heatseg.surfaces.model import Surface

CUBE_V = np.array([[x, y, z] for x in (-1.0, 1.0) for y in (-1.0, 1.0) for z in (-1.0, 1.0)])


def noisy_box(levels=3, noise=0.02, seed=0):
    """The cube [-1, 1]^3 subdivided ``levels`` times, vertices moved along their normals; the
    side of each face (0..5) and the six exact planes."""
    F = np.array([[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1],
                  [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]])
    V, F = igl.upsample(CUBE_V, F, levels)
    N = igl.per_vertex_normals(V, F)
    W = V + np.random.default_rng(seed).normal(0, noise, len(V))[:, None] * N
    FN = igl.per_face_normals(V, F, np.zeros(3))
    axis = np.abs(FN).argmax(axis=1)
    side = 2 * axis + (FN[np.arange(len(F)), axis] > 0)
    planes = []
    for k in range(6):
        n = np.zeros(3)
        n[k // 2] = 1.0 if k % 2 else -1.0
        planes.append(Surface("plane", {"point": n.copy(), "normal": n}, rms=noise,
                              max_dev=4 * noise))
    return W, F.astype(np.int64), side.astype(np.int64), planes


def test_onto_surfaces_finds_the_line_of_two_planes_and_the_point_of_three():
    P = np.random.default_rng(1).uniform(-2, 2, (20, 3))
    S = [Surface("plane", {"point": np.zeros(3), "normal": e}) for e in np.eye(3)]
    res = [lambda X, s=s: (s.distance(X), s.normals(X)) for s in S]
    X, r = onto_surfaces(P, res[:2])
    assert np.abs(X[:, :2]).max() < 1e-12 and np.allclose(X[:, 2], P[:, 2]) and r.max() < 1e-12
    X, r = onto_surfaces(P, res)
    assert np.abs(X).max() < 1e-12


def test_move_limit_skips_surfaces_without_a_deviation():
    assert move_limit([0.25, np.nan, np.inf], 2.0) == pytest.approx(1.5)


def test_noisy_box_curves_lie_on_its_edges_and_corners():
    V, F, side, planes = noisy_box()
    curves = boundary_curves(V, F, side, planes, tol=0.05)
    inner = [c for c in curves if c.right >= 0]
    assert len(inner) == 12 and all(c.method == "intersection" for c in inner)
    for c in inner:
        # on the edge of the two sides: both coordinates at +-1, to round-off
        fixed = [s // 2 for s in (c.left, c.right)]
        assert np.allclose(np.abs(c.points[:, fixed]), 1.0, atol=1e-9)
        raw = V[c.verts][:, fixed]
        assert np.abs(np.abs(raw) - 1).max() > 1e-3  # the mesh chain was off the edge
        assert c.moved <= move_limit([4 * 0.02] * 2, 0.25)
    ends = np.array([c.points[[0, -1]] for c in inner]).reshape(-1, 3)
    assert np.allclose(np.abs(ends), 1.0, atol=1e-9)  # corners at the cube's corners


def test_a_surface_that_does_not_fit_along_the_chain_does_not_trim_it():
    V, F, side, planes = noisy_box()
    n = np.array([0.0, 0.12, 1.0]) / np.linalg.norm([0.0, 0.12, 1.0])  # +z plane tilted 7 deg
    planes[5] = Surface("plane", {"point": np.array([0.0, 0, 1]), "normal": n}, rms=0.02,
                        max_dev=0.08)
    curves = boundary_curves(V, F, side, planes, tol=0.05)
    for c in curves:
        if 5 in (c.left, c.right):
            assert c.method == "smoothed"
        elif c.right >= 0:
            assert c.method == "intersection"


def test_a_segment_of_a_face_or_two_does_not_pin_its_curves():
    V, F, side, planes = noisy_box()
    labels = side.copy()
    labels[np.flatnonzero(side == 5)[:1]] = 6  # one face of the +z side on its own
    f = np.flatnonzero(labels == 6)
    planes = planes + [Surface("plane", {"point": V[F[f[0]]].mean(axis=0),
                                         "normal": np.array([0.0, 0, 1])}, rms=0.0, max_dev=0.0)]
    curves = boundary_curves(V, F, labels, planes, tol=0.05)
    assert all(c.method == "smoothed" for c in curves if 6 in (c.left, c.right))


def test_tangent_join_is_smoothed_not_intersected():
    """A plane running tangentially into a cylinder: the intersection does not pin the curve
    down, so the noisy chain is smoothed (shorter, still near it)."""
    h, noise = 0.25, 0.02
    V, F, S, fits = plane_into_cylinder(noise, 0, h)
    labels = (S > 0).astype(np.int64)
    surfaces = [Surface(s.kind, s.params, rms=noise, max_dev=4 * noise) for s in fits.values()]
    g = boundary_graph(V, F, labels, 2)
    assert [(ch.left, ch.right) for ch in g.chains if ch.right >= 0] in ([(0, 1)], [(1, 0)])
    (curve,) = [c for c in boundary_curves(V, F, labels, surfaces, tol=2.5 * noise)
                if c.right >= 0]
    assert curve.method == "smoothed"
    assert curve.length < np.linalg.norm(np.diff(V[curve.verts], axis=0), axis=1).sum()
    assert np.abs(curve.points[:, 0]).max() < 2 * h  # still at the join
