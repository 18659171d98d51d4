"""Tests for igl_heatseg.parameterization.atlas: packing charts into [0,1]^2 and OBJ writers."""

from __future__ import annotations

import igl
import numpy as np
import pytest

from igl_heatseg.errors import MeshError
from igl_heatseg.io.results import write_atlas_obj, write_chart_obj
from igl_heatseg.parameterization.atlas import (
    atlas_corner_uv,
    boxes_overlap,
    min_area_rotation,
    pack_charts,
)
from igl_heatseg.parameterization.cut import cut_to_disk

#: Exactness of coordinates re-read from OBJ files written with 17 significant digits.
OBJ_ROUNDTRIP_TOL = 0.0
#: Relative tolerance for lengths/areas after rigid motion and common scaling.
SHAPE_RTOL = 1e-9


def signed_areas(UV, F):
    a = UV[F[:, 1]] - UV[F[:, 0]]
    b = UV[F[:, 2]] - UV[F[:, 0]]
    return (a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]) / 2


def grid_chart(nx, ny, sx=1.0, sy=1.0, angle=0.0, offset=(0.0, 0.0)):
    x, y = np.meshgrid(np.linspace(0, sx, nx + 1), np.linspace(0, sy, ny + 1))
    P = np.c_[x.ravel(), y.ravel()]
    c, s = np.cos(angle), np.sin(angle)
    P = P @ np.array([[c, s], [-s, c]]) + offset
    F = []
    for k in range(ny):
        for i in range(nx):
            a = k * (nx + 1) + i
            F += [[a, a + 1, a + nx + 2], [a, a + nx + 2, a + nx + 1]]
    return P, np.array(F, dtype=np.int64)


def random_charts(k, seed):
    rng = np.random.default_rng(seed)
    uvs, faces = [], []
    for _ in range(k):
        P, F = grid_chart(
            int(rng.integers(1, 6)),
            int(rng.integers(1, 6)),
            sx=rng.uniform(0.05, 3),
            sy=rng.uniform(0.05, 3),
            angle=rng.uniform(-np.pi, np.pi),
            offset=rng.uniform(-10, 10, 2),
        )
        uvs.append(P)
        faces.append(F)
    return uvs, faces


@pytest.mark.parametrize("seed", [0, 1, 2])
@pytest.mark.parametrize("k", [1, 2, 7, 40])
def test_packing_no_overlap_in_unit_square(k, seed):
    uvs, faces = random_charts(k, seed)
    atlas = pack_charts(uvs, faces, packer="boxes")
    assert len(atlas.uvs) == k
    for Q in atlas.uvs:
        assert Q.min() >= 0.0 and Q.max() <= 1.0
    # boxes are at least the gutter apart (up to rounding)
    assert len(boxes_overlap(atlas.boxes, gap=atlas.gutter * (1 - 1e-6))) == 0
    # the box really bounds its chart
    for Q, B in zip(atlas.uvs, atlas.boxes, strict=True):
        np.testing.assert_allclose(B, [*Q.min(0), *Q.max(0)])
    # the layout touches the far side of the square in one axis (normalised)
    far = max(B[2:].max() for B in atlas.boxes)
    assert far == pytest.approx(1 - atlas.gutter / 2, abs=1e-9)
    assert 0 < atlas.fill <= 1


def test_packing_is_rigid_plus_common_scale_and_keeps_orientation():
    uvs, faces = random_charts(12, seed=5)
    atlas = pack_charts(uvs, faces)
    for P, F, Q in zip(uvs, faces, atlas.uvs, strict=True):
        E = np.concatenate([F[:, [0, 1]], F[:, [1, 2]]])
        lp = np.linalg.norm(P[E[:, 0]] - P[E[:, 1]], axis=1)
        lq = np.linalg.norm(Q[E[:, 0]] - Q[E[:, 1]], axis=1)
        np.testing.assert_allclose(lq, atlas.scale * lp, rtol=SHAPE_RTOL)
        # no mirror: signed areas keep their sign
        assert (np.sign(signed_areas(Q, F)) == np.sign(signed_areas(P, F))).all()


def test_relative_areas_follow_3d_areas():
    sq, F = grid_chart(2, 2)
    # the same 3D area given to charts of very different UV size: equal size in the atlas
    atlas = pack_charts([sq, 10 * sq, 0.1 * sq], [F, F, F], areas=[1.0, 1.0, 4.0])
    a = [abs(signed_areas(Q, F).sum()) for Q in atlas.uvs]
    assert a[1] == pytest.approx(a[0], rel=SHAPE_RTOL)
    assert a[2] == pytest.approx(4 * a[0], rel=SHAPE_RTOL)


def test_min_area_rotation_of_rotated_rectangle():
    P, _ = grid_chart(3, 1, sx=3.0, sy=1.0, angle=0.3)
    t = min_area_rotation(P)
    c, s = np.cos(t), np.sin(t)
    Q = P @ np.array([[c, s], [-s, c]])
    ext = np.ptp(Q, axis=0)
    np.testing.assert_allclose(ext, [3.0, 1.0], rtol=1e-12)  # landscape, tight


def _hull_reference(P):
    """Andrew's monotone chain on all points (what atlas.convex_hull did before its filter)."""
    P = np.unique(P, axis=0)
    if len(P) < 3:
        return P

    def half(points):
        out = []
        for p in points:
            while len(out) >= 2:
                o, a = out[-2], out[-1]
                if (a[0] - o[0]) * (p[1] - o[1]) - (a[1] - o[1]) * (p[0] - o[0]) > 0:
                    break
                out.pop()
            out.append(p)
        return out

    pts = [tuple(p) for p in P]
    return np.array(half(pts)[:-1] + half(pts[::-1])[:-1])


@pytest.mark.parametrize("kind", ["normal", "anisotropic", "circle", "lattice"])
def test_filtered_hull_equals_the_full_monotone_chain(kind):
    from igl_heatseg.parameterization.atlas import convex_hull

    rng = np.random.default_rng(7)
    for n in (3, 50, 200, 3000):
        if kind == "normal":
            P = rng.normal(size=(n, 2))
        elif kind == "anisotropic":
            P = rng.random((n, 2)) * [1e-6, 1e6]
        elif kind == "circle":  # every point (nearly) on the hull
            t = rng.random(n) * 2 * np.pi
            P = np.c_[np.cos(t), np.sin(t)] * (1 - 1e-12 * rng.random((n, 1)))
        else:  # duplicates and collinear points
            P = np.round(rng.normal(size=(n, 2)) * 3)
        np.testing.assert_array_equal(convex_hull(P), _hull_reference(P))


def test_obj_text_is_the_per_line_format(tmp_path):
    """Block formatting writes exactly the lines of per-row ``%`` formatting (more rows than
    one block of the writer, and a partial last block)."""
    rng = np.random.default_rng(3)
    n = 70_000
    V = rng.normal(size=(n, 3)) * 10.0 ** rng.integers(-30, 30, (n, 1))
    V[0] = [-0.0, 1e-320, np.pi]
    UV = rng.random((n, 2))
    F = rng.integers(0, n, (n + 3, 3))
    write_chart_obj(tmp_path / "a.obj", V, F, UV)
    lines = ["v %.17g %.17g %.17g" % tuple(r) for r in V.tolist()]
    lines += ["vt %.17g %.17g" % tuple(r) for r in UV.tolist()]
    I = np.stack([F + 1, F + 1], axis=2).reshape(-1, 6)
    lines += ["f %d/%d %d/%d %d/%d" % tuple(r) for r in I.tolist()]
    text = (tmp_path / "a.obj").read_text().split("\n")
    assert text[0].startswith("#") and text[1:] == lines + [""]


def test_pack_rejects_bad_input():
    sq, F = grid_chart(1, 1)
    with pytest.raises(MeshError, match="2 UV arrays but 1"):
        pack_charts([sq, sq], [F])
    with pytest.raises(MeshError, match=r"chart 0: `uv` should have shape \(n,2\)"):
        pack_charts([np.zeros((4, 3))], [F])
    with pytest.raises(MeshError, match="chart 1: face indices"):
        pack_charts([sq, sq], [F, F + 10])
    with pytest.raises(MeshError, match="zero UV area"):
        pack_charts([np.zeros_like(sq)], [F])
    with pytest.raises(MeshError, match="NaN"):
        pack_charts([np.full_like(sq, np.nan)], [F])
    with pytest.raises(MeshError, match="areas"):
        pack_charts([sq], [F], areas=[-1.0])
    with pytest.raises(MeshError, match="gutter"):
        pack_charts([sq], [F], gutter=0.7)
    with pytest.raises(MeshError, match="no charts"):
        pack_charts([], [])


def test_boxes_overlap():
    B = [[0, 0, 1, 1], [1, 0, 2, 1], [0.5, 0.5, 1.5, 1.5], [3, 3, 4, 4]]
    pairs = boxes_overlap(B)
    assert sorted(map(tuple, pairs.tolist())) == [(0, 2), (1, 2)]  # touching is fine
    assert (0, 1) in set(map(tuple, boxes_overlap(B, gap=0.1).tolist()))


def test_chart_obj_roundtrip(tmp_path):
    P, F = grid_chart(3, 2, sx=1 / 3, sy=np.pi)
    V = np.c_[P, np.sin(P[:, 0])]
    path = tmp_path / "chart_000.obj"
    write_chart_obj(path, V, F, P * np.e)
    V2, TC, _, F2, FTC, _ = igl.readOBJ(str(path))
    np.testing.assert_array_equal(V2, V)
    np.testing.assert_array_equal(TC, P * np.e)
    np.testing.assert_array_equal(F2, F)
    np.testing.assert_array_equal(FTC, F)
    text = path.read_text().splitlines()
    assert sum(ln.startswith("f ") for ln in text) == len(F)
    assert any(ln.startswith("f 1/1 ") for ln in text)  # 1-based


def test_chart_obj_rejects_mismatch(tmp_path):
    P, F = grid_chart(1, 1)
    V = np.c_[P, np.zeros(len(P))]
    with pytest.raises(MeshError, match="UV"):
        write_chart_obj(tmp_path / "a.obj", V, F, P[:-1])
    with pytest.raises(MeshError, match="outside"):
        write_chart_obj(tmp_path / "a.obj", V, F + 4, P)


def cylinder(nu=16, nv=4):
    t = np.linspace(0, 2 * np.pi, nu, endpoint=False)
    V = np.concatenate([np.c_[np.cos(t), np.sin(t), np.full(nu, z)] for z in range(nv + 1)])
    F = []
    for k in range(nv):
        for i in range(nu):
            j = (i + 1) % nu
            a, b, c, d = k * nu + i, k * nu + j, (k + 1) * nu + j, (k + 1) * nu + i
            F += [[a, b, c], [a, c, d]]
    return V, np.array(F, dtype=np.int64)


def test_atlas_obj_roundtrip_with_cut_chart(tmp_path):
    # Two charts of a cylinder: bottom half (cut open, a seam) and top half (cut open).
    V, F = cylinder()
    m = len(F)
    halves = [np.arange(m // 2), np.arange(m // 2, m)]
    uvs, chart_F = [], []
    for faces in halves:
        res = cut_to_disk(V, F[faces])
        assert res.topology_after.is_disk
        # unroll: u = angle (0..2pi, seam copies get 2pi), v = z
        v_cut = res.cut_edges[0, 0]
        ang = np.arctan2(res.V[:, 1], res.V[:, 0]) - np.arctan2(V[v_cut, 1], V[v_cut, 0])
        ang = np.round(ang % (2 * np.pi), 12) % (2 * np.pi)  # the seam at exactly 0
        uv = np.c_[ang, res.V[:, 2]]
        # the copy of a seam vertex in faces on the "high" side gets 2pi
        for f in range(len(res.F)):
            a = uv[res.F[f], 0]
            if a.max() - a.min() > np.pi:
                for j in range(3):
                    if uv[res.F[f, j], 0] < np.pi:
                        uv[res.F[f, j], 0] += 2 * np.pi
        uvs.append(uv)
        chart_F.append(res.F)
    for uv, Fc in zip(uvs, chart_F, strict=True):
        assert (signed_areas(uv, Fc) > 0).all()  # a bijective unrolling
    atlas = pack_charts(uvs, chart_F)
    C = atlas_corner_uv(m, halves, chart_F, atlas.uvs)
    path = tmp_path / "atlas.obj"
    write_atlas_obj(path, V, F, C)
    V2, TC, _, F2, FTC, _ = igl.readOBJ(str(path))
    np.testing.assert_array_equal(V2, V)
    np.testing.assert_array_equal(F2, F)  # input face order
    np.testing.assert_array_equal(TC[FTC], C)
    # one vt per distinct corner UV: each chart's cut vertices, no more
    assert len(TC) == sum(len(u) for u in atlas.uvs)
    assert TC.min() >= 0 and TC.max() <= 1


def test_atlas_corner_uv_rejects_uncovered_faces():
    P, F = grid_chart(1, 1)
    with pytest.raises(MeshError, match="exactly one"):
        atlas_corner_uv(3, [np.array([0, 1])], [F], [P])
    with pytest.raises(MeshError, match="exactly one"):
        atlas_corner_uv(2, [np.array([0, 1]), np.array([1, 0])], [F, F], [P, P])


def test_atlas_obj_rejects_bad_corner_uv(tmp_path):
    V, F = cylinder()
    with pytest.raises(MeshError, match="corner_uv"):
        write_atlas_obj(tmp_path / "a.obj", V, F, np.zeros((len(F), 3)))
    C = np.zeros((len(F), 3, 2))
    C[3, 1, 0] = np.nan
    with pytest.raises(MeshError, match="not finite on 1 face"):
        write_atlas_obj(tmp_path / "a.obj", V, F, C)


def l_chart(n=6, size=1.0):
    """An L-shaped grid chart (three unit squares' worth of cells), as (UV, F)."""
    P, F = grid_chart(2 * n, 2 * n, 2 * size, 2 * size)
    c = (P[F].mean(axis=1) < size).any(axis=1)  # drop the upper-right quarter
    F = F[c]
    used = np.unique(F)
    remap = np.full(len(P), -1)
    remap[used] = np.arange(len(used))
    return P[used], remap[F]


def inside(poly, p):
    """Even-odd point-in-polygon test; ``poly`` (n, 2) or a list of loops (holes)."""
    loops = poly if isinstance(poly, list) else [poly]
    a = np.concatenate(loops)
    b = np.concatenate([np.roll(lp, -1, axis=0) for lp in loops])
    cross = (a[:, 1] > p[1]) != (b[:, 1] > p[1])
    x = a[:, 0] + (p[1] - a[:, 1]) * (b[:, 0] - a[:, 0]) / np.where(cross, b[:, 1] - a[:, 1], 1)
    return bool(np.count_nonzero(cross & (x > p[0])) % 2)


def boundary_edges(F):
    """Boundary edges (e, 2) of a chart over all its loops (a chart may have holes)."""
    from igl_heatseg.mesh.topology import boundary_loops

    return np.concatenate([np.c_[lp, np.roll(lp, -1)] for lp in boundary_loops(F)])


def charts_overlap(uvs, faces):
    """Whether any two packed charts overlap: boundary crossings, or one inside another."""
    from igl_heatseg.mesh.topology import boundary_loops
    from igl_heatseg.parameterization.bijectivity import boundary_self_intersections

    P = np.concatenate(uvs)
    off = np.cumsum([0] + [len(U) for U in uvs])
    E = np.concatenate([boundary_edges(F) + o for F, o in zip(faces, off, strict=False)])
    pairs, _ = boundary_self_intersections(P, E)
    chart = np.searchsorted(off, E[:, 0], side="right") - 1
    if (chart[pairs[:, 0]] != chart[pairs[:, 1]]).any():
        return True
    for i, (U, F) in enumerate(zip(uvs, faces, strict=True)):
        loops = [U[lp] for lp in boundary_loops(F)]
        for j, W in enumerate(uvs):
            if i != j and inside(loops, W[faces[j][0]].mean(axis=0)):  # a point of chart j
                return True
    return False


def _point_segment(P, S0, S1):
    """(n, m) distances from points P (n, 2) to segments S0 S1 (m, 2)."""
    d = S1 - S0
    t = ((P[:, None] - S0[None]) * d[None]).sum(-1) / np.maximum((d * d).sum(-1), 1e-300)
    foot = S0[None] + np.clip(t, 0.0, 1.0)[..., None] * d[None]
    return np.linalg.norm(P[:, None] - foot, axis=-1)


def min_chart_gap(uvs, faces):
    """Smallest distance between the boundaries of two different charts (exact for
    boundaries that do not cross: the minimum over endpoint-to-segment distances)."""
    best = np.inf
    edges = [boundary_edges(F) for F in faces]
    for i in range(len(uvs)):
        A0, A1 = uvs[i][edges[i][:, 0]], uvs[i][edges[i][:, 1]]
        for j in range(i + 1, len(uvs)):
            B0, B1 = uvs[j][edges[j][:, 0]], uvs[j][edges[j][:, 1]]
            best = min(
                best,
                _point_segment(A0, B0, B1).min(),
                _point_segment(B0, A0, A1).min(),
            )
    return best


def random_l_charts(k, seed):
    """k L-shaped charts of random size (0.3-1) and rotation."""
    rng = np.random.default_rng(seed)
    uvs, faces = [], []
    for _ in range(k):
        P, F = l_chart(size=rng.uniform(0.3, 1.0))
        t = rng.uniform(-np.pi, np.pi)
        uvs.append(P @ np.array([[np.cos(t), np.sin(t)], [-np.sin(t), np.cos(t)]]))
        faces.append(F)
    return uvs, faces


@pytest.mark.parametrize("k", [2, 5, 12])
def test_outline_packing_nests_charts_without_overlap(k):
    uvs, faces = random_l_charts(k, seed=k)
    boxes = pack_charts(uvs, faces, packer="boxes")
    atlas = pack_charts(uvs, faces, packer="outlines")
    assert not charts_overlap(atlas.uvs, faces)
    for Q, F, U in zip(atlas.uvs, faces, uvs, strict=True):
        assert Q.min() >= 0.0 and Q.max() <= 1.0
        assert (signed_areas(Q, F) > 0).all() == (signed_areas(U, F) > 0).all()  # rigid
    assert atlas.fill > boxes.fill
    assert pack_charts(uvs, faces).fill == max(atlas.fill, boxes.fill)  # "auto"


def test_outline_packing_keeps_the_gutter():
    uvs, faces = zip(*[l_chart() for _ in range(4)], strict=True)
    atlas = pack_charts(list(uvs), list(faces), packer="outlines", gutter=0.02)
    # vertices of different charts are at least the gutter apart
    for i in range(4):
        for j in range(i + 1, 4):
            d = np.linalg.norm(atlas.uvs[i][:, None] - atlas.uvs[j][None], axis=2).min()
            assert d >= 0.02 * (1 - 1e-9)


def test_outline_packing_fills_the_square():
    """Twelve L-shaped charts of random size and rotation: the outline packer (any rotation,
    finer raster) fills at least 75 % of the square (the quarter-turn packer before: 65 %)
    without overlaps, and keeps every chart's orientation."""
    uvs, faces = random_l_charts(12, seed=12)
    atlas = pack_charts(uvs, faces, packer="outlines")
    assert atlas.fill >= 0.75
    assert not charts_overlap(atlas.uvs, faces)
    for Q, F, U in zip(atlas.uvs, faces, uvs, strict=True):
        assert Q.min() >= 0.0 and Q.max() <= 1.0
        assert np.all(np.sign(signed_areas(Q, F)) == np.sign(signed_areas(U, F)))


@pytest.mark.parametrize("k", [5, 30])
def test_outline_packing_keeps_the_gutter_along_boundaries(k):
    """Packed outlines are at least the gutter apart (boundaries sampled 50 times per edge;
    measured 1.01-1.09 gutters at the closest pair)."""
    from scipy.spatial import cKDTree

    from igl_heatseg.mesh.topology import boundary_loops

    uvs, faces = random_l_charts(k, seed=k)
    atlas = pack_charts(uvs, faces, packer="outlines")
    s = np.linspace(0, 1, 50)[:, None, None]
    pts = []
    for Q, F in zip(atlas.uvs, faces, strict=True):
        lp = boundary_loops(F)[0]
        pts.append((Q[lp][None] * (1 - s) + Q[np.roll(lp, -1)][None] * s).reshape(-1, 2))
    closest = min(cKDTree(pts[i]).query(pts[j])[0].min() for i in range(k) for j in range(i + 1, k))
    assert closest >= atlas.gutter * (1 - 1e-6)


def sub_chart(P, F, keep):
    """The chart of the faces ``keep`` of ``(P, F)``, vertices renumbered."""
    F = F[keep]
    used = np.unique(F)
    remap = np.full(len(P), -1)
    remap[used] = np.arange(len(used))
    return P[used], remap[F]


def triangle_chart(n=4, size=1.0):
    """A right isosceles triangle (legs ``size``) as a grid chart."""
    P, F = grid_chart(n, n, size, size)
    return sub_chart(P, F, P[F].mean(axis=1).sum(axis=1) < size)


def ring_chart(n=10, hole=(2, 8)):
    """An ``n`` x ``n`` square chart with a square hole (two boundary loops)."""
    P, F = grid_chart(n, n, float(n), float(n))
    c = P[F].mean(axis=1)
    return sub_chart(P, F, ~((c > hole[0]) & (c < hole[1])).all(axis=1))


def rotate(P, t):
    return P @ np.array([[np.cos(t), np.sin(t)], [-np.sin(t), np.cos(t)]])


def mixed_charts(seed):
    """L shapes, triangles, thin strips and rectangles at random rotations and offsets."""
    rng = np.random.default_rng(seed)
    uvs, faces = [], []
    for k in range(12):
        kind = k % 4
        if kind == 0:
            P, F = l_chart(size=rng.uniform(0.3, 1.0))
        elif kind == 1:
            P, F = triangle_chart(size=rng.uniform(0.5, 1.5))
        elif kind == 2:
            P, F = grid_chart(8, 1, rng.uniform(1.0, 3.0), rng.uniform(0.05, 0.2))
        else:
            P, F = grid_chart(2, 3, rng.uniform(0.3, 1.0), rng.uniform(0.3, 1.0))
        uvs.append(rotate(P, rng.uniform(-np.pi, np.pi)) + rng.uniform(-5, 5, 2))
        faces.append(F)
    return uvs, faces, rng.uniform(0.5, 2.0, len(uvs))


@pytest.mark.parametrize("seed", [0, 1])
@pytest.mark.parametrize("packer", ["outlines", "auto"])
def test_packing_mixed_shapes_is_a_rotation_with_one_scale_and_keeps_the_gutter(seed, packer):
    """Every chart is rotated (the reported angle, never mirrored), scaled by one factor
    times its own area factor, lies in the unit square, overlaps no other chart, and the
    exact distance between the boundaries of any two charts is at least the gutter."""
    uvs, faces, areas = mixed_charts(seed)
    atlas = pack_charts(uvs, faces, areas=areas, packer=packer, gutter=0.01)
    assert not charts_overlap(atlas.uvs, faces)
    assert min_chart_gap(atlas.uvs, faces) >= atlas.gutter * (1 - 1e-9)
    assert atlas.gutter > 0.005
    for i, (P, F, Q) in enumerate(zip(uvs, faces, atlas.uvs, strict=True)):
        assert Q.min() >= 0.0 and Q.max() <= 1.0
        assert np.all(np.sign(signed_areas(Q, F)) == np.sign(signed_areas(P, F)))
        # edge vectors: Q = s R(angle) P + t with s = scale * chart scale
        s = atlas.scale * atlas.chart_scales[i]
        np.testing.assert_allclose(
            (Q[F[:, 1]] - Q[F[:, 0]]),
            s * rotate(P[F[:, 1]] - P[F[:, 0]], atlas.rotations[i]),
            atol=1e-12,
        )
    # the chart scales make UV areas proportional to the given areas
    a = np.array([abs(signed_areas(Q, F).sum()) for Q, F in zip(atlas.uvs, faces, strict=True)])
    np.testing.assert_allclose(a / a.sum(), areas / areas.sum(), rtol=1e-9)


def test_outline_packing_is_deterministic():
    uvs, faces, areas = mixed_charts(3)
    a = pack_charts(uvs, faces, areas=areas, packer="outlines")
    b = pack_charts(uvs, faces, areas=areas, packer="outlines")
    for Qa, Qb in zip(a.uvs, b.uvs, strict=True):
        np.testing.assert_array_equal(Qa, Qb)


def test_outline_packing_fills_with_triangle_pairs_and_l_rectangle_mixes():
    """Eight equal right triangles pair into squares, four L shapes and four 3 x 1
    rectangles into rectangles: fill >= 0.85 (the quarter-turn outline packer: .66, .65)."""
    T, Ft = triangle_chart()
    atlas = pack_charts([T] * 8, [Ft] * 8)
    assert atlas.fill >= 0.85
    assert not charts_overlap(atlas.uvs, [Ft] * 8)
    L, Fl = l_chart()
    R, Fr = grid_chart(3, 1, 3.0, 1.0)
    atlas = pack_charts([L] * 4 + [R] * 4, [Fl] * 4 + [Fr] * 4)
    assert atlas.fill >= 0.85
    assert not charts_overlap(atlas.uvs, [Fl] * 4 + [Fr] * 4)


def test_outline_packing_turns_a_long_strip_to_the_diagonal():
    """A 10 x 0.6 strip with eight unit squares: only a strip along the diagonal keeps the
    square small (fill >= 0.22; quarter turns only: .14)."""
    strip, Fs = grid_chart(20, 1, 10.0, 0.6)
    sq, Fq = grid_chart(2, 2)
    atlas = pack_charts([strip] + [sq] * 8, [Fs] + [Fq] * 8)
    assert atlas.fill >= 0.22
    assert abs(np.sin(2 * atlas.rotations[0])) > 0.5  # far from a quarter turn
    assert not charts_overlap(atlas.uvs, [Fs] + [Fq] * 8)


def test_outline_packing_nests_a_chart_in_a_hole():
    """A 3 x 3 square goes into the 6 x 6 hole of a 10 x 10 ring chart."""
    ring, Fr = ring_chart()
    sq, Fq = grid_chart(3, 3, 3.0, 3.0)
    atlas = pack_charts([ring, sq], [Fr, Fq], packer="outlines")
    box = atlas.boxes
    assert np.all(box[1, :2] > box[0, :2]) and np.all(box[1, 2:] < box[0, 2:])
    assert not charts_overlap(atlas.uvs, [Fr, Fq])
    assert min_chart_gap(atlas.uvs, [Fr, Fq]) >= atlas.gutter * (1 - 1e-9)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_rasterize_chart_is_conservative_and_tight(seed):
    """Every point of the chart (sampled in its triangles and on its boundary) falls in a
    marked pixel, and every marked pixel lies within a pixel diagonal of the chart: at most
    area + sqrt(2) * perimeter + 2 pi pixels."""
    from igl_heatseg.parameterization.outline_pack import rasterize_chart

    rng = np.random.default_rng(seed)
    for P, F in [
        l_chart(size=rng.uniform(3, 9)),
        triangle_chart(size=rng.uniform(3, 9)),
        ring_chart(),
        grid_chart(5, 1, rng.uniform(5, 20), rng.uniform(0.2, 1)),
    ]:
        P = rotate(P, rng.uniform(-np.pi, np.pi))
        P = P - P.min(axis=0) + rng.uniform(0, 1, 2)  # not on the pixel grid
        pad = 2
        M = rasterize_chart(P, F, 1.0, pad)
        u = rng.random((len(F), 30, 2))
        u[u.sum(-1) > 1] = 1 - u[u.sum(-1) > 1]
        T = P[F]
        S = T[:, None, 0] + u[..., :1] * (T[:, None, 1] - T[:, None, 0])
        S = S + u[..., 1:] * (T[:, None, 2] - T[:, None, 0])
        E = boundary_edges(F)
        t = rng.random((len(E), 1))
        S = np.concatenate([S.reshape(-1, 2), P[E[:, 0]] * (1 - t) + P[E[:, 1]] * t, P])
        assert M[np.floor(S[:, 1]).astype(int) + pad, np.floor(S[:, 0]).astype(int) + pad].all()
        area = abs(signed_areas(P, F).sum())
        perimeter = np.linalg.norm(P[E[:, 1]] - P[E[:, 0]], axis=1).sum()
        assert M.sum() <= area + np.sqrt(2) * perimeter + 2 * np.pi


@pytest.mark.parametrize("gap", [0.0, 0.5, 1.0, 1.3, 2.0, 2.9])
def test_gutter_structure_holds_the_pixels_closer_than_the_gap(gap):
    from igl_heatseg.parameterization.outline_pack import gutter_structure

    S = gutter_structure(gap)
    r = S.shape[0] // 2
    big = r + 3
    d = np.maximum(np.abs(np.arange(-big, big + 1)) - 1, 0)
    want = np.hypot(d[:, None], d[None, :]) < gap  # distance between the pixel squares
    want[big, big] = True
    got = np.zeros_like(want)
    got[big - r : big + r + 1, big - r : big + r + 1] = S
    np.testing.assert_array_equal(got, want)
