"""Analytic test meshes (numpy only), consistently oriented, outward normals."""

from __future__ import annotations

import numpy as np

from igl_heatseg.mesh.checks import validate_mesh


def grid(nx: int, ny: int, sx: float = 1.0, sy: float = 1.0):
    """Flat (nx+1) x (ny+1) vertex grid in the z=0 plane, normals +z."""
    x, y = np.meshgrid(np.linspace(0, sx, nx + 1), np.linspace(0, sy, ny + 1), indexing="ij")
    V = np.c_[x.ravel(), y.ravel(), np.zeros(x.size)]
    idx = np.arange((nx + 1) * (ny + 1)).reshape(nx + 1, ny + 1)
    a, b = idx[:-1, :-1].ravel(), idx[1:, :-1].ravel()
    c, d = idx[1:, 1:].ravel(), idx[:-1, 1:].ravel()
    F = np.r_[np.c_[a, b, c], np.c_[a, c, d]]
    return V, F


def cube(n: int = 6):
    """Closed unit cube [-1,1]^3, each side an n x n grid; duplicate corners merged."""
    Vg, Fg = grid(n, n, 2.0, 2.0)
    Vg = Vg - [1.0, 1.0, 0.0]
    Vs, Fs = [], []
    # Map grid (u, v) onto each side so that the grid's +z normal points outward.
    sides = [
        lambda u, v: np.c_[u, v, np.ones_like(u)],  # +z
        lambda u, v: np.c_[v, u, -np.ones_like(u)],  # -z
        lambda u, v: np.c_[np.ones_like(u), u, v],  # +x
        lambda u, v: np.c_[-np.ones_like(u), v, u],  # -x
        lambda u, v: np.c_[v, np.ones_like(u), u],  # +y
        lambda u, v: np.c_[u, -np.ones_like(u), v],  # -y
    ]
    for k, f in enumerate(sides):
        Vs.append(f(Vg[:, 0], Vg[:, 1]))
        Fs.append(Fg + k * len(Vg))
    m = validate_mesh(np.vstack(Vs), np.vstack(Fs))
    return m.V, m.F


def cylinder(
    n_around: int = 64,
    n_height: int = 8,
    radius: float = 1.0,
    height: float = 2.0,
    caps: bool = True,
):
    """Cylinder along z; side (n_around x n_height quads), optional fan caps."""
    t = np.linspace(0, 2 * np.pi, n_around, endpoint=False)
    z = np.linspace(0, height, n_height + 1)
    V = np.c_[
        np.tile(radius * np.cos(t), len(z)),
        np.tile(radius * np.sin(t), len(z)),
        np.repeat(z, n_around),
    ]
    idx = np.arange(len(V)).reshape(len(z), n_around)
    a = idx[:-1].ravel()
    b = np.roll(idx[:-1], -1, axis=1).ravel()
    c = np.roll(idx[1:], -1, axis=1).ravel()
    d = idx[1:].ravel()
    F = np.r_[np.c_[a, b, c], np.c_[a, c, d]]
    if caps:
        # rings of the caps: two inner rings so that caps have interior seed vertices
        Vc, Fc = [V], [F]
        off = len(V)
        for zc, ring, sign in ((0.0, idx[0], -1), (height, idx[-1], 1)):
            r2 = np.c_[0.5 * radius * np.cos(t), 0.5 * radius * np.sin(t), np.full(n_around, zc)]
            ctr = np.array([[0.0, 0.0, zc]])
            Vc += [r2, ctr]
            inner = off + np.arange(n_around)
            center = off + n_around
            nxt = np.roll(np.arange(n_around), -1)
            q1 = np.c_[ring, ring[nxt], inner[nxt]]
            q2 = np.c_[ring, inner[nxt], inner]
            fan = np.c_[inner, inner[nxt], np.full(n_around, center)]
            Fcap = np.r_[q1, q2, fan]
            if sign < 0:  # bottom cap faces -z
                Fcap = Fcap[:, ::-1]
            Fc.append(Fcap)
            off += n_around + 1
        V, F = np.vstack(Vc), np.vstack(Fc)
    return V, F


def disk(n_around: int = 32, n_rings: int = 6):
    """Flat unit disk in z=0, normals +z, with one boundary loop."""
    Vs = [np.zeros((1, 3))]
    Fs = []
    prev = np.zeros(1, dtype=np.int64)
    off = 1
    t = np.linspace(0, 2 * np.pi, n_around, endpoint=False)
    for r in range(1, n_rings + 1):
        ring = off + np.arange(n_around)
        Vs.append(np.c_[r / n_rings * np.cos(t), r / n_rings * np.sin(t), np.zeros(n_around)])
        nxt = np.roll(np.arange(n_around), -1)
        if r == 1:
            Fs.append(np.c_[np.zeros(n_around, dtype=np.int64), ring, ring[nxt]])
        else:
            Fs.append(np.c_[prev, ring, ring[nxt]])
            Fs.append(np.c_[prev, ring[nxt], prev[nxt]])
        prev = ring
        off += n_around
    return np.vstack(Vs), np.vstack(Fs)


def sphere(levels: int = 4):
    """Loop-subdivided icosahedron projected to the unit sphere."""
    import igl

    V, F = igl.icosahedron()
    for _ in range(levels):
        V, F = igl.upsample(V, F)
        V = V / np.linalg.norm(V, axis=1, keepdims=True)
    return V, F


def plane_into_cylinder(noise: float, seed: int = 0, h: float = 0.25, R: float = 4.0):
    """A plane z = 0 (x < 0) running tangentially into a cylinder of radius R (axis along y
    at height R), gridded by arc length s in [-6, 6] and y in [0, 6], vertices moved by Gaussian
    noise: V, F (consistently oriented), the arc length of each face's centroid, and the two
    exact surfaces {0: plane, 1: cylinder}."""
    from igl_heatseg.surfaces.model import Surface

    s, y = np.meshgrid(np.arange(-6, 6 + h / 2, h), np.arange(0, 6 + h / 2, h), indexing="ij")
    s, y = s.ravel(), y.ravel()
    phi = np.maximum(s, 0) / R
    V = np.c_[np.where(s < 0, s, R * np.sin(phi)), y, np.where(s < 0, 0, R - R * np.cos(phi))]
    ns, ny = len(np.arange(-6, 6 + h / 2, h)), len(np.arange(0, 6 + h / 2, h))
    idx = np.arange(ns * ny).reshape(ns, ny)
    a, b = idx[:-1, :-1].ravel(), idx[1:, :-1].ravel()
    c, d = idx[1:, 1:].ravel(), idx[:-1, 1:].ravel()
    F = np.r_[np.c_[a, b, c], np.c_[a, c, d]].astype(np.int64)
    V = V + np.random.default_rng(seed).normal(scale=noise, size=V.shape)
    plane = Surface("plane", {"point": np.zeros(3), "normal": np.array([0.0, 0, 1])})
    cyl = Surface("cylinder", {"point": np.array([0.0, 0, R]), "axis": np.array([0.0, 1, 0]),
                               "radius": R})
    S = np.r_[s][F].mean(axis=1)  # arc length of each face's centroid
    return V, F, S, {0: plane, 1: cyl}


def pipe_bend(noise: float, seed: int = 0, r: float = 3.0, R: float = 10.0, length: float = 12.0,
              h: float = 0.4):
    """A tube of radius r: a straight cylinder along x (arc length s in [-length, 0]) running
    tangentially into a 90-degree torus bend of major radius R towards +z, gridded at about h
    along and around, vertices moved by Gaussian noise: V, F, and the arc length of each face's
    centroid (negative on the cylinder)."""
    s = np.arange(-length, R * np.pi / 2 + h / 2, h)
    phi = np.arange(0.0, 2 * np.pi, h / r)
    S, P = np.meshgrid(s, phi, indexing="ij")
    t = np.clip(S, 0, None) / R
    C = np.stack([np.where(S < 0, S, R * np.sin(t)), 0 * S, np.where(S < 0, 0, R - R * np.cos(t))],
                 axis=-1)
    N1 = np.stack([-np.sin(t), 0 * S, np.cos(t)], axis=-1)
    N2 = np.stack([0 * S, 1 + 0 * S, 0 * S], axis=-1)
    V = (C + r * (np.cos(P)[..., None] * N1 + np.sin(P)[..., None] * N2)).reshape(-1, 3)
    idx = np.arange(S.size).reshape(S.shape)
    a, b = idx[:-1].ravel(), idx[1:].ravel()
    c, d = np.roll(idx[1:], -1, axis=1).ravel(), np.roll(idx[:-1], -1, axis=1).ravel()
    F = np.r_[np.c_[a, b, c], np.c_[a, c, d]].astype(np.int64)
    V = V + np.random.default_rng(seed).normal(scale=noise, size=V.shape)
    return V, F, S.ravel()[F].mean(axis=1)


def revolved(profile, n=96):
    """A surface of revolution about z, one row of quads (two triangles each) per segment of
    the ``(r, z)`` profile polyline, ``n`` around; returns V, F and each face's profile
    segment."""
    t = 2 * np.pi * np.arange(n) / n
    V = np.vstack([np.c_[r * np.cos(t), r * np.sin(t), np.full(n, z)] for r, z in profile])
    j = np.arange(n)
    F = np.vstack([np.r_[np.c_[i * n + j, i * n + (j + 1) % n, (i + 1) * n + (j + 1) % n],
                         np.c_[i * n + j, (i + 1) * n + (j + 1) % n, (i + 1) * n + j]]
                   for i in range(len(profile) - 1)]).astype(np.int64)
    return V, F, np.repeat(np.arange(len(profile) - 1), 2 * n)


def thread_profile(ridges: int):
    """``(r, z)`` profile of ``ridges`` V-thread ridges of a clean generated bolt (held-out
    bolt_s18012_frontal_n0): flank, crest, flank, then the next ridge from the valley; one
    row each when revolved. The creases turn by 37 degrees (flank to crest) and 74 (the
    valley)."""
    prof = [(9.95, 0.0)]
    for _ in range(ridges):
        z = prof[-1][1]
        prof += [(10.68, z + 0.97), (10.68, z + 1.45), (9.95, z + 2.42)]
    return prof


def extruded(profile, h: float, width: float = 8.0, noise: float = 0.0, seed: int = 0):
    """The ``(x, z)`` profile polyline swept along y over ``width``, gridded at about ``h``
    (the profile's corners are grid lines), vertices moved by Gaussian noise of ``noise``:
    V, F, the profile segment of each face and the arc length of its centroid."""
    P = np.asarray(profile, dtype=np.float64)
    knots = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(P, axis=0), axis=1))]
    s = np.unique(np.r_[np.arange(0.0, knots[-1] + 1e-9, h), knots])
    x, z = np.interp(s, knots, P[:, 0]), np.interp(s, knots, P[:, 1])
    y = np.arange(0.0, width + 1e-9, h)
    ns, ny = len(s), len(y)
    V = np.c_[np.repeat(x, ny), np.tile(y, ns), np.repeat(z, ny)]
    idx = np.arange(ns * ny).reshape(ns, ny)
    a, b = idx[:-1, :-1].ravel(), idx[1:, :-1].ravel()
    c, d = idx[1:, 1:].ravel(), idx[:-1, 1:].ravel()
    F = np.r_[np.c_[a, b, c], np.c_[a, c, d]].astype(np.int64)
    sc = np.repeat(s, ny)[F].mean(axis=1)
    V = V + np.random.default_rng(seed).normal(scale=noise, size=V.shape)
    return V, F, np.searchsorted(knots, sc) - 1, sc


def blind_hole(n: int = 12, rings: int = 40, h: float = 0.5, r: float = 1.0,
               noise: float = 0.0, seed: int = 0):
    """The wall of a round hole (an ``n``-sided prism of radius ``r``, ``rings`` rows of height
    ``h``, open at the top) closed at z = 0 by a fan of ``n`` triangles (faces ``0..n-1``)
    around the centre (vertex 0); vertices moved by Gaussian noise of ``noise``: V, F."""
    t = np.linspace(0, 2 * np.pi, n, endpoint=False)
    ring = np.c_[r * np.cos(t), r * np.sin(t)]
    V = np.vstack([[[0.0, 0, 0]]] + [np.c_[ring, np.full(n, h * z)] for z in range(rings + 1)])
    i, j = np.arange(n), (np.arange(n) + 1) % n
    F = [np.c_[np.zeros(n, dtype=np.int64), 1 + j, 1 + i]]
    for q in range(rings):
        a, b = 1 + n * q, 1 + n * (q + 1)
        F += [np.c_[a + i, a + j, b + j], np.c_[a + i, b + j, b + i]]
    V = V + np.random.default_rng(seed).normal(scale=noise, size=V.shape)
    return V, np.concatenate(F).astype(np.int64)


def rounded_box(a: float = 2.0, r: float = 1.0, n: int = 12, noise: float = 0.0, seed: int = 0):
    """A box [-a-r, a+r]^3 with every edge rounded with radius ``r``: a cube whose sides are
    ``n`` x ``n`` grids, each point ``p`` moved to ``clamp(p, -a, a) + r * unit(p - clamp)``
    (planes, quarter-cylinder fillets, sphere-octant corners), then by Gaussian noise of
    ``noise``. Returns V, F and each face's true piece: ``kind`` (0 plane, 1 fillet,
    2 corner) and the sign pattern of its clamped centroid (the corner it belongs to)."""
    V, F = cube(n)
    V = V * (a + r)
    Q = np.clip(V, -a, a)
    D = V - Q
    V = Q + r * D / np.maximum(np.linalg.norm(D, axis=1, keepdims=True), 1e-12)
    C = V[F].mean(axis=1)
    kind = (np.abs(C) > a + 1e-9).sum(axis=1) - 1
    V = V + np.random.default_rng(seed).normal(scale=noise, size=V.shape)
    return V, F, kind, np.sign(C)
