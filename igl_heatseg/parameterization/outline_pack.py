"""Pack charts by their outlines on a raster (issue 13: an atlas as tight as xatlas).

Every chart map is bijective, so its image is the polygon bounded by the image of its boundary
loops.  Each chart (scaled to the common texel density) is rasterised *exactly
conservatively* at several rotation angles: the pixels that meet the closed polygon (pixel
centres inside it, plus every pixel a boundary edge passes through).  The pixels closer than
the gap to a chart's pixels form its *halo*; two charts are at least the gap apart when
neither's pixels meet the other's halo.  The texel is set so that the gap is just under a
whole number of pixels (one, by default): the halo then wastes least.

Charts are placed one by one in a square *bin* of ``s`` pixels: among the positions where
the chart's halo meets no placed chart and stays inside the bin, the one with the largest
*contact* (the fraction of a ring of pixels around the halo, about a quarter of the chart's
size wide, on placed charts or the bin walls), then the lowest, then the leftmost; over all
its angles (8 for large or long charts, 4 for the others).  Collision and contact at every
position come from one FFT correlation of the occupancy grid with
``halo + ring / (2 * ring size)``, each chosen position checked exactly.  A chart that fits
nowhere grows the bin as little as possible.  The bin side is bisected for one chart order
(longest side first), then other orders try to beat the best layout by a pixel, within a
fixed amount of work (deterministic: no clock); the smallest layout is kept.

Charts are thus at least the gap apart and never overlap (although their bounding boxes
may), every chart is only rotated (orientation kept) and translated.
"""

from __future__ import annotations

import numpy as np
from scipy import fft, ndimage

from ..mesh.topology import boundary_loops

__all__ = [
    "rasterize_chart",
    "rotate_points",
    "gutter_structure",
    "pack_outlines",
    "OUTLINE_PIXELS",
    "OUTLINE_MAX_CHARTS",
]

#: Pixels covered by the charts' boxes together (sets the texel size of the raster; with
#: the default gutter the gap is then about one pixel, see :func:`pack_outlines`).
OUTLINE_PIXELS: int = 60_000

#: Outline packing is used up to this many charts.
OUTLINE_MAX_CHARTS: int = 500

#: Rotations tried (evenly spaced over a full turn, from the minimum-area rectangle) for the
#: charts holding at least :data:`_BIG_SHARE` of the area or longer than :data:`_LONG` times
#: the square root of the total box area (a long strip may need a diagonal), and for the rest.
_ANGLES_BIG, _ANGLES_SMALL = 8, 4
_BIG_SHARE = 0.02
_LONG = 0.3

#: Work allowed for all layouts together: pixels of the grids correlated, plus
#: :data:`_OVERHEAD` per correlation (its fixed cost); about 1 s on the reference machine.
_WORK = 3e8
_OVERHEAD = 8000

#: The first bin tried, as a fill of the chart pixels.
_FIRST_FILL = 0.8

#: Width of the contact ring around a chart's halo, per square root of its pixel count.
_RING = 0.25

#: Orders tried after the three sorted ones: longest side first, each side scaled by a
#: random factor in ``1 +- _JITTER`` (fixed seed).
_JITTERED = 20
_JITTER = 0.2

#: Rounding margin (pixel units) used when a coordinate falls on a pixel border.
_EPS = 1e-7

#: Charts are rasterised with their minimum this far (pixel units) inside their corner
#: pixel, so that the pixels left of and below it (touched on their border) stay empty.
_SHIFT = 1e-5


def _mark(M: np.ndarray, ii: np.ndarray, jj: np.ndarray) -> None:
    ok = (ii >= 0) & (ii < M.shape[0]) & (jj >= 0) & (jj < M.shape[1])
    M[ii[ok], jj[ok]] = True


def _ranges(lo: np.ndarray, hi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """All integers ``lo[e] <= k < hi[e]``: ``(e, k)`` pairs."""
    n = np.maximum(hi - lo, 0)
    e = np.repeat(np.arange(len(lo)), n)
    k = np.arange(n.sum()) - np.repeat(np.cumsum(n) - n, n) + np.repeat(lo, n)
    return e, k


def rasterize_chart(
    P: np.ndarray, F: np.ndarray, texel: float, pad: int, loops: list | None = None
) -> np.ndarray:
    """Exactly conservative pixel mask of a chart's image: every pixel meeting the polygon.

    Parameters
    ----------
    P : (n, 2) float64
        Chart UVs with their minimum at the origin.
    F : (m, 3) int64
        Triangles (a disk, or any triangulation whose boundary loops bound its image).
    texel : float
        Pixel size in the units of ``P``.
    pad : int
        Empty pixels added around the chart (the chart's origin is at pixel ``(pad, pad)``).
    loops : list of (b,) int64, optional
        Boundary loops of ``F`` (computed when omitted).

    Returns
    -------
    (h, w) bool
        Row ``i``, column ``j`` covers ``[(j - pad) t, (j - pad + 1) t] x [(i - pad) t, ...]``.

    Examples
    --------
    >>> import numpy as np
    >>> sq = np.array([[0.0, 0], [4, 0], [4, 4], [0, 4]]); F = np.array([[0, 1, 2], [0, 2, 3]])
    >>> M = rasterize_chart(sq + 0.5, F, 1.0, 0)  # a 4 x 4 square across 5 x 5 pixels
    >>> M.shape, int(M.sum())
    ((5, 5), 25)
    >>> int(rasterize_chart(sq * 0.999, F, 1.0, 1)[1:-1, 1:-1].sum())
    16
    """
    loops = boundary_loops(F) if loops is None else loops
    X = P / texel + pad  # pixel units
    w = int(np.floor(X[:, 0].max() + _EPS)) + 1 + pad
    h = int(np.floor(X[:, 1].max() + _EPS)) + 1 + pad
    M = np.zeros((h, w), dtype=bool)
    A = np.concatenate([X[lp] for lp in loops])
    B = np.concatenate([X[np.roll(lp, -1)] for lp in loops])
    # interior: pixel centres inside the polygon (even-odd over all loops), a span per pair
    # of crossings of a row's centre line
    lo, hi = np.minimum(A[:, 1], B[:, 1]), np.maximum(A[:, 1], B[:, 1])
    e, rows = _ranges(np.ceil(lo - 0.5).astype(np.int64), np.ceil(hi - 0.5).astype(np.int64))
    a, b = A[e], B[e]
    xs = a[:, 0] + (rows + 0.5 - a[:, 1]) * (b[:, 0] - a[:, 0]) / (b[:, 1] - a[:, 1])
    o = np.lexsort((xs, rows))
    rows, xs = rows[o][0::2], xs[o]
    j0 = np.clip(np.ceil(xs[0::2] - 0.5).astype(np.int64), 0, w)
    j1 = np.clip(np.floor(xs[1::2] - 0.5).astype(np.int64) + 1, 0, w)
    keep = j1 > j0
    span = np.zeros((h, w + 1), dtype=np.int32)
    np.add.at(span, (rows[keep], j0[keep]), 1)
    np.add.at(span, (rows[keep], j1[keep]), -1)
    M |= np.cumsum(span, axis=1)[:, :w] > 0
    # boundary: the pixels on both sides of every crossing of a grid line, and the vertices'
    for ax in (0, 1):
        lo, hi = np.minimum(A[:, ax], B[:, ax]), np.maximum(A[:, ax], B[:, ax])
        e, k = _ranges(np.ceil(lo).astype(np.int64), np.floor(hi).astype(np.int64) + 1)
        a, b = A[e], B[e]
        d = b[:, ax] - a[:, ax]
        t = (k - a[:, ax]) / np.where(d != 0, d, 1.0)
        v = a[:, 1 - ax] + t * (b[:, 1 - ax] - a[:, 1 - ax])
        for dv in (-_EPS, _EPS):
            c = np.floor(v + dv).astype(np.int64)
            for dk in (-1, 0):
                _mark(M, *((c, k + dk) if ax == 0 else (k + dk, c)))
    for dx in (-_EPS, _EPS):
        for dy in (-_EPS, _EPS):
            ii = np.floor(X[:, 1] + dy).astype(np.int64)
            _mark(M, ii, np.floor(X[:, 0] + dx).astype(np.int64))
    return M


def gutter_structure(gap: float) -> np.ndarray:
    """Pixel offsets ``(di, dj)`` whose pixel squares are closer than ``gap`` (pixel units).

    Dilating a chart's pixels by this structure gives its halo: pixels outside it are at
    least ``gap`` from every pixel of the chart.

    Parameters
    ----------
    gap : float
        Distance in pixels, ``>= 0``.

    Returns
    -------
    (2 r + 1, 2 r + 1) bool
        Centred at ``(r, r)``.

    Examples
    --------
    >>> gutter_structure(0.0).astype(int).tolist()
    [[1]]
    >>> gutter_structure(1.2).astype(int).tolist()
    [[0, 1, 1, 1, 0], [1, 1, 1, 1, 1], [1, 1, 1, 1, 1], [1, 1, 1, 1, 1], [0, 1, 1, 1, 0]]
    """
    r = int(np.ceil(gap)) + 1
    d = np.maximum(np.abs(np.arange(-r, r + 1)) - 1, 0).astype(np.float64)
    S = np.hypot(d[:, None], d[None, :]) < gap
    S[r, r] = True
    keep = np.flatnonzero(S.any(axis=0))
    r0 = r - int(keep[0]) if len(keep) else r
    return S[r - r0 : r + r0 + 1, r - r0 : r + r0 + 1]


class _Shape:
    """One chart at one angle.

    ``R``: its pixels, ``pad`` empty pixels around (the chart's corner at pixel
    ``(pad, pad)``); ``hr, wr``: its extent in pixels from there.  ``halo``: the pixels closer
    than the gap to ``R``, ``b`` more empty pixels around; ``ring``: the pixels of the frame
    within ``b`` of the halo (Chebyshev), counted.  ``K = halo + ring / (2 * ring count)``:
    correlated with the occupancy, it gives ``overlap + contact / 2`` at every position
    (contact: the fraction of the ring on occupied pixels or walls, in ``[0, 1]``).
    """

    __slots__ = ("R", "K", "halo", "ring", "hr", "wr", "angle", "b")

    def __init__(self, R: np.ndarray, halo: np.ndarray, pad: int, angle: float, b: int):
        Dp = np.pad(halo, b)
        ring = ndimage.maximum_filter(Dp, size=2 * b + 1) & ~Dp  # separable box dilation
        self.R = R
        self.ring = int(ring.sum())
        self.K = (Dp + ring * (0.5 / max(self.ring, 1))).astype(np.float32)
        self.halo = Dp
        rows, cols = np.nonzero(R)
        self.hr = int(rows.max()) + 1 - pad
        self.wr = int(cols.max()) + 1 - pad
        self.angle = angle
        self.b = b


def rotate_points(P: np.ndarray, t: float) -> np.ndarray:
    """Points rotated by ``t`` radians counter-clockwise about the origin.

    Parameters
    ----------
    P : (p, 2) float64
    t : float

    Returns
    -------
    (p, 2) float64

    Examples
    --------
    >>> import numpy as np
    >>> rotate_points(np.array([[1.0, 0.0]]), np.pi / 2).round(12).tolist()
    [[0.0, 1.0]]
    """
    c, s = np.cos(t), np.sin(t)
    return P @ np.array([[c, s], [-s, c]])


def _shapes(local: list, faces: list, texel: float, gap: float, n_angles: list) -> tuple:
    """Every chart's :class:`_Shape` per angle, and the pad (halo radius) in pixels."""
    S = gutter_structure(gap)
    pad = S.shape[0] // 2
    out = []
    for P, F, na in zip(local, faces, n_angles, strict=True):
        loops = boundary_loops(F)
        rot: list = []
        for t in np.arange(na) * (2 * np.pi / na):
            Q = rotate_points(P, t) if t else P
            R = rasterize_chart(Q - Q.min(axis=0) + _SHIFT * texel, F, texel, pad, loops)
            # one ring width for all angles of a chart (its frame in the grid)
            b = rot[0].b if rot else int(np.clip(round(_RING * np.sqrt(R.sum())), 2, 16))
            rot.append(_Shape(R, ndimage.binary_dilation(R, S) if pad else R, pad, float(t), b))
        out.append(rot)
    return out, pad


def _best(W: np.ndarray, Wh: np.ndarray, sh: _Shape, n: int, side: int | None):
    """Best position of shape ``sh`` on the grid ``W`` (spectrum ``Wh``) where the kernel's
    frame spans ``n`` pixels: ``(key, y, x)`` or ``None``; the larger key is better: the
    contact in thousandths, then the lowest, then the leftmost position; when growing
    (``side`` = current bin side) the smallest bin side reached comes first."""
    kh, kw = sh.K.shape
    ny, nx = n - kh + 1, n - kw + 1
    if ny <= 0 or nx <= 0:
        return None
    g = W.shape[0]
    # correlation = convolution with the flipped kernel (rfft2 of the padded kernel, whose
    # rows past kh are zero: one transform along x on kh rows, then along y)
    P = fft.fft(fft.rfft(sh.K[::-1, ::-1], n=g, axis=1), n=g, axis=0)
    P *= Wh
    C = fft.irfft2(P, s=W.shape)[kh - 1 : kh - 1 + ny, kw - 1 : kw - 1 + nx]
    C *= 2000.0  # 2000 * overlap + contact in thousandths
    free = C < 1500.0  # no halo pixel on an occupied one (FFT rounding is ~1e-2 at most)
    contact = np.rint(C, out=C)
    if side is None:
        score = np.where(free, contact, -1.0)
    else:
        reach = np.maximum(np.arange(ny)[:, None] + sh.hr, np.arange(nx)[None, :] + sh.wr)
        score = np.where(free, contact - np.maximum(reach, side) * 2000.0, -np.inf)
    while True:
        y, x = divmod(int(np.argmax(score)), nx)  # the first maximum: lowest, then leftmost
        if not free[y, x]:
            return None
        if not W[y : y + kh, x : x + kw][sh.halo].any():  # exact check (FFT rounding)
            grew = 0 if side is None else max(y + sh.hr, x + sh.wr, side)
            return (-grew, int(contact[y, x]), -(y * n + x)), y, x
        free[y, x] = False
        score[y, x] = -np.inf


def _place(occ: np.ndarray, side: int, rot: list, pad: int, grow: bool = False) -> tuple:
    """Best position of a chart (its shapes ``rot``, one per angle) in the bin of ``side``
    pixels holding ``occ`` (or, ``grow``, in a bin grown as little as possible):
    ``((key, y, x, angle index) or None, work)``."""
    # kernel frames span [0, n): the bin at [b + pad, b + pad + side), walls outside [b, n - b)
    b = rot[0].b
    n = side + (max(max(s.hr, s.wr) for s in rot) if grow else 0) + 2 * pad + 2 * b
    g = fft.next_fast_len(n, real=True)
    W = np.ones((g, g), dtype=np.float32)
    W[b : n - b, b : n - b] = 0
    o = min(side, occ.shape[0])
    W[pad + b : pad + b + o, pad + b : pad + b + o] = occ[:o, :o]
    Wh = fft.rfft2(W)
    best = None
    for q, sh in enumerate(rot):
        got = _best(W, Wh, sh, n, side if grow else None)
        if got is not None and (best is None or got[0] > best[0]):
            best = (got[0], got[1], got[2], q)
    return best, len(rot) * (g * g + _OVERHEAD) + g * g


def _stamp(occ: np.ndarray, sh: _Shape, pad: int, y: int, x: int) -> None:
    """Add a chart's pixels to ``occ``, its corner pixel ``(pad, pad)`` at ``(y, x)``."""
    occ[y : y + sh.hr, x : x + sh.wr] += sh.R[pad : pad + sh.hr, pad : pad + sh.wr]


def _layout(shapes: list, order: np.ndarray, pad: int, s0: int) -> tuple:
    """Place charts in ``order`` in a bin of ``s0`` pixels, grown when a chart fits nowhere.

    Returns ``(pos, used, grown, work)``: ``pos[i] = (y, x, angle index)`` of chart ``i``'s
    corner pixel in the bin, the side of the square the charts' pixels span, whether the bin
    had to grow, and the grid pixels correlated.
    """
    side = s0
    used = 0
    occ = np.zeros((s0, s0), dtype=np.float32)
    pos = [(0, 0, 0)] * len(shapes)
    work = 0.0
    for i in order:
        best, w = _place(occ, side, shapes[i], pad)
        work += w
        if best is None:
            best, w = _place(occ, side, shapes[i], pad, grow=True)
            work += w
        if best is None:  # cannot happen: the grown bin has room for the chart beside all
            raise RuntimeError("pack_outlines: internal error, a chart fits nowhere")
        _, y, x, q = best
        sh = shapes[i][q]
        used = max(used, y + sh.hr, x + sh.wr)
        if used > occ.shape[0]:
            grown = np.zeros((used, used), dtype=np.float32)
            grown[: occ.shape[0], : occ.shape[1]] = occ
            occ = grown
        side = max(side, used)
        _stamp(occ, sh, pad, y, x)
        pos[i] = (y, x, q)
    return pos, used, side > s0, work


def _orders(shapes: list) -> list:
    """Placement orders tried: longest side first, largest area first, longest outline
    first, then longest side first with sizes jittered (a fixed seed: deterministic)."""
    px = np.array([s[0].R.sum() for s in shapes])
    longest = np.array([max(s[0].hr, s[0].wr) for s in shapes])
    ring = np.array([s[0].ring for s in shapes])
    out = [np.lexsort((-px, -longest)), np.lexsort((-longest, -px)), np.lexsort((-px, -ring))]
    rng = np.random.default_rng(0)
    for _ in range(_JITTERED):
        j = rng.uniform(1 - _JITTER, 1 + _JITTER, len(shapes))
        out.append(np.argsort(-longest * j, kind="stable"))
    unique, seen = [], set()
    for o in out:  # few charts: many repeats
        if o.tobytes() not in seen:
            seen.add(o.tobytes())
            unique.append(o)
    return unique


def pack_outlines(
    local: list, faces: list, gap: float, pixels: int | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """Place charts by their outlines (see the module docstring).

    Parameters
    ----------
    local : list of (n_i, 2) float64
        Charts in common units, minimum at the origin.
    faces : list of (m_i, 3) int64
        Their triangles.
    gap : float
        Smallest distance between two charts, in the units of ``local``.
    pixels : int, optional
        Raster size: pixels covered by the charts' boxes together (default
        :data:`OUTLINE_PIXELS`), before the texel is adjusted to make the gap a whole number
        of pixels.

    Returns
    -------
    offsets : (k, 2) float64
        Translation of every chart after its rotation by ``angles`` about the origin and
        moving its minimum back to the origin.
    angles : (k,) float64
        Rotation of every chart (radians, counter-clockwise).

    Examples
    --------
    >>> import numpy as np
    >>> sq = np.array([[0.0, 0], [1, 0], [1, 1], [0, 1]]); F = np.array([[0, 1, 2], [0, 2, 3]])
    >>> off, ang = pack_outlines([sq, sq, sq, sq], [F] * 4, 0.0)
    >>> span = (off + 1).max(axis=0) - off.min(axis=0)
    >>> bool(np.all(span < 2.1)), ang.shape
    (True, (4,))
    """
    pixels = OUTLINE_PIXELS if pixels is None else pixels
    area = np.array([np.prod(np.maximum(P.max(axis=0), 1e-300)) for P in local])
    texel = float(np.sqrt(area.sum() / pixels))
    m = round(gap / texel)
    if m >= 1 and gap / m > 0.7 * texel:  # the gap a whole number of pixels (just under):
        texel = gap / m * (1 + 1e-9)  # the halo wastes least (at most twice the pixels)
    longest = np.array([P.max() for P in local])
    big = (area >= _BIG_SHARE * area.sum()) | (longest >= _LONG * np.sqrt(area.sum()))
    angles = np.where(big, _ANGLES_BIG, _ANGLES_SMALL)
    shapes, pad = _shapes(local, faces, texel, gap / texel, angles)
    px = np.array([s[0].R.sum() for s in shapes])
    orders = _orders(shapes)
    lo = max(int(np.sqrt(px.sum())), max(min(max(s.hr, s.wr) for s in r) for r in shapes)) - 1
    s_try = max(int(np.sqrt(px.sum() / _FIRST_FILL)), lo + 1)
    best = None
    work = 0.0
    # the first order: bisection of the bin side between a side that grew and the best one
    while work < _WORK and (best is None or best[1] - lo > 1):
        pos, used, grown, w = _layout(shapes, orders[0], pad, s_try)
        work += w
        if best is None or used < best[1]:
            best = (pos, used)
        if grown:
            lo = max(lo, s_try)
        s_try = (lo + best[1]) // 2
    # the other orders, each as long as it beats the best layout by a pixel
    for order in orders[1:]:
        while work < _WORK:
            pos, used, grown, w = _layout(shapes, order, pad, best[1] - 1)
            work += w
            if grown:
                break
            best = (pos, used)
    pos = best[0]
    angles = np.array([shapes[i][q].angle for i, (_, _, q) in enumerate(pos)])
    offsets = (np.array([(x, y) for y, x, _ in pos], dtype=np.float64) + _SHIFT) * texel
    return offsets, angles
