"""Boundaries between two fitted surfaces placed by a minimum cut (alpha-beta swap).

Where two faces of a part meet at a crease, the faces on either side lie on one fitted surface
and off the other, and moving each face to the surface it lies on (the Lloyd passes of
:mod:`~igl_heatseg.surfaces.refine`) puts the boundary on the crease.  Where they meet
tangentially (a fillet into its plane, a pipe's cylinder into its elbow's torus), a band of
faces lies within the noise of both surfaces, and face-by-face moves leave the boundary
wherever the heat fields put it: a zig-zag along triangle edges, up to 1.8 times the true
boundary's length on the noisy tuning parts (pipe elbows).

Here the labels of two adjacent segments ``a`` and ``b`` are chosen together, over the band of
their faces near the common boundary that could lie on either surface, by the labelling that
minimises (Boykov, Veksler & Zabih 2001, the alpha-beta swap move)::

    E = sum_f area_f * min((d_f / tol)^2, CAP) + SMOOTHNESS * h * sum_(f,g) |e_fg| [l_f != l_g]

``d_f`` is the RMS distance of face ``f``'s corners to the surface of its label and ``h`` the
mean edge length, so both terms are areas: a boundary one mean edge longer costs what a face of
area ``h^2`` at ``sqrt(SMOOTHNESS)`` tolerances from its surface does. The data term sets where
the boundary lies (the distances of the faces of a tangent join grow quadratically away from it,
and the band's integral finds the line); the length term makes the line straight instead of
following the noise. Faces that lie off the other surface (RMS beyond GROW_TOL x tol, a corner
beyond MAX_DEV_FACTOR x tol, or a normal beyond GROW_ANGLE) keep their label and are the cut's
fixed ends, so a crease boundary and a small true face (a chamfer) are never moved. A cut that
leaves either segment farther from its surface than the tolerance (or than before) is undone.
The minimum cut is exact (:func:`scipy.sparse.csgraph.maximum_flow`).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import breadth_first_order, maximum_flow

from ..errors import MeshError
from ..mesh.geometry import face_areas
from ..mesh.topology import label_pieces
from .samples import segment_adjacency
from .segment_fit import GROW_ANGLE, GROW_TOL, corner_max_dev, corner_rms, normal_angle
from .select import MAX_DEV_FACTOR

__all__ = ["binary_min_cut", "swap_boundaries", "SMOOTHNESS", "CAP", "BAND_RINGS"]

#: Weight of the boundary length (per mean edge length) against the faces' squared distances
#: (in tolerances, times their area).
SMOOTHNESS = 0.25

#: Squared distance (in tolerances) at which a face's data cost stops growing.
CAP = 9.0

#: Faces within this many rings of the common boundary may change label.
BAND_RINGS = 6

#: Total capacity the integer flow network is scaled to (int32 capacities).
_SCALE = 2.0**29


def binary_min_cut(cost0, cost1, ei, ej, w) -> np.ndarray:
    """Exact minimum of ``sum_f cost_(l_f)(f) + sum_k w_k [l_(ei_k) != l_(ej_k)]`` over binary
    labels (a minimum s-t cut).

    Parameters
    ----------
    cost0, cost1 : (n,) array_like of float
        Non-negative cost of each node taking label 0 / label 1.
    ei, ej : (k,) array_like of int
        Pairs of nodes (each pair once).
    w : (k,) array_like of float
        Non-negative cost of each pair taking different labels.

    Returns
    -------
    (n,) bool
        True for the nodes labelled 1.  Costs are rounded to a grid of ``total / 2**29`` (the
        flow network's capacities are int32), so ties may go either way.

    Raises
    ------
    MeshError
        On mismatched shapes, negative or non-finite costs, or pairs outside ``0..n-1``.

    Examples
    --------
    >>> import numpy as np
    >>> # a chain of 4 nodes: the ends prefer 0 and 1, the middle ones barely care
    >>> c0, c1 = np.array([0, 1.0, 1.1, 9]), np.array([9, 1.3, 1.0, 0])
    >>> binary_min_cut(c0, c1, [0, 1, 2], [1, 2, 3], [0.5, 0.5, 0.5]).tolist()
    [False, False, True, True]
    >>> binary_min_cut(c0, c1, [0, 1, 2], [1, 2, 3], [0.5, 5.0, 0.5]).tolist()  # one cut only
    [False, False, False, True]
    """
    c0 = np.asarray(cost0, dtype=np.float64)
    c1 = np.asarray(cost1, dtype=np.float64)
    ei = np.asarray(ei, dtype=np.int64)
    ej = np.asarray(ej, dtype=np.int64)
    w = np.asarray(w, dtype=np.float64)
    n = len(c0)
    if not (c1.shape == c0.shape == (n,) and ei.shape == ej.shape == w.shape == (len(w),)):
        raise MeshError(f"binary_min_cut: costs of shapes {c0.shape} and {c1.shape}, pairs "
                        f"{ei.shape} and {ej.shape}, weights {w.shape}: expected (n,) and (k,)")
    if not (np.all(np.isfinite(c0) & (c0 >= 0)) and np.all(np.isfinite(c1) & (c1 >= 0))
            and np.all(np.isfinite(w) & (w >= 0))):
        raise MeshError("binary_min_cut: costs and weights must be finite and >= 0")
    if len(ei) and not (min(ei.min(), ej.min()) >= 0 and max(ei.max(), ej.max()) < n):
        raise MeshError(f"binary_min_cut: pair indices outside 0..{n - 1}")
    if n == 0:
        return np.zeros(0, dtype=bool)
    base = np.minimum(c0, c1)
    c0, c1 = c0 - base, c1 - base
    total = c0.sum() + c1.sum() + 2.0 * w.sum()
    if not total > 0:
        return np.zeros(n, dtype=bool)
    unit = total / _SCALE
    s, t = n, n + 1
    nodes = np.arange(n)
    # s -> f is cut when f takes label 1 (costs c1); f -> t when it takes label 0 (costs c0)
    rows = np.r_[np.full(n, s), nodes, ei, ej]
    cols = np.r_[nodes, np.full(n, t), ej, ei]
    cap = np.rint(np.r_[c1, c0, w, w] / unit).astype(np.int64)
    keep = cap > 0
    C = sp.csr_array((cap[keep].astype(np.int32), (rows[keep], cols[keep])), shape=(n + 2, n + 2))
    C.sum_duplicates()
    flow = maximum_flow(C, s, t, method="dinic").flow
    R = (C.astype(np.int64) - flow.astype(np.int64)).tocsr()
    R.data = (R.data > 0).astype(np.int8)
    R.eliminate_zeros()
    reach = breadth_first_order(R, s, directed=True, return_predecessors=False)
    label1 = np.ones(n + 2, dtype=bool)
    label1[reach] = False
    return label1[:n]


def _band(F, TT, labels, a, b, rings):
    """Faces of segments ``a`` and ``b`` within ``rings`` rings (over their own faces) of their
    common boundary."""
    ab = (labels == a) | (labels == b)
    nb = np.where(TT >= 0, TT, 0)
    nl = np.where(TT >= 0, labels[nb], -1)
    other = np.where(labels[:, None] == a, b, a)
    band = ab & (nl == other).any(axis=1)
    for _ in range(rings):
        grow = np.zeros(len(F), dtype=bool)
        grow[nb[band][TT[band] >= 0]] = True
        band |= grow & ab
    return np.flatnonzero(band)


def _rms(V, F, mask, s) -> float:
    """RMS over the faces in ``mask`` of their corners' RMS distance to ``s``."""
    return float(np.sqrt(np.mean(corner_rms(V, F, np.flatnonzero(mask), s) ** 2)))


def _drop_islands(F, TT, labels, a, b, index, area) -> None:
    """Pieces of ``a`` or ``b`` cut off their segment's largest piece by the cut go back to the
    other label when they are made of free faces (``index >= 0``): the segments stay
    face-connected, and a speck of noise fitting the other surface is no new segment."""
    ab = np.flatnonzero((labels == a) | (labels == b))
    comp = label_pieces(F, labels, TT)[ab]
    for x, y in ((a, b), (b, a)):
        mine = labels[ab] == x
        pieces = np.unique(comp[mine])
        if len(pieces) < 2:
            continue
        weight = np.bincount(comp[mine], weights=area[ab[mine]], minlength=comp.max() + 1)
        for p in pieces[pieces != np.argmax(weight)].tolist():
            faces = ab[comp == p]
            if np.all(index[faces] >= 0):
                labels[faces] = y


def swap_boundaries(V, F, labels, fits: dict, tol: float, TT, FN, *, smoothness=None,
                    rings=None) -> set:
    """Place the boundary of every pair of adjacent analytic segments by a minimum cut.

    Parameters
    ----------
    V : (n, 3) float64
        Positions (distances are measured here).
    F : (m, 3) int64
    labels : (m,) int64
        Segment of each face; changed in place.
    fits : dict
        Segment id -> :class:`~igl_heatseg.surfaces.model.Surface`; pairs where either is not
        analytic are left alone.
    tol : float
        Fit tolerance (model units, > 0).
    TT : (m, 3) int64
        Face-face adjacency (-1 on a border), as from ``igl.triangle_triangle_adjacency``.
    FN : (m, 3) float64
        Unit face normals.
    smoothness : float, optional
        Boundary-length weight; default :data:`SMOOTHNESS`.
    rings : int, optional
        Band width in face rings; default :data:`BAND_RINGS`.

    Returns
    -------
    set of int
        Segments whose faces changed (to refit).  No segment is emptied.

    Examples
    --------
    >>> import numpy as np
    >>> import igl
    >>> from igl_heatseg.surfaces.model import Surface
    >>> x, y = np.meshgrid(np.arange(11.0), np.arange(5.0))
    >>> V = np.c_[x.ravel(), y.ravel(), 0.02 * np.maximum(x.ravel() - 5, 0)]  # a slight fold
    >>> i = np.arange(55).reshape(5, 11)[:-1, :-1].ravel()
    >>> F = np.r_[np.c_[i, i + 1, i + 12], np.c_[i, i + 12, i + 11]]
    >>> a = Surface("plane", {"point": np.zeros(3), "normal": np.array([0, 0, 1.0])})
    >>> n = np.array([-0.02, 0, 1.0])
    >>> b = Surface("plane", {"point": np.array([5.0, 0, 0]), "normal": n / np.linalg.norm(n)})
    >>> labels = (V[F].mean(axis=1)[:, 0] > 5).astype(np.int64)
    >>> labels[[4, 45]] = 1, 0                                        # two teeth
    >>> TT = igl.triangle_triangle_adjacency(F)[0]
    >>> FN = igl.per_face_normals(V, F, np.zeros(3))
    >>> sorted(swap_boundaries(V, F, labels, {0: a, 1: b}, 0.1, TT, FN))
    [0, 1]
    >>> labels.tolist() == (V[F].mean(axis=1)[:, 0] > 5).tolist()    # straight on the fold
    True
    """
    smoothness = SMOOTHNESS if smoothness is None else float(smoothness)
    rings = BAND_RINGS if rings is None else int(rings)
    area = face_areas(V, F)
    # edge k of face f joins corners k and k + 1 (igl.triangle_triangle_adjacency's order)
    elen = np.linalg.norm(V[F[:, [1, 2, 0]]] - V[F], axis=2)
    h = float(np.mean(elen))
    fa, fb = segment_adjacency(F, labels, TT)
    la, lb = labels[fa], labels[fb]
    pairs = np.unique(np.c_[np.minimum(la, lb), np.maximum(la, lb)], axis=0)
    changed: set = set()
    for a, b in pairs.tolist():
        if not (fits[a].is_analytic and fits[b].is_analytic):
            continue
        band = _band(F, TT, labels, a, b, rings)
        if len(band) < 2:
            continue
        d = np.c_[corner_rms(V, F, band, fits[a]), corner_rms(V, F, band, fits[b])]
        ang = np.c_[normal_angle(V, F, FN, band, fits[a]), normal_angle(V, F, FN, band, fits[b])]
        own = (labels[band] == b).astype(np.int64)
        oth = 1 - own
        rows = np.arange(len(band))
        far = np.c_[corner_max_dev(V, F, band, fits[a]), corner_max_dev(V, F, band, fits[b])]
        free = ((d[rows, oth] <= GROW_TOL * tol) & (far[rows, oth] <= MAX_DEV_FACTOR * tol)
                & (ang[rows, oth] <= GROW_ANGLE))
        if not np.any(free):
            continue
        faces = band[free]
        index = np.full(len(F), -1, dtype=np.int64)
        index[faces] = np.arange(len(faces))
        cost = area[faces, None] * np.minimum((d[free] / tol) ** 2, CAP)
        if not np.all(np.isfinite(cost)):  # a degenerate fit: leave this pair as it is
            continue
        # pairs of free faces, and free faces next to fixed faces of a or b
        nb = TT[faces]
        k = np.nonzero(nb >= 0)
        f, g = faces[k[0]], nb[k]
        wlen = smoothness * h * elen[f, k[1]]
        inner = (index[g] >= 0) & (f < g)
        fixed = (index[g] < 0) & ((labels[g] == a) | (labels[g] == b))
        c = cost.copy()
        gl = (labels[g[fixed]] == b).astype(np.int64)  # a fixed neighbour's label, 0 = a
        np.add.at(c, (index[f[fixed]], 1 - gl), wlen[fixed])  # differing from it costs
        to_b = binary_min_cut(c[:, 0], c[:, 1], index[f[inner]], index[g[inner]], wlen[inner])
        new = np.where(to_b, b, a)
        if np.array_equal(new, labels[faces]):
            continue
        old = labels[faces].copy()
        before = [_rms(V, F, labels == x, fits[x]) for x in (a, b)]
        labels[faces] = new
        _drop_islands(F, TT, labels, a, b, index, area)
        if not (np.any(labels == a) and np.any(labels == b)) or any(
                _rms(V, F, labels == x, fits[x]) > max(tol, r)
                for x, r in zip((a, b), before, strict=True)):
            labels[faces] = old  # never empty a segment, nor push it off its surface
            continue
        changed.update((a, b))
    return changed
