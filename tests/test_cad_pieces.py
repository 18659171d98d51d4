"""Freeform segments that are not disks are cut into disk pieces, each a B-spline face."""

from __future__ import annotations

import numpy as np
import pytest

from igl_heatseg.cad.pieces import collapse_status, disk_pieces, is_disk, split_nondisk_freeform
from igl_heatseg.surfaces.model import Surface


def grid_mesh(nu: int, nv: int, point, wrap_u: bool = False):
    """Triangles of a (u, v) grid mapped by ``point(u, v)``; ``wrap_u`` closes it in u."""
    us = np.arange(nu) / nu if wrap_u else np.linspace(0, 1, nu)
    vs = np.linspace(0, 1, nv)
    U, W = np.meshgrid(us, vs, indexing="ij")
    V = np.array([point(u, v) for u, v in zip(U.ravel(), W.ravel(), strict=True)])
    idx = np.arange(nu * nv).reshape(nu, nv)
    cols = nu if wrap_u else nu - 1
    F = []
    for i in range(cols):
        j = (i + 1) % nu
        for k in range(nv - 1):
            a, b, c, d = idx[i, k], idx[j, k], idx[j, k + 1], idx[i, k + 1]
            F += [[a, b, c], [a, c, d]]
    return V, np.array(F, dtype=np.int64)


def wavy_ring(nu=48, nv=8):
    """A flat-ish annulus r in [1, 2] with a bump: a freeform surface with a hole."""
    def p(u, v):
        t, r = 2 * np.pi * u, 1 + v
        return [r * np.cos(t), r * np.sin(t), 0.15 * np.sin(3 * t) * np.sin(np.pi * v)]
    return grid_mesh(nu, nv, p, wrap_u=True)


def test_a_disk_is_one_piece_and_a_ring_two():
    V, F = grid_mesh(6, 5, lambda u, v: [u, v, u * v])
    assert is_disk(F)
    assert [len(p) for p in disk_pieces(V, F, np.arange(len(F)))] == [len(F)]
    V, F = wavy_ring()
    assert not is_disk(F)
    pieces = disk_pieces(V, F, np.arange(len(F)))
    assert len(pieces) == 2 and all(is_disk(F[p]) for p in pieces)
    assert sorted(np.concatenate(pieces).tolist()) == list(range(len(F)))


@pytest.mark.parametrize("length", [0.5, 6.0])
def test_a_tube_short_or_long_becomes_disks(length):
    """A long tube splits along its length first (two tubes), then across: every axis is
    tried and every piece must be a disk."""
    V, F = grid_mesh(32, 12, lambda u, v: [np.cos(2 * np.pi * u), np.sin(2 * np.pi * u),
                                           length * v], wrap_u=True)
    pieces = disk_pieces(V, F, np.arange(len(F)))
    assert pieces is not None and all(is_disk(F[p]) for p in pieces)
    assert sum(len(p) for p in pieces) == len(F)


def test_split_relabels_freeform_only_and_collapse_gives_one_entry_per_segment():
    V, F = wavy_ring()
    plane = grid_mesh(4, 4, lambda u, v: [5 + u, v, 0.0])
    V2, F2 = np.r_[V, plane[0]], np.r_[F, plane[1] + len(V)]
    labels = np.r_[np.zeros(len(F), np.int64), np.ones(len(plane[1]), np.int64)]
    surfs = [Surface("freeform", {"centroid": np.zeros(3)}),
             Surface("plane", {"point": np.array([5.0, 0, 0]), "normal": np.array([0, 0, 1.0])})]
    lab, out, uv, origin = split_nondisk_freeform(V2, F2, labels, surfs)
    assert origin.tolist() == [0, 1, 0] and [s.kind for s in out] == ["freeform", "plane",
                                                                       "freeform"]
    assert set(lab[labels == 1].tolist()) == {1} and set(lab[labels == 0].tolist()) == {0, 2}
    # a segment with a chart is left whole
    assert split_nondisk_freeform(V2, F2, labels, surfs, [([0], [[0, 0]]), None])[3].tolist() \
        == [0, 1]
    st = [dict(index=i, kind=s.kind, status="built", reason=None, max_dev=0.1 * i)
          for i, s in enumerate(out)]
    st[2].update(status="faceted", reason="B-spline fit error 9")
    done = collapse_status(st, origin)
    assert [e["status"] for e in done] == ["faceted", "built"]
    assert done[0]["pieces"] == 2 and "1 of its 2 disk pieces" in done[0]["reason"]


def test_a_freeform_ring_is_built_as_two_bspline_faces():
    pytest.importorskip("OCP")
    from igl_heatseg.cad import build_brep

    V, F = wavy_ring()
    res = build_brep(V, F, np.zeros(len(F), np.int64),
                     [Surface("freeform", {"centroid": np.zeros(3)})])
    assert len(res.faces) == 1
    face = res.faces[0]
    assert face["status"] == "built" and face["built_as"] == "bspline" and face["pieces"] == 2
    fid = res.fidelity
    assert fid["valid"] and fid["faces"] == 2
    assert fid["free_edges"] == 4  # the two rims, an arc of each on each piece
    assert fid["hausdorff_rel"] < 0.01


class _Result:
    def __init__(self, k, faceted_model, solids):
        self.faces = [dict(index=i, kind="freeform", status="faceted" if faceted_model else
                           "built", reason="x" if faceted_model else None, max_dev=0.0,
                           built_as=None if faceted_model else "bspline") for i in range(k)]
        self.faceted_model, self.fidelity = faceted_model, {"solids": solids}

    @property
    def not_built(self):
        return [f for f in self.faces if f["status"] != "built"]


@pytest.mark.parametrize("pieces_ok", [True, False])
def test_a_model_in_pieces_that_fails_is_built_again_whole(pieces_ok):
    """Pieces that leave the whole model faceted (a coarse bolt thread did) fall back to the
    segment whole; pieces that work are kept after one build."""
    V, F = wavy_ring()
    calls = []

    def build(V, F, labels, surfaces, uv, tol, progress):
        calls.append(len(surfaces))
        split = len(surfaces) > 1
        return _Result(len(surfaces), faceted_model=split and not pieces_ok, solids=0)

    from igl_heatseg.cad.pieces import build_in_pieces

    res = build_in_pieces(build, V, F, np.zeros(len(F), np.int64),
                          [Surface("freeform", {"centroid": np.zeros(3)})], None, None, None)
    assert len(res.faces) == 1 and res.faces[0]["status"] == "built"
    if pieces_ok:  # an open ring makes no solid: not a failure
        assert calls == [2] and res.faces[0]["pieces"] == 2
    else:
        assert calls == [2, 1] and "pieces" not in res.faces[0]
