"""Boundaries placed by a minimum cut: exactness of the cut, a tangent join straightened, a
crease and a thin strip left alone."""

from __future__ import annotations

import itertools

import igl
import numpy as np
import pytest
from meshes import plane_into_cylinder

from igl_heatseg.evaluation.surfaces import boundary_length
from igl_heatseg.mesh.geometry import face_areas
from igl_heatseg.surfaces.boundary_cut import binary_min_cut, swap_boundaries
from igl_heatseg.surfaces.model import Surface


def _energy(c0, c1, ei, ej, w, lab):
    return float(np.where(lab, c1, c0).sum() + w[lab[ei] != lab[ej]].sum())


@pytest.mark.parametrize("seed", range(12))
def test_binary_min_cut_is_the_exact_minimum(seed):
    rng = np.random.default_rng(seed)
    n = int(rng.integers(1, 10))
    c0, c1 = rng.uniform(0, 2, n), rng.uniform(0, 2, n)
    pairs = [p for p in itertools.combinations(range(n), 2) if rng.uniform() < 0.4]
    ei = np.array([p[0] for p in pairs], dtype=np.int64)
    ej = np.array([p[1] for p in pairs], dtype=np.int64)
    w = rng.uniform(0, 1.5, len(pairs))
    lab = binary_min_cut(c0, c1, ei, ej, w)
    best = min(_energy(c0, c1, ei, ej, w, np.array(b, dtype=bool))
               for b in itertools.product([0, 1], repeat=n))
    assert lab.dtype == bool and lab.shape == (n,)
    assert _energy(c0, c1, ei, ej, w, lab) <= best + 1e-6 * (1 + best)


def test_binary_min_cut_without_pairs_takes_each_cheaper_label():
    lab = binary_min_cut([1.0, 0.0, 2.0], [0.0, 1.0, 3.0], [], [], [])
    assert lab.tolist() == [True, False, False]


@pytest.mark.parametrize("args, match", [
    (([1.0, 2.0], [0.0], [], [], []), "shapes"),
    (([1.0, np.nan], [0.0, 1.0], [], [], []), "finite"),
    (([1.0, 0.0], [0.0, 1.0], [0], [1], [-1.0]), "finite and >= 0"),
    (([1.0, 0.0], [0.0, 1.0], [0], [2], [1.0]), "outside"),
])
def test_binary_min_cut_rejects_bad_input(args, match):
    from igl_heatseg.errors import MeshError

    with pytest.raises(MeshError, match=match):
        binary_min_cut(*args)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_tangent_join_zigzag_is_straightened(seed):
    """The plane and the cylinder are within the noise of each other over a band of faces, and
    the initial boundary wanders through it (as the heat fields leave it): the cut makes it
    the straight line it is, about where it is."""
    h, noise = 0.25, 0.025
    V, F, S, fits = plane_into_cylinder(noise, seed, h)
    truth = (S > 0).astype(np.int64)
    y = V[F][:, :, 1].mean(axis=1)
    labels = (S > 0.6 * np.sin(2.0 * y) + np.random.default_rng(seed).normal(0, 0.15, len(F))
              ).astype(np.int64)
    labels = np.where(np.abs(S) > 1.5, truth, labels)  # a noisy band, right far from the join
    TT = igl.triangle_triangle_adjacency(F)[0]
    FN = igl.per_face_normals(V, F, np.zeros(3))
    A = face_areas(V, F)
    true_len = boundary_length(V, F, truth)
    before_len = boundary_length(V, F, labels)
    wrong_before = A[labels != truth].sum()
    assert before_len > 1.5 * true_len and np.abs(S[labels != truth]).max() > 2 * h
    changed = swap_boundaries(V, F, labels, fits, 2.5 * noise, TT, FN)
    assert changed == {0, 1}
    assert boundary_length(V, F, labels) < 1.15 * true_len
    # within two faces of the join, where the two surfaces are 0.03 noise levels apart
    assert np.abs(S[labels != truth]).max() < 2 * h
    assert A[labels != truth].sum() < wrong_before


def _folded_strip(angle: float):
    """Three flat panels of a 1 x 6 strip, the middle one a single row of triangles, folded
    by ``angle`` at each of the two lines between them."""
    x = np.array([0.0, 1, 2, 2.2, 3.2, 4.2])
    t = np.r_[0, 0, angle, 2 * angle, 2 * angle]  # direction of segment i (x[i] to x[i + 1])
    P = np.r_[[[0.0, 0.0]], np.cumsum(np.diff(x)[:, None] * np.c_[np.cos(t), np.sin(t)], axis=0)]
    V, F = [], []
    for yy in np.arange(0, 7.0):
        V += [[p[0], yy, p[1]] for p in P]
    V = np.array(V)
    n = len(x)
    for j in range(6):
        for i in range(n - 1):
            a, b, c, d = j * n + i, j * n + i + 1, (j + 1) * n + i + 1, (j + 1) * n + i
            F += [[a, b, c], [a, c, d]]
    F = np.array(F, dtype=np.int64)
    cx = np.r_[x][F % n].mean(axis=1)
    labels = np.where(cx < 2, 0, np.where(cx < 2.2, 1, 2)).astype(np.int64)
    return V, F, labels


@pytest.mark.parametrize("smoothness", [None, 100.0])
@pytest.mark.parametrize("angle", [np.radians(45), np.radians(90)])
def test_crease_boundaries_and_a_thin_true_face_stay(angle, smoothness):
    """Faces across a crease lie off the other surface: they are the cut's fixed ends, and a
    true face one triangle wide (a chamfer) keeps every face, even when the boundary length
    weighs 400 times the default (a cut that pushes a segment off its surface is undone)."""
    V, F, labels = _folded_strip(angle / 2)
    fits = {}
    for k in range(3):
        P = V[np.unique(F[labels == k])]
        c = P.mean(axis=0)
        n = np.linalg.svd(P - c)[2][2]
        fits[k] = Surface("plane", {"point": c, "normal": n})
    TT = igl.triangle_triangle_adjacency(F)[0]
    FN = igl.per_face_normals(V, F, np.zeros(3))
    before = labels.copy()
    assert swap_boundaries(V, F, labels, fits, 0.01, TT, FN, smoothness=smoothness) == set()
    assert np.array_equal(labels, before)
