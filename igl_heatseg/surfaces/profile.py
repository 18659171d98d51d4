"""Whether a torus fitted to an exact tessellation is evidence: its profile rows and creases.

A torus has three parameters in its profile (the tube's centre and radius in a half-plane
through the axis). On an exact tessellation of a surface of revolution the vertices lie on a
few circles, *rows*, and any three rows lie on one tube circle; four do whenever the profile
is symmetric (an isosceles trapezoid is cyclic). So a thread ridge of a clean bolt, a cone
flank, a cylinder crest and a cone flank each one triangle wide, is a torus to the vertices,
and to the face normals too: the normal of a chord inscribed in a circle is the circle's
normal at the chord's middle (measured on tuning bolt_s1018_coarse_n0 and held-out
bolt_s18012_frontal_n0: every ridge one torus, RMS 0).

What tells a coarse blend from such a ridge is how it meets its neighbours. A fillet is
tangent to them: the faces across its first and last rows turn by about half a facet step,
less than its facets turn at its inner rows. The ridge's flanks meet the next groove at a
crease twice as sharp as its inner ones. :func:`torus_evidence` refuses a torus on at most
:data:`FEW_ROWS` rows when an end row is such a crease.
"""

from __future__ import annotations

import igl
import numpy as np

from .model import Surface

__all__ = ["profile_rows", "torus_evidence", "FEW_ROWS", "ROW_GAP", "TANGENT_RATIO"]

#: Vertices are on one row when their arc positions around the tube are within ROW_GAP x the
#: mean edge length of the faces (an exact export: equal to round-off; noise of 0.05 x the
#: edge length spreads a row wider, and a noisy torus is not judged here).
ROW_GAP = 0.05

#: A torus on at most this many rows is evidence only when tangent to its neighbours (with
#: five or more, the fit itself is: two rows beyond the profile's three parameters).
FEW_ROWS = 4

#: ... tangent: the faces across each end row turn, in the median, by at most TANGENT_RATIO x
#: the median turn across the inner rows (a fillet: about 0.5; a thread ridge: 2).
TANGENT_RATIO = 1.25


def profile_rows(V, F, faces, s: Surface):
    """The rows of a torus's vertices: the circles around its axis they lie on.

    Parameters
    ----------
    V : (n, 3) float64
        Positions.
    F : (m, 3) int64
        Triangles.
    faces : (f,) int64
        The faces fitted by ``s``.
    s : Surface
        A torus.

    Returns
    -------
    verts : (q,) int64
        The faces' vertices.
    row : (q,) int64 or None
        Row of each vertex, ``0..r-1`` in order of the angle around the tube; None when the
        vertices are not on rows (a row wider than ROW_GAP x the mean edge length: a dense or
        noisy mesh).

    Examples
    --------
    Three rings of a tube of radius 1 around a circle of radius 3, 24 vertices each, in two
    bands of triangles:

    >>> import numpy as np
    >>> from igl_heatseg.surfaces.model import Surface
    >>> t, a = np.linspace(0, 2 * np.pi, 24, endpoint=False), np.radians([-30, 0, 30])
    >>> V = np.array([[(3 + np.cos(b)) * np.cos(u), (3 + np.cos(b)) * np.sin(u), np.sin(b)]
    ...               for b in a for u in t])
    >>> F = np.array([f for i in range(2) for j in range(24) for f in (
    ...     [24 * i + j, 24 * i + (j + 1) % 24, 24 * (i + 1) + j],
    ...     [24 * i + (j + 1) % 24, 24 * (i + 1) + (j + 1) % 24, 24 * (i + 1) + j])])
    >>> s = Surface("torus", {"center": np.zeros(3), "axis": np.array([0.0, 0, 1]),
    ...                       "major_radius": 3.0, "minor_radius": 1.0})
    >>> verts, row = profile_rows(V, F, np.arange(len(F)), s)
    >>> np.bincount(row).tolist()
    [24, 24, 24]
    """
    verts = np.unique(F[faces])
    p = s.params
    d = V[verts] - p["center"]
    z = d @ p["axis"]
    rho = np.linalg.norm(d - np.outer(z, p["axis"]), axis=1)
    x, y = rho - p["major_radius"], z  # in the tube's circle; angles from the mean direction
    mx, my = np.mean(x), np.mean(y)  # (not from atan2's cut: a concave fillet straddles it)
    arc = p["minor_radius"] * np.arctan2(mx * y - my * x, mx * x + my * y)
    E = np.sort(np.r_[F[faces][:, [0, 1]], F[faces][:, [1, 2]], F[faces][:, [2, 0]]], axis=1)
    h = float(np.linalg.norm(V[E[:, 0]] - V[E[:, 1]], axis=1).mean())
    order = np.argsort(arc, kind="stable")
    new = np.r_[False, np.diff(arc[order]) > ROW_GAP * h]
    row = np.empty(len(verts), dtype=np.int64)
    row[order] = np.cumsum(new)
    lo = np.full(int(row.max()) + 1, np.inf)
    hi = np.full(len(lo), -np.inf)
    np.minimum.at(lo, row, arc)
    np.maximum.at(hi, row, arc)
    if np.any(hi - lo > ROW_GAP * h):
        return verts, None
    return verts, row


def torus_evidence(V, F, faces, s: Surface, FN) -> bool:
    """Whether a torus fit of ``faces`` is evidence of a torus, not of rows that any torus fits.

    False on two rows or fewer (one band of faces: a cone). On three or four exact rows, False
    when the faces across an end row turn, in the median, by more than :data:`TANGENT_RATIO` x
    the median turn across the inner rows: a ridge between creases, not a blend tangent to its
    neighbours. Else True: on rows that are not exact (:func:`profile_rows` gives None), on
    more than :data:`FEW_ROWS` rows, and where no end row is a crease (no neighbour across
    it, or the set's border does not follow the rows).

    Parameters
    ----------
    V : (n, 3) float64
        Positions.
    F : (m, 3) int64
        Triangles of the whole mesh (the neighbours are read here).
    faces : (f,) int64
        The faces fitted by ``s``.
    s : Surface
        A torus fit of ``faces``.
    FN : (m, 3) float64
        Unit face normals by face id, consistently oriented.

    Returns
    -------
    bool

    Examples
    --------
    A thread ridge (a cone flank, a cylinder crest, a cone flank; 24 facets per turn) and the
    next flank across the valley; the ridge's rows lie on a torus:

    >>> import numpy as np
    >>> from igl_heatseg.mesh.geometry import face_normals
    >>> from igl_heatseg.surfaces.select import fit_surface
    >>> from igl_heatseg.surfaces.samples import vertex_samples
    >>> t = np.linspace(0, 2 * np.pi, 24, endpoint=False)
    >>> prof = [(9.95, 0.0), (10.68, 0.97), (10.68, 1.45), (9.95, 2.42), (10.68, 3.39)]
    >>> V = np.array([[r * np.cos(u), r * np.sin(u), z] for r, z in prof for u in t])
    >>> F = np.array([f for i in range(4) for j in range(24) for f in (
    ...     [24 * i + j, 24 * i + (j + 1) % 24, 24 * (i + 1) + j],
    ...     [24 * i + (j + 1) % 24, 24 * (i + 1) + (j + 1) % 24, 24 * (i + 1) + j])])
    >>> ridge = np.arange(3 * 48)
    >>> s = fit_surface(*vertex_samples(V, F, ridge), tol=1e-6, kinds=("torus",))
    >>> s.kind, torus_evidence(V, F, ridge, s, face_normals(V, F))
    ('torus', False)
    """
    faces = np.asarray(faces, dtype=np.int64)
    verts, row = profile_rows(V, F, faces, s)
    if row is None:
        return True
    rows = int(row.max()) + 1
    if rows > FEW_ROWS:
        return True
    if rows <= 2:
        return False
    row_of = np.full(len(V), -1, dtype=np.int64)
    row_of[verts] = row
    # the set and the faces touching it, with their adjacency (TT[i, j]: the face across the
    # edge from corner j to corner j + 1)
    sub = np.flatnonzero(np.isin(F, verts).any(axis=1))
    Fs = F[sub]
    TT = igl.triangle_triangle_adjacency(np.ascontiguousarray(Fs))[0]
    inside = np.isin(sub, faces)
    r0, r1 = row_of[Fs], row_of[np.roll(Fs, -1, axis=1)]
    along = inside[:, None] & (r0 == r1) & (r0 >= 0) & (TT >= 0)  # edges along a row
    i, j = np.nonzero(along)
    g = TT[i, j]

    def turn(f, h):
        return np.arccos(np.clip(np.einsum("ij,ij->i", FN[sub[f]], FN[sub[h]]), -1.0, 1.0))

    inner_edge = inside[g] & (g > i)  # inner rows: each edge shared by two of the faces once
    inner = turn(i[inner_edge], g[inner_edge])
    end = ~inside[g]  # end rows: the face across is outside the set (none at the mesh border)
    if not len(inner) or not end.any():  # no end row to judge: border off the rows, or none
        return True
    ends, brow = turn(i[end], g[end]), r0[i[end], j[end]]
    bar = TANGENT_RATIO * float(np.median(inner))
    for r in (0, rows - 1):
        at = brow == r
        if at.any() and float(np.median(ends[at])) > bar:
            return False
    return True
