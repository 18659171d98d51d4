"""Border faces that lie on a neighbour's surface, handed to that neighbour before the build.

A segment's border runs along mesh edges and can zig-zag across the crease it should follow:
a few of its faces lie on the neighbouring face's surface.  Their far corners are then farther
than the modelling tolerance from the segment's own surface, and the whole segment, hundreds
of faces of one plane, is faceted for them ("surface deviates").  On the 40 tuning parts, of
the 111 segments faceted that way, 92 deviated only within two face rings of their border, and
on every noise-0.1 or noise-0.05 part with dense triangles every far vertex lay within the
tolerance of a neighbour's surface.

No OpenCASCADE here: this runs before the build.
"""

from __future__ import annotations

import igl
import numpy as np
from scipy.sparse import csgraph, csr_matrix

from igl_heatseg.mesh.geometry import face_normals

__all__ = ["hand_over_border_faces"]

#: Passes over the borders (a face behind a handed-over one becomes a border face).
PASSES = 3


def _connected(F: np.ndarray, TT: np.ndarray, faces: np.ndarray) -> bool:
    """Whether ``faces`` (rows of ``F``) are edge-connected."""
    if len(faces) <= 1:
        return True
    local = np.full(len(F), -1)
    local[faces] = np.arange(len(faces))
    nb = local[np.where(TT[faces] >= 0, TT[faces], 0)]
    ok = (TT[faces] >= 0) & (nb >= 0)
    rows = np.repeat(np.arange(len(faces)), 3)[ok.ravel()]
    A = csr_matrix((np.ones(len(rows)), (rows, nb.ravel()[ok.ravel()])),
                   shape=(len(faces), len(faces)))
    return csgraph.connected_components(A, directed=False)[0] == 1


def hand_over_border_faces(V, F, labels, surfaces, tol):
    """Give a segment's border faces that lie on an adjacent segment's analytic surface to it.

    Only segments farther than ``tol`` from their own analytic surface give faces away: a face
    of such a segment with a corner farther than ``tol`` from that surface goes to an
    edge-adjacent segment whose analytic surface has all three corners within ``tol`` and
    whose normal is nearer the face's than the own surface's normal (the one nearest, when
    several qualify); up to PASSES times, as faces behind handed-over ones reach the border.
    A segment gives faces away only when it is then within ``tol`` of its surface, keeps at
    least half of its faces and every segment involved stays edge-connected; else it gives
    none (a segment still deviating is built as a B-spline or faceted: moving its border
    would only change that fit). The surfaces are not refitted.

    Parameters
    ----------
    V : (n, 3) float64
        Vertex positions.
    F : (m, 3) int64
        Triangles, consistently oriented.
    labels : (m,) int64
        Segment of every face, ``0..k-1``.
    surfaces : list of Surface
        ``surfaces[a]`` fitted to segment ``a`` (``outward``: the mesh normals point to its
        positive distance).
    tol : float
        Modelling tolerance (model units).

    Returns
    -------
    labels : (m,) int64
        A new array (the input is not changed).
    moved : int
        Faces handed over.

    Examples
    --------
    A strip of two planes meeting at a right angle, one face of the vertical one labelled
    with the horizontal one:

    >>> import numpy as np
    >>> from igl_heatseg.surfaces.model import Surface
    >>> V = np.array([[x, y, 0.0] for y in (0, 1) for x in (0, 1, 2)]
    ...              + [[2.0, y, 1.0] for y in (0, 1)])
    >>> F = np.array([[0, 1, 4], [0, 4, 3], [1, 2, 5], [1, 5, 4], [2, 6, 7], [2, 7, 5]])
    >>> floor = Surface("plane", {"point": np.zeros(3), "normal": np.array([0., 0, 1])})
    >>> wall = Surface("plane", {"point": np.array([2., 0, 0]), "normal": np.array([-1., 0, 0])})
    >>> new, moved = hand_over_border_faces(V, F, np.array([0, 0, 0, 0, 0, 1]),
    ...                                     [floor, wall], tol=0.1)
    >>> new.tolist(), moved
    ([0, 0, 0, 0, 1, 1], 1)
    """
    labels = np.asarray(labels, dtype=np.int64).copy()
    k = len(surfaces)
    if k < 2:
        return labels, 0
    TT = igl.triangle_triangle_adjacency(F)[0]
    FN = face_normals(V, F)
    sign = np.array([1.0 if s.outward else -1.0 for s in surfaces])
    analytic = np.array([s.is_analytic for s in surfaces])
    start = np.bincount(labels, minlength=k)

    def corner_dev(a, faces):
        return np.abs(surfaces[a].distance(V[F[faces].ravel()])).reshape(-1, 3).max(axis=1)

    def alignment(a, faces):
        C = V[F[faces]].mean(axis=1)
        return np.einsum("ij,ij->i", FN[faces], sign[a] * surfaces[a].normals(C))

    work = labels.copy()
    for _ in range(PASSES):
        new = work.copy()
        for a in np.flatnonzero(analytic).tolist():
            faces = np.flatnonzero(work == a)
            far = faces[corner_dev(a, faces) > tol]
            if len(far) == 0:
                continue
            nb = work[np.where(TT[far] >= 0, TT[far], far[:, None])]  # (f, 3)
            best = np.full(len(far), -1)
            score = alignment(a, far)  # a neighbour must beat the own surface's alignment
            for b in np.unique(nb).tolist():
                if b == a or not analytic[b]:
                    continue
                rows = np.flatnonzero((nb == b).any(axis=1))
                cos = alignment(b, far[rows])
                ok = (corner_dev(b, far[rows]) <= tol) & (cos > score[rows])
                best[rows[ok]], score[rows[ok]] = b, cos[ok]
            new[far[best >= 0]] = best[best >= 0]
        if np.array_equal(new, work):
            break
        work = new
    # a segment gives faces away only when that brings it within the tolerance, keeps half its
    # faces and leaves every segment edge-connected; else it gives none
    while True:
        changed = False
        for a in np.unique(labels[work != labels]).tolist():
            rest = np.flatnonzero(work == a)
            touched = np.unique(np.r_[a, work[labels == a]])
            if corner_dev(a, rest).max(initial=0.0) > tol or 2 * len(rest) < start[a] or \
                    not all(_connected(F, TT, np.flatnonzero(work == b)) for b in touched):
                back = labels == a
                work[back] = a
                changed = True
        if not changed:
            break
    return work, int((work != labels).sum())
