"""Freeform segments that are not disks, cut into disks so that each gets a B-spline face.

A B-spline face is fitted over a chart, and a chart needs a disk. A freeform segment with
holes (a fillet ring around a bore, a blend band round a boss) had no chart in the ``cad``
command and was written as a faceted patch of hundreds of triangles. Here such a segment is
cut into pieces that are disks: its faces are split at the median of their centroids along one
of the segment's principal axes (a ring halves across its hole; a long tube along its length
would not, so every axis is tried); every edge-connected piece of each side that is not a disk
yet is split again, up to :data:`MAX_DEPTH` times. The split with the fewest pieces, then the
shortest cut, is kept; a segment no split turns into disks is left whole (faceted, as before).

Each piece is built as a face of its own (a freeform face bounded by the cuts); the report
keeps one entry per segment and counts its pieces (:func:`collapse_status`). A model with
pieces that ends up fully faceted, or without the solid, is built again with the segments whole
(:func:`build_in_pieces`): B-spline pieces of a coarse bolt thread left sewn faces invalid and
the rebuilds faceted every segment.
"""

from __future__ import annotations

import logging

import igl
import numpy as np

from igl_heatseg.mesh.topology import face_components
from igl_heatseg.surfaces.model import Surface

__all__ = ["is_disk", "disk_pieces", "split_nondisk_freeform", "collapse_status",
           "build_in_pieces", "MAX_DEPTH"]

logger = logging.getLogger(__name__)

#: Rounds of splitting (at most 2**MAX_DEPTH pieces per segment).
MAX_DEPTH = 3

#: Fewest faces of a piece (a B-spline over a chart of fewer triangles is not worth a face).
MIN_PIECE_FACES = 8


def is_disk(F: np.ndarray) -> bool:
    """Whether triangles form a topological disk: edge-connected, edge-manifold, one boundary
    loop, Euler characteristic 1.

    Parameters
    ----------
    F : (q, 3) int64
        Triangles (any vertex numbering).

    Returns
    -------
    bool

    Examples
    --------
    >>> import numpy as np
    >>> is_disk(np.array([[0, 1, 2], [0, 2, 3]]))
    True
    >>> ring = np.array([[i, (i + 1) % 4, 4 + i] for i in range(4)]
    ...                 + [[(i + 1) % 4, 4 + (i + 1) % 4, 4 + i] for i in range(4)])
    >>> is_disk(ring)    # an annulus: two boundary loops
    False
    """
    F = np.asarray(F, dtype=np.int64)
    if len(F) == 0 or face_components(F)[0] != 1:
        return False
    E = np.sort(np.r_[F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]], axis=1)
    edges, uses = np.unique(E, axis=0, return_counts=True)
    if np.any(uses > 2):
        return False
    nv = len(np.unique(F))
    if nv - len(edges) + len(F) != 1:
        return False
    border = edges[uses == 1]
    if len(border) < 3:
        return False
    # one loop: every border vertex has two border edges and the border is connected
    verts, deg = np.unique(border, return_counts=True)
    if np.any(deg != 2):
        return False
    index = {int(v): i for i, v in enumerate(verts)}
    parent = list(range(len(verts)))

    def find(i):
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    for a, b in border.tolist():
        parent[find(index[a])] = find(index[b])
    return len({find(i) for i in range(len(verts))}) == 1


def _cut_length(V, F, sides: np.ndarray) -> float:
    """Total length of the edges between faces of different pieces."""
    E = np.r_[F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]]
    owner = np.tile(sides, 3)
    key = np.sort(E, axis=1)
    order = np.lexsort((key[:, 1], key[:, 0]))
    k, o = key[order], owner[order]
    same = np.all(k[1:] == k[:-1], axis=1) & (o[1:] != o[:-1])
    return float(np.linalg.norm(V[k[1:][same, 0]] - V[k[1:][same, 1]], axis=1).sum())


def _split(V, F, depth: int):
    """Pieces (lists of face indices into ``F``) that are all disks, or None."""
    if is_disk(F):
        return [np.arange(len(F))]
    if depth == 0 or len(F) < 2 * MIN_PIECE_FACES:
        return None
    C = V[F].mean(axis=1)
    _, _, axes = np.linalg.svd(C - C.mean(axis=0), full_matrices=False)
    best, best_key = None, None
    for axis in axes:
        x = C @ axis
        side = x > np.median(x)
        pieces = []
        for half in (np.flatnonzero(side), np.flatnonzero(~side)):
            if len(half) == 0:
                break
            count, comp = face_components(F[half])
            for c in range(count):
                part = half[comp == c]
                if len(part) < MIN_PIECE_FACES:
                    pieces = None
                    break
                sub = _split(V, F[part], depth - 1)
                if sub is None:
                    pieces = None
                    break
                pieces += [part[s] for s in sub]
            if pieces is None:
                break
        else:
            sides = np.empty(len(F), dtype=np.int64)
            for i, p in enumerate(pieces):
                sides[p] = i
            key = (len(pieces), _cut_length(V, F, sides))
            if best_key is None or key < best_key:
                best, best_key = pieces, key
    return best


def disk_pieces(V: np.ndarray, F: np.ndarray, faces: np.ndarray) -> list | None:
    """Cut a face set into disks (see the module docstring).

    Parameters
    ----------
    V : (n, 3) float64
    F : (m, 3) int64
    faces : (q,) int64
        The face set (one segment), edge-connected.

    Returns
    -------
    list of (q_i,) int64 or None
        Face indices (into ``F``) of each piece, every piece a disk of at least
        :data:`MIN_PIECE_FACES` faces, together all of ``faces``; ``[faces]`` when it is a disk
        already; None when no split of :data:`MAX_DEPTH` rounds gives disks.

    Examples
    --------
    >>> import numpy as np
    >>> t = np.linspace(0, 2 * np.pi, 25)[:-1]
    >>> V = np.r_[np.c_[np.cos(t), np.sin(t), 0 * t], np.c_[2 * np.cos(t), 2 * np.sin(t), 0 * t]]
    >>> F = np.array([[i, (i + 1) % 24, 24 + i] for i in range(24)]
    ...              + [[(i + 1) % 24, 24 + (i + 1) % 24, 24 + i] for i in range(24)])
    >>> pieces = disk_pieces(V, F, np.arange(48))    # a flat ring: two half-rings
    >>> [len(p) for p in pieces], all(is_disk(F[p]) for p in pieces)
    ([24, 24], True)
    """
    faces = np.asarray(faces, dtype=np.int64)
    out = _split(V, F[faces], MAX_DEPTH)
    return None if out is None else [faces[np.sort(p)] for p in out]


def split_nondisk_freeform(V, F, labels, surfaces, uv=None):
    """Relabel the freeform segments without a chart that are not disks into disk pieces.

    Parameters
    ----------
    V : (n, 3) float64
    F : (m, 3) int64
    labels : (m,) int64
        Segments ``0..k-1``.
    surfaces : list of Surface
        ``k`` fitted surfaces.
    uv : list, optional
        Per segment, a chart or None (a segment with a chart is left as it is).

    Returns
    -------
    labels : (m,) int64
        The first piece of a split segment keeps its label; the others get ``k, k+1, ...``.
    surfaces : list of Surface
        ``surfaces`` followed by one freeform surface per new piece.
    uv : list or None
        ``uv`` followed by None per new piece.
    origin : (k',) int64
        The input segment of every output segment (``origin[a] == a`` for ``a < k``).

    Examples
    --------
    >>> import numpy as np
    >>> F = np.array([[0, 1, 2], [0, 2, 3]])
    >>> out = split_nondisk_freeform(np.eye(4, 3), F, np.array([0, 0]),
    ...                              [Surface("freeform", {"centroid": np.zeros(3)})])
    >>> out[0].tolist(), out[3].tolist()    # a disk already: nothing to split
    ([0, 0], [0])
    """
    labels = np.array(labels, dtype=np.int64)
    surfaces, origin = list(surfaces), list(range(len(surfaces)))
    uv = None if uv is None else list(uv)
    for a, s in enumerate(list(surfaces)):
        if s.is_analytic or (uv is not None and uv[a] is not None):
            continue
        faces = np.flatnonzero(labels == a)
        pieces = disk_pieces(V, F, faces)
        if pieces is None or len(pieces) == 1:
            continue
        logger.info("freeform segment %d is not a disk: built as %d pieces (segments %d..%d "
                    "in the messages below)", a, len(pieces), len(surfaces),
                    len(surfaces) + len(pieces) - 2)
        for p in pieces[1:]:
            labels[p] = len(surfaces)
            surfaces.append(Surface("freeform", dict(s.params), rms=s.rms, max_dev=s.max_dev,
                                    outward=s.outward))
            origin.append(a)
            if uv is not None:
                uv.append(None)
    return labels, surfaces, uv, np.asarray(origin, dtype=np.int64)


def collapse_status(status: list, origin: np.ndarray) -> list:
    """Per-segment report entries from per-piece ones.

    Parameters
    ----------
    status : list of dict
        :attr:`CadResult.faces` of the pieces (``index`` = piece).
    origin : (k',) int64
        From :func:`split_nondisk_freeform`.

    Returns
    -------
    list of dict
        One entry per input segment (``k = origin.max() + 1``): a split segment is ``built``
        when all its pieces are, else ``faceted`` (the first failing piece's reason), and
        gets ``pieces`` (their count) and ``max_dev`` (the largest).

    Examples
    --------
    >>> st = [dict(index=0, kind="freeform", status="built", reason=None, max_dev=0.1),
    ...       dict(index=1, kind="freeform", status="built", reason=None, max_dev=0.2)]
    >>> out = collapse_status(st, np.array([0, 0]))
    >>> len(out), out[0]["status"], out[0]["pieces"], out[0]["max_dev"]
    (1, 'built', 2, 0.2)
    """
    k = int(origin.max()) + 1 if len(origin) else 0
    out = [dict(status[a]) for a in range(k)]
    for a in range(k):
        mine = [status[b] for b in np.flatnonzero(origin == a).tolist()]
        if len(mine) == 1:
            continue
        failed = [e for e in mine if e["status"] != "built"]
        out[a]["pieces"] = len(mine)
        devs = [e["max_dev"] for e in mine if e.get("max_dev") is not None]
        out[a]["max_dev"] = max(devs) if devs else None
        if failed:  # built_as: how the pieces built were made, if any
            out[a].update(status="faceted",
                          built_as=next((e.get("built_as") for e in mine
                                         if e["status"] == "built"), None),
                          reason=f"{len(failed)} of its {len(mine)} disk pieces faceted: "
                                 f"{failed[0]['reason']}")
    return out


def build_in_pieces(build, V, F, labels, surfaces, uv, tol, progress):
    """Build a B-Rep with the non-disk freeform segments cut into disk pieces, and again with
    them whole when the pieces' model is worse.

    Parameters
    ----------
    build : callable
        ``build(V, F, labels, surfaces, uv, tol, progress) -> CadResult`` (one report entry
        per segment it is given).
    V : (n, 3) float64
    F : (m, 3) int64
    labels : (m,) int64
    surfaces : list of Surface
    uv : list or None
    tol : float or None
    progress : callable

    Returns
    -------
    CadResult
        With one :attr:`~CadResult.faces` entry per input segment (:func:`collapse_status`).
        When a segment was split and that model is fully faceted or (of a closed mesh) no
        solid, the model with every segment whole is built too and the better kept (not fully
        faceted, then a solid, then fewer faceted segments; ties keep the pieces).

    Examples
    --------
    >>> import numpy as np
    >>> calls = []
    >>> class R:
    ...     def __init__(self, k):
    ...         self.faces = [dict(index=i, status="built", max_dev=0.0) for i in range(k)]
    ...         self.faceted_model, self.fidelity, self.not_built = False, {"solids": 1}, []
    >>> def build(V, F, labels, surfaces, uv, tol, progress):
    ...     calls.append(len(surfaces))
    ...     return R(len(surfaces))
    >>> F = np.array([[0, 1, 2], [0, 2, 3]])
    >>> res = build_in_pieces(build, np.eye(4, 3), F, np.zeros(2, np.int64),
    ...                       [Surface("freeform", {"centroid": np.zeros(3)})], None, None, None)
    >>> calls, len(res.faces)    # a disk: one build, one entry
    ([1], 1)
    """
    split = split_nondisk_freeform(V, F, labels, surfaces, uv)
    res, origin = build(V, F, *split[:3], tol, progress), split[3]
    closed = len(igl.boundary_facets(F)[0]) == 0
    if len(origin) > len(surfaces) and (
            res.faceted_model or (closed and not res.fidelity.get("solids"))):
        logger.warning("the model with %d freeform segment(s) cut into disk pieces is %s; "
                       "building it with them whole", len(set(origin[len(surfaces):].tolist())),
                       "fully faceted" if res.faceted_model else "no solid")
        whole = build(V, F, labels, surfaces, uv, tol, progress)

        def rank(r):
            return (not r.faceted_model, bool(r.fidelity.get("solids")), -len(r.not_built))

        if rank(whole) > rank(res):
            res, origin = whole, np.arange(len(surfaces))
    res.faces = collapse_status(res.faces, origin)
    return res
