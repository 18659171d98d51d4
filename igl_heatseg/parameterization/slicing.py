"""Straight cuts through a chart's map that make it pack better: long charts cut across,
C-shaped ones halved (:func:`split_for_packing`); the map is not changed, only the faces are
dealt out (:func:`~igl_heatseg.parameterization.split.cut_for_packing` keeps it for every
piece).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

from ..mesh.geometry import uv_areas
from ..mesh.topology import edge_topology, face_components
from .cut import chart_topology

__all__ = [
    "split_for_packing",
    "PACK_MAX_ASPECT",
    "PACK_PIECE_ASPECT",
    "PACK_MIN_BOX_FILL",
    "PACK_MIN_HALVE_FACES",
    "PACK_HALVE_MIN_FACES",
    "SLICE_SHIFTS",
]

#: A chart whose map's minimum-area rectangle is longer than this times its width, and whose
#: area is at least ``split.PACK_MIN_AREA_FRACTION`` of the mesh's, is cut across its length for
#: packing (a long strip alone caps the fill of a square atlas at 1 / aspect).
PACK_MAX_ASPECT: float = 4.0

#: Aspect ratio of the pieces of a chart cut for packing (at most).
PACK_PIECE_ASPECT: float = 2.0

#: A chart filling less than this of its minimum-area rectangle is halved for packing.
PACK_MIN_BOX_FILL: float = 0.45

#: ... when it has at least this many faces (by default; a chart of one row of facets has few) ...
PACK_MIN_HALVE_FACES: int = 40

#: ... and in the pipeline's trial of C-shaped charts, of any size (a thin ring cut open: a
#: thread flank's cone, 48 faces on a coarse bolt) and down to this many faces, when the atlas
#: then fills more (``igl_heatseg.pipeline.stages``).
PACK_HALVE_MIN_FACES: int = 4

#: Positions tried for each cut of a slicing that leaves a piece with a hole (evenly over
#: half a slice either way, nearest first).
SLICE_SHIFTS: int = 21


def _box(UV: np.ndarray, F: np.ndarray):
    """Minimum-area rectangle of a piece: rotated coordinates (all rows), min, extent, fill."""
    from .atlas import min_area_rotation, rotate_points

    used = np.unique(F)
    Q = np.zeros((len(UV), 2))
    Q[used] = rotate_points(UV[used], min_area_rotation(UV[used]))
    lo, ext = Q[used].min(axis=0), np.ptp(Q[used], axis=0)
    area = float(np.abs(uv_areas(UV, F)).sum())
    return Q, lo, ext, area / max(float(ext[0] * ext[1]), 1e-300)


def _slices(F: np.ndarray, Q: np.ndarray, lo, ext, n: int, shift: bool = False) -> list | None:
    """``n`` slices across the long axis (faces by centroid, strays merged), or ``None`` when
    one is not a disk.

    Equal slices first. When one is not a disk (a strip with holes: the side of a knob with a
    ring of dimples, cut open, holds a whole dimple in every slice) and ``shift``, each cut in
    turn moves by up to half a slice (in :data:`SLICE_SHIFTS` steps, nearest first) to where
    the slice it closes is made of disks: through a hole. Such a slice may fall into pieces
    (the seam that joined the holes cuts it lengthwise): each piece is then a slice of its
    own."""
    axis = int(np.argmax(ext))
    c = Q[F].mean(axis=1)[:, axis]
    t = (c - lo[axis]) / ext[axis] * n  # slice coordinate: slice i holds [i, i + 1)
    pieces = _disk_slices(F, np.clip(t.astype(np.int64), 0, n - 1), n)
    if pieces is not None or n < 2 or not shift:
        return pieces
    shifts = sorted(np.linspace(-0.5, 0.5, SLICE_SHIFTS), key=abs)
    k = np.full(len(F), n - 1, dtype=np.int64)
    left = -np.inf
    for i in range(1, n):
        for d in shifts:
            piece = np.flatnonzero((t >= left) & (t < i + d))
            if len(piece) and _disks(F[piece]) is not None:
                k[piece] = i - 1
                left = i + d
                break
        else:
            return None
    out = []
    for i in range(n):
        p = np.flatnonzero(k == i)
        parts = _disks(F[p]) if len(p) else []
        if parts is None:
            return None
        out += [p[q] for q in parts]
    return out


def _disks(F: np.ndarray) -> list | None:
    """The face components of ``F`` (row indices), or ``None`` when one is not a disk."""
    count, comp = face_components(F)
    parts = [np.flatnonzero(comp == j) for j in range(count)]
    for q in parts:
        if not chart_topology(F[q], name="piece").is_disk:
            return None
    return parts


def _disk_slices(F: np.ndarray, k: np.ndarray, n: int) -> list | None:
    """The pieces ``k == 0..n-1`` (strays merged), or ``None`` when one is not a disk."""
    k = _merge_strays(F, k)
    pieces = [p for p in (np.flatnonzero(k == i) for i in range(n)) if len(p)]
    for p in pieces:
        if not chart_topology(F[p], name="piece").is_disk:
            return None
    return pieces


def split_for_packing(
    UV: np.ndarray,
    F: np.ndarray,
    max_aspect: float = PACK_MAX_ASPECT,
    depth: int = 3,
    *,
    max_length: float = np.inf,
    big: bool = True,
    min_faces: int = PACK_MIN_HALVE_FACES,
    shift: bool = False,
) -> list | None:
    """Cut a chart that packs badly into pieces that pack well, by straight cuts in the map.

    A chart longer than ``max_length`` (its minimum-area rectangle's long side) is cut across
    into pieces no longer than that; a ``big`` chart more than ``max_aspect`` times as long as
    wide, into pieces of aspect ratio about :data:`PACK_PIECE_ASPECT`; a ``big`` chart that
    fills less than :data:`PACK_MIN_BOX_FILL` of its rectangle (a C-shaped chart, e.g. a ring
    cut open) is halved across its length.  Pieces are cut again the same way (``depth``
    levels), halves only as long as halving helps.  Faces go to the piece holding their
    centroid (stray faces join a neighbour); a cut whose pieces are not all disks is not
    made.

    Parameters
    ----------
    UV : (n, 2) float64
        A bijective map (``NaN`` allowed for rows ``F`` does not use).
    F : (m, 3) int64
        Disk triangulation.
    max_aspect : float
        Aspect ratio above which a big chart is cut across.
    depth : int
        Levels of cutting pieces again.
    max_length : float
        Length (units of ``UV``) above which a chart of any size is cut across.
    big : bool
        Whether the aspect-ratio and box-fill rules apply (a chart large enough to matter).
    min_faces : int
        Fewest faces of a chart halved for its box fill.
    shift : bool
        Move cuts through holes when equal slices are not all disks (:func:`_slices`); for
        cuts kept only when the atlas packs tighter (a strip of 217 x 29 with a row of dimples
        sliced this way filled its atlas 0.743 instead of 0.430; the big charts, cut without
        that check, also took such cuts, and some of their atlases packed worse).

    Returns
    -------
    list of (m_i,) int64 or None
        Face indices of the pieces (each a disk), ``None`` when the chart is left whole.

    Examples
    --------
    >>> import numpy as np
    >>> x, y = np.meshgrid(np.arange(21.0), np.arange(3.0))
    >>> UV = np.stack([x.ravel(), y.ravel()], 1)  # a 20 x 2 strip
    >>> i = np.arange(63).reshape(3, 21)[:-1, :-1].ravel()
    >>> F = np.concatenate([np.stack([i, i + 1, i + 22], 1), np.stack([i, i + 22, i + 21], 1)])
    >>> [len(p) for p in split_for_packing(UV, F)]
    [16, 16, 16, 16, 16]
    >>> [len(p) for p in split_for_packing(UV, F, big=False, max_length=12.0)]
    [40, 40]
    >>> split_for_packing(UV, F, big=False) is None
    True
    """
    F = np.asarray(F, dtype=np.int64)
    UV = np.asarray(UV, dtype=np.float64)
    Q, lo, ext, fill = _box(UV, F)
    if not ext.min() > 0:
        return None
    n = int(np.ceil(ext.max() / max_length)) if ext.max() > max_length else 1
    if big and ext.max() > max_aspect * ext.min():
        n = max(n, int(np.ceil(ext.max() / ext.min() / PACK_PIECE_ASPECT)))
    pieces = _slices(F, Q, lo, ext, n, shift) if n > 1 else None
    if pieces is not None:
        if depth <= 0:
            return pieces
        out = []
        for p in pieces:  # a slice of a ring cut open may still fill its rectangle badly
            sub = split_for_packing(UV, F[p], max_aspect, depth - 1, max_length=max_length,
                                    big=big, min_faces=min_faces, shift=shift)
            out += [p] if sub is None else [p[q] for q in sub]
        return out
    if not big or fill >= PACK_MIN_BOX_FILL or depth <= 0 or len(F) < min_faces:
        return None
    halves = _slices(F, Q, lo, ext, 2, shift)
    if halves is None or len(halves) < 2:
        return None
    fills = [_box(UV, F[h])[3] for h in halves]
    if min(fills) <= fill:  # halving did not help
        return None
    out = []
    for h, f in zip(halves, fills, strict=True):
        sub = (
            split_for_packing(UV, F[h], max_aspect, depth - 1, max_length=max_length, big=big,
                              min_faces=min_faces, shift=shift)
            if f < PACK_MIN_BOX_FILL
            else None
        )
        out += [h] if sub is None else [h[p] for p in sub]
    return out


def _merge_strays(F: np.ndarray, k: np.ndarray, rounds: int = 4) -> np.ndarray:
    """Faces of a piece outside its largest face component join a neighbouring piece (a
    jagged boundary leaves a few faces across a straight cut)."""
    topo = edge_topology(F)
    ef = topo.EF[topo.edge_face_count == 2]
    m = len(F)
    for _ in range(rounds):
        same = k[ef[:, 0]] == k[ef[:, 1]]
        A = sp.csr_matrix((np.ones(int(same.sum())), (ef[same, 0], ef[same, 1])), shape=(m, m))
        _, comp = connected_components(A, directed=False)
        size = np.bincount(comp)
        big = np.zeros(k.max() + 1, dtype=np.int64)  # size of each piece's largest component
        np.maximum.at(big, k, size[comp])
        stray = size[comp] < big[k]
        if not stray.any():
            break
        for a, b in ((0, 1), (1, 0)):  # a stray face takes a neighbour's piece
            e = ~same & stray[ef[:, a]]
            k[ef[e, a]] = k[ef[e, b]]
    return k
