"""Tests for the chart maps of igl_heatseg.parameterization: Hessian eigenmaps, Gram correction,
fallbacks, distortion."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from igl_heatseg.errors import MeshError
from igl_heatseg.parameterization.chart import HLLE_SKIP_CURVATURE, parameterize_chart
from igl_heatseg.parameterization.distortion import distortion
from igl_heatseg.parameterization.eigenmap import gram_correction
from igl_heatseg.parameterization.fallback import mean_value_laplacian, repair_map, tutte_map
from igl_heatseg.parameterization.methods import METHODS, compare_methods, map_chart
from igl_heatseg.parameterization.prepare import (
    certify_oriented,
    limit_blas_threads,
    total_abs_curvature,
)

#: Edge lengths of a flat chart after the Gram correction (issue 3: 1e-8).
ISOMETRY_TOL = 1e-8
#: Rigid-motion fit of a cylinder patch's map to its developed rectangle, relative to its size.
RECT_TOL_CURVED = 1e-8
RECT_TOL_HLLE = 1e-8  # intrinsic local coordinates (the default)
#: The same with the paper's tangent-plane projection (O(h^2) metric error).
RECT_TOL_HLLE_PROJECTION = 1e-2


def grid(nx, ny, sx=1.0, sy=1.0, jitter=0.0, seed=0):
    x, y = np.meshgrid(np.linspace(0, sx, nx + 1), np.linspace(0, sy, ny + 1), indexing="ij")
    V = np.c_[x.ravel(), y.ravel(), np.zeros(x.size)]
    idx = np.arange(V.shape[0]).reshape(nx + 1, ny + 1)
    if jitter:
        inner = idx[1:-1, 1:-1].ravel()
        rng = np.random.default_rng(seed)
        V[inner, :2] += rng.uniform(-jitter, jitter, (len(inner), 2)) * min(sx / nx, sy / ny)
    a, b = idx[:-1, :-1].ravel(), idx[1:, :-1].ravel()
    c, d = idx[1:, 1:].ravel(), idx[:-1, 1:].ravel()
    return V, np.r_[np.c_[a, b, c], np.c_[a, c, d]]


def cylinder_patch(nu, nv, angle=np.pi, r=1.0, h=2.0):
    """A rectangle of a cylinder, already cut open (a disk), and its developed rectangle."""
    V, F = grid(nu, nv)
    th = V[:, 0] * angle
    V3 = np.c_[r * np.cos(th), r * np.sin(th), V[:, 1] * h]
    chord = 2 * r * np.sin(angle / nu / 2)  # the polyhedral surface develops along chords
    return V3, F, np.c_[V[:, 0] * nu * chord, V[:, 1] * h]


def sphere_cap(theta_max, nr=12, nt=32):
    """Polar-grid spherical cap of the unit sphere, from the pole to polar angle theta_max."""
    th = np.linspace(0, theta_max, nr + 1)[1:]
    ph = np.linspace(0, 2 * np.pi, nt, endpoint=False)
    T, P = np.meshgrid(th, ph, indexing="ij")
    ring = np.stack([np.sin(T) * np.cos(P), np.sin(T) * np.sin(P), np.cos(T)], -1).reshape(-1, 3)
    V = np.r_[[[0.0, 0.0, 1.0]], ring]
    F = [[0, 1 + j, 1 + (j + 1) % nt] for j in range(nt)]
    for i in range(nr - 1):
        for j in range(nt):
            a, b = 1 + i * nt + j, 1 + i * nt + (j + 1) % nt
            F += [[a, a + nt, b + nt], [a, b + nt, b]]
    return V, np.array(F)


def edge_lengths(X, F):
    E = np.unique(np.sort(np.r_[F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]], axis=1), axis=0)
    return np.linalg.norm(X[E[:, 1]] - X[E[:, 0]], axis=1)


def rigid_fit_error(UV, T):
    """Max deviation after the best rotation (+ reflection) and translation."""
    A = UV - UV.mean(0)
    B = T - T.mean(0)
    U, _, Wt = np.linalg.svd(A.T @ B)
    return np.abs(A @ (U @ Wt) - B).max()


# ------------------------------------------------------------------------------------------
# analytic cases


@pytest.mark.parametrize("energy", ["hlle", "curved"])
def test_flat_grid_maps_isometrically(energy):
    V, F = grid(14, 9, sx=3.0, sy=1.5, jitter=0.3)
    V = V @ np.array([[0.8, 0.0, 0.6], [0.0, 1.0, 0.0], [-0.6, 0.0, 0.8]])  # tilted plane
    res = parameterize_chart(V, F, energy)
    assert res.method == f"hessian-{energy}"
    assert res.bijective and not res.fallback_used
    assert np.abs(edge_lengths(res.UV, F) - edge_lengths(V, F)).max() < ISOMETRY_TOL
    assert res.distortion["sym_dirichlet"] == pytest.approx(4.0, abs=1e-8)
    assert res.distortion["conformal_max"] == pytest.approx(1.0, abs=1e-8)
    assert not res.certificate.mirrored


@pytest.mark.parametrize("energy,tol", [("curved", RECT_TOL_CURVED), ("hlle", RECT_TOL_HLLE)])
def test_cylinder_patch_maps_to_rectangle(energy, tol):
    V, F, T = cylinder_patch(36, 16)
    res = parameterize_chart(V, F, energy)
    assert res.method == f"hessian-{energy}" and res.bijective
    size = np.ptp(T, axis=0).max()
    assert rigid_fit_error(res.UV, T) < tol * size


def test_cylinder_patch_projection_coordinates_are_approximate():
    V, F, T = cylinder_patch(36, 16)
    res = parameterize_chart(V, F, "hlle", coords="projection")
    err = rigid_fit_error(res.UV, T) / np.ptp(T, axis=0).max()
    assert res.bijective
    assert RECT_TOL_HLLE < err < RECT_TOL_HLLE_PROJECTION


@pytest.mark.parametrize("energy", ["hlle", "curved"])
def test_folded_sheet_unfolds_isometrically(energy):
    """A developable chart with a 90-degree crease maps to the flat sheet."""
    V, F = grid(12, 8)
    x = V[:, 0]
    V3 = np.c_[np.minimum(x, 0.5), V[:, 1], np.maximum(x - 0.5, 0.0)]
    res = parameterize_chart(V3, F, energy)
    assert res.method == f"hessian-{energy}" and res.bijective
    assert np.abs(edge_lengths(res.UV, F) - edge_lengths(V3, F)).max() < ISOMETRY_TOL
    assert rigid_fit_error(res.UV, V[:, :2]) < ISOMETRY_TOL


def test_gram_correction_undoes_an_affine_map():
    V, F = grid(5, 4, jitter=0.3)
    A = np.array([[2.0, 0.7], [-0.3, 0.5]])
    Y = V[:, :2] @ A + [3.0, -1.0]
    UV, G = gram_correction(Y, V, F)
    assert np.allclose(G, np.linalg.inv(A.T @ A), atol=1e-10)  # rows: d_Y = d_X A
    assert np.abs(edge_lengths(UV, F) - edge_lengths(V, F)).max() < ISOMETRY_TOL


def test_mirror_image_is_turned_over_not_flipped():
    V, F = grid(6, 6)
    res = map_chart(V, F, "tutte")
    assert res.bijective and res.flips == 0
    # the stored map is counter-clockwise
    assert not res.certificate.mirrored
    res2 = map_chart(V[:, [1, 0, 2]], F, "tutte")  # input mirrored: triangles run clockwise
    assert res2.bijective and res2.flips == 0 and not res2.certificate.mirrored


@pytest.mark.parametrize("nf", [1, 2, 3])
@pytest.mark.parametrize("energy", ["hlle", "curved"])
def test_tiny_charts(nf, energy):
    th = np.linspace(0.0, 2.0, 4)
    V = np.r_[[[0.0, 0.0, 0.0]], np.c_[np.cos(th), np.sin(th), 0.1 * np.ones(4)]]
    F = np.array([[0, 1, 2], [0, 2, 3], [0, 3, 4]])[:nf]
    res = parameterize_chart(V[: nf + 2], F, energy)
    assert res.bijective
    assert np.isfinite(res.UV).all()
    if nf == 1:  # a single triangle is laid out exactly
        assert np.allclose(edge_lengths(res.UV, F), edge_lengths(V, F), atol=1e-12)


def test_fallback_on_non_bijective_hessian_map():
    """A cap covering more than a hemisphere folds in both Hessian maps; the fallback is
    bijective and recorded."""
    V, F = sphere_cap(2.4)
    res = parameterize_chart(V, F, "hlle")
    assert res.fallback_used
    assert res.method in ("tutte", "tutte+slim")
    assert res.bijective
    first = res.attempts[0]
    assert first["method"] == "hessian-hlle" and not first["bijective"]
    assert first["flips"] > 0
    # (a repair may be tried first: the cap's two coordinate eigenvalues are degenerate, so
    # which HLLE map comes out depends on the eigen-solver; it is never kept here)
    methods = [a["method"] for a in res.attempts]
    assert "tutte" in methods
    assert all(not a["kept"] for a in res.attempts if a["method"].endswith("+repair"))
    # No fallback: the flagged Hessian map is returned as is.
    raw = parameterize_chart(V, F, "hlle", fallback="none")
    assert raw.method == "hessian-hlle" and not raw.bijective and raw.flips > 0


def test_repair_untangles_a_local_fold():
    """Mean value weights reproduce linear maps, so repairing a fold in an isometric map of a
    flat grid restores the isometry exactly."""
    from igl_heatseg.parameterization.bijectivity import certify_map

    V, F = grid(6, 6, jitter=0.25, seed=1)
    UV = V[:, :2].copy()
    centre = 3 * 7 + 3
    UV[centre] += [0.4, 0.3]  # across its one-ring: local flips
    cert = certify_map(UV, F)
    assert cert.flips > 0 and cert.overlaps == 0
    UVr, cert_r, rounds = repair_map(UV, V, F, cert)
    assert cert_r.bijective and rounds >= 1
    assert np.abs(UVr - V[:, :2]).max() < 1e-12
    # Nothing to do on a bijective map; overlaps are not repaired.
    same, _, r0 = repair_map(V[:, :2], V, F, certify_map(V[:, :2], F))
    assert r0 == 0 and np.array_equal(same, V[:, :2])


def test_auto_energy_tries_hlle_then_curved():
    V, F = grid(6, 5, jitter=0.2)
    res = parameterize_chart(V, F, "auto")
    assert res.method == "hessian-hlle" and [a["method"] for a in res.attempts] == ["hessian-hlle"]
    V, F = sphere_cap(2.4)
    res = parameterize_chart(V, F, "auto")
    assert [a["method"] for a in res.attempts][:2] == ["hessian-hlle", "hessian-curved"]
    assert res.bijective and res.fallback_used


def noisy_grid(n=24, noise=0.3, seed=2):
    """A flat grid with normal noise (a scan-like chart): large total absolute curvature."""
    V, F = grid(n, n)
    V[:, 2] = np.random.default_rng(seed).normal(0.0, noise / n, V.shape[0])
    return V, F


def test_total_abs_curvature():
    V, F = grid(6, 5, jitter=0.2)
    assert total_abs_curvature(V, F) < 1e-12
    V, F, _ = cylinder_patch(8, 4)
    assert total_abs_curvature(V, F) < 1e-9  # developable
    a = 1.0
    V, F = sphere_cap(a, nr=24, nt=64)
    # Gauss-Bonnet: the interior angle defects sum to ~ the cap's area 2 pi (1 - cos a)
    assert total_abs_curvature(V, F) == pytest.approx(2 * np.pi * (1 - np.cos(a)), rel=0.05)
    assert total_abs_curvature(*noisy_grid()) > HLLE_SKIP_CURVATURE


def test_auto_energy_skips_hlle_on_scan_like_charts():
    V, F = noisy_grid()
    res = parameterize_chart(V, F, "auto")
    first = res.attempts[0]
    assert first["method"] == "hessian-hlle" and first["skipped"] and not first["bijective"]
    assert first["total_abs_curvature"] > HLLE_SKIP_CURVATURE and "reason" in first
    assert res.attempts[1]["method"] == "hessian-curved"
    assert res.bijective
    # never skipped when asked for HLLE, or with the test turned off
    res = parameterize_chart(V, F, "hlle")
    assert "skipped" not in res.attempts[0]
    res = parameterize_chart(V, F, "auto", hlle_skip_curvature=None)
    assert "skipped" not in res.attempts[0] and res.attempts[0]["method"] == "hessian-hlle"
    # flat and developable charts keep HLLE (curvature recorded)
    res = parameterize_chart(*grid(6, 5, jitter=0.2), "auto")
    assert res.method == "hessian-hlle" and res.attempts[0]["total_abs_curvature"] < 1e-9


def test_mirrored_certificate_is_the_recomputed_one():
    """certify_oriented turns a mirror image over without certifying it again: same
    certificate."""
    from igl_heatseg.parameterization.bijectivity import certify_map

    V, F = sphere_cap(2.4)
    for UV in (tutte_map(V, F), map_chart(V, F, "hessian-hlle", name="c").UV):
        M = UV * [-1.0, 1.0]
        assert certify_map(M, F).mirrored
        UVf, cert = certify_oriented(M, V, F, "c")
        ref = certify_map(UVf, F)
        assert not cert.mirrored and cert.orientation == 1
        assert cert.summary() == ref.summary()
        for key in ("flipped_faces", "degenerate_faces", "overlap_edges", "wound_vertices"):
            assert np.array_equal(getattr(cert, key), getattr(ref, key))


def test_slim_fallback_records_its_iterations():
    V, F = sphere_cap(2.4)
    res = parameterize_chart(V, F, "curved")
    slim = [a for a in res.attempts if a["method"].startswith("tutte+slim")]
    assert slim and slim[0]["method"] == "tutte+slim"
    assert 0 <= slim[0]["accepted_iterations"] <= 30
    assert slim[0]["bijective_iterations"] <= 30
    # the fixed-boundary variant only when no free-boundary iterate is bijective
    assert (len(slim) == 2) == (slim[0]["accepted_iterations"] == 0)
    assert res.bijective


def test_limit_blas_threads_restores_the_thread_count():
    from threadpoolctl import threadpool_info

    def blas_threads():
        return [d["num_threads"] for d in threadpool_info() if d["user_api"] == "blas"]

    before = blas_threads()
    assert before  # numpy's BLAS is found
    with limit_blas_threads(1):
        assert all(n == 1 for n in blas_threads())
    assert blas_threads() == before
    with limit_blas_threads(None):
        assert blas_threads() == before


@pytest.mark.parametrize("weights", ["mean_value", "uniform"])
def test_tutte_is_bijective_on_bad_triangles(weights):
    from igl_heatseg.parameterization.bijectivity import certify_map

    V, F = grid(10, 10, jitter=0.45, seed=3)
    V[:, 2] = np.sin(5 * V[:, 0]) * 0.5
    UV = tutte_map(V, F, weights=weights)
    assert certify_map(UV, F).bijective
    # Boundary on the unit circle.
    from igl_heatseg.mesh.topology import boundary_loops

    assert np.allclose(np.linalg.norm(UV[boundary_loops(F)[0]], axis=1), 1.0)


def test_mean_value_tutte_reproduces_flat_interior():
    """Mean value weights have linear precision: with the boundary at its own positions a flat
    chart's interior comes back exactly (uniform weights do not on a jittered grid)."""
    V, F = grid(8, 8, jitter=0.3, seed=2)
    L = mean_value_laplacian(V, F)
    from igl_heatseg.mesh.topology import boundary_loops

    bnd = boundary_loops(F)[0]
    inner = np.setdiff1d(np.arange(len(V)), bnd)
    assert np.abs((L @ V[:, :2])[inner]).max() < 1e-12


def test_unreferenced_vertices_get_nan():
    V, F = grid(3, 3)
    V = np.r_[V, [[9.0, 9.0, 9.0]]]
    res = parameterize_chart(V, F)
    assert np.isnan(res.UV[-1]).all() and np.isfinite(res.UV[:-1]).all()


# ------------------------------------------------------------------------------------------
# distortion


def test_distortion_of_known_maps():
    V, F = grid(4, 4, jitter=0.2)
    ident = distortion(V, F, V[:, :2])
    assert ident["conformal_mean"] == pytest.approx(1.0)
    assert ident["area_max"] == pytest.approx(1.0)
    assert ident["sym_dirichlet"] == pytest.approx(4.0)
    assert ident["stretch_max"] == pytest.approx(1.0)
    # Uniform scaling is normalised away.
    assert distortion(V, F, 7.0 * V[:, :2])["sym_dirichlet"] == pytest.approx(4.0)
    # Stretch (2, 1): after area normalisation s = (sqrt 2, 1/sqrt 2).
    d = distortion(V, F, V[:, :2] * [2.0, 1.0])
    assert d["conformal_mean"] == pytest.approx(2.0)
    assert d["conformal_max"] == pytest.approx(2.0)
    assert d["area_mean"] == pytest.approx(1.0)
    assert d["sym_dirichlet"] == pytest.approx(2.0 + 0.5 + 0.5 + 2.0)
    assert d["stretch_max"] == pytest.approx(np.sqrt(2.0))
    # Non-uniform area: left half scaled by 2 along x, right half not -> area ratio varies.
    UV = V[:, :2].copy()
    UV[:, 0] = np.where(UV[:, 0] < 0.5, 2 * UV[:, 0], UV[:, 0] + 0.5)
    d = distortion(V, F, UV)
    assert d["area_max"] > 1.2


def test_degenerate_map_has_infinite_distortion():
    V, F = grid(2, 2)
    UV = V[:, :2].copy()
    UV[:, 1] = 0.0
    UV[0] = [0.0, 1.0]  # keep some area so that normalisation is defined
    d = distortion(V, F, UV)
    assert np.isinf(d["conformal_max"]) and np.isinf(d["sym_dirichlet"])


# ------------------------------------------------------------------------------------------
# baselines and comparison


def test_all_methods_run_through_the_certificate():
    V, F, _ = cylinder_patch(12, 6)
    rows = compare_methods([("cyl", V, F)], methods=METHODS)
    assert [r["method"] for r in rows] == list(METHODS)
    for r in rows:
        assert "error" not in r, r
        assert r["faces"] == len(F)
        assert r["bijective"] in (True, False)
        assert r["sym_dirichlet"] >= 4.0 - 1e-9
    by = {r["method"]: r for r in rows}
    # On a developable chart the Hessian maps are isometric, harmonic (circle) is not.
    assert by["hessian-curved"]["sym_dirichlet"] == pytest.approx(4.0, abs=1e-6)
    assert by["hessian-hlle"]["sym_dirichlet"] == pytest.approx(4.0, abs=1e-4)
    assert by["harmonic"]["sym_dirichlet"] > 4.5
    assert by["tutte"]["bijective"]


# ------------------------------------------------------------------------------------------
# input errors


def test_non_disk_charts_are_rejected():
    # annulus: a full cylinder without caps
    V, F, _ = cylinder_patch(12, 4, angle=2 * np.pi)
    n = 13
    # weld the seam: vertex i*(nv+1)+j with i == nu equals i == 0
    ids = np.arange(len(V)).reshape(n, 5)
    weld = np.arange(len(V))
    weld[ids[-1]] = ids[0]
    F2 = weld[F]
    with pytest.raises(MeshError, match="disk"):
        parameterize_chart(V, F2)
    # two components
    Vg, Fg = grid(2, 2)
    with pytest.raises(MeshError, match="disk"):
        parameterize_chart(np.r_[Vg, Vg + 5], np.r_[Fg, Fg + len(Vg)])


def test_bad_arguments_raise():
    V, F = grid(3, 3)
    with pytest.raises(MeshError, match="energy"):
        parameterize_chart(V, F, "biharmonic")
    with pytest.raises(MeshError, match="fallback"):
        parameterize_chart(V, F, fallback="arap")
    with pytest.raises(MeshError, match="method"):
        map_chart(V, F, "magic")
    with pytest.raises(MeshError, match="shape"):
        parameterize_chart(V[:, :2], F)
    with pytest.raises(MeshError, match="outside"):
        parameterize_chart(V, F + 100)


# ------------------------------------------------------------------------------------------
# a real mesh


@pytest.mark.slow
def test_fandisk_charts_are_all_bijective(fandisk):
    """Segment fandisk, cut every chart to a disk, parameterize: every chart bijective."""
    from igl_heatseg.parameterization.cut import cut_to_disk
    from igl_heatseg.segmentation.paper import segment_mesh

    seg = segment_mesh(fandisk)
    k = int(seg.labels.max()) + 1
    assert k >= 5
    n_fallback = 0
    for c in range(k):
        faces = np.flatnonzero(seg.labels == c)
        cut = cut_to_disk(fandisk.V, fandisk.F[faces], name=f"chart {c}")
        res = parameterize_chart(cut.V, cut.F, "hlle", name=f"chart {c}")
        assert res.bijective, (c, res.attempts)
        n_fallback += res.fallback_used
    assert n_fallback < k  # most charts keep their Hessian map


def test_quality_choice_keeps_the_lowest_energy_bijective_map():
    """A deep spherical cap: the Hessian map is bijective but stretched; SLIM from it (or
    Tutte + SLIM) is kept when it is lower by more than the margin, and scaled to true area."""
    from igl_heatseg.parameterization.chart import HESSIAN_MARGIN

    V, F = sphere_cap(1.6, nr=10, nt=28)
    first = parameterize_chart(V, F, "curved", choose="first")
    best = parameterize_chart(V, F, "curved")
    assert best.bijective
    energies = [
        a["sym_dirichlet"] for a in best.attempts if a.get("bijective") and "sym_dirichlet" in a
    ]
    assert best.distortion["sym_dirichlet"] == pytest.approx(min(energies), rel=1e-9) or (
        best.method.startswith("hessian-")
        and best.distortion["sym_dirichlet"] <= HESSIAN_MARGIN * min(energies)
    )
    assert best.distortion["sym_dirichlet"] <= first.distortion["sym_dirichlet"] + 1e-12
    a3 = 0.5 * np.linalg.norm(np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]]), axis=1)
    d1, d2 = best.UV[F[:, 1]] - best.UV[F[:, 0]], best.UV[F[:, 2]] - best.UV[F[:, 0]]
    auv = 0.5 * np.abs(d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0])
    assert auv.sum() == pytest.approx(a3.sum(), rel=1e-9)  # true scale


def test_near_isometric_hessian_map_is_kept_without_alternatives():
    V, F = grid(6, 5, jitter=0.2)
    res = parameterize_chart(V, F)
    assert res.method == "hessian-hlle"
    assert [a["method"] for a in res.attempts] == ["hessian-hlle"]


def test_start_map_is_a_candidate():
    V, F = sphere_cap(1.6, nr=10, nt=28)
    ref = parameterize_chart(V, F, "curved")
    res = parameterize_chart(V, F, "curved", start_uv=ref.UV)
    assert any(a["method"] == "start" and a["bijective"] for a in res.attempts)
    assert res.distortion["sym_dirichlet"] <= ref.distortion["sym_dirichlet"] * (1 + 1e-9)


def test_split_for_distortion_lowers_the_energy_of_a_strongly_curved_chart():
    from igl_heatseg.parameterization.cut import cut_to_disk
    from igl_heatseg.parameterization.split import parameterize_pieces, split_for_distortion

    V, F = sphere_cap(2.6, nr=14, nt=32)  # most of a sphere
    res = cut_to_disk(V, F)

    def param(Vp, Fp, name, start):
        return parameterize_chart(Vp, Fp, "curved", start_uv=start, name=name)

    whole = param(res.V, res.F, "c", None)
    pieces = split_for_distortion(res.V, res.F, whole.UV)
    assert pieces is not None and len(pieces) == 2
    assert np.array_equal(np.sort(np.concatenate(pieces)), np.arange(len(res.F)))
    out = parameterize_pieces(res, param, sd_max=4.5)
    assert len(out) >= 2 and all(q.bijective for _, _, q in out)
    rows = np.sort(np.concatenate([r for r, _, _ in out]))
    assert np.array_equal(rows, np.arange(len(res.F)))
    area = np.array([len(r) for r, _, _ in out], dtype=float)
    mean = sum(q.distortion["sym_dirichlet"] * a for (_, _, q), a in zip(out, area, strict=True))
    assert mean / area.sum() < whole.distortion["sym_dirichlet"]


def test_split_for_distortion_halves_a_chart_without_interior_vertices():
    """A coarse export's chart (a strip: every vertex on its boundary) has no seam through
    an interior vertex; it is halved into two disks instead (before: no split)."""
    from igl_heatseg.parameterization.cut import chart_topology
    from igl_heatseg.parameterization.split import split_for_distortion

    # a strip of 16 triangles bent along a half circle (no interior vertex)
    t = np.linspace(0, np.pi, 9)
    top = np.c_[np.cos(t), np.sin(t), np.full(9, 0.4)]
    bot = np.c_[np.cos(t), np.sin(t), np.zeros(9)]
    V = np.vstack([bot, top])
    F = np.array([f for i in range(8) for f in ([i, i + 1, 10 + i], [i, 10 + i, 9 + i])])
    # a map squeezing the right half: far from isometric, still bijective
    s = np.r_[0, np.cumsum(np.linalg.norm(np.diff(bot, axis=0), axis=1))]
    s = np.where(s > s[-1] / 2, s[-1] / 2 + 0.1 * (s - s[-1] / 2), s)
    UV = np.c_[np.r_[s, s], np.r_[np.zeros(9), np.full(9, 0.4)]]
    pieces = split_for_distortion(V, F, UV)
    assert pieces is not None and len(pieces) == 2
    assert np.array_equal(np.sort(np.concatenate(pieces)), np.arange(len(F)))
    assert all(chart_topology(F[p]).is_disk for p in pieces)


def _strip(n: int = 40, w: int = 2):
    """A flat n x w strip of unit squares (two triangles each), as 3D points and faces."""
    x, y = np.meshgrid(np.arange(n + 1.0), np.arange(w + 1.0))
    V = np.stack([x.ravel(), y.ravel(), 0 * x.ravel()], 1)
    i = np.arange((w + 1) * (n + 1)).reshape(w + 1, n + 1)[:-1, :-1].ravel()
    F = np.concatenate([np.stack([i, i + 1, i + n + 2], 1), np.stack([i, i + n + 2, i + n + 1], 1)])
    return V, F


def test_long_chart_of_any_size_is_cut_for_packing_into_pieces_no_longer_than_the_bound():
    """A strip too small for the aspect-ratio rule is still cut when it is longer than the
    bound (a long chart sets the side of a square atlas); the bound is in 3D units, whatever
    the scale of the map."""
    from igl_heatseg.parameterization.cut import chart_topology, cut_to_disk
    from igl_heatseg.parameterization.split import cut_for_packing, split_for_packing

    V, F = _strip(40, 2)
    UV = V[:, :2]
    assert split_for_packing(UV, F, big=False) is None
    for bound in (7.0, 12.0, 25.0):
        pieces = split_for_packing(UV, F, big=False, max_length=bound)
        assert len(pieces) == int(np.ceil(40 / bound))
        assert np.array_equal(np.sort(np.concatenate(pieces)), np.arange(len(F)))
        for p in pieces:
            assert chart_topology(F[p]).is_disk
            assert np.ptp(UV[np.unique(F[p]), 0]) <= bound + 1  # one column of slack
    res = cut_to_disk(V, F)
    param = parameterize_chart(res.V, res.F)
    scaled = dataclasses.replace(param, UV=param.UV * 1e3)
    for q in (param, scaled):
        out = cut_for_packing(res, q, max_length=12.0, big=False)
        assert len(out) == 4 and all(piece.bijective for _, _, piece in out)


def _thin_ring_cut_open(n: int = 24, r: float = 10.0, w: float = 1.0, turn: float = 330.0):
    """A flat annulus band of one row (``n`` quads over ``turn`` degrees, two triangles each),
    radii ``r`` to ``r + w``: a thread flank's cone ring cut open, as its map lays it out."""
    t = np.radians(np.linspace(0.0, turn, n + 1))
    V = np.r_[np.c_[r * np.cos(t), r * np.sin(t), 0 * t],
              np.c_[(r + w) * np.cos(t), (r + w) * np.sin(t), 0 * t]]
    j = np.arange(n)
    F = np.r_[np.c_[j, j + 1, n + 2 + j], np.c_[j, n + 2 + j, n + 1 + j]].astype(np.int64)
    return V, F


def test_a_thin_c_shaped_chart_of_few_faces_is_halved_for_packing_into_arcs():
    """A thin ring cut open fills 0.12 of its rectangle. The box-fill rule halves it while
    that helps; with the default size guard (40 faces) its 48 faces are halved once, with the
    pipeline's last trial's (``PACK_HALVE_MIN_FACES``) into arcs that fill their rectangles
    (a coarse clean bolt's 12 thread flanks: the atlas from 0.466 to 0.717)."""
    from igl_heatseg.mesh.geometry import uv_areas
    from igl_heatseg.parameterization.atlas import min_area_rotation, rotate_points
    from igl_heatseg.parameterization.cut import chart_topology, cut_to_disk
    from igl_heatseg.parameterization.split import (
        PACK_HALVE_MIN_FACES,
        cut_for_packing,
        split_for_packing,
    )

    def box_fill(UV, F):  # the share of its minimum-area rectangle a piece fills
        P = UV[np.unique(F)]
        ext = np.ptp(rotate_points(P, min_area_rotation(P)), axis=0)
        return float(np.abs(uv_areas(UV, F)).sum() / (ext[0] * ext[1]))

    V, F = _thin_ring_cut_open()
    UV = V[:, :2]
    whole = box_fill(UV, F)
    assert whole < 0.15
    few = split_for_packing(UV, F, np.inf, big=True)
    arcs = split_for_packing(UV, F, np.inf, big=True, min_faces=PACK_HALVE_MIN_FACES)
    assert len(few) == 2 and len(arcs) >= 8
    assert np.array_equal(np.sort(np.concatenate(arcs)), np.arange(len(F)))
    for p in arcs:
        assert chart_topology(F[p]).is_disk
        assert box_fill(UV, F[p]) > 3 * whole
    res = cut_to_disk(V, F)
    out = cut_for_packing(res, parameterize_chart(res.V, res.F), max_aspect=np.inf,
                          min_faces=PACK_HALVE_MIN_FACES)
    assert len(out) == len(arcs) and all(q.bijective for *_, q in out)


def test_a_strip_with_holes_is_sliced_through_its_holes(data_dir):
    """The side of a dimpled knob cut open (f20 knob_s20019_irregular_n0, robust mode: a
    strip 217 x 29 with a row of dimples, whose map is shipped): every equal slice held a
    dimple as a hole, so it was never cut, and its atlas filled 0.430. Cuts moved through the
    dimples give disks (a slice the seam between two dimples cuts lengthwise is two)."""
    from igl_heatseg.parameterization.cut import chart_topology
    from igl_heatseg.parameterization.split import split_for_packing

    d = np.load(data_dir / "strip_with_dimples.npz")
    UV, F = d["UV"], d["F"].astype(np.int64)
    assert chart_topology(F).is_disk
    length = np.ptp(UV, axis=0).max()
    for n in (2, 3, 4):
        assert split_for_packing(UV, F, big=False, max_length=1.01 * length / n) is None
        pieces = split_for_packing(UV, F, big=False, max_length=1.01 * length / n, shift=True)
        assert pieces is not None and len(pieces) >= n
        assert np.array_equal(np.sort(np.concatenate(pieces)), np.arange(len(F)))
        assert all(chart_topology(F[p]).is_disk for p in pieces)


def test_no_piece_is_cut_for_packing_more_stretched_than_the_bound_and_its_chart():
    """A strip 40 long whose map is stretched 2.5 times along its last 4 units: the chart as
    a whole meets the per-chart bound (5), the end piece alone does not; it joins the piece
    next to it (unless the bound is raised), as for spikes peeled (:func:`peel_for_packing`)."""
    from igl_heatseg.parameterization.cut import chart_topology, cut_to_disk
    from igl_heatseg.parameterization.distortion import distortion
    from igl_heatseg.parameterization.split import cut_for_packing

    V, F = _strip(40, 2)
    res = cut_to_disk(V, F)
    param = parameterize_chart(res.V, res.F)
    UV = res.V[:, :2].copy()  # the flat strip's isometric map, its end stretched
    end = UV[:, 0] > 36
    UV[end, 0] = 36 + 2.5 * (UV[end, 0] - 36)
    stretched = dataclasses.replace(param, UV=UV, distortion=distortion(res.V, res.F, UV))
    assert stretched.distortion["sym_dirichlet"] < 5
    out = cut_for_packing(res, stretched, max_length=12.0, big=False, sd_max=np.inf)
    assert len(out) == 4
    assert max(q.distortion["sym_dirichlet"] for *_, q in out) > 5
    out = cut_for_packing(res, stretched, max_length=12.0, big=False)
    assert len(out) == 3 and max(q.distortion["sym_dirichlet"] for *_, q in out) < 5
    assert np.array_equal(np.sort(np.concatenate([f for f, _, _ in out])), np.arange(len(F)))
    far = out[-1][0]  # the end piece and its neighbour: one disk
    assert chart_topology(F[far]).is_disk and all(q.bijective for *_, q in out)
    assert np.isin(np.flatnonzero(V[F].mean(axis=1)[:, 0] > 36), far).all()
    assert len(cut_for_packing(res, param, max_length=12.0, big=False)) == 4


def test_cad_gets_the_map_of_a_chart_cut_for_packing_put_together_again():
    """Pieces cut for packing keep their chart's map: CAD's freeform fit gets that map whole;
    pieces mapped separately (cut for distortion) give no chart."""
    from igl_heatseg.cad.segments import chart_uvs
    from igl_heatseg.parameterization.cut import cut_to_disk
    from igl_heatseg.parameterization.split import cut_for_packing, restrict_cut
    from igl_heatseg.pipeline.results import Chart
    from igl_heatseg.surfaces.model import Surface

    V, F = _strip(40, 2)
    res = cut_to_disk(V, F)
    param = parameterize_chart(res.V, res.F)
    out = cut_for_packing(res, param, max_length=12.0, big=False)
    charts = [Chart(id=i, segment=0, faces=rows, split_from=0, cut=sub, param=q)
              for i, (rows, sub, q) in enumerate(out)]
    free = [Surface("freeform", {"centroid": V.mean(axis=0)})]
    ids, UV = chart_uvs(np.zeros(len(F), np.int64), free, charts)[0]
    used = np.unique(res.F)
    order = np.argsort(res.vertex_map[used])
    assert np.array_equal(ids, res.vertex_map[used][order])
    assert np.array_equal(UV, param.UV[used][order])
    # two halves with maps of their own: no chart for the segment
    half = V[F].mean(axis=1)[:, 0] < 20
    own = []
    for rows in (np.flatnonzero(half), np.flatnonzero(~half)):
        sub = restrict_cut(res, rows)
        own.append(Chart(id=len(own), segment=0, faces=rows, split_from=0, cut=sub,
                         param=parameterize_chart(sub.V, sub.F)))
    assert chart_uvs(np.zeros(len(F), np.int64), free, own) is None


def test_split_for_distortion_finds_an_uneven_halving_when_no_even_one_is_a_disk():
    """A coarse chart (36 faces, 2 interior vertices; a piece of a generated domed cap's
    chart, its map rounded) that no straight line or grown piece halves evenly into two disks:
    the evenest split into two disks is taken (before: none; the chart kept an energy of 16)."""
    from igl_heatseg.parameterization.cut import chart_topology
    from igl_heatseg.parameterization.split import split_for_distortion

    F = np.array([0, 11, 10, 1, 12, 11, 2, 13, 12, 3, 14, 13, 4, 15, 14, 5, 16, 15, 6, 17, 16,
                  6, 16, 5, 7, 18, 17, 7, 17, 6, 8, 22, 21, 16, 29, 28, 16, 17, 29, 19, 20, 25,
                  18, 29, 17, 21, 25, 20, 15, 16, 28, 22, 26, 25, 22, 25, 21, 14, 15, 28, 23,
                  26, 22, 13, 14, 28, 24, 26, 23, 32, 28, 27, 31, 27, 26, 31, 26, 24, 31, 32,
                  27, 33, 13, 28, 33, 12, 13, 33, 28, 32, 30, 31, 24, 30, 24, 35, 34, 9, 10, 34,
                  10, 11, 34, 11, 12, 34, 12, 33]).reshape(-1, 3)
    UV = np.array([15.9, 0.0, 30.1, 3.9, 39.1, 9.5, 42.5, 13.0, 50.9, 23.6, 53.6, 33.5, 53.8,
                   34.2, 54.1, 35.0, 27.5, 100.0, 12.6, 1.6, 13.9, 2.1, 22.9, 4.4, 31.8, 8.1,
                   39.2, 13.2, 44.5, 19.9, 49.8, 29.3, 51.3, 40.4, 52.0, 40.7, 53.6, 44.5, 52.2,
                   84.2, 51.7, 84.3, 51.2, 84.2, 38.6, 91.5, 37.4, 91.0, 36.7, 90.8, 50.5, 82.7,
                   52.8, 74.1, 52.0, 64.8, 48.3, 55.5, 53.9, 52.8, 20.4, 95.6, 11.5, 95.3, 7.6,
                   92.6, 4.2, 89.1, 0.0, 85.1, 34.8, 91.7]).reshape(-1, 2)
    V = np.c_[UV, np.zeros(len(UV))]
    assert chart_topology(F).is_disk
    pieces = split_for_distortion(V, F, UV)
    assert pieces is not None and len(pieces) == 2
    assert np.array_equal(np.sort(np.concatenate(pieces)), np.arange(len(F)))
    assert all(chart_topology(F[p]).is_disk for p in pieces)
    assert min(map(len, pieces)) >= 0.3 * len(F)


def test_a_tutte_map_that_flips_with_mean_value_weights_is_made_with_uniform_ones(data_dir):
    """Both are bijective in exact arithmetic; on this noisy chart (data/CREDITS.md) the mean
    value map flips 4 triangles, and the chart was left without a bijective map."""
    from igl_heatseg.parameterization.bijectivity import certify_map
    from igl_heatseg.parameterization.fallback import tutte_map

    d = np.load(data_dir / "chart_mean_value_tutte_flips.npz")
    V, F = d["V"], d["F"]
    assert not certify_map(tutte_map(V, F), F).bijective
    assert certify_map(tutte_map(V, F, weights="uniform"), F).bijective
    p = parameterize_chart(V, F)
    assert p.bijective and certify_map(p.UV, F).bijective
    assert any(a["method"] == "tutte" and a["bijective"] for a in p.attempts)


def test_a_chart_with_no_bijective_map_is_split_until_its_pieces_have_one(data_dir):
    """The Tutte maps of this noisy chart (data/CREDITS.md) collapse a region to triangles of
    1e-31 of the circle's area (flips with mean value and with uniform weights) and its
    Hessian maps flip: it had no bijective map. Split along a seam through its most stretched
    region, both halves get one."""
    from igl_heatseg.parameterization.bijectivity import certify_map
    from igl_heatseg.parameterization.cut import cut_to_disk
    from igl_heatseg.parameterization.fallback import tutte_map
    from igl_heatseg.parameterization.split import parameterize_pieces

    d = np.load(data_dir / "chart_tutte_collapses.npz")
    V, F = d["V"], d["F"].astype(np.int64)
    assert not certify_map(tutte_map(V, F, weights="uniform"), F).bijective
    res = cut_to_disk(V, F)

    def param(Vp, Fp, name, start):
        return parameterize_chart(Vp, Fp, name=name, start_uv=start)

    whole = parameterize_pieces(res, param, split_unmapped=False)
    assert len(whole) == 1 and not whole[0][2].bijective
    out = parameterize_pieces(res, param)
    assert len(out) >= 2
    assert np.array_equal(np.sort(np.concatenate([rows for rows, _, _ in out])), np.arange(len(F)))
    for _, piece, q in out:
        assert q.bijective and certify_map(q.UV, piece.F).bijective
        assert q.distortion["sym_dirichlet"] < 6

