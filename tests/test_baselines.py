"""Tests for igl_heatseg.segmentation.baselines on meshes with known answers."""

from __future__ import annotations

import igl
import numpy as np
import pytest

from igl_heatseg.segmentation.baselines import (
    CONVEX_ETA,
    dihedral_region_growing,
    random_walk_weights,
    random_walks,
    relabel_by_area,
    xatlas_charts,
)
from igl_heatseg.errors import MeshError
from igl_heatseg.evaluation.metrics import coverage, purity

CUBE_V = np.array([[x, y, z] for x in (0.0, 1) for y in (0.0, 1) for z in (0.0, 1)])
CUBE_F = np.array(
    [[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1],
     [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]]
)  # fmt: skip


def fine_box(levels: int = 3, scale=(2.0, 1.0, 0.5)):
    """A box with each side subdivided (midpoint upsampling) and its side id per face."""
    V, F = igl.upsample(CUBE_V, CUBE_F, levels)
    side = np.repeat(np.arange(6), 2 * 4**levels)  # upsample keeps each parent's children together
    return V * np.asarray(scale), F, side


def test_fine_box_side_labels_are_right():
    V, F, side = fine_box()
    N = np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]])
    N /= np.linalg.norm(N, axis=1, keepdims=True)
    for s in range(6):
        assert np.allclose(N[side == s], N[side == s][0])


def test_region_growing_cube_and_box():
    labels = dihedral_region_growing(CUBE_V, CUBE_F)
    assert len(np.unique(labels)) == 6
    V, F, side = fine_box()
    labels = dihedral_region_growing(V, F)
    assert purity(labels, side) == 1.0 and coverage(labels, side) == 1.0
    # areas decrease with the label: the two 2x1 sides come first
    A = np.bincount(labels, weights=igl.doublearea(V, F) / 2)
    assert np.all(np.diff(A) <= 1e-12) and A[0] == pytest.approx(2.0)
    # a threshold above 90 degrees joins everything
    assert len(np.unique(dihedral_region_growing(V, F, theta=np.pi / 2 + 0.1))) == 1


def test_random_walks_recovers_box_sides():
    V, F, side = fine_box()
    labels = random_walks(V, F)
    assert len(np.unique(labels)) == 6
    assert purity(labels, side) == pytest.approx(1.0) and coverage(labels, side) == pytest.approx(
        1.0
    )


def test_random_walks_on_a_fine_sphere_is_one_segment():
    V, F = igl.loop(*igl.icosahedron(), 3)
    assert len(np.unique(random_walks(V, F))) == 1


def test_random_walk_weights_flat_convex_concave():
    # flat square: all weights 1
    V = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]])
    F = np.array([[0, 1, 2], [1, 3, 2]])
    assert np.allclose(random_walk_weights(V, F)[1], 1.0)
    # a strip along y, normals up: flat, rising at 45 degrees, flat again.  The crease at y=1
    # is a valley (concave), the one at y=2 a ridge (convex), with the same dihedral angle.
    ys, zs = [0.0, 1, 2, 3], [0.0, 0, 1, 1]
    V = np.array([[x, y, z] for y, z in zip(ys, zs, strict=True) for x in (0.0, 1.0)])
    F = np.array([[2 * i, 2 * i + 1, 2 * i + 2] for i in range(3)]
                 + [[2 * i + 1, 2 * i + 3, 2 * i + 2] for i in range(3)])  # fmt: skip
    pairs, w = random_walk_weights(V, F)
    ymid = V[F].mean(axis=1)[:, 1]
    lo = np.minimum(ymid[pairs[:, 0]], ymid[pairs[:, 1]])
    hi = np.maximum(ymid[pairs[:, 0]], ymid[pairs[:, 1]])
    valley = (lo < 1) & (hi > 1)
    ridge = (lo < 2) & (hi > 2)
    assert valley.sum() == 1 and ridge.sum() == 1
    d = 1 - np.cos(np.pi / 4)
    mean = (1.0 + CONVEX_ETA) * d / len(w)
    assert w[valley][0] == pytest.approx(np.exp(-d / mean))
    assert w[ridge][0] == pytest.approx(np.exp(-CONVEX_ETA * d / mean))
    assert np.allclose(w[~valley & ~ridge], 1.0)


def test_relabel_by_area():
    assert relabel_by_area([5, 5, 9, 2], [1.0, 1.0, 3.0, 0.5]).tolist() == [1, 1, 0, 2]
    assert relabel_by_area([3, 4], [1.0, 1.0]).tolist() == [0, 1]  # ties: smaller id first


def test_bad_input_raises():
    with pytest.raises(MeshError, match="theta"):
        dihedral_region_growing(CUBE_V, CUBE_F, theta=-1.0)
    with pytest.raises(MeshError, match="eps"):
        random_walks(CUBE_V, CUBE_F, eps=2.0)
    with pytest.raises(MeshError, match="shape"):
        random_walks(CUBE_V[:, :2], CUBE_F)


def test_xatlas_charts_stay_inside_box_sides():
    pytest.importorskip("xatlas", reason="xatlas (pip install xatlas) not installed")
    V, F, side = fine_box()
    labels = xatlas_charts(V, F)
    assert labels.shape == (len(F),) and labels.min() == 0
    assert np.array_equal(np.unique(labels), np.arange(labels.max() + 1))
    assert purity(labels, side) == pytest.approx(1.0)
    with pytest.raises(MeshError, match="no option"):
        xatlas_charts(V, F, not_an_option=1)
