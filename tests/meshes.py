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
