"""Tests of igl_heatseg.surfaces.fit: analytic samples of every kind (exact, noisy, small
patches, rigid motions and scales), kind selection, degenerate input, noise level and
tolerance on tessellated meshes, and the Surface distance / projection round trip."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from igl_heatseg.errors import MeshError
from igl_heatseg.surfaces.fit import (
    face_residuals,
    face_samples,
    fit_cone,
    fit_cylinder,
    fit_plane,
    fit_sphere,
    fit_surface,
    fit_tolerance,
    fit_torus,
    noise_level,
    surface_residual,
    within_tolerance,
)
from igl_heatseg.surfaces.model import ANALYTIC_KINDS, SURFACE_KINDS, Surface

# Derandomized: the same bounded examples on every run (CI stays reproducible). The thresholds
# were also checked on about 2,000 other seeded cases outside the suite.
EXAMPLES = settings(max_examples=12, deadline=None, derandomize=True)


# ----------------------------------------------------------------------------- samplers
# Each returns points P and unit outward normals N of a patch in canonical position
# (axis z, centre / apex at the origin), from a parameter grid with jitter.


def _grid(rng, n, lo0, hi0, lo1, hi1):
    a = rng.uniform(lo0, hi0, n)
    b = rng.uniform(lo1, hi1, n)
    return a, b


def plane_patch(rng, n=400, size=1.0):
    x, y = _grid(rng, n, -size, size, -size, size)
    return np.c_[x, y, 0 * x], np.tile([0.0, 0.0, 1.0], (n, 1))


def cylinder_patch(rng, radius=1.0, arc=2 * np.pi, height=2.0, n=400):
    t, z = _grid(rng, n, 0, arc, 0, height)
    U = np.c_[np.cos(t), np.sin(t), 0 * t]
    return radius * U + np.c_[0 * t, 0 * t, z], U


def cone_patch(rng, half_angle=0.4, arc=2 * np.pi, s0=1.0, s1=2.0, n=400):
    """Points at generatrix length s in [s0, s1] from the apex."""
    t, s = _grid(rng, n, 0, arc, s0, s1)
    ca, sa = math.cos(half_angle), math.sin(half_angle)
    U = np.c_[np.cos(t), np.sin(t), 0 * t]
    P = s[:, None] * (sa * U + ca * np.array([0, 0, 1.0]))
    return P, ca * U - sa * np.array([0, 0, 1.0])


def sphere_patch(rng, radius=1.0, polar=np.pi, n=400):
    """Cap of polar half-angle ``polar`` around +z (np.pi: the whole sphere)."""
    t, c = _grid(rng, n, 0, 2 * np.pi, math.cos(polar), 1.0)
    s = np.sqrt(1 - c * c)
    U = np.c_[s * np.cos(t), s * np.sin(t), c]
    return radius * U, U


def torus_patch(rng, R=3.0, r=1.0, u_arc=2 * np.pi, v0=0.0, v1=2 * np.pi, n=600):
    u, v = _grid(rng, n, 0, u_arc, v0, v1)
    Nt = np.c_[np.cos(v) * np.cos(u), np.cos(v) * np.sin(u), np.sin(v)]
    return R * np.c_[np.cos(u), np.sin(u), 0 * u] + r * Nt, Nt


def rigid(rng, scale=1.0):
    """Random rotation Q, translation t; maps x -> scale * Q x + t."""
    Q, Rm = np.linalg.qr(rng.normal(size=(3, 3)))
    Q = Q * np.sign(np.diag(Rm))
    if np.linalg.det(Q) < 0:
        Q[:, 0] *= -1
    t = rng.normal(size=3) * 10 * scale
    return Q, t


def move(P, N, Q, t, scale):
    return scale * P @ Q.T + t, N @ Q.T


def parallel(a, b, tol):
    return abs(abs(float(np.dot(a, b))) - 1.0) < tol


def axis_distance(point, axis, q):
    d = q - point
    return np.linalg.norm(d - (d @ axis) * axis)


seeds = st.integers(0, 2**32 - 1)
scales = st.sampled_from([1e-3, 0.1, 1.0, 37.0, 1e3])


# ----------------------------------------------------------------------------- exact recovery


@EXAMPLES
@given(seed=seeds, scale=scales)
def test_plane_exact(seed, scale):
    rng = np.random.default_rng(seed)
    Q, t = rigid(rng, scale)
    P, N = move(*plane_patch(rng), Q, t, scale)
    s = fit_plane(P, -N)
    assert parallel(s.params["normal"], Q[:, 2], 1e-12)
    assert s.params["normal"] @ Q[:, 2] < 0  # oriented like the given normals
    assert s.rms < 1e-9 * scale and s.outward


@EXAMPLES
@given(seed=seeds, scale=scales, outward=st.booleans())
def test_sphere_exact(seed, scale, outward):
    rng = np.random.default_rng(seed)
    Q, t = rigid(rng, scale)
    P, N = move(*sphere_patch(rng, radius=2.0, polar=rng.uniform(0.3, np.pi)), Q, t, scale)
    s = fit_sphere(P, N if outward else -N)
    assert np.allclose(s.params["center"], t, atol=1e-7 * scale)
    assert s.params["radius"] == pytest.approx(2.0 * scale, rel=1e-7)
    assert s.outward == outward and s.max_dev < 1e-7 * scale


@EXAMPLES
@given(seed=seeds, scale=scales)
def test_cylinder_exact(seed, scale):
    rng = np.random.default_rng(seed)
    Q, t = rigid(rng, scale)
    P, N = move(*cylinder_patch(rng, radius=1.5, arc=rng.uniform(0.5, 2 * np.pi)), Q, t, scale)
    s = fit_cylinder(P, -N, w=rng.uniform(0.5, 2.0, len(P)))  # a hole: normals inward
    assert parallel(s.params["axis"], Q[:, 2], 1e-9)
    assert axis_distance(s.params["point"], s.params["axis"], t) < 1e-7 * scale
    assert s.params["radius"] == pytest.approx(1.5 * scale, rel=1e-7)
    assert not s.outward and s.rms < 1e-7 * scale


@EXAMPLES
@given(seed=seeds, scale=scales, half_angle=st.floats(0.1, 1.3))
def test_cone_exact(seed, scale, half_angle):
    rng = np.random.default_rng(seed)
    Q, t = rigid(rng, scale)
    P, N = move(*cone_patch(rng, half_angle, arc=rng.uniform(2.0, 2 * np.pi)), Q, t, scale)
    s = fit_cone(P, N)
    assert np.allclose(s.params["apex"], t, atol=1e-6 * scale)
    assert s.params["axis"] @ Q[:, 2] == pytest.approx(1.0, abs=1e-9)
    assert s.params["half_angle"] == pytest.approx(half_angle, abs=1e-7)
    assert s.outward and s.rms < 1e-7 * scale


@EXAMPLES
@given(seed=seeds, scale=scales)
def test_torus_exact(seed, scale):
    rng = np.random.default_rng(seed)
    Q, t = rigid(rng, scale)
    P, N = move(*torus_patch(rng, R=3.0, r=0.8), Q, t, scale)
    s = fit_torus(P, N)
    assert np.allclose(s.params["center"], t, atol=1e-7 * scale)
    assert parallel(s.params["axis"], Q[:, 2], 1e-9)
    assert s.params["major_radius"] == pytest.approx(3.0 * scale, rel=1e-7)
    assert s.params["minor_radius"] == pytest.approx(0.8 * scale, rel=1e-7)
    assert s.outward and s.rms < 1e-7 * scale


# ----------------------------------------------------------------------------- noise, patches


def noisy(rng, P, N, sigma, normal_sigma=0.02):
    """Gaussian noise of std sigma on the points, and on the normals (renormalised)."""
    Nn = N + normal_sigma * rng.normal(size=N.shape)
    return P + sigma * rng.normal(size=P.shape), Nn / np.linalg.norm(Nn, axis=1)[:, None]


@EXAMPLES
@given(seed=seeds, scale=scales)
def test_noisy_patches_recover_parameters(seed, scale):
    """Small patches with noise 1e-3 (relative): a 30-degree cylinder wedge, a fillet strip
    (a quarter of a torus tube over 90 degrees), a narrow cone frustum band, a sphere cap."""
    rng = np.random.default_rng(seed)
    Q, t = rigid(rng, scale)
    sig = 1e-3 * scale

    P, N = noisy(rng, *move(*cylinder_patch(rng, 5.0, math.radians(30), 1.0), Q, t, scale), sig)
    s = fit_cylinder(P, N)
    assert s.params["radius"] == pytest.approx(5 * scale, rel=0.02)
    assert parallel(s.params["axis"], Q[:, 2], 1e-4)

    P, N = noisy(rng, *move(*torus_patch(rng, 10.0, 1.0, np.pi / 2, 0, np.pi / 2), Q, t, scale),
                 sig)
    s = fit_torus(P, N)
    assert s.params["major_radius"] == pytest.approx(10 * scale, rel=0.01)
    assert s.params["minor_radius"] == pytest.approx(scale, rel=0.01)

    P, N = noisy(rng, *move(*cone_patch(rng, 0.5, 2 * np.pi, 1.0, 1.1), Q, t, scale), sig)
    s = fit_cone(P, N)
    assert s.params["half_angle"] == pytest.approx(0.5, abs=0.01)
    assert np.linalg.norm(s.params["apex"] - t) < 0.03 * scale

    P, N = noisy(rng, *move(*sphere_patch(rng, 3.0, 0.5), Q, t, scale), sig)
    s = fit_sphere(P, N)
    assert s.params["radius"] == pytest.approx(3 * scale, rel=0.01)
    for s in (fit_plane(P, N), fit_cylinder(P, N), fit_cone(P, N), fit_torus(P, N)):
        assert s is None or (math.isfinite(s.rms) and s.rms > 0)


# ----------------------------------------------------------------------------- kind selection

CASES = {
    "plane": lambda rng: plane_patch(rng),
    "cylinder": lambda rng: cylinder_patch(rng, 2.0, math.radians(60), 2.0),
    "cone": lambda rng: cone_patch(rng, 0.3, math.radians(120), 1.0, 3.0),
    "sphere": lambda rng: sphere_patch(rng, 2.0, 0.8),
    "torus": lambda rng: torus_patch(rng, 6.0, 1.0, math.radians(60), 0, np.pi / 2),
}


@settings(max_examples=6, deadline=None, derandomize=True)
@given(seed=seeds, scale=scales)
@pytest.mark.parametrize("kind", list(CASES))
def test_fit_surface_chooses_the_kind(kind, seed, scale):
    """Noise sigma and tol = 3 sigma: each kind is chosen as itself (a plane not a sphere, a
    cylinder not a cone, a fillet band a torus, not freeform), and params come back."""
    rng = np.random.default_rng(seed)
    Q, t = rigid(rng, scale)
    sig = 1e-3 * scale
    P, N = noisy(rng, *move(*CASES[kind](rng), Q, t, scale), sig)
    s = fit_surface(P, N, w=rng.uniform(0.5, 1.5, len(P)), tol=3 * sig)
    assert s.kind == kind
    assert s.rms < 1.5 * sig and within_tolerance(s, P, 3 * sig)


def test_fit_surface_freeform_bump():
    """A plane with a Gaussian bump is no analytic kind."""
    rng = np.random.default_rng(3)
    x, y = rng.uniform(-1, 1, (2, 2000))
    z = 0.05 * np.exp(-(x**2 + y**2) / 0.1)
    gx, gy = -2 * x / 0.1 * z, -2 * y / 0.1 * z
    N = np.c_[-gx, -gy, np.ones_like(x)]
    N /= np.linalg.norm(N, axis=1)[:, None]
    s = fit_surface(np.c_[x, y, z], N, tol=1e-3)
    assert s.kind == "freeform"
    assert s.rms > 1e-3 and math.isfinite(s.max_dev)
    assert s.to_dict()["type"] == "freeform"


def test_fit_surface_rejects_surfaces_the_normals_contradict():
    """Points on a cylinder whose normals run along its axis (a stack of flat rings): no kind
    fits both, whatever the distances."""
    from igl_heatseg.surfaces import select as F

    rng = np.random.default_rng(4)
    P, N_true = cylinder_patch(rng, 1.0, 2 * np.pi, 2.0)
    N = np.tile([0.0, 0.0, 1.0], (len(P), 1))
    s = fit_cylinder(P, N_true)
    assert s.rms < 1e-9  # the distances alone are perfect
    w = np.full(len(P), 1.0 / len(P))
    assert F._normal_agreement(s, P, N, w) < 1e-9
    assert F._normal_agreement(s, P, N_true, w) == pytest.approx(1.0)
    assert fit_surface(P, N, tol=1e-3).kind == "freeform"
    assert fit_surface(P, N_true, tol=1e-3).kind == "cylinder"


def test_fit_surface_single_kind_and_errors():
    rng = np.random.default_rng(0)
    P, N = cylinder_patch(rng, 1.0, np.pi, 1.0)
    assert fit_surface(P, N, tol=1e-6, kinds=("cylinder",)).kind == "cylinder"
    assert fit_surface(P, N, tol=1e-6, kinds=("plane",)).kind == "freeform"
    assert fit_surface(P, N).kind == "cylinder"  # default tolerance: relative to the spread
    with pytest.raises(MeshError, match="kinds"):
        fit_surface(P, N, tol=1e-3, kinds=("cube",))
    with pytest.raises(MeshError, match="tol"):
        fit_surface(P, N, tol=-1.0)
    with pytest.raises(MeshError, match=r"P must have shape \(p, 3\), got \(5, 2\)"):
        fit_plane(np.zeros((5, 2)))
    with pytest.raises(MeshError, match="N must have the shape"):
        fit_cylinder(P, N[:-1])
    with pytest.raises(MeshError, match="N is required"):
        fit_cone(P, None)
    with pytest.raises(MeshError, match="w"):
        fit_sphere(P, N, w=-np.ones(len(P)))
    with pytest.raises(MeshError, match="non-finite"):
        fit_plane(np.full((4, 3), np.nan))


# ----------------------------------------------------------------------------- degeneracies


def _finite(s):
    if s is None:
        return True
    vals = [np.asarray(v, dtype=float) for v in s.params.values()]
    return all(np.all(np.isfinite(v)) for v in vals) and math.isfinite(s.rms)


def test_degenerate_inputs_stay_finite():
    """Each fit on data of a simpler (or no) kind returns None or a finite surface."""
    rng = np.random.default_rng(1)
    datasets = [
        plane_patch(rng),  # planar: sphere/cylinder/cone/torus do not apply
        cylinder_patch(rng, 1.0, np.pi, 2.0),  # cone of zero angle, torus of infinite radius
        sphere_patch(rng, 1e7, 1e-7),  # a sphere so large it is a plane
        cylinder_patch(rng, 1e7, 1e-7, 1.0),  # same for a cylinder
        cone_patch(rng, 1e-7, np.pi, 1e7, 1e7 + 2),  # apex 1e7 away: a cylinder of radius 1
        torus_patch(rng, 1e8, 1.0, 1e-8, 0, np.pi),  # a torus so wide it is a cylinder
        (np.c_[np.linspace(0, 1, 20), np.zeros((20, 2))], np.tile([0, 0, 1.0], (20, 1))),
        (np.ones((10, 3)), np.tile([0, 0, 1.0], (10, 1))),  # all points equal
        (np.eye(3), np.eye(3)),  # too few points
    ]
    for P, N in datasets:
        for fit in (fit_plane, fit_sphere, fit_cylinder, fit_cone, fit_torus):
            assert _finite(fit(P, N)), fit.__name__
        s = fit_surface(P, N, tol=1e-6)
        assert s.kind in SURFACE_KINDS
    P, N = plane_patch(rng)
    assert fit_sphere(P, N) is None and fit_cylinder(P, N) is None
    P, N = cylinder_patch(rng, 1.0, np.pi, 2.0)
    assert fit_cone(P, N) is None and fit_torus(P, N) is None
    assert fit_surface(*sphere_patch(rng, 1e7, 1e-7), tol=1e-6).kind == "plane"
    assert fit_surface(*cone_patch(rng, 1e-7, np.pi, 1e7, 1e7 + 2), tol=1e-6).kind == "cylinder"
    assert fit_surface(*torus_patch(rng, 1e8, 1.0, 1e-8, 0, np.pi), tol=1e-6).kind == "cylinder"


def test_zero_weights_are_ignored():
    rng = np.random.default_rng(2)
    P, N = sphere_patch(rng, 1.0, 1.0)
    P[:50] += 5.0  # outliers with zero weight
    w = np.r_[np.zeros(50), np.ones(len(P) - 50)]
    s = fit_sphere(P, N, w=w)
    assert s.params["radius"] == pytest.approx(1.0, rel=1e-7) and s.max_dev < 1e-7
    assert s.area == pytest.approx(len(P) - 50)


# ----------------------------------------------------------------------------- meshes


def periodic_grid(nu, nv, close_v):
    """Triangles of an nu x nv vertex grid, periodic in u (and in v when close_v)."""
    i, j = np.meshgrid(np.arange(nu), np.arange(nv if close_v else nv - 1), indexing="ij")

    def idx(a, b):
        return (a % nu) * nv + (b % nv)

    a, b, c, d = idx(i, j), idx(i + 1, j), idx(i + 1, j + 1), idx(i, j + 1)
    return np.r_[np.c_[a.ravel(), b.ravel(), c.ravel()], np.c_[a.ravel(), c.ravel(), d.ravel()]]


def cylinder_mesh(n_around, n_height, radius=1.0, height=2.0):
    """Open cylinder along z, outward faces."""
    t = 2 * np.pi * np.arange(n_around) / n_around
    T, Z = np.meshgrid(t, np.linspace(0, height, n_height + 1), indexing="ij")
    V = np.c_[radius * np.cos(T.ravel()), radius * np.sin(T.ravel()), Z.ravel()]
    return V, periodic_grid(n_around, n_height + 1, False)


def torus_mesh(nu, nv, R=3.0, r=1.0):
    U, W = np.meshgrid(2 * np.pi * np.arange(nu) / nu, 2 * np.pi * np.arange(nv) / nv,
                       indexing="ij")
    U, W = U.ravel(), W.ravel()
    V = np.c_[(R + r * np.cos(W)) * np.cos(U), (R + r * np.cos(W)) * np.sin(U), r * np.sin(W)]
    return V, periodic_grid(nu, nv, True)


def folded_grid(n=10):
    """Unit square grid in z=0 whose half x > 0.5 is folded up to the wall x = 0.5 (a 90-degree
    crease): returns V, F and the flat half's faces."""
    x, y = np.meshgrid(np.linspace(0, 1, n + 1), np.linspace(0, 1, n + 1), indexing="ij")
    x, y = x.ravel(), y.ravel()
    V = np.c_[np.minimum(x, 0.5), y, np.maximum(x - 0.5, 0.0)]
    i = np.arange((n + 1) * (n + 1)).reshape(n + 1, n + 1)[:-1, :-1].ravel()
    F = np.r_[np.c_[i, i + n + 1, i + n + 2], np.c_[i, i + n + 2, i + 1]]
    flat = np.flatnonzero(V[F].mean(axis=1)[:, 2] < 1e-12)
    return V, F, flat


def with_normal_noise(V, F, sigma, seed=0):
    import igl

    VN = igl.per_vertex_normals(V, F.astype(np.int64))
    return V + sigma * np.random.default_rng(seed).normal(size=(len(V), 1)) * VN


def test_noise_level_clean_meshes_near_zero():
    """Vertices exactly on the surface: the facets' chord error is not noise."""
    for V, F, bound in [
        (*cylinder_mesh(12, 8), 1e-9),  # 30-degree facets: still exactly 0
        (*cylinder_mesh(64, 16), 1e-9),
        (*folded_grid()[:2], 1e-9),  # planes and a crease (a minority of vertices)
        (*torus_mesh(60, 24), 0.02),  # doubly curved: O(h^3) left by the 1-ring quadric
    ]:
        h = np.mean(np.linalg.norm(V[F[:, 0]] - V[F[:, 1]], axis=1))
        assert noise_level(V, F) < bound * h


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_a_clean_curved_mesh_without_coplanar_faces_is_an_exact_tessellation(seed):
    """A part that is nearly all curved, densely and irregularly tessellated, has too few
    coplanar face pairs for the first test of ``exact_tessellation`` (f24
    saddle_boss_s24004_irregular_n0: 4.5 % of its edges, and refined as a noisy mesh its big
    cylinder stayed in 6 segments); its noise level, 0 but for round-off, says it is exact.
    Noise of 0.05 edge lengths (the least in the generated sets) is not."""
    import igl

    from igl_heatseg.surfaces.tolerance import exact_tessellation

    V, F = igl.loop(*igl.icosahedron(), 3)
    rng = np.random.default_rng(seed)
    V = V + rng.normal(scale=0.3 * igl.avg_edge_length(V, F), size=V.shape)  # irregular
    V /= np.linalg.norm(V, axis=1, keepdims=True)                            # on the sphere
    h = igl.avg_edge_length(V, F)
    FN = igl.per_face_normals(V, F, np.zeros(3))
    TT = igl.triangle_triangle_adjacency(F)[0]
    assert (np.einsum("fj,fkj->fk", FN, FN[TT]) > 1 - 1e-9).mean() < 0.01  # no coplanar pairs
    assert exact_tessellation(V, F)
    assert not exact_tessellation(with_normal_noise(V, F, 0.05 * h, seed), F)


@pytest.mark.parametrize("rel_sigma", [0.01, 0.05])
@pytest.mark.parametrize("mesh", ["cylinder", "torus"])
def test_noise_level_measures_normal_noise(mesh, rel_sigma):
    V, F = cylinder_mesh(64, 24) if mesh == "cylinder" else torus_mesh(90, 36)
    h = np.mean(np.linalg.norm(V[F[:, 0]] - V[F[:, 1]], axis=1))
    sigma = rel_sigma * h
    est = noise_level(with_normal_noise(V, F, sigma), F)
    assert 0.7 * sigma < est < 1.4 * sigma


def test_tolerance_accepts_a_coarse_cylinder_and_is_scale_invariant():
    """12 facets per circle: face centroids r (1 - cos 15deg) inside; still a cylinder."""
    V, F = cylinder_mesh(12, 8, radius=2.0, height=3.0)
    tol = fit_tolerance(V, F)
    chord = 2.0 * (1 - math.cos(math.pi / 12))
    assert chord < tol < 1.2 * chord
    P, N, w = face_samples(V, F, np.arange(len(F)))
    s = fit_surface(P, N, w, tol=tol)
    assert s.kind == "cylinder" and abs(s.params["radius"] - 2.0) < chord
    assert np.all(face_residuals(V, F, np.arange(len(F)), s) <= 3.0 * tol)
    for k in (1e-3, 1e3):
        Vk = k * V + [5.0, -7.0, 1.0]
        assert fit_tolerance(Vk, F) == pytest.approx(k * tol, rel=1e-9)
        assert fit_surface(*face_samples(Vk, F, np.arange(len(F))), tol=k * tol).kind == "cylinder"


def test_tolerance_per_segment_chord_error():
    """A coarse small hole (12 facets) beside a finely tessellated large cylinder: the mesh's
    chord error is the fine one's; the hole's own tolerance covers its coarse facets."""
    V1, F1 = cylinder_mesh(240, 8, radius=5.0, height=2.0)
    V2, F2 = cylinder_mesh(12, 8, radius=1.0, height=2.0)
    V, F = np.r_[V1, V2 + [20.0, 0, 0]], np.r_[F1, F2 + len(V1)]
    hole = np.arange(len(F1), len(F))
    chord = 1.0 - math.cos(math.pi / 12)
    assert fit_tolerance(V, F) < 0.5 * chord
    tol = fit_tolerance(V, F, noise=noise_level(V, F), faces=hole)
    assert chord < tol < 1.2 * chord
    assert fit_surface(*face_samples(V, F, hole), tol=tol).kind == "cylinder"


def test_tolerance_covers_noise():
    V, F = torus_mesh(90, 36)
    h = np.mean(np.linalg.norm(V[F[:, 0]] - V[F[:, 1]], axis=1))
    Vn = with_normal_noise(V, F, 0.03 * h)
    tol = fit_tolerance(Vn, F)
    assert 2.0 * 0.03 * h < tol < 4.0 * 0.03 * h
    assert fit_surface(*face_samples(Vn, F, np.arange(len(F))), tol=tol).kind == "torus"
    assert fit_tolerance(Vn, F, noise=0.0) < tol


def test_face_samples_of_a_segment():
    V, F, flat = folded_grid()
    P, N, w = face_samples(V, F, flat)
    verts = np.unique(F[flat])
    assert len(P) == len(verts) + len(flat)
    assert w.sum() == pytest.approx(0.5) and np.all(w > 0)  # the flat half's area
    assert np.allclose(N, [0, 0, 1])  # crease vertices: normals of the segment's faces only
    mask = np.zeros(len(F), bool)
    mask[flat] = True
    assert np.array_equal(face_samples(V, F, mask)[0], P)
    s = fit_surface(P, N, w, tol=1e-6)
    assert s.kind == "plane" and s.area == pytest.approx(0.5)
    assert np.all(face_residuals(V, F, flat, s) < 1e-12)
    r = face_residuals(V, F, np.arange(len(F)), s)
    assert r.shape == (len(F),) and r.max() == pytest.approx(0.5)
    with pytest.raises(MeshError, match="faces"):
        face_samples(V, F, [len(F)])
    with pytest.raises(MeshError, match="F"):
        face_samples(V, F + len(V), flat)
    with pytest.raises(MeshError, match="F must be"):
        noise_level(V, F[:, :2])


# ----------------------------------------------------------------------------- Surface model


def surface_of(kind, rng):
    a = rng.normal(size=3)
    a /= np.linalg.norm(a)
    c = rng.normal(size=3)
    return {
        "plane": Surface("plane", {"point": c, "normal": a}),
        "cylinder": Surface("cylinder", {"point": c, "axis": a, "radius": 1.3}),
        "cone": Surface("cone", {"apex": c, "axis": a, "half_angle": 0.6}),
        "sphere": Surface("sphere", {"center": c, "radius": 0.7}),
        "torus": Surface("torus", {"center": c, "axis": a, "major_radius": 2.0,
                                   "minor_radius": 0.5}),
    }[kind]


@EXAMPLES
@given(seed=seeds)
@pytest.mark.parametrize("kind", ANALYTIC_KINDS)
def test_distance_project_round_trip(kind, seed):
    """project then distance = 0; |distance| = |P - project(P)|; normals = gradient of
    distance (central differences) wherever the distance is smooth."""
    rng = np.random.default_rng(seed)
    s = surface_of(kind, rng)
    P = rng.normal(size=(200, 3)) * 2.0
    X = s.project(P)
    d = s.distance(P)
    assert np.allclose(s.distance(X), 0.0, atol=1e-12)
    assert np.allclose(np.abs(d), np.linalg.norm(P - X, axis=1), atol=1e-12)
    G = s.normals(P)
    assert np.allclose(np.linalg.norm(G, axis=1), 1.0)
    assert np.allclose(P - X, d[:, None] * G, atol=1e-9)
    e = 1e-6
    fd = np.stack([(s.distance(P + e * u) - s.distance(P - e * u)) / (2 * e) for u in np.eye(3)],
                  axis=1)
    smooth = np.all(np.abs(fd - G) < 1e-4, axis=1)
    assert smooth.mean() > 0.9  # off the axis / apex / medial set
    rms, dev = surface_residual(s, P)
    assert rms == pytest.approx(np.sqrt(np.mean(d * d))) and dev == pytest.approx(np.abs(d).max())


SMALL = {
    "cylinder": lambda rng: cylinder_patch(rng, 5.0, math.radians(30), 1.0),  # 30-deg wedge
    "torus": lambda rng: torus_patch(rng, 10.0, 1.0, np.pi / 2, 0, np.pi / 2),  # convex fillet
    "torus ": lambda rng: torus_patch(rng, 4.0, 1.0, np.pi / 3, np.pi / 2, np.pi),  # concave
    "torus  ": lambda rng: torus_patch(rng, 10.0, 1.0, np.pi / 12, 0, np.pi / 2),  # 15-deg arc
    "cone": lambda rng: cone_patch(rng, 0.5, 2 * np.pi, 1.0, 1.1),  # narrow frustum band
    "cone ": lambda rng: cone_patch(rng, 0.3, np.pi / 3, 1.0, 2.0),  # 60-degree wedge
    "sphere": lambda rng: sphere_patch(rng, 3.0, 0.3),  # small cap
}


@settings(max_examples=4, deadline=None, derandomize=True)
@given(seed=seeds, scale=scales)
@pytest.mark.parametrize("kind", list(SMALL))
def test_small_patches_with_noisy_normals(kind, seed, scale):
    """Normals off by ~6 degrees (0.1 rad per component, like face normals of a noisy scan):
    the seeds still lead to the right kind (the torus seed from tube centres, not only from
    the Pluecker axis, whose lever arm is the major radius)."""
    rng = np.random.default_rng(seed)
    Q, t = rigid(rng, scale)
    sig = 1e-3 * scale
    P, N = noisy(rng, *move(*SMALL[kind](rng), Q, t, scale), sig, normal_sigma=0.1)
    assert fit_surface(P, N, tol=3 * sig).kind == kind.strip()


@settings(max_examples=25, deadline=None, derandomize=True)
@given(seed=seeds, p=st.integers(1, 60), spread=st.sampled_from([1e-9, 1e-3, 1.0, 1e6]),
       flat=st.sampled_from([0, 1, 2, 3]))
def test_random_input_never_raises_or_gives_nan(seed, p, spread, flat):
    """Arbitrary clouds (flattened to planes, lines or points) and normals: each fit returns
    None or finite parameters and residuals; fit_surface always returns a Surface."""
    rng = np.random.default_rng(seed)
    P = rng.normal(size=(p, 3)) * spread + rng.normal(size=3) * 1e3
    P[:, :flat] = P[0, :flat]
    N = rng.normal(size=(p, 3))
    N /= np.linalg.norm(N, axis=1)[:, None]
    w = rng.uniform(0, 1, p) if seed % 2 else None
    for fit in (fit_plane, fit_sphere, fit_cylinder, fit_cone, fit_torus):
        s = fit(P, N, w)
        assert _finite(s) and (s is None or math.isfinite(s.max_dev)), fit.__name__
    assert fit_surface(P, N, w, tol=1e-3 * spread).kind in SURFACE_KINDS


def test_analytic_jacobians_match_central_differences():
    """The Levenberg-Marquardt Jacobians of every kind, at generic parameters."""
    from igl_heatseg.surfaces import primitives as F

    rng = np.random.default_rng(0)
    X, sw = rng.normal(size=(40, 3)), rng.uniform(0.5, 1.0, 40)
    a0 = F._unit(rng.normal(size=3))
    n0 = F._orth(a0)
    cases = [
        (F._sphere_res(a0), [0.1, -0.2, 0.3, 0.4]),
        (F._cylinder_res(a0, n0)[0], [0.1, -0.2, 0.3, 0.5, 0.4]),
        (F._cylinder_res(a0, n0)[0], [0.05, 0.1, -0.3, 0.2, 1e-9]),  # nearly a plane
        (F._cone_res(a0), [0.1, -0.2, 0.3, 0.2, 1.5, 0.4]),
        (F._torus_res(a0, np.array([0.3, -0.2, 0.1]), 3.0)[0],
         [0.1, -0.2, 0.3, 0.2, 0.1, 3.2, 1.0]),
    ]
    for make_res, t in cases:
        res, t = make_res(X, sw), np.array(t)
        r, J = res(t, True)
        assert np.array_equal(r, res(t))
        e = 1e-6
        Jfd = np.stack([(res(t + e * u) - res(t - e * u)) / (2 * e) for u in np.eye(len(t))], 1)
        assert np.abs(J - Jfd).max() < 1e-7 * np.abs(Jfd).max()


def test_abc_cad_patches_get_their_brep_types(data_dir):
    """ABC model 00007974_5 (15,702 faces, exact B-Rep face labels: 14 planes, 10 cylinders):
    with the mesh's own tolerance each patch gets its B-Rep type, but patch 22, a thin round
    tessellated by two strips turning 141 degrees (no fit can tell it from a crease)."""
    import igl

    V, F = igl.read_triangle_mesh(str(data_dir / "abc_00007974_5.ply"))
    V, F = V.astype(np.float64), F.astype(np.int64)
    labels = np.loadtxt(data_dir / "abc_00007974_5.facelabels.txt", dtype=np.int64)
    types = dict(line.split() for line in open(data_dir / "abc_00007974_5.surface_types.txt"))
    noise = noise_level(V, F)
    h = np.mean(np.linalg.norm(V[F[:, 0]] - V[F[:, 1]], axis=1))
    assert noise < 1e-6 * h  # exact CAD tessellation
    tol = fit_tolerance(V, F, noise=noise)
    wrong, wrong_seg = set(), set()
    for k in np.unique(labels):
        faces = np.flatnonzero(labels == k)
        P, N, w = face_samples(V, F, faces)
        if fit_surface(P, N, w, tol=tol).kind != types[str(k)].lower():
            wrong.add(int(k))
        tol_k = fit_tolerance(V, F, noise=noise, faces=faces)
        if fit_surface(P, N, w, tol=tol_k).kind != types[str(k)].lower():
            wrong_seg.add(int(k))
    assert wrong <= {22} and wrong_seg <= {22}


SCAN = Path(__file__).resolve().parents[2] / "shared" / "data" / "scan" / "block_noisy.obj"


@pytest.mark.skipif(not SCAN.exists(), reason="shared scan mesh not present")
def test_noise_level_of_a_noisy_scan_against_its_clean_original(data_dir):
    """block_noisy.obj is block.ply with noisy vertices (same faces): the estimate matches the
    true normal component of the displacements, and the clean block measures ~0."""
    import igl

    V0, F0 = igl.read_triangle_mesh(str(data_dir / "block.ply"))
    V1, F1 = igl.read_triangle_mesh(str(SCAN))
    F0, F1 = F0.astype(np.int64), F1.astype(np.int64)
    assert np.array_equal(F0, F1)
    VN = igl.per_vertex_normals(V0, F0)
    true = np.einsum("ij,ij->i", V1 - V0, VN).std()
    assert noise_level(V1, F1) == pytest.approx(true, rel=0.1)
    assert noise_level(V0, F0) < 1e-3 * true


ABC6 = Path(__file__).resolve().parents[2] / "shared" / "data" / "mechanical" / "abc_00000006_0"


@pytest.mark.skipif(not ABC6.with_suffix(".obj").exists(), reason="shared ABC mesh not present")
def test_abc_cones_and_cylinder_get_their_brep_types():
    """ABC model 00000006_0 (32,664 faces; 8 planes, 6 cones, 1 cylinder): every exact B-Rep
    patch gets its type with the mesh's own tolerance, cones with their 45-degree angle."""
    import igl

    V, F = igl.read_triangle_mesh(str(ABC6.with_suffix(".obj")))
    V, F = V.astype(np.float64), F.astype(np.int64)
    labels = np.loadtxt(f"{ABC6}.facelabels.txt", dtype=np.int64)
    types = dict(line.split() for line in open(f"{ABC6}.surface_types.txt"))
    tol = fit_tolerance(V, F)
    for k in np.unique(labels):
        s = fit_surface(*face_samples(V, F, np.flatnonzero(labels == k)), tol=tol)
        assert s.kind == types[str(k)].lower()
        if s.kind == "cone":
            assert s.params["half_angle"] == pytest.approx(math.pi / 4, abs=0.01)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_fit_faces_tries_curved_kinds_when_a_plane_is_near_only_by_distance(seed):
    """A noisy quarter fillet (radius 5, noise 0.4) is within a tolerance of 1 of a plane by
    its distances alone (RMS ~0.7), but half its faces tilt more than GROW_ANGLE from that
    plane: the plane is refused and the cylinder, next in line, is the fit (not freeform)."""
    from igl_heatseg.surfaces.segment_fit import fit_faces

    t, y = np.meshgrid(np.linspace(0, np.pi / 2, 25), np.linspace(0, 10, 21), indexing="ij")
    W = np.c_[5 * np.cos(t.ravel()), y.ravel(), 5 * np.sin(t.ravel())]
    V = W + np.random.default_rng(seed).normal(scale=0.4, size=W.shape)
    idx = np.arange(V.shape[0]).reshape(t.shape)
    a, b = idx[:-1, :-1].ravel(), idx[1:, :-1].ravel()
    c, d = idx[1:, 1:].ravel(), idx[:-1, 1:].ravel()
    F = np.r_[np.c_[a, b, c], np.c_[a, c, d]].astype(np.int64)
    faces = np.arange(len(F))
    # normals from a smooth copy (the robust pipeline's denoised positions), distances on V
    assert fit_faces(V, F, faces, 1.0, kinds=("plane",), W=W).kind == "freeform"
    s = fit_faces(V, F, faces, 1.0, W=W)
    assert s.kind == "cylinder", s.kind
    assert abs(s.params["radius"] - 5) < 0.5


def test_fit_faces_takes_the_raw_normals_when_the_denoised_ones_tilt_a_narrow_face():
    """A narrow 45-degree chamfer between two wide planes comes out of the bilateral filter
    tilted towards them (tuning plate_s1001_frontal_n0.05: about 30 degrees). Its vertices
    lie on a plane and its own face normals agree with it: a plane, not freeform. The normals
    of a quarter fillet do not agree with a plane either way (the test above)."""
    from igl_heatseg.mesh.geometry import face_normals
    from igl_heatseg.surfaces.segment_fit import fit_faces, normals_agree

    x, y = np.meshgrid(np.linspace(0, 2, 5), np.linspace(0, 20, 21), indexing="ij")
    V = np.c_[x.ravel(), y.ravel(), x.ravel()]  # the chamfer: z = x, 45 degrees
    V += np.random.default_rng(0).normal(scale=0.01, size=V.shape)
    W = V * [1.0, 1.0, 0.27]  # its denoised copy: tilted to 15 degrees
    idx = np.arange(V.shape[0]).reshape(x.shape)
    a, b = idx[:-1, :-1].ravel(), idx[1:, :-1].ravel()
    c, d = idx[1:, 1:].ravel(), idx[:-1, 1:].ravel()
    F = np.r_[np.c_[a, b, c], np.c_[a, c, d]].astype(np.int64)
    faces = np.arange(len(F))
    s = fit_faces(V, F, faces, 0.05, W=W)
    assert s.kind == "plane", s.kind
    FN = face_normals(W, F)
    assert not normals_agree(V, F, FN, faces, s)  # the tilted normals alone refuse it
    assert normals_agree(V, F, FN, faces, s, raw=True)
    # without W the normals come from V: nothing to fall back on, the same answer
    assert fit_faces(V, F, faces, 0.05).kind == "plane"


def _slot_wall(r=4.62, half=23.2, h=9.5, step=math.radians(18.0)):
    """The flat wall of a slot as a coarse CAD export meshes it (two long triangles), with the
    first facet triangle of each round end (one at the bottom, one at the top)."""
    s, c = r * math.sin(step), r * math.cos(step)
    V = np.array([[-half, -r, 0], [half, -r, 0], [half, -r, h], [-half, -r, h],
                  [half + s, -c, h], [-half - s, -c, 0]], dtype=np.float64)
    F = np.array([[0, 1, 2], [0, 2, 3], [1, 4, 2], [0, 5, 3]], dtype=np.int64)
    return V, F


def test_fit_faces_keeps_a_plane_that_all_but_two_slivers_lie_on():
    """The six corners of a slot's wall and of one facet of each round end lie on a sphere
    (radius ~150: it bulges ~1.8 units between the wall's vertices), and an exact
    tessellation's tolerance is too small for the plane the facets leave by 0.2 units. The
    plane explains 96 % of the area: it is the fit, and the two facets are left to the
    boundary moves (seen on a coarse generated bracket: Hausdorff 1.6 % of the diagonal)."""
    from igl_heatseg.surfaces.segment_fit import fit_faces

    V, F = _slot_wall()
    s = fit_faces(V, F, np.arange(4), 1e-3)
    assert s.kind == "plane", s.kind
    assert abs(abs(s.params["normal"][1]) - 1) < 1e-9
    assert s.area == pytest.approx(2 * 46.4 * 9.5 / 2)
    # without the trimming (as merges fit) the sphere through all six corners stays
    assert fit_faces(V, F, np.arange(4), 1e-3, trim=False).kind != "plane"


def test_fit_faces_keeps_a_coarse_half_cylinder_curved():
    """A coarse half cylinder (10 facets): no plane holds 95 % of its area, so the cylinder
    stays."""
    from igl_heatseg.surfaces.segment_fit import fit_faces

    t = np.linspace(0, np.pi, 11)
    ring = np.c_[4 * np.cos(t), 4 * np.sin(t)]
    V = np.r_[np.c_[ring, np.zeros(11)], np.c_[ring, np.full(11, 9.0)]]
    i = np.arange(10)
    F = np.r_[np.c_[i, i + 1, i + 12], np.c_[i, i + 12, i + 11]].astype(np.int64)
    s = fit_faces(V, F, np.arange(len(F)), 1e-3)
    assert s.kind == "cylinder", s.kind
    assert s.params["radius"] == pytest.approx(4.0, rel=1e-6)


def test_fit_of_a_segment_whose_one_face_holds_nearly_all_its_area():
    """A quarter cylinder of small faces and one long sliver along the axis holding 97 % of
    the area (a repaired STL's segment): the least-trimmed step that looks for a simpler
    surface on most of the area keeps no face, and is skipped (it crashed on the repaired
    abc_stl2_00000002_001 in robust mode). Also: the samples of no face are empty floats."""
    from igl_heatseg.surfaces.samples import vertex_samples
    from igl_heatseg.surfaces.segment_fit import fit_faces

    t, z = np.meshgrid(np.linspace(0, np.pi / 2, 9), np.linspace(0, 1, 5))
    V = np.c_[np.cos(t.ravel()), np.sin(t.ravel()), z.ravel()]
    i = np.arange(45).reshape(5, 9)[:-1, :-1].ravel()
    F = np.r_[np.c_[i, i + 1, i + 10], np.c_[i, i + 10, i + 9]]
    V = np.r_[V, [[1, 0, 200], [np.cos(0.6), np.sin(0.6), 100]]]
    F = np.r_[F, [[0, 45, 46]]]
    A = 0.5 * np.linalg.norm(np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]]), axis=1)
    assert A[-1] > 0.95 * A.sum()
    s = fit_faces(V, F, np.arange(len(F)), 1e-6)
    assert s.kind == "cylinder" and s.params["radius"] == pytest.approx(1.0)
    P, N, w = vertex_samples(V, F, np.zeros(0, np.int64))
    assert P.shape == N.shape == (0, 3) and w.shape == (0,)
    assert N.dtype == w.dtype == np.float64


def _noisy_revolved(profile, sigma, seed, rings=14, around=48):
    """A band of a surface of revolution about z, ``(r, z) = profile(t)`` for ``t`` in
    ``[0, 1]``, with Gaussian noise ``sigma`` on every vertex; returns noisy V, F and the clean
    positions (for the normals, as the robust pipeline's denoised copy)."""
    t, ph = np.meshgrid(np.linspace(0, 1, rings), 2 * np.pi * np.arange(around) / around,
                        indexing="ij")
    r, z = profile(t.ravel())
    W = np.c_[r * np.cos(ph.ravel()), r * np.sin(ph.ravel()), z]
    V = W + np.random.default_rng(seed).normal(scale=sigma, size=W.shape)
    idx = np.arange(len(W)).reshape(t.shape)
    nxt = np.roll(idx, -1, axis=1)
    a, b, c, d = idx[:-1].ravel(), idx[1:].ravel(), nxt[1:].ravel(), nxt[:-1].ravel()
    return V, np.r_[np.c_[a, b, c], np.c_[a, c, d]].astype(np.int64), W


@pytest.mark.parametrize("seed", range(3))
@pytest.mark.parametrize("sigma", [0.3, 0.4])
def test_a_noisy_dome_is_a_sphere_though_a_cone_is_within_tolerance(seed, sigma):
    """A spherical cap (radius 20, 5 to 50 degrees from the pole) with noise 0.3-0.4 and a
    tolerance of 2.5 noise levels: a cone is within tolerance (RMS 0.6-0.8 tol) and is tried
    first, but the sphere, with fewer parameters, fits 1.5 times closer. A cone band of the
    same size stays a cone (no sphere is within tolerance of it)."""
    from igl_heatseg.surfaces.segment_fit import fit_faces

    def cap(t):
        a = np.radians(5 + 45 * t)
        return 20 * np.sin(a), 20 * np.cos(a)

    def cone(t):
        a = np.radians(5 + 45 * t)
        return 20 * np.sin(a), -16 * np.sin(a)

    tol = 2.5 * sigma
    V, F, W = _noisy_revolved(cap, sigma, seed)
    faces = np.arange(len(F))
    c = fit_faces(V, F, faces, tol, kinds=("cone",), W=W)
    assert c.kind == "cone" and c.rms <= tol  # the cone alone is within tolerance
    s = fit_faces(V, F, faces, tol, W=W)
    assert s.kind == "sphere" and abs(s.params["radius"] - 20) < 0.5
    assert s.rms * 1.3 <= c.rms
    V, F, W = _noisy_revolved(cone, sigma, seed)
    assert fit_faces(V, F, np.arange(len(F)), tol, W=W).kind == "cone"
