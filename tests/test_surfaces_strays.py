"""Stray border faces (a triangle standing across its segment's surface) go to their neighbour."""

from __future__ import annotations

import igl
import numpy as np

from igl_heatseg.mesh.geometry import face_normals
from igl_heatseg.surfaces.model import Surface
from igl_heatseg.surfaces.strays import shed_strays
from meshes import cube


def _sides(V, F):
    """Cube side of every face (0..5: +z -z +x -x +y -y) and the six planes."""
    FN = face_normals(V, F)
    axes = np.array([[0, 0, 1], [0, 0, -1], [1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0]], float)
    labels = np.argmax(FN @ axes.T, axis=1)
    fits = {k: Surface("plane", {"point": a, "normal": a}) for k, a in enumerate(axes)}
    return labels, fits, FN


def test_triangles_across_an_edge_go_back_to_their_side():
    V, F = cube(6)
    labels, fits, FN = _sides(V, F)
    truth = labels.copy()
    TT = igl.triangle_triangle_adjacency(F)[0]
    # three +x triangles along the edge with +z labelled +z (a flank on a side plane)
    edge = np.flatnonzero((labels == 2) & (TT >= 0).all(axis=1) &
                          (labels[np.maximum(TT, 0)] == 0).any(axis=1))[:3]
    assert len(edge) == 3
    labels[edge] = 0
    assert shed_strays(V, F, labels, fits, 0.01, TT, FN) == 3
    assert np.array_equal(labels, truth)


def test_a_stray_no_neighbour_takes_stays():
    # the +x side fitted by a plane parallel to +z (a recessed floor's plane): its faces stand
    # across it, and across the +z, -z, +y and -y planes of the segments around them, so no
    # neighbour takes them and nothing moves (before: each went to the neighbour whose face
    # normal was nearest, and made that plane's segment unexplained)
    V, F = cube(6)
    labels, fits, FN = _sides(V, F)
    fits[2] = Surface("plane", {"point": np.array([0.0, 0, -0.5]), "normal": np.array([0., 0, 1])})
    before = labels.copy()
    TT = igl.triangle_triangle_adjacency(F)[0]
    assert shed_strays(V, F, labels, fits, 0.01, TT, FN) == 0
    assert np.array_equal(labels, before)
    # a freeform neighbour takes them: the +z side unfitted, the border row of +x goes to it
    fits[0] = Surface("freeform", {"centroid": np.array([0.0, 0, 1])})
    assert shed_strays(V, F, labels, fits, 0.01, TT, FN) > 0
    assert set(np.unique(before[labels != before]).tolist()) == {2}
    assert set(np.unique(labels[labels != before]).tolist()) == {0}


def test_noise_makes_no_strays():
    # noise of a fifth of an edge (the tolerance as the noise: half of it) tilts the normals,
    # not by 60 degrees: nothing moves
    V, F = cube(6)
    labels, fits, _ = _sides(V, F)
    truth = labels.copy()
    sigma = 0.2 * 2.0 / 6
    V = V + np.random.default_rng(1).normal(0.0, sigma, V.shape)
    TT = igl.triangle_triangle_adjacency(F)[0]
    assert shed_strays(V, F, labels, fits, 0.5 * sigma, TT, face_normals(V, F)) == 0
    assert np.array_equal(labels, truth)


def test_a_segment_of_strays_is_not_emptied():
    V, F = cube(6)
    labels, fits, FN = _sides(V, F)
    TT = igl.triangle_triangle_adjacency(F)[0]
    one = np.flatnonzero(labels == 2)[0]
    labels[one] = 6  # one +x triangle with the +z plane: a stray, but all of its segment
    fits[6] = fits[0]
    assert shed_strays(V, F, labels, fits, 0.01, TT, FN) == 0
    assert labels[one] == 6


def test_a_segment_is_not_cut_apart():
    # the +z and -z sides labelled +z, joined by a strip of +x faces: the strip's faces are
    # strays, but moving them would cut the segment in two, so they stay
    from igl_heatseg.mesh.topology import label_pieces

    V, F = cube(6)
    labels, fits, FN = _sides(V, F)
    TT = igl.triangle_triangle_adjacency(F)[0]
    C = V[F].mean(axis=1)
    strip = np.flatnonzero((labels == 2) & (np.abs(C[:, 1]) < 1.0 / 3))
    labels[strip] = 0
    labels[labels == 1] = 0
    before = labels.copy()
    assert shed_strays(V, F, labels, fits, 0.01, TT, FN) == 0
    assert np.array_equal(labels, before)
    assert len(np.unique(label_pieces(F, labels, TT)[labels == 0])) == 1


def _prism_with_roof(turn_deg: float):
    """A strip of faces: floor (2 big triangles), then two roof facets each turning by
    ``turn_deg`` from the last, as a coarse export of a rounded edge would have."""
    t1, t2 = np.radians(turn_deg), np.radians(2 * turn_deg)
    P = [np.array([0.0, 0.0]), np.array([10.0, 0.0])]
    P.append(P[-1] + np.array([np.cos(t1), np.sin(t1)]))
    P.append(P[-1] + np.array([np.cos(t2), np.sin(t2)]))
    V = np.array([[x, y, z] for z in (0.0, 3.0) for x, y in P])
    n = len(P)
    F = []
    for i in range(n - 1):  # quad (i, i+1) x (bottom, top)
        F += [[i, i + 1, n + i + 1], [i, n + i + 1, n + i]]
    return V, np.array(F, dtype=np.int64)


def test_split_at_creases_small_piece_across_a_crease_becomes_its_own_segment():
    from igl_heatseg.surfaces.strays import split_at_creases

    V, F = _prism_with_roof(60.0)  # 60 degrees per facet: creases
    TT = igl.triangle_triangle_adjacency(F)[0]
    FN = igl.per_face_normals(V, F, np.zeros(3))
    area = 0.5 * igl.doublearea(V, F)
    labels = np.array([0, 0, 0, 0, 1, 1])  # the first roof facet wrongly with the floor
    out, moved = split_at_creases(F, labels, TT, FN, area)
    # it joins segment 1 only across a crease too: a segment of its own
    assert moved == 2 and out.tolist() == [0, 0, 2, 2, 1, 1]


def test_split_at_creases_keeps_large_pieces_and_smooth_turns():
    from igl_heatseg.surfaces.strays import split_at_creases

    for turn in (30.0, 60.0):
        V, F = _prism_with_roof(turn)
        TT = igl.triangle_triangle_adjacency(F)[0]
        FN = igl.per_face_normals(V, F, np.zeros(3))
        area = 0.5 * igl.doublearea(V, F)
        labels = np.array([0, 0, 1, 1, 1, 1])  # the rounded edge's two facets: one segment
        out, moved = split_at_creases(F, labels, TT, FN, area)
        # 30 degrees is no crease; at 60 each facet is half the segment: both stay
        assert moved == 0 and out.tolist() == labels.tolist()


def _tube(facets: int, radius: float = 1.0, height: float = 2.0):
    """An open tube of ``facets`` flat facets whose vertices lie on a cylinder (a CAD export of
    a small hole): two triangles per facet, facet ``i`` = faces ``2i, 2i + 1``."""
    t = np.arange(facets) * 2 * np.pi / facets
    ring = np.c_[radius * np.cos(t), radius * np.sin(t)]
    V = np.r_[np.c_[ring, np.zeros(facets)], np.c_[ring, np.full(facets, height)]]
    F = []
    for i in range(facets):
        j = (i + 1) % facets
        F += [[i, j, facets + j], [i, facets + j, facets + i]]
    return V, np.array(F, dtype=np.int64)


def test_split_at_creases_keeps_the_facets_of_a_coarse_cylinder_together():
    from igl_heatseg.surfaces.strays import split_at_creases

    V, F = _tube(8)  # 45 degrees between facets: every facet is a crease-free piece
    # a cap triangle across the rim, its corners on the cylinder too, square to it
    F = np.r_[F, [[1, 0, 4]]]
    TT = igl.triangle_triangle_adjacency(F)[0]
    FN = igl.per_face_normals(V, F, np.zeros(3))
    area = 0.5 * igl.doublearea(V, F)
    labels = np.zeros(len(F), dtype=np.int64)
    # without the positions every facet but the first leaves (each 1/8 of the segment)
    out, moved = split_at_creases(F, labels, TT, FN, area)
    assert moved == 15 and len(np.unique(out[:16])) == 8
    # with them the facets lie on the segment's cylinder and stay; the cap triangle leaves
    out, moved = split_at_creases(F, labels, TT, FN, area, V, 1e-6)
    assert moved == 1 and out[:16].tolist() == [0] * 16 and out[16] == 1
    # a segment whose faces no surface explains keeps the old rule
    bent = V.copy()
    bent[8:, 0] += 0.3 * bent[8:, 1]  # the top ring sheared: no cylinder through both rings
    out, moved = split_at_creases(F, labels, TT, FN, area, bent, 1e-6)
    assert moved == 15


def _coarse_cylinder(n=12):
    """A coarse capped cylinder (n facets, one row; caps with inner rings), exact; labels side
    0, top 1, bottom 2, and the fitted surfaces."""
    from meshes import cylinder

    from igl_heatseg.surfaces.segment_fit import fit_faces

    V, F = cylinder(n_around=n, n_height=1, radius=3.0, height=2.0)
    FN = face_normals(V, F)
    labels = np.where(FN[:, 2] > 0.9, 1, np.where(FN[:, 2] < -0.9, 2, 0))
    fits = {k: fit_faces(V, F, np.flatnonzero(labels == k), 1e-6, FN=FN) for k in range(3)}
    return V, F, FN, labels, fits


def test_a_mixture_of_a_facet_and_a_cap_triangle_goes_back_to_both():
    from igl_heatseg.surfaces.segment_fit import fit_faces
    from igl_heatseg.surfaces.strays import dissolve_mixtures

    V, F, FN, truth, fits = _coarse_cylinder()
    assert [fits[k].kind for k in range(3)] == ["cylinder", "plane", "plane"]
    TT = igl.triangle_triangle_adjacency(F)[0]
    side = np.flatnonzero(truth == 0)
    f = side[(truth[TT[side]] == 1).any(axis=1)][0]   # a facet triangle on the top rim
    g = TT[f][truth[TT[f]] == 1][0]                  # the cap triangle across its edge
    labels = truth.copy()
    labels[[f, g]] = 3
    fits[3] = fit_faces(V, F, np.array([f, g]), 1e-6, FN=FN)  # (of whatever kind)
    new, n = dissolve_mixtures(V, F, labels, fits, 1e-6, TT, FN)
    assert n == 1 and np.array_equal(new, truth)


def test_a_cap_whose_corners_are_on_the_rim_stays():
    # a top cap fanned from one rim vertex: every corner on the cylinder, every normal square
    # to it; the cap keeps its segment, and so does a facet beside it
    from igl_heatseg.surfaces.segment_fit import fit_faces
    from igl_heatseg.surfaces.strays import dissolve_mixtures

    n = 10
    t = np.linspace(0, 2 * np.pi, n, endpoint=False)
    V = np.r_[np.c_[np.cos(t), np.sin(t), 0 * t], np.c_[np.cos(t), np.sin(t), 0 * t + 3]]
    i = np.arange(n)
    j = (i + 1) % n
    side = np.r_[np.c_[i, j, j + n], np.c_[i, j + n, i + n]]
    cap = np.c_[np.full(n - 2, n), n + np.arange(1, n - 1), n + np.arange(2, n)]
    F = np.r_[side, cap]
    FN = face_normals(V, F)
    labels = np.r_[np.zeros(len(side), np.int64), np.ones(len(cap), np.int64)]
    fits = {k: fit_faces(V, F, np.flatnonzero(labels == k), 1e-6, FN=FN) for k in range(2)}
    assert fits[0].kind == "cylinder" and fits[1].kind == "plane"
    TT = igl.triangle_triangle_adjacency(F)[0]
    new, n_moved = dissolve_mixtures(V, F, labels, fits, 1e-6, TT, FN)
    assert n_moved == 0 and np.array_equal(new, labels)


def test_a_few_border_faces_off_a_cylinder_are_no_chords(monkeypatch):
    # a coarse cylinder's side (24 facets) with one cap triangle in its segment: the triangle's
    # centroid is 23 times farther inside the cylinder than the facets', but it holds 1.5 % of
    # the area: it stays, for the boundary moves. Where its share is over CHORD_SHARE, it leaves.
    import igl_heatseg.surfaces.strays as S
    from igl_heatseg.mesh.geometry import face_areas

    V, F, FN, truth, fits = _coarse_cylinder(n=24)
    TT = igl.triangle_triangle_adjacency(F)[0]
    side = np.flatnonzero(truth == 0)
    f = side[(truth[TT[side]] == 1).any(axis=1)][0]
    g = TT[f][truth[TT[f]] == 1][0]               # a cap triangle beside the side
    labels = truth.copy()
    labels[g] = 0
    A = face_areas(V, F)
    share = A[g] / A[labels == 0].sum()
    assert share < S.CHORD_SHARE
    new, n = S.split_chords(V, F, labels, fits, 1e-6, TT)
    assert n == 0 and np.array_equal(new, labels)
    monkeypatch.setattr(S, "CHORD_SHARE", share / 2)
    new, n = S.split_chords(V, F, labels, fits, 1e-6, TT)
    assert n == 1 and (new == new[g]).sum() == 1 and len(np.unique(new[side])) == 1
