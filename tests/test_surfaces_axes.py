"""Coaxial typing: narrow bands of a turned part typed by the part's own axes."""

from __future__ import annotations

import math

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from igl_heatseg.surfaces.axes import coaxial_surfaces, part_axes, snap_to_axes
from igl_heatseg.surfaces.model import Surface
from igl_heatseg.surfaces.segment_fit import fit_faces


def profile_ring(profile, n=90, noise=0.0, seed=0):
    """A surface of revolution about z through the (r, z) profile points, ``n`` columns,
    normals away from the axis; the faces of band i (between profile points i and i + 1) are
    ``band == i``."""
    P = np.asarray(profile, dtype=np.float64)
    t = 2 * np.pi * np.arange(n) / n
    V = np.vstack([np.c_[r * np.cos(t), r * np.sin(t), np.full(n, z)] for r, z in P])
    j = np.arange(n)
    F = np.vstack([np.r_[np.c_[i * n + j, i * n + (j + 1) % n, (i + 1) * n + j],
                         np.c_[i * n + (j + 1) % n, (i + 1) * n + (j + 1) % n, (i + 1) * n + j]]
                   for i in range(len(P) - 1)]).astype(np.int64)
    band = np.repeat(np.arange(len(P) - 1), 2 * n)
    if noise:
        V = V + np.random.default_rng(seed).normal(scale=noise, size=V.shape)
    return V, F, band


def columns(V, F, n, first, last):
    """Faces whose first corner lies in columns first..last of an ``n``-column ring."""
    col = np.mod(F[:, 0], n)
    return (col >= first) & (col <= last)


def test_profile_ring_is_a_closed_band_mesh():
    V, F, band = profile_ring([(10, 0), (10, 2)], n=12)
    E = np.sort(np.r_[F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]], axis=1)
    _, counts = np.unique(E, axis=0, return_counts=True)
    assert len(F) == 24 and set(counts.tolist()) <= {1, 2} and (counts == 1).sum() == 24


def test_narrow_band_of_a_noisy_cylinder_becomes_coaxial_cylinder():
    n = 90
    V, F, _ = profile_ring([(40, z) for z in np.linspace(0, 4, 9)], n=n, noise=0.03)
    labels = columns(V, F, n, 0, 0).astype(np.int64) ^ 1  # segment 0: a one-column band
    tol = 0.1
    S = [fit_faces(V, F, np.flatnonzero(labels == k), tol) for k in (0, 1)]
    assert S[0].kind == "plane" and S[1].kind == "cylinder"
    S2, n_snapped = snap_to_axes(V, F, labels, S, tol)
    assert n_snapped == 1 and S2[0].kind == "cylinder"
    assert abs(S2[0].params["radius"] - 40) < 0.05
    assert S2[0].rms < S[0].rms and S2[0].outward
    assert S2[1] is S[1]
    assert math.isclose(S2[0].area, S[0].area, rel_tol=1e-9)


def test_cone_band_becomes_coaxial_cone():
    n = 90
    # a cylinder (the axis) and a narrow conical band above it (slope 0.5: half angle 26.6 deg)
    prof = [(30, z) for z in np.linspace(0, 6, 7)] + [(30 + 0.5 * z, 6 + z)
                                                     for z in np.linspace(0.5, 2, 4)]
    V, F, band = profile_ring(prof, n=n, noise=0.02)
    narrow = columns(V, F, n, 0, 1)
    labels = np.where(band < 6, 0, np.where(narrow, 1, 2)).astype(np.int64)
    tol = 0.08
    S = [fit_faces(V, F, np.flatnonzero(labels == k), tol) for k in (0, 1, 2)]
    S[1] = fit_faces(V, F, np.flatnonzero(labels == 1), tol, kinds=("plane",))
    S2, _ = snap_to_axes(V, F, labels, S, tol)
    assert S2[1].kind == "cone"
    assert abs(math.tan(S2[1].params["half_angle"]) - 0.5) < 0.02
    assert S2[1].params["axis"][2] > 0  # opening upwards


def test_a_flat_beside_the_axis_stays_a_plane():
    # a flat face 400 from a z-axis bore: a coaxial cylinder (1 parameter) is within the noise
    # of it, but fits it worse than its plane (3), and the parameter count alone decides nothing
    rng = np.random.default_rng(1)
    x, z = np.meshgrid(np.linspace(-3, 3, 13), np.linspace(0, 4, 9))
    flat = np.c_[x.ravel(), np.full(x.size, 400.0), z.ravel()] + rng.normal(0, 0.02, (x.size, 3))
    Vb, Fb, _ = profile_ring([(5, z) for z in np.linspace(0, 4, 9)], n=60, noise=0.02)
    a = np.arange(13 * 9).reshape(9, 13)
    q0, q1, q2, q3 = a[:-1, :-1].ravel(), a[:-1, 1:].ravel(), a[1:, 1:].ravel(), a[1:, :-1].ravel()
    Ff = np.r_[np.c_[q0, q1, q2], np.c_[q0, q2, q3]] + len(Vb)
    V, F = np.r_[Vb, flat], np.r_[Fb, Ff].astype(np.int64)
    labels = np.r_[np.zeros(len(Fb)), np.ones(len(Ff))].astype(np.int64)
    tol = 0.08
    S = [fit_faces(V, F, np.flatnonzero(labels == k), tol) for k in (0, 1)]
    assert [s.kind for s in S] == ["cylinder", "plane"]
    S2, n_snapped = snap_to_axes(V, F, labels, S, tol)
    assert n_snapped == 0 and S2[1].kind == "plane"


def test_an_exact_end_cap_stays_a_plane():
    n = 48
    V, F, band = profile_ring([(0.5, 0), (10, 0), (10, 3), (10, 6)], n=n)
    labels = np.minimum(band, 1).astype(np.int64)  # the flat annulus, then the cylinder
    tol = 1e-3
    S = [fit_faces(V, F, np.flatnonzero(labels == k), tol) for k in (0, 1)]
    assert [s.kind for s in S] == ["plane", "cylinder"]
    S2, n_snapped = snap_to_axes(V, F, labels, S, tol)
    assert n_snapped == 0 and S2[0].kind == "plane"


def test_part_axes_groups_coaxial_segments_and_skips_small_or_bad_fits():
    z = np.array([0.0, 0, 1])
    x = np.array([1.0, 0, 0])
    V = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [5, 5, 5]])
    F = np.array([[0, 1, 2], [0, 1, 3], [0, 2, 3], [1, 2, 3], [1, 2, 4]])
    S = [Surface("cylinder", {"point": np.zeros(3), "axis": z, "radius": 1.0}, rms=0.0),
         Surface("cone", {"apex": 2 * z, "axis": -z, "half_angle": 0.3}, rms=0.0),
         Surface("cylinder", {"point": np.zeros(3), "axis": x, "radius": 1.0}, rms=0.0),
         Surface("cylinder", {"point": np.zeros(3), "axis": x, "radius": 1.0}, rms=1.0),
         Surface("plane", {"point": np.zeros(3), "normal": z}, rms=0.0)]
    axes = part_axes(V, F, np.arange(5), S, 0.01)
    assert len(axes) == 2  # z (cylinder + cone), x; the bad fit and the plane give none
    dirs = sorted(tuple(np.abs(a).round(6)) for _, a in axes)
    assert dirs == [(0.0, 0.0, 1.0), (1.0, 0.0, 0.0)]


@settings(max_examples=40, deadline=None)
@given(st.floats(0.5, 50.0), st.floats(-2.0, 2.0), st.floats(0.0, 2 * np.pi),
       st.floats(0.2, 1.5), st.integers(0, 10_000))
def test_coaxial_surfaces_recover_exact_cylinders_and_cones(r0, slope, phi, theta, seed):
    rng = np.random.default_rng(seed)
    axis = np.array([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)])
    u = np.cross(axis, [0.0, 0, 1] if abs(axis[2]) < 0.9 else [1.0, 0, 0])
    u /= np.linalg.norm(u)
    v = np.cross(axis, u)
    point = rng.normal(size=3)
    h = rng.uniform(0, 2, 50)
    t = rng.uniform(0, 0.5, 50)
    r = r0 + slope * h
    if np.any(r <= 0.05):
        return
    radial = np.outer(np.cos(t), u) + np.outer(np.sin(t), v)
    P = point + np.outer(h, axis) + r[:, None] * radial
    w = np.full(50, 1 / 50)
    out = coaxial_surfaces(P, radial, w, point, axis)
    angle = math.atan(abs(slope))
    if slope == 0 or angle < math.radians(5) or angle > math.radians(80):
        assert len(out) == 1 or abs(math.tan(out[1].params["half_angle"]) - abs(slope)) < 1e-6
    if abs(slope) < 1e-12:
        assert out[0].rms < 1e-9 * r0 and abs(out[0].params["radius"] - r0) < 1e-9 * r0
    if math.radians(5) <= angle <= math.radians(80):
        cone = out[1]
        assert cone.kind == "cone" and cone.rms < 1e-8 * max(r0, 1)
        assert abs(math.tan(cone.params["half_angle"]) - abs(slope)) < 1e-8
        # the cone opens where the radius grows
        assert np.sign(cone.params["axis"] @ axis) == np.sign(slope)
