"""Property tests for the Hessian energies (igl_heatseg.parameterization.hessian)."""

from __future__ import annotations

import igl
import numpy as np
import pytest
import scipy.linalg as sla

from igl_heatseg.errors import MeshError
from igl_heatseg.parameterization.hessian import (
    HLLE_MIN_NEIGHBORS,
    curved_hessian_energy,
    hessian_energy,
    hlle_energy,
    vertex_neighborhoods,
)

#: |K f| on affine f, relative to ||K|| ||f||.
AFFINE_RTOL = 1e-10
#: Smallest eigenvalue of K >= -PSD_RTOL * largest.
PSD_RTOL = 1e-10


def grid(nx, ny, jitter=0.0, seed=0):
    """Flat (nx+1) x (ny+1) grid of [0,1]^2 in z=0, optionally with jittered interior."""
    x, y = np.meshgrid(np.linspace(0, 1, nx + 1), np.linspace(0, 1, ny + 1), indexing="ij")
    V = np.c_[x.ravel(), y.ravel(), np.zeros(x.size)]
    idx = np.arange(V.shape[0]).reshape(nx + 1, ny + 1)
    if jitter:
        inner = idx[1:-1, 1:-1].ravel()
        rng = np.random.default_rng(seed)
        V[inner, :2] += rng.uniform(-jitter, jitter, (len(inner), 2)) / max(nx, ny)
    a, b = idx[:-1, :-1].ravel(), idx[1:, :-1].ravel()
    c, d = idx[1:, 1:].ravel(), idx[:-1, 1:].ravel()
    return V, np.r_[np.c_[a, b, c], np.c_[a, c, d]]


def cylinder_patch(nu, nv, angle=np.pi, r=1.0, h=2.0):
    """A rectangle of a cylinder (already a disk); returns V, F and intrinsic (s, z) coords
    of the polyhedral surface (s measured along chords)."""
    V, F = grid(nu, nv)
    th = V[:, 0] * angle
    V3 = np.c_[r * np.cos(th), r * np.sin(th), V[:, 1] * h]
    chord = 2 * r * np.sin(angle / nu / 2)
    S = np.c_[V[:, 0] * nu * chord, V[:, 1] * h]
    return V3, F, S


def folded_sheet(nx=12, ny=8, angle=np.pi / 2):
    """A flat sheet folded along x = 0.5 by ``angle`` (developable, with a sharp crease);
    returns V, F and its unfolded coordinates."""
    V, F = grid(nx, ny)
    x = V[:, 0]
    fold = 0.5
    V3 = np.c_[
        np.where(x <= fold, x, fold + (x - fold) * np.cos(angle)),
        V[:, 1],
        np.where(x <= fold, 0.0, (x - fold) * np.sin(angle)),
    ]
    return V3, F, V[:, :2].copy()


def rayleigh(K, M, f):
    f = f - (M @ f).sum() / M.sum()
    return (f @ K @ f) / (f @ M @ f)


ENERGIES = [
    ("hlle-intrinsic", lambda V, F: hlle_energy(V, F, coords="intrinsic")),
    ("hlle-normal", lambda V, F: hlle_energy(V, F, coords="normal")),
    ("hlle-projection", lambda V, F: hlle_energy(V, F, coords="projection")),
    ("hlle-chord", lambda V, F: hlle_energy(V, F, coords="chord")),
    ("curved", curved_hessian_energy),
]


@pytest.mark.parametrize("name,energy", ENERGIES, ids=[e[0] for e in ENERGIES])
def test_symmetric_psd_and_zero_on_affine(name, energy):
    V, F = grid(9, 7, jitter=0.3)
    K = energy(V, F)
    assert K.shape == (len(V), len(V))
    assert abs(K - K.T).max() == 0.0
    Kd = K.toarray()
    lam = sla.eigvalsh(Kd)
    assert lam[0] >= -PSD_RTOL * lam[-1]
    scale = np.abs(Kd).sum(axis=1).max()
    for f in (np.ones(len(V)), V[:, 0], V[:, 1], 3.0 - 2.0 * V[:, 0] + 0.5 * V[:, 1]):
        assert np.abs(K @ f).max() <= AFFINE_RTOL * scale * np.abs(f).max()
    # Exactly three null directions on a flat chart: the next eigenvalue is clearly positive.
    assert lam[3] > 1e6 * max(abs(lam[0]), abs(lam[2]), 1e-300)


def test_hlle_is_a_hessian_norm():
    """f = x^2/2 + 3xy + y^2: Hess f = [[1, 3], [3, 2]], ||Hess f||_F^2 = 23 everywhere (the
    local frames are rotated, so only rotation invariants are checked)."""
    V, F = grid(12, 12, jitter=0.2)
    K, B, A = hlle_energy(V, F, return_parts=True)
    f = 0.5 * V[:, 0] ** 2 + V[:, 1] ** 2 + 3 * V[:, 0] * V[:, 1]  # (1, 3, 2): 1 + 2*9 + 4
    Hf = (B @ f).reshape(-1, 3)
    assert np.allclose((Hf**2).sum(axis=1), 23.0, rtol=1e-9)
    assert np.allclose(Hf[:, 0] + Hf[:, 2], 3.0, rtol=1e-9)  # trace
    assert np.isclose(f @ K @ f, 23.0 * A.sum(), rtol=1e-9)
    assert np.isclose(A.sum(), 1.0)


def test_scaling():
    """K(sV) = K(V) / s^2 (Hessian squared ~ 1/L^4, area ~ L^2)."""
    V, F = grid(6, 6, jitter=0.3)
    V[:, 2] = 0.3 * np.sin(3 * V[:, 0])
    K1 = hlle_energy(V, F)
    K2 = hlle_energy(3.0 * V, F)
    assert abs(K1 / 9.0 - K2).max() <= 1e-9 * abs(K2).max()


@pytest.mark.parametrize(
    "name,energy,rq_max",
    [
        ("hlle-intrinsic", lambda V, F: hlle_energy(V, F), 1e-10),
        ("hlle-normal", lambda V, F: hlle_energy(V, F, coords="normal"), 1e-5),
        ("hlle-projection", lambda V, F: hlle_energy(V, F, coords="projection"), 1e-2),
        ("curved", curved_hessian_energy, 1e-8),
    ],
    ids=["hlle-intrinsic", "hlle-normal", "hlle-projection", "curved"],
)
def test_cylinder_intrinsic_coordinates_are_near_null(name, energy, rq_max):
    """Developable chart: Rayleigh quotients of (s, z) are tiny next to the first non-affine
    eigenvalue (the projection variant of HLLE is the least accurate, O(h^2))."""
    V, F, S = cylinder_patch(30, 20)
    K = energy(V, F)
    M = igl.massmatrix(V, F, igl.MASSMATRIX_TYPE_VORONOI).toarray()
    lam = sla.eigh(K.toarray(), M, eigvals_only=True, subset_by_index=[0, 3])
    first_nonaffine = lam[3]
    assert first_nonaffine > 1.0
    for f in S.T:
        f = f - (M @ f).sum() / M.sum()
        rq = (f @ K @ f) / (f @ M @ f)
        assert rq <= rq_max * first_nonaffine, (name, rq, first_nonaffine)


def test_creased_developable_chart():
    """A sheet folded by 90 degrees is intrinsically flat: the intrinsic HLLE and the curved
    Hessian keep its unfolded coordinates in the null space; the tangent-plane variants of HLLE
    (quadric fits across the crease) do not."""
    V, F, S = folded_sheet()
    M = igl.massmatrix(V, F, igl.MASSMATRIX_TYPE_VORONOI).toarray()
    for K in (hlle_energy(V, F), curved_hessian_energy(V, F)):
        lam = sla.eigh(K.toarray(), M, eigvals_only=True, subset_by_index=[0, 3])
        assert lam[2] < 1e-8 * lam[3]
        assert max(rayleigh(K, M, f) for f in S.T) < 1e-10 * lam[3]
    for coords in ("projection", "normal"):
        K = hlle_energy(V, F, coords=coords)
        lam = sla.eigh(K.toarray(), M, eigvals_only=True, subset_by_index=[0, 3])
        assert rayleigh(K, M, S[:, 0]) > 1e-2 * lam[3]


def test_hlle_normal_coordinates_converge_faster_than_projection():
    """Refining the cylinder: the projection error falls ~h^2, normal coordinates much faster."""
    rq = {}
    for coords in ("projection", "normal"):
        out = []
        for n in (16, 32):
            V, F, S = cylinder_patch(n, n)
            K = hlle_energy(V, F, coords=coords)
            s = S[:, 0] - S[:, 0].mean()
            out.append((s @ K @ s) / (s @ s))
        rq[coords] = out
    assert rq["projection"][1] < rq["projection"][0] / 3.0
    assert rq["normal"][1] < rq["normal"][0] / 10.0
    assert rq["normal"][1] < 1e-2 * rq["projection"][1]


def test_neighborhoods_grow_to_minimum():
    V, F = grid(6, 6)
    N = vertex_neighborhoods(len(V), F)
    size = np.diff(N.indptr) - 1
    assert size.min() >= HLLE_MIN_NEIGHBORS
    assert np.all(N.diagonal())
    # An interior vertex of this regular triangulation has 6 one-ring and 18 two-ring vertices.
    centre = 3 * 7 + 3
    assert size[centre] == 18
    # Tiny mesh: one triangle, the neighbourhood is the whole triangle.
    N1 = vertex_neighborhoods(3, np.array([[0, 1, 2]]))
    assert N1.toarray().all()


def test_tiny_charts_stay_affine_exact():
    """Under-determined fits (fewer than 6 neighbours) still annihilate affine functions."""
    th = np.linspace(0.0, 2.0, 4)
    V = np.r_[[[0.0, 0.0, 0.0]], np.c_[np.cos(th), np.sin(th), 0.1 * np.ones(4)]]
    F = np.array([[0, 1, 2], [0, 2, 3], [0, 3, 4]])
    for K in (hlle_energy(V, F), curved_hessian_energy(V, F)):
        assert np.isfinite(K.toarray()).all()
        assert sla.eigvalsh(K.toarray())[0] >= -1e-10 * max(1.0, abs(K).max())
    Vp = np.c_[V[:, :2], np.zeros(5)]  # the same fan, flat
    K = hlle_energy(Vp, F)
    assert np.abs(K @ Vp[:, 0]).max() < 1e-10 * max(1.0, abs(K).max())


def test_large_chart_builds(tmp_path):
    """~100k triangles assemble (vectorised, no per-vertex Python loop)."""
    V, F = grid(250, 200)
    V[:, 2] = 0.1 * np.sin(4 * V[:, 0])
    K = hlle_energy(V, F)
    assert K.shape == (len(V), len(V))
    assert np.abs(K @ np.ones(len(V))).max() < 1e-8 * abs(K).max()


def test_bad_input_raises():
    V, F = grid(2, 2)
    with pytest.raises(MeshError, match="coords"):
        hlle_energy(V, F, coords="geodesic")
    with pytest.raises(MeshError, match="area"):
        hlle_energy(V, F, area="cotan")
    with pytest.raises(MeshError, match="shape"):
        hlle_energy(V[:, :2], F)
    with pytest.raises(MeshError, match="outside"):
        hlle_energy(V, F + 50)
    with pytest.raises(MeshError, match="energy"):
        hessian_energy(V, F, "biharmonic")
    with pytest.raises(MeshError):
        curved_hessian_energy(V, F - 10)
