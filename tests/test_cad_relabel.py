"""Border faces that lie on a neighbour's surface are built with the neighbour's face."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.sparse.csgraph import connected_components

pytest.importorskip("OCP")

from test_cad import box_mesh, box_planes  # noqa: E402

from igl_heatseg.cad import build_brep  # noqa: E402
from igl_heatseg.cad.relabel import hand_over_border_faces  # noqa: E402
from igl_heatseg.mesh.topology import face_adjacency  # noqa: E402


def _zigzag_cube(n=6):
    """A cube whose top segment (0) also holds the +x side's faces along their shared edge,
    every other one: their lower corners lie on the +x plane, a third of the side below the
    top."""
    V, F, labels = box_mesh(n)
    C = V[F].mean(axis=1)
    top_edge = (labels == 2) & (C[:, 2] > 1 - 1.0 / n)
    wrong = np.flatnonzero(top_edge)[::2]
    labels = labels.copy()
    labels[wrong] = 0
    return V, F, labels, wrong


def test_cube_with_a_zigzag_border_is_built_exact():
    V, F, labels, wrong = _zigzag_cube()
    new, moved = hand_over_border_faces(V, F, labels, box_planes(), tol=0.03)
    assert moved == len(wrong) and (new[wrong] == 2).all()
    assert (np.delete(new, wrong) == np.delete(labels, wrong)).all()
    res = build_brep(V, F, labels, box_planes())
    assert all(f["status"] == "built" for f in res.faces)
    assert sorted(map(tuple, res.handed_over)) == sorted((int(f), 0, 2) for f in wrong)
    fid = res.fidelity
    assert fid["valid"] and fid["solids"] == 1 and fid["faces"] == 6
    assert abs(fid["volume"] - 8.0) / 8.0 < 1e-6
    assert res.to_report()["handed_over"] == [list(x) for x in res.handed_over]


def test_without_the_hand_over_the_zigzag_segment_is_faceted(monkeypatch):
    """The case above fails without the hand-over: this is what it is for."""
    import igl_heatseg.cad.build as build

    monkeypatch.setattr(build, "hand_over_border_faces", lambda V, F, lab, s, tol: (lab, 0))
    V, F, labels, _ = _zigzag_cube()
    res = build_brep(V, F, labels, box_planes())
    assert res.faces[0]["status"] == "faceted"
    assert res.faces[0]["reason"].startswith("surface deviates")


def test_faces_on_their_own_surface_or_on_no_neighbours_stay():
    V, F, labels = box_mesh(6)
    same, moved = hand_over_border_faces(V, F, labels, box_planes(), tol=0.03)
    assert moved == 0 and (same == labels).all()
    # a bump in the middle of the top: far from the top plane and from every neighbour
    V = V.copy()
    mid = np.flatnonzero((np.abs(V[:, :2]).max(axis=1) < 0.2) & (V[:, 2] > 0.99))
    V[mid, 2] += 0.3
    same, moved = hand_over_border_faces(V, F, labels, box_planes(), tol=0.03)
    assert moved == 0 and (same == labels).all()


@pytest.mark.parametrize("seed", range(6))
def test_hand_over_invariants_on_random_border_errors(seed):
    """Random border faces mislabelled with a random neighbour: moved faces lie within the
    tolerance of their new surface, faces within it of their own stay, every segment stays
    edge-connected and keeps at least half its faces."""
    rng = np.random.default_rng(seed)
    V, F, truth = box_mesh(8)
    A = face_adjacency(F).tocoo()
    pairs = np.c_[A.row, A.col][truth[A.row] != truth[A.col]]
    pick = pairs[rng.choice(len(pairs), 12, replace=False)]
    labels = truth.copy()
    labels[pick[:, 0]] = truth[pick[:, 1]]
    planes = box_planes()
    tol = 0.03
    new, moved = hand_over_border_faces(V, F, labels, planes, tol)
    changed = np.flatnonzero(new != labels)
    assert moved == len(changed)
    for f in changed:
        assert np.abs(planes[new[f]].distance(V[F[f]])).max() <= tol
        assert np.abs(planes[labels[f]].distance(V[F[f]])).max() > tol
    Adj = face_adjacency(F).tocsr()

    def connected(faces):
        return connected_components(Adj[faces][:, faces], directed=False)[0] == 1

    for a in range(6):
        faces = np.flatnonzero(new == a)
        assert 2 * len(faces) >= (labels == a).sum()
        if connected(np.flatnonzero(labels == a)):
            assert connected(faces)
    # every face given back here lands on its true side
    assert (new[changed] == truth[changed]).all()
