"""A loose segment across a smooth joint gives its faces to the neighbours they lie on
(``surfaces.loose.absorb_loose``); one across a crease with no neighbour to take its faces is
split there (``surfaces.loose.split_loose``)."""
import igl
import numpy as np
import pytest
from meshes import pipe_bend, plane_into_cylinder

from igl_heatseg.mesh.geometry import face_normals
from igl_heatseg.surfaces.loose import LOOSE_RATIO, absorb_loose, split_loose
from igl_heatseg.surfaces.segment_fit import fit_faces


def _adjacency(F):
    return igl.triangle_triangle_adjacency(F)[0]


def _fits(V, F, labels, tol, FN):
    return {k: fit_faces(V, F, np.flatnonzero(labels == k), tol, FN=FN)
            for k in np.unique(labels).tolist()}


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_a_piece_across_a_pipe_bend_joint_goes_to_the_cylinder_and_the_torus(seed):
    # the tuning pipe elbow's case: a piece, three quarters torus and a quarter cylinder, fits
    # one cylinder within tolerance but looser than the noise, between the straight cylinder's
    # segment and the bend's
    V, F, S = pipe_bend(0.05, seed)
    labels = np.digitize(S, [-4.0, 4.0]).astype(np.int64)
    TT, FN = _adjacency(F), face_normals(V, F)
    tol = 0.15
    fits = _fits(V, F, labels, tol, FN)
    assert fits[1].is_analytic and fits[1].rms > LOOSE_RATIO * max(fits[0].rms, fits[2].rms)
    assert absorb_loose(V, F, labels, fits, tol, TT, FN=FN) == 1
    assert sorted(fits) == [0, 2]
    assert (fits[0].kind, fits[2].kind) == ("cylinder", "torus")
    # the border is at the joint: within one unit of it the two surfaces are less than the noise
    # apart (16 % of the piece's faces go either way there); farther off, under 3 % go astray
    astray = ((S < -2) & (labels == 2)) | ((S > 2) & (labels == 0))
    assert astray.sum() < 0.03 * ((S > -4) & (S < 4)).sum()
    assert max(fits[0].rms, fits[2].rms) < 1.1 * 0.05


def test_segments_at_the_noise_are_left_alone():
    V, F, S = pipe_bend(0.05, 0)
    labels = (S > 0).astype(np.int64)
    TT, FN = _adjacency(F), face_normals(V, F)
    fits = _fits(V, F, labels, 0.15, FN)
    before = labels.copy()
    assert absorb_loose(V, F, labels, fits, 0.15, TT, FN=FN) == 0
    assert (labels == before).all()


def test_a_loose_segment_its_neighbour_reaches_only_at_the_border_stays():
    # the cylinder is noisier than the plane (a worse-scanned region): loose, but the plane
    # reaches only the faces near the tangent join, under LOOSE_TAKE_SHARE of its area
    V, F, S, _ = plane_into_cylinder(0.02, 0)
    rng = np.random.default_rng(5)
    on_cyl = np.unique(F[S > 0.5])
    V[on_cyl] += rng.normal(scale=0.03, size=(len(on_cyl), 3))
    labels = (S > 0).astype(np.int64)
    TT, FN = _adjacency(F), face_normals(V, F)
    fits = _fits(V, F, labels, 0.1, FN)
    fits[2] = fits[3] = fits[0]  # (more segments at the plane's noise level)
    assert fits[1].rms > LOOSE_RATIO * fits[0].rms
    assert absorb_loose(V, F, labels, fits, 0.1, TT, FN=FN) == 0
    assert sorted(np.unique(labels).tolist()) == [0, 1]


def _strip_of_plane(seed, bend_deg=0.0, strip_noise=1.0, sigma=0.02, w=6.0):
    """A 40 x 20 noisy grid (spacing 0.5), bent by ``bend_deg`` at x = 0, its noise
    ``strip_noise`` times larger within ``w`` of it; labels: the two flanks and the strip."""
    x, y = np.meshgrid(np.linspace(-20, 20, 81), np.linspace(0, 20, 41), indexing="ij")
    z = np.tan(np.radians(bend_deg)) * np.clip(x, 0, None)
    V = np.c_[x.ravel(), y.ravel(), z.ravel()]
    scale = np.where(np.abs(V[:, 0]) < w, strip_noise, 1.0)
    V[:, 2] += np.random.default_rng(seed).normal(0, sigma, len(V)) * scale
    i = (np.arange(80)[:, None] * 41 + np.arange(40)).ravel()
    F = np.r_[np.c_[i, i + 41, i + 42], np.c_[i, i + 42, i + 1]]
    xf = V[F].mean(axis=1)[:, 0]
    return V, F, xf, np.digitize(xf, [-w, w]).astype(np.int64)


def _split_strip(labels, V, F, tol=0.05):
    """The strip's fits and ``split_loose`` with refine's region growing as its split."""
    from igl_heatseg.surfaces.refine import grow_regions

    TT, FN = _adjacency(F), face_normals(V, F)
    fits = _fits(V, F, labels, tol, FN)

    def split(faces, t):
        sub = grow_regions(V, F, faces, t, FN, TT)
        parts = [faces[sub == r] for r in range(int(sub.max()) + 1)]
        return parts, [fit_faces(V, F, p, tol, FN=FN) for p in parts]
    before = {k: (s.kind, s.rms) for k, s in fits.items()}
    return before, split_loose(V, F, labels, fits, tol, split), fits


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_a_loose_strip_across_a_crease_is_split_at_it(seed):
    # a 5-degree crease inside one segment: a cylinder explains it within tolerance, at 1.4-1.5
    # times the flanks' RMS; cut near the noise, it falls into the two planes
    V, F, xf, labels = _strip_of_plane(seed, bend_deg=5.0)
    before, n, fits = _split_strip(labels, V, F)
    assert before[1][0] == "cylinder" and before[1][1] > LOOSE_RATIO * before[0][1]
    assert n == 1
    strip = np.abs(xf) < 6
    pieces = np.unique(labels[strip])
    assert len(pieces) == 2 and all(fits[k].kind == "plane" for k in pieces)
    left = labels[strip & (xf < -1)]
    right = labels[strip & (xf > 1)]
    assert len(np.unique(left)) == 1 and len(np.unique(right)) == 1 and left[0] != right[0]


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_a_noisier_patch_of_one_plane_is_not_split(seed):
    # the strip fits its plane at 1.7-1.8 times the flanks' RMS because it is noisier, not bent:
    # its pieces fit no better, and it stays whole
    V, F, _, labels = _strip_of_plane(seed, strip_noise=1.7)
    start = labels.copy()
    before, n, fits = _split_strip(labels, V, F)
    assert before[1][0] == "plane" and before[1][1] > LOOSE_RATIO * before[0][1]
    assert n == 0 and (labels == start).all() and sorted(fits) == [0, 1, 2]
