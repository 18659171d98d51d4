"""Splitting unexplained segments: the RANSAC regions and their cylinder candidates."""

from __future__ import annotations

import igl
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from meshes import revolved, thread_profile

from igl_heatseg.mesh.geometry import face_normals
from igl_heatseg.surfaces import refine as R
from igl_heatseg.surfaces.split import crease_regions, cylinder_from_normals, ransac_regions
from igl_heatseg.surfaces.tolerance import vertex_tolerance


def hole_in_plane(n=24, r_in=2.0, r_out=5.0, depth=3.0, rings=6, noise=0.0, seed=0):
    """A plane annulus (z = 0, radii r_in..r_out) and the wall of its hole (the cylinder of
    radius r_in below it), one mesh; truth 0 for the wall's faces, 1 for the plane's."""
    t = 2 * np.pi * np.arange(n) / n
    ring = np.c_[np.cos(t), np.sin(t)]
    rows = [np.c_[r_in * ring, np.full(n, z)] for z in np.linspace(-depth, 0, rings + 1)[:-1]]
    rows += [np.c_[r * ring, np.zeros(n)] for r in np.linspace(r_in, r_out, rings + 1)]
    V = np.vstack(rows)
    j = np.arange(n)
    F = np.vstack([np.r_[np.c_[i * n + j, i * n + (j + 1) % n, (i + 1) * n + (j + 1) % n],
                         np.c_[i * n + j, (i + 1) * n + (j + 1) % n, (i + 1) * n + j]]
                   for i in range(len(rows) - 1)]).astype(np.int64)
    truth = (np.arange(len(F)) >= 2 * n * rings).astype(np.int64)
    if noise:
        N = igl.per_vertex_normals(V, F)
        V = V + np.random.default_rng(seed).normal(scale=noise, size=(len(V), 1)) * N
    return V, F, truth


@settings(max_examples=40, deadline=None)
@given(
    st.floats(0.1, 50.0),
    st.floats(-1.0, 1.0), st.floats(0.0, 2 * np.pi),
    st.floats(0.3, 3.0), st.integers(0, 10_000),
)
def test_cylinder_from_normals_recovers_exact_cylinders(r, cz, phi, arc, seed):
    """Points on any cylinder, with its normals, over an arc of 0.3 to 3 radians."""
    rng = np.random.default_rng(seed)
    a = np.array([np.sqrt(1 - cz * cz) * np.cos(phi), np.sqrt(1 - cz * cz) * np.sin(phi), cz])
    u = np.cross(a, [1.0, 0, 0] if abs(a[0]) < 0.9 else [0, 1.0, 0])
    u /= np.linalg.norm(u)
    v = np.cross(a, u)
    t = rng.uniform(0, arc, 12)
    N = np.cos(t)[:, None] * u + np.sin(t)[:, None] * v
    c0 = rng.normal(size=3) * 10
    C = c0 + r * N + rng.uniform(-r, r, 12)[:, None] * a
    s = cylinder_from_normals(C, N * rng.choice([-1, 1], 12)[:, None], 2 * r)
    assert s is not None
    assert abs(abs(s.params["axis"] @ a) - 1) < 1e-9
    assert abs(s.params["radius"] - r) < 1e-7 * max(r, 1)
    assert np.abs(s.distance(C)).max() < 1e-7 * max(r, 1)


def test_cylinder_from_normals_refuses_flat_patches():
    C = np.random.default_rng(0).uniform(size=(10, 3)) * [1, 1, 0]
    N = np.tile([0.0, 0, 1], (10, 1))
    assert cylinder_from_normals(C, N, 1.0) is None


def test_ransac_splits_a_noisy_hole_from_its_plane_where_growth_shatters_it():
    """Two rings of a hole of radius ~20 noise levels fit a plane: region growing shatters the
    wall; RANSAC's cylinder candidates take it whole."""
    V, F, truth = hole_in_plane(noise=0.05)
    tol = vertex_tolerance(V, F)
    TT = igl.triangle_triangle_adjacency(F)[0]
    FN = face_normals(V, F)
    faces = np.arange(len(F))
    grown = R.grow_regions(V, F, faces, tol, FN, TT, None, R.SPLIT_RMS_RATIO_NOISY, True)
    assert np.bincount(grown[truth == 0]).max() < 0.9 * (truth == 0).sum()
    region = ransac_regions(V, F, faces, tol, FN, TT)
    for t in (0, 1):
        share = np.bincount(region[truth == t]).max() / (truth == t).sum()
        assert share >= 0.98
    assert len(np.unique(region[truth == 0][:1])) == 1
    assert region[truth == 0][0] != region[truth == 1][0]
    res = R.refine_segmentation(V, F, np.zeros(len(F), dtype=np.int64), tol)
    assert sorted(s.kind for s in res.surfaces) == ["cylinder", "plane"]


def test_ransac_regions_are_deterministic_and_cover_every_face():
    V, F, _ = hole_in_plane(noise=0.05, seed=3)
    tol = vertex_tolerance(V, F)
    TT = igl.triangle_triangle_adjacency(F)[0]
    FN = face_normals(V, F)
    faces = np.arange(0, len(F))
    a = ransac_regions(V, F, faces, tol, FN, TT)
    b = ransac_regions(V, F, faces, tol, FN, TT)
    assert np.array_equal(a, b)
    assert a.min() == 0 and np.array_equal(np.unique(a), np.arange(a.max() + 1))


def test_fold_weak_keeps_a_piece_its_surface():
    # a hole's wall grown as one piece, and the triangles of the plane along its rim left over
    # by the growth one by one: folded into the wall they made it freeform (a noisy plate's
    # holes, tuning plate_s1001); they stay pieces of their own, the wall keeps its cylinder
    from igl_heatseg.surfaces.segment_fit import fit_faces
    from igl_heatseg.surfaces.split import fold_weak

    V, F, truth = hole_in_plane(noise=0.01, seed=3)
    tol = 0.05
    TT = igl.triangle_triangle_adjacency(F)[0]
    FN = face_normals(V, F)
    wall = np.flatnonzero(truth == 0)
    rim = np.flatnonzero((truth == 1) & (TT >= 0).all(axis=1) &
                         (truth[np.maximum(TT, 0)] == 0).any(axis=1))
    parts = [wall] + [rim[i:i + 1] for i in range(len(rim))]
    fits = [fit_faces(V, F, p, tol, FN=FN) for p in parts]
    assert fits[0].kind == "cylinder"
    out, out_fits = fold_weak(V, F, TT, tol, None, FN, parts, fits)
    assert np.array_equal(np.sort(out[0]), wall) and out_fits[0].kind == "cylinder"
    assert len(out) == 1 + len(rim)


# a thread ridge of a clean bolt: a cone flank, a cylinder crest and a cone flank, each one row
RIDGE = [(10.0, 0.0), (10.9, 0.5), (10.9, 0.8), (10.0, 1.3)]


def test_crease_regions_cut_a_thread_ridge_into_its_three_faces():
    V, F, truth = revolved(RIDGE)  # one row per face: cone, cylinder, cone
    TT = igl.triangle_triangle_adjacency(F)[0]
    region = crease_regions(V, F, np.arange(len(F)), vertex_tolerance(V, F), TT)
    assert len(np.unique(region)) == 3
    assert all(len(np.unique(region[truth == k])) == 1 for k in range(3))


def test_an_exact_thread_ridge_that_growth_shatters_is_split_at_its_creases(data_dir):
    """A ridge of a clean generated bolt (two cone flanks and a cylinder crest, 686 faces, a
    few triangles wide): region growing breaks the flanks into pieces of 8-12 faces that are
    no evidence, and the refinement left it one freeform segment (7 of them on that bolt)."""
    d = np.load(data_dir / "bolt_thread_ridge.npz")
    V, F, truth = d["V"], d["F"], d["truth"]
    TT = igl.triangle_triangle_adjacency(F)[0]
    FN = face_normals(V, F)
    faces = np.arange(len(F))
    tol = 8.2e-4  # the whole bolt's vertex_tolerance (this piece alone reads as noisy)
    assert len(np.unique(R.grow_regions(V, F, faces, tol, FN, TT))) > 3
    parts, fits = R._split(V, F, faces, tol, FN, TT, None, R.SPLIT_RMS_RATIO, True, set())
    assert sorted(f.kind for f in fits) == ["cone", "cone", "cylinder"]
    assert sorted(len(np.unique(truth[p])) for p in parts) == [1, 1, 1]
    assert all(f.rms < 1e-2 * tol for f in fits)


def test_crease_regions_leave_whole_what_a_crease_does_not_cut_into_surfaces():
    # rows of a smooth profile, each exactly a cone, turning by less than a crease (a quarter
    # circle in 6 rows: 15 degrees); the ridge with its crest bent into two cones but one
    # flank bent too (a piece that is no analytic surface); a plane strip folded by 30 degrees
    # with one triangle of its fold line turned (the cut leaves one piece)
    quarter = [(10 + np.sin(a), 1 - np.cos(a)) for a in np.linspace(0, np.pi / 2, 7)]
    V, F, _ = revolved(quarter)
    TT = igl.triangle_triangle_adjacency(F)[0]
    assert (crease_regions(V, F, np.arange(len(F)), vertex_tolerance(V, F), TT) == 0).all()
    V, F, truth = revolved(RIDGE)
    V[F[truth == 0][::7]] += [0, 0, 0.05]  # the first flank off its cone
    TT = igl.triangle_triangle_adjacency(F)[0]
    assert (crease_regions(V, F, np.arange(len(F)), vertex_tolerance(V, F), TT) == 0).all()


TWO_RIDGES = thread_profile(2)

# a shaft (r = 10), a fillet of radius 1 in three facets, and a flange face (z = 1)
FILLET = ([(10.0, z) for z in np.linspace(-3.0, 0.0, 4)]
          + [(11.0 - np.cos(a), np.sin(a)) for a in np.radians([30.0, 60.0, 90.0])]
          + [(r, 1.0) for r in (12.0, 13.0, 14.0)])


def _torus_of(V, F, faces):
    from igl_heatseg.surfaces.samples import vertex_samples
    from igl_heatseg.surfaces.select import fit_surface

    s = fit_surface(*vertex_samples(V, F, faces), tol=1e-6, kinds=("torus",))
    assert s.kind == "torus" and s.rms < 1e-9  # the rows lie on a torus exactly
    return s


def test_a_torus_through_a_ridges_rows_is_no_evidence_but_a_tangent_fillets_is():
    """Any three rows of a surface of revolution lie on a torus, and four of a symmetric
    profile do; a thread ridge's torus (cone, cylinder, cone) meets the next flank at a crease
    twice as sharp as its own, a fillet's torus meets its shaft and flange tangentially."""
    from igl_heatseg.surfaces.profile import profile_rows, torus_evidence
    from igl_heatseg.surfaces.segment_fit import fit_faces

    V, F, seg = revolved(TWO_RIDGES, n=24)
    FN = face_normals(V, F)
    ridge = np.flatnonzero(seg <= 2)
    s = _torus_of(V, F, ridge)
    assert np.bincount(profile_rows(V, F, ridge, s)[1]).tolist() == [24] * 4
    assert not torus_evidence(V, F, ridge, s, FN)
    assert fit_faces(V, F, ridge, 1e-6).kind == "freeform"  # was a torus
    # a flank and its crest: three rows (a torus through any three), next to the valley
    two = np.flatnonzero((seg >= 3) & (seg <= 4))
    assert not torus_evidence(V, F, two, _torus_of(V, F, two), FN)

    V, F, seg = revolved(FILLET, n=24)
    FN = face_normals(V, F)
    fillet = np.flatnonzero((seg >= 3) & (seg <= 5))
    s = _torus_of(V, F, fillet)
    assert torus_evidence(V, F, fillet, s, FN)
    got = fit_faces(V, F, fillet, 1e-6)
    assert got.kind == "torus" and abs(got.params["minor_radius"] - 1.0) < 1e-6
    # noisy rows are not judged (noise 0.05 x the mean edge length, the benchmark's least)
    h = igl.avg_edge_length(V, F)
    Vn = V + np.random.default_rng(0).normal(scale=0.05 * h, size=V.shape)
    assert profile_rows(Vn, F, fillet, s)[1] is None
    assert torus_evidence(Vn, F, fillet, s, face_normals(Vn, F))


@pytest.mark.parametrize("profile", [TWO_RIDGES[:4], TWO_RIDGES], ids=["one ridge", "two ridges"])
def test_crease_regions_split_ridges_of_24_facets_into_their_faces(profile):
    """At 24 facets per turn the facets turn by 15-30 degrees, as much as a ridge's flank
    does against its crest: the valleys are cut by angle, the ridges by their rows
    (:func:`row_regions`); every profile segment is one region, a cone or a cylinder."""
    from igl_heatseg.surfaces.segment_fit import fit_faces

    V, F, truth = revolved(profile, n=24)
    TT = igl.triangle_triangle_adjacency(F)[0]
    tol = vertex_tolerance(V, F)
    region = crease_regions(V, F, np.arange(len(F)), tol, TT)
    assert len(np.unique(region)) == len(profile) - 1
    assert all(len(np.unique(region[truth == k])) == 1 for k in range(len(profile) - 1))
    kinds = [fit_faces(V, F, np.flatnonzero(region == r), tol).kind for r in np.unique(region)]
    assert set(kinds) == {"cone", "cylinder"}


def test_profile_rows_follow_the_profile_across_the_inner_equator_of_the_tube():
    """A concave fillet lies on the inner side of its tube, where the angle around the tube
    passes +-180 degrees: its rows are numbered along the profile all the same (on
    f16 flange_s16008_coarse_n0, rows numbered across the cut made a fillet freeform)."""
    from igl_heatseg.surfaces.model import Surface
    from igl_heatseg.surfaces.profile import profile_rows

    prof = [(11.0 + np.cos(a), np.sin(a)) for a in np.radians([150.0, 170.0, 190.0, 210.0])]
    V, F, seg = revolved(prof, n=24)
    s = Surface("torus", {"center": np.zeros(3), "axis": np.array([0.0, 0, 1]),
                          "major_radius": 11.0, "minor_radius": 1.0})
    verts, row = profile_rows(V, F, np.arange(len(F)), s)
    assert np.array_equal(row, np.repeat(np.arange(4), 24)[verts])
