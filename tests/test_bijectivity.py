"""Tests for igl_heatseg.parameterization.bijectivity: flips, mirror images, folds, boundary
overlaps, winding."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

from igl_heatseg.errors import MeshError
from igl_heatseg.mesh.topology import boundary_loops
from igl_heatseg.parameterization.bijectivity import (
    boundary_self_intersections,
    certify_map,
    exact_orient,
    exact_orient_many,
    segments_intersect,
    signed_areas,
)


def grid(nx, ny):
    """(nx+1) x (ny+1) unit-square grid, counter-clockwise triangles; returns UV (n,2), F."""
    x, y = np.meshgrid(np.linspace(0, 1, nx + 1), np.linspace(0, 1, ny + 1), indexing="ij")
    UV = np.c_[x.ravel(), y.ravel()]
    idx = np.arange(UV.shape[0]).reshape(nx + 1, ny + 1)
    a, b = idx[:-1, :-1].ravel(), idx[1:, :-1].ravel()
    c, d = idx[1:, 1:].ravel(), idx[:-1, 1:].ravel()
    return UV, np.r_[np.c_[a, b, c], np.c_[a, c, d]]


def spiral(UV, turns):
    """Wrap the unit square around the origin: u -> angle (``turns`` full turns), v -> radius."""
    th = 2 * np.pi * turns * UV[:, 0]
    r = 1.0 + UV[:, 1]
    return np.c_[r * np.cos(th), r * np.sin(th)]


def brute_force_pairs(UV, edges):
    """All-pairs reference: intersecting non-adjacent closed segments (exact via fractions)."""
    from fractions import Fraction

    def orient(a, b, c):
        a, b, c = [tuple(map(Fraction, p)) for p in (a, b, c)]
        d = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
        return (d > 0) - (d < 0)

    def on_seg(a, b, c):  # c collinear with ab: within the box?
        return min(a[0], b[0]) <= c[0] <= max(a[0], b[0]) and min(a[1], b[1]) <= c[1] <= max(
            a[1], b[1]
        )

    out = []
    for i in range(len(edges)):
        for j in range(i + 1, len(edges)):
            if set(edges[i].tolist()) & set(edges[j].tolist()):
                continue
            p1, p2 = UV[edges[i, 0]].tolist(), UV[edges[i, 1]].tolist()
            q1, q2 = UV[edges[j, 0]].tolist(), UV[edges[j, 1]].tolist()
            o1, o2 = orient(p1, p2, q1), orient(p1, p2, q2)
            o3, o4 = orient(q1, q2, p1), orient(q1, q2, p2)
            hit = (o1 * o2 < 0 and o3 * o4 < 0) or (
                (o1 == 0 and on_seg(p1, p2, q1))
                or (o2 == 0 and on_seg(p1, p2, q2))
                or (o3 == 0 and on_seg(q1, q2, p1))
                or (o4 == 0 and on_seg(q1, q2, p2))
            )
            if hit:
                out.append((i, j))
    return out


def loop_edges(F):
    lp = boundary_loops(F)[0]
    return np.c_[lp, np.roll(lp, -1)]


# ------------------------------------------------------------------------------------------


def test_identity_map_is_bijective():
    UV, F = grid(6, 5)
    cert = certify_map(UV, F)
    assert cert.bijective
    assert (cert.flips, cert.degenerate, cert.overlaps, cert.wound) == (0, 0, 0, 0)
    assert not cert.mirrored and cert.orientation == 1
    assert cert.boundary_loops == 1


def test_mirrored_map_is_not_flipped():
    UV, F = grid(6, 5)
    cert = certify_map(UV * [-1.0, 1.0], F)
    assert cert.mirrored and cert.orientation == -1
    assert cert.flips == 0
    assert cert.bijective
    area, sign = signed_areas(UV * [-1.0, 1.0], F)
    assert np.all(sign == -1) and np.all(area < 0)


def test_folded_map_is_caught():
    UV, F = grid(4, 4)
    centre = 12  # interior vertex (2, 2)
    UV = UV.copy()
    UV[centre] = [0.9, 0.9]  # dragged across its one-ring: some incident triangles flip
    cert = certify_map(UV, F)
    assert not cert.bijective
    assert cert.flips > 0
    incident = np.flatnonzero((F == centre).any(axis=1))
    assert set(cert.flipped_faces.tolist()) <= set(incident.tolist())
    # Mirroring the folded map does not hide the fold.
    assert certify_map(UV * [-1.0, 1.0], F).flips == cert.flips


def test_boundary_self_intersection_is_caught():
    UV, F = grid(40, 4)
    wrapped = spiral(UV, 1.1)  # more than one turn: the strip overlaps itself
    cert = certify_map(wrapped, F)
    assert cert.flips == 0 and cert.degenerate == 0
    assert cert.overlaps > 0
    assert not cert.bijective
    # Less than a full turn: an embedded annular sector.
    assert certify_map(spiral(UV, 0.9), F).bijective


def test_overlap_count_matches_brute_force():
    UV, F = grid(30, 3)
    wrapped = spiral(UV, 1.3)
    E = loop_edges(F)
    pairs, _ = boundary_self_intersections(wrapped, E)
    ref = brute_force_pairs(wrapped, E)
    assert [tuple(p) for p in pairs.tolist()] == sorted(ref)
    assert len(ref) > 0


@settings(max_examples=25, deadline=None)
@given(st.integers(min_value=0, max_value=10_000), st.floats(min_value=0.01, max_value=0.6))
@example(231, 0.125)  # snapped vertices: zero-length boundary edges (was a false positive)
def test_grid_search_equals_brute_force_on_random_boundaries(seed, amp):
    """Random perturbations of a boundary polygon: the grid finds exactly the all-pairs hits."""
    rng = np.random.default_rng(seed)
    UV, F = grid(8, 8)
    E = loop_edges(F)
    P = UV + amp * rng.standard_normal(UV.shape)
    # Snap to a coarse lattice sometimes, to create exact touching and collinear cases.
    if seed % 3 == 0:
        P = np.round(P * 8) / 8
    pairs, _ = boundary_self_intersections(P, E)
    got = [tuple(p) for p in pairs.tolist() if not (set(E[p[0]]) & set(E[p[1]]))]
    assert got == sorted(brute_force_pairs(P, E))


def test_zero_length_segment_off_the_line_does_not_intersect():
    P = np.array([[0.5, 0.2]])  # a point inside the other segment's bounding box, off its line
    Q1, Q2 = np.array([[0.0, 0.0]]), np.array([[1.0, 1.0]])
    assert not segments_intersect(P, P, Q1, Q2)[0]
    on = np.array([[0.25, 0.25]])
    assert segments_intersect(on, on, Q1, Q2)[0]


def test_touching_boundary_counts_as_overlap():
    """A boundary vertex lying exactly on a non-adjacent boundary edge is not simple."""
    UV, F = grid(4, 1)  # strip of 5 x 2 vertices; bottom row ids 0,2,4,6,8; top 1,3,5,7,9
    UV = UV.copy()
    # Bend the strip into a U and push its right end onto the left end's top edge exactly.
    P = UV.copy()
    P[[8, 9]] = [[0.25, 0.0], [0.25, 1.0]]  # right end laid over the segment 0-2 / 1-3
    P[8] = [0.125, 0.0]  # exactly on the edge (0,2) from (0,0) to (0.25,0)
    cert = certify_map(P, F)
    assert cert.overlaps > 0
    assert not cert.bijective


def test_degenerate_triangle_is_caught():
    # Exactly collinear corners: zero area, detected exactly (not a flip).
    UV = np.array([[0.0, 0.0], [1.0, 1.0], [0.5, 0.5], [0.0, 1.0]])
    cert = certify_map(UV, np.array([[0, 1, 2], [0, 3, 1]]))
    assert cert.degenerate == 1 and cert.degenerate_faces.tolist() == [0]
    assert cert.flips == 0 and not cert.bijective
    # A needle: nonzero but relatively negligible area.
    UV = np.array([[0.0, 0.0], [1.0, 0.0], [0.5, 1e-14], [0.0, 1.0]])
    cert = certify_map(UV, np.array([[0, 1, 2], [0, 1, 3]]))
    assert cert.degenerate == 1 and not cert.bijective


def test_tiny_near_collinear_triangle_sign_is_exact():
    """Orientation decided exactly where the float determinant is unreliable."""
    a = np.array([0.5, 0.5])
    b = np.array([12.0, 12.0])
    c = np.array([24.0, 24.0 + 2.0**-48])  # left of ab by a hair
    UV = np.array([a, b, c])
    _, sign = signed_areas(UV, np.array([[0, 1, 2]]))
    assert sign[0] == 1
    _, sign = signed_areas(UV, np.array([[0, 2, 1]]))
    assert sign[0] == -1


_COORDS = st.one_of(
    st.sampled_from([0.0, -0.0, 5e-324, -5e-324, 2.0**-1022, 1e-300, 1.0, -1.0, 0.5, 3.0, 1e300]),
    st.floats(allow_nan=False, allow_infinity=False, width=64),
)


@settings(max_examples=300, deadline=None)
@given(st.lists(st.lists(_COORDS, min_size=6, max_size=6), min_size=1, max_size=8))
def test_vectorised_exact_orientation_matches_rationals(rows):
    """The integer (object array) evaluation equals the rational one, extremes included."""
    X = np.array(rows, dtype=np.float64)
    A, B, C = X[:, 0:2], X[:, 2:4], X[:, 4:6]
    ref = [
        exact_orient(a.tolist(), b.tolist(), c.tolist()) for a, b, c in zip(A, B, C, strict=True)
    ]
    assert exact_orient_many(A, B, C).tolist() == ref


def test_vectorised_exact_orientation_on_near_collinear_points():
    rng = np.random.default_rng(5)
    A = rng.normal(size=(500, 2))
    B = rng.normal(size=(500, 2))
    C = A + rng.normal(size=(500, 1)) * (B - A)  # collinear up to rounding
    C[::3] = A[::3]  # exactly coincident: orientation 0
    got = exact_orient_many(A, B, C)
    ref = [
        exact_orient(a.tolist(), b.tolist(), c.tolist()) for a, b, c in zip(A, B, C, strict=True)
    ]
    assert got.tolist() == ref
    assert np.all(got[::3] == 0) and np.any(got != 0)


def test_collapsed_map_is_certified_quickly_and_exactly():
    """Every triangle of a map collapsed onto a line is degenerate (all signs decided exactly
    in the vectorised path)."""
    UV, F = grid(40, 40)
    line = np.c_[UV[:, 0] + 0.3 * UV[:, 1], 2.0 * (UV[:, 0] + 0.3 * UV[:, 1])]
    cert = certify_map(line, F)
    assert cert.degenerate == F.shape[0] and cert.flips == 0 and not cert.bijective


def test_given_boundary_loops_give_the_same_certificate():
    UV, F = grid(8, 7)
    for W in (UV, spiral(UV, 1.05), UV * [-1, 1]):
        a = certify_map(W, F)
        b = certify_map(W, F, loops=boundary_loops(F))
        assert a.summary() == b.summary()
        assert np.array_equal(a.overlap_edges, b.overlap_edges)


def test_wound_vertex_is_caught():
    """A fan whose rim goes around the centre twice: every triangle positive, not injective."""
    k = 8
    ang = 2 * (2 * np.pi) * np.arange(k) / k  # two turns
    rad = np.where(np.arange(k) < k // 2, 1.0, 2.0)
    UV = np.r_[[[0.0, 0.0]], np.c_[rad * np.cos(ang), rad * np.sin(ang)]]
    F = np.array([[0, 1 + i, 1 + (i + 1) % k] for i in range(k)])
    cert = certify_map(UV, F)
    assert cert.flips == 0 and cert.degenerate == 0
    assert cert.wound == 1 and cert.wound_vertices.tolist() == [0]
    assert not cert.bijective


def test_large_chart_is_certified(tmp_path):
    """~100k triangles: a spiral overlap is found and an embedding passes (grid, not pairs)."""
    UV, F = grid(250, 200)
    assert F.shape[0] == 100_000
    assert certify_map(UV, F).bijective
    cert = certify_map(spiral(UV, 1.05), F)
    assert cert.overlaps > 0 and cert.flips == 0
    assert cert.seconds < 30.0


def test_bad_input_raises():
    UV, F = grid(2, 2)
    with pytest.raises(MeshError, match="shape"):
        certify_map(np.c_[UV, UV[:, 0]], F)
    with pytest.raises(MeshError, match="outside"):
        certify_map(UV, F + 100)
    bad = UV.copy()
    bad[0] = np.nan
    with pytest.raises(MeshError, match="NaN"):
        certify_map(bad, F)
    with pytest.raises(MeshError):
        certify_map(UV, np.zeros((0, 3), dtype=int))
