"""Machined parts with exact per-face B-Rep labels, reproducible from a seed.

Each part is built with gmsh's OpenCASCADE kernel (boxes, cylinders, cones; fillets,
chamfers, drilled through and blind holes, bosses, rounded slots, pockets), its surface is
meshed by gmsh, and every triangle keeps the id of the B-Rep face (gmsh surface entity) it was
meshed on.  The output mirrors the ABC files in ``shared/data``: ``NAME.obj``,
``NAME.facelabels.txt`` (one label per OBJ face, ``0..k-1``) and ``NAME.surface_types.txt``
(``k Type`` per line; types as in ABC: Plane, Cylinder, Cone, Sphere, Torus, BSpline, Other).

Options: ``noise`` moves every vertex along its (area-weighted) vertex normal by a Gaussian
with standard deviation ``noise * mean edge length``; ``irregular`` in [0, 1) modulates the
target edge length in space by up to that fraction (random smooth field) and switches gmsh to
its MeshAdapt algorithm, so triangle sizes and shapes vary.

Importable::

    import sys; sys.path.insert(0, "tools")
    from make_parts import make_part, add_normal_noise, write_part, KINDS
    part = make_part(3, kind="flange", target_faces=15000)

Command line::

    python tools/make_parts.py --out parts --seeds 0 1 2 3 4 --noise 0.05

Requires ``gmsh`` (PyPI wheel, includes OpenCASCADE; runs headless).
"""

from __future__ import annotations

import argparse
import logging
import math
import os
import sys
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

logger = logging.getLogger("make_parts")

__all__ = [
    "KINDS",
    "Part",
    "make_part",
    "add_normal_noise",
    "mean_edge_length",
    "write_part",
    "read_part",
    "main",
]

#: Part recipes, in the order ``kind=None`` cycles through them (``seed % len(KINDS)``).
KINDS = ("rounded_box", "plate", "bracket", "flange", "block")

#: Default number of triangles aimed at (the result is within FACE_COUNT_SLACK of it).
TARGET_FACES_DEFAULT = 15000

#: Accepted ratio between the triangle count and the target before remeshing with a new size.
FACE_COUNT_SLACK = 1.35

#: Triangles per 2*pi of curvature gmsh aims at on curved faces (small fillets get rows).
CURVATURE_ELEMENTS = 12

#: Smallest triangle size allowed by curvature refinement, as a fraction of the target size.
MIN_SIZE_RATIO = 3.0

#: Tolerance (model units, parts are ~100 units) for selecting edges by their bounding box.
BBOX_TOL = 1e-4

#: Attempts with fresh random parameters when OpenCASCADE rejects a fillet or boolean.
MAX_ATTEMPTS = 6

#: gmsh surface type names -> ABC surface type names.
_TYPE_NAMES = {
    "Plane": "Plane",
    "Cylinder": "Cylinder",
    "Cone": "Cone",
    "Sphere": "Sphere",
    "Torus": "Torus",
    "BSpline surface": "BSpline",
    "Bezier surface": "BSpline",
    "SurfaceOfRevolution": "Revolution",
    "SurfaceOfExtrusion": "Extrusion",
}


@dataclass
class Part:
    """A meshed part with exact B-Rep face labels.

    Attributes
    ----------
    V : (n, 3) float64
        Vertex positions (model units, the part is roughly 100 units across).
    F : (m, 3) int64
        Triangles, consistently oriented with outward normals (positive signed volume).
    labels : (m,) int64
        B-Rep face id of each triangle, ``0..k-1`` (gmsh surface tags in increasing order).
    surface_types : list of str, length k
        Surface type of each label (ABC names: Plane, Cylinder, Cone, Sphere, Torus, ...).
    kind : str
        Recipe name, one of :data:`KINDS`.
    seed : int
    params : dict
        The random dimensions drawn for the part and the meshing options.
    """

    V: np.ndarray
    F: np.ndarray
    labels: np.ndarray
    surface_types: list
    kind: str
    seed: int
    params: dict = field(default_factory=dict)

    @property
    def name(self) -> str:
        """``part_<seed>_<kind>``."""
        return f"part_{self.seed:03d}_{self.kind}"


# --------------------------------------------------------------------------------------------
# Geometry helpers (gmsh must be initialised, a model current)
# --------------------------------------------------------------------------------------------


def _gmsh():
    try:
        import gmsh
    except ImportError as exc:  # soft dependency
        raise ImportError("make_parts needs gmsh (with OpenCASCADE): pip install gmsh") from exc
    return gmsh


def _bbox(occ, dim: int, tag: int) -> np.ndarray:
    return np.array(occ.getBoundingBox(dim, tag))


def _select(occ, dim: int, pred) -> list[int]:
    """Tags of OCC entities of ``dim`` whose bounding box (xmin..zmax) satisfies ``pred``."""
    return [t for _, t in occ.getEntities(dim) if pred(_bbox(occ, dim, t))]


def _near(a, b) -> bool:
    return abs(a - b) < BBOX_TOL * 100


def _only_volume(occ) -> int:
    vols = occ.getEntities(3)
    if len(vols) != 1:
        raise RuntimeError(f"expected one solid, got {len(vols)}")
    return vols[0][1]


def _fuse(occ, a: int, b: int) -> int:
    out, _ = occ.fuse([(3, a)], [(3, b)])
    return out[0][1]


def _cut(occ, a: int, tools: list[int]) -> int:
    out, _ = occ.cut([(3, a)], [(3, t) for t in tools])
    return out[0][1]


def _vertical_hole(occ, x, y, z0, z1, r) -> int:
    return occ.addCylinder(x, y, z0, 0, 0, z1 - z0, r)


def _drilled_blind_hole(occ, x, y, ztop, depth, r) -> int:
    """A drilled hole from ``ztop`` down ``depth`` with a 118-degree conical tip."""
    cyl = occ.addCylinder(x, y, ztop - depth, 0, 0, depth + 1.0, r)
    tip = r / math.tan(math.radians(59.0))
    cone = occ.addCone(x, y, ztop - depth, 0, 0, -tip, r, 0.0)
    return _fuse(occ, cyl, cone)


def _rounded_slot(occ, x0, x1, y, z0, z1, w) -> list[int]:
    """Cutting tools of a slot along x from ``x0`` to ``x1`` (centres of the round ends).

    Three separate tools (box and two cylinders) cut in one go: fusing them first leaves one
    end as an OCC surface gmsh cannot type.
    """
    box = occ.addBox(x0, y - w / 2, z0, x1 - x0, w, z1 - z0)
    c0 = occ.addCylinder(x0, y, z0, 0, 0, z1 - z0, w / 2)
    c1 = occ.addCylinder(x1, y, z0, 0, 0, z1 - z0, w / 2)
    return [box, c0, c1]


# --------------------------------------------------------------------------------------------
# Recipes: each draws its dimensions from rng, builds one solid, returns its parameters
# --------------------------------------------------------------------------------------------


def _rounded_box(occ, rng) -> dict:
    L, W, H = rng.uniform(60, 100), rng.uniform(40, 70), rng.uniform(20, 40)
    r = rng.uniform(0.1, 0.25) * H
    b = occ.addBox(-L / 2, -W / 2, 0, L, W, H)
    occ.fillet([b], [t for _, t in occ.getEntities(1)], [r])
    return dict(L=L, W=W, H=H, fillet=r)


def _plate(occ, rng) -> dict:
    L, W, T = rng.uniform(80, 120), rng.uniform(50, 80), rng.uniform(8, 14)
    rc, ch = rng.uniform(6, 12), rng.uniform(1.0, 2.5)
    b = occ.addBox(-L / 2, -W / 2, 0, L, W, T)
    vert = _select(occ, 1, lambda q: _near(q[5] - q[2], T) and _near(q[0], q[3]))
    b = occ.fillet([b], vert, [rc])[0][1]
    top_c = _select(occ, 1, lambda q: _near(q[2], T) and _near(q[5], T))
    top_s = _select(occ, 2, lambda q: _near(q[2], T) and _near(q[5], T))
    b = occ.chamfer([b], top_c, top_s * len(top_c), [ch])[0][1]
    # boss with a junction fillet and a bore
    rb, hb = rng.uniform(10, 16), rng.uniform(8, 15)
    b = _fuse(occ, b, occ.addCylinder(0, 0, T, 0, 0, hb, rb))
    rf = rng.uniform(1.5, 3.0)
    junction = _select(
        occ, 1, lambda q: _near(q[2], T) and _near(q[5], T) and _near(q[3] - q[0], 2 * rb)
    )
    b = occ.fillet([b], junction, [rf])[0][1]
    rbore = rng.uniform(4, rb - 4)
    tools = [_vertical_hole(occ, 0, 0, -1, T + hb + 1, rbore)]
    # four corner holes, counterbored on even seeds of the draw
    m, rh = rc + rng.uniform(2, 5), rng.uniform(2.5, 4.5)
    cbore = bool(rng.integers(0, 2))
    for sx in (-1, 1):
        for sy in (-1, 1):
            x, y = sx * (L / 2 - m), sy * (W / 2 - m)
            tools.append(_vertical_hole(occ, x, y, -1, T + 1, rh))
            if cbore:
                tools.append(_vertical_hole(occ, x, y, T - 0.4 * T, T + 1, rh * 1.7))
    _cut(occ, b, tools)
    return dict(
        L=L,
        W=W,
        T=T,
        corner_fillet=rc,
        chamfer=ch,
        boss_r=rb,
        boss_h=hb,
        boss_fillet=rf,
        bore=rbore,
        hole_r=rh,
        counterbore=cbore,
    )


def _bracket(occ, rng) -> dict:
    L, W, T = rng.uniform(80, 110), rng.uniform(40, 60), rng.uniform(8, 12)
    T2, Hw = rng.uniform(8, 12), rng.uniform(45, 70)
    ch = rng.uniform(3, 6)
    base = occ.addBox(-L / 2, -W / 2, 0, L, W, T)
    outer = _select(
        occ, 1, lambda q: _near(q[0], L / 2) and _near(q[3], L / 2) and _near(q[5] - q[2], T)
    )
    face = _select(occ, 2, lambda q: _near(q[0], L / 2) and _near(q[3], L / 2))
    base = occ.chamfer([base], outer, face * len(outer), [ch])[0][1]
    wall = occ.addBox(-L / 2, -W / 2, 0, T2, W, Hw)
    b = _fuse(occ, base, wall)
    rf = rng.uniform(3, 6)
    xi = -L / 2 + T2
    inner = _select(
        occ,
        1,
        lambda q: _near(q[0], xi) and _near(q[3], xi) and _near(q[2], T) and _near(q[5], T),
    )
    b = occ.fillet([b], inner, [rf])[0][1]
    # rounded slot through the base, two holes through the wall
    ws = rng.uniform(6, 10)
    x0 = xi + rf + ws / 2 + rng.uniform(4, 8)
    x1 = L / 2 - ch - ws / 2 - rng.uniform(6, 10)
    tools = _rounded_slot(occ, x0, x1, 0, -1, T + 1, ws)
    rh, zh = rng.uniform(3, 5), rng.uniform(0.55, 0.75) * Hw
    for sy in (-1, 1):
        tools.append(occ.addCylinder(-L / 2 - 1, sy * W / 4, zh, T2 + 2, 0, 0, rh))
    _cut(occ, b, tools)
    return dict(
        L=L,
        W=W,
        T=T,
        wall_T=T2,
        wall_H=Hw,
        chamfer=ch,
        fillet=rf,
        slot_w=ws,
        slot=(x0, x1),
        hole_r=rh,
        hole_z=zh,
    )


def _flange(occ, rng) -> dict:
    R, T = rng.uniform(40, 55), rng.uniform(8, 14)
    d = rng.uniform(1.5, 3.0)
    disk = occ.addCylinder(0, 0, 0, 0, 0, T, R)
    rim = _select(occ, 1, lambda q: _near(q[2], T) and _near(q[5], T))
    top = _select(occ, 2, lambda q: _near(q[2], T) and _near(q[5], T))
    disk = occ.chamfer([disk], rim, top * len(rim), [d])[0][1]
    rh, hh = rng.uniform(14, 22), rng.uniform(12, 25)
    b = _fuse(occ, disk, occ.addCylinder(0, 0, T, 0, 0, hh, rh))
    rf = rng.uniform(2, 4)
    junction = _select(
        occ, 1, lambda q: _near(q[2], T) and _near(q[5], T) and _near(q[3] - q[0], 2 * rh)
    )
    b = occ.fillet([b], junction, [rf])[0][1]
    rbore = rng.uniform(6, rh - 6)
    tools = [_vertical_hole(occ, 0, 0, -1, T + hh + 1, rbore)]
    # keyway: a slot cut along the bore
    kw = rng.uniform(3, 5)
    tools.append(occ.addBox(rbore - 1.5, -kw / 2, -1, 3.5, kw, T + hh + 2))
    n = int(rng.choice([4, 6, 8]))
    rhole = rng.uniform(3, 5)
    rmin, rmax = rh + rf + rhole + 2, R - d - rhole - 2
    rbolt = rng.uniform(rmin, max(rmin, rmax))
    phase = rng.uniform(0, 2 * math.pi / n)
    for k in range(n):
        a = phase + 2 * math.pi * k / n
        tools.append(
            _vertical_hole(occ, rbolt * math.cos(a), rbolt * math.sin(a), -1, T + 1, rhole)
        )
    _cut(occ, b, tools)
    return dict(
        R=R,
        T=T,
        chamfer=d,
        hub_r=rh,
        hub_h=hh,
        fillet=rf,
        bore=rbore,
        keyway=kw,
        n_bolts=n,
        bolt_r=rhole,
        bolt_circle=rbolt,
    )


def _block(occ, rng) -> dict:
    L, W, H = rng.uniform(70, 100), rng.uniform(50, 70), rng.uniform(30, 45)
    ch = rng.uniform(2, 4)
    b = occ.addBox(-L / 2, -W / 2, 0, L, W, H)
    top_c = _select(occ, 1, lambda q: _near(q[2], H) and _near(q[5], H))
    top_s = _select(occ, 2, lambda q: _near(q[2], H) and _near(q[5], H))
    b = occ.chamfer([b], top_c, top_s * len(top_c), [ch])[0][1]
    # pocket with filleted vertical corners, in the left half
    Lp, Wp = rng.uniform(0.3, 0.4) * L, rng.uniform(0.5, 0.65) * W
    Dp, rp = rng.uniform(0.3, 0.5) * H, rng.uniform(3, 6)
    xp = -L / 2 + ch + rng.uniform(5, 8)
    pocket = occ.addBox(xp, -Wp / 2, H - Dp, Lp, Wp, Dp + 1)
    pv = _select(
        occ,
        1,
        lambda q: (
            _near(q[0], q[3])
            and _near(q[1], q[4])
            and _near(q[5] - q[2], Dp + 1)
            and q[0] > xp - 1e-3
            and q[3] < xp + Lp + 1e-3
            and q[2] > H - Dp - 1e-3
        ),
    )
    pocket = occ.fillet([pocket], pv, [rp])[0][1]
    tools = [pocket]
    # blind drilled holes in the right half, one horizontal through hole
    rh = rng.uniform(3, 4.5)
    xh = rng.uniform(0.1, 0.2) * L
    for sy in (-1, 1):
        tools.append(_drilled_blind_hole(occ, xh, sy * W / 4, H, rng.uniform(0.4, 0.7) * H, rh))
    rs = rng.uniform(3, 5)  # side through hole, clear of the pocket and the blind holes
    tools.append(occ.addCylinder(0.35 * L, -W / 2 - 1, 0.25 * H, 0, W + 2, 0, rs))
    _cut(occ, b, tools)
    return dict(
        L=L,
        W=W,
        H=H,
        chamfer=ch,
        pocket=(Lp, Wp, Dp),
        pocket_fillet=rp,
        hole_r=rh,
        side_hole_r=rs,
    )


_RECIPES = {
    "rounded_box": _rounded_box,
    "plate": _plate,
    "bracket": _bracket,
    "flange": _flange,
    "block": _block,
}


# --------------------------------------------------------------------------------------------
# Meshing
# --------------------------------------------------------------------------------------------


def _mesh_surfaces(gmsh, h: float, irregular: float, rng) -> tuple:
    """Mesh the current model's surfaces; return V, F, surface tag per face, surface types."""
    gmsh.model.mesh.clear()
    gmsh.option.setNumber("Mesh.MeshSizeMax", h)
    gmsh.option.setNumber("Mesh.MeshSizeMin", h / MIN_SIZE_RATIO)
    gmsh.option.setNumber("Mesh.MeshSizeFromCurvature", CURVATURE_ELEMENTS)
    gmsh.option.setNumber("Mesh.Algorithm", 1 if irregular > 0 else 6)
    if irregular > 0:
        k = rng.uniform(0.04, 0.09, 3)
        ph = rng.uniform(0, 2 * math.pi, 3)
        expr = (
            f"{h}*(1+{irregular}*Sin({k[0]}*x+{ph[0]})*Sin({k[1]}*y+{ph[1]})"
            f"*Sin({k[2]}*z+{ph[2]}))/(1+{irregular})"
        )
        fid = gmsh.model.mesh.field.add("MathEval")
        gmsh.model.mesh.field.setString(fid, "F", expr)
        gmsh.model.mesh.field.setAsBackgroundMesh(fid)
        gmsh.option.setNumber("Mesh.MeshSizeExtendFromBoundary", 0)
    gmsh.model.mesh.generate(2)
    tags, coords, _ = gmsh.model.mesh.getNodes()
    index = np.full(int(tags.max()) + 1, -1, dtype=np.int64)
    index[tags.astype(np.int64)] = np.arange(len(tags))
    V = coords.reshape(-1, 3)
    Fs, Ls, types = [], [], []
    for _, s in sorted(gmsh.model.getEntities(2)):
        etypes, _, enodes = gmsh.model.mesh.getElements(2, s)
        tri = [n for t, n in zip(etypes, enodes, strict=True) if t == 2]
        if len(etypes) != len(tri):
            raise RuntimeError(f"surface {s}: non-triangle elements {list(etypes)}")
        Fk = index[np.concatenate(tri).astype(np.int64)].reshape(-1, 3) if tri else None
        if Fk is None or len(Fk) == 0:
            raise RuntimeError(f"surface {s} got no triangles")
        Ls.append(np.full(len(Fk), len(types), dtype=np.int64))
        Fs.append(Fk)
        types.append(_TYPE_NAMES.get(gmsh.model.getType(2, s), "Other"))
    return V, np.concatenate(Fs), np.concatenate(Ls), types


def _orient_outward(V: np.ndarray, F: np.ndarray) -> np.ndarray:
    """Consistent orientation (BFS over faces), then outward: positive signed volume."""
    import igl

    FF, C = igl.bfs_orient(F)
    FF = np.asarray(FF, dtype=np.int64)
    C = np.asarray(C).ravel()
    for c in np.unique(C):
        sel = C == c
        P = V[FF[sel]]
        vol = np.einsum("ij,ij->i", P[:, 0], np.cross(P[:, 1], P[:, 2])).sum() / 6.0
        if vol < 0:
            FF[sel] = FF[sel][:, ::-1]
    return FF


def _compact(V: np.ndarray, F: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    used = np.unique(F)
    remap = np.full(len(V), -1, dtype=np.int64)
    remap[used] = np.arange(len(used))
    return np.ascontiguousarray(V[used], dtype=np.float64), remap[F]


def make_part(
    seed: int,
    kind: str | None = None,
    *,
    target_faces: int = TARGET_FACES_DEFAULT,
    irregular: float = 0.0,
    noise: float = 0.0,
) -> Part:
    """Build, mesh and label one machined part.

    Parameters
    ----------
    seed : int
        Seeds every random choice (dimensions, irregular size field, noise): the same
        arguments give the same mesh.
    kind : str, optional
        One of :data:`KINDS`; default ``KINDS[seed % len(KINDS)]``.
    target_faces : int
        Approximate triangle count (the mesh size is adapted until the count is within a
        factor :data:`FACE_COUNT_SLACK`); keep it in 5k-40k.
    irregular : float in [0, 1)
        Strength of the spatial variation of the triangle size (0 = uniform Frontal-Delaunay).
    noise : float
        Gaussian displacement along vertex normals, standard deviation ``noise`` times the mean
        edge length (0 = exact).

    Returns
    -------
    Part
        Closed, manifold, outward-oriented mesh with one label per triangle.

    Raises
    ------
    ValueError
        Unknown ``kind`` or out-of-range options.
    RuntimeError
        If OpenCASCADE rejects every one of :data:`MAX_ATTEMPTS` random parameter draws.
    """
    kind = KINDS[seed % len(KINDS)] if kind is None else kind
    if kind not in _RECIPES:
        raise ValueError(f"kind must be one of {KINDS}, got {kind!r}")
    if not 0.0 <= irregular < 1.0:
        raise ValueError(f"irregular must be in [0, 1), got {irregular}")
    if noise < 0:
        raise ValueError(f"noise must be >= 0, got {noise}")
    if target_faces < 100:
        raise ValueError(f"target_faces must be at least 100, got {target_faces}")
    gmsh = _gmsh()
    last_error = None
    for attempt in range(MAX_ATTEMPTS):
        rng = np.random.default_rng([seed, attempt])
        gmsh.initialize(readConfigFiles=False, interruptible=False)
        try:
            gmsh.option.setNumber("General.Terminal", 0)
            gmsh.option.setNumber("General.NumThreads", 1)
            gmsh.model.add(f"part_{seed}")
            occ = gmsh.model.occ
            try:
                params = _RECIPES[kind](occ, rng)
                occ.removeAllDuplicates()
                occ.synchronize()
                _only_volume(occ)
            except Exception as exc:  # OpenCASCADE rejected this draw: draw again
                last_error = exc
                logger.info("seed %d %s attempt %d failed: %s", seed, kind, attempt, exc)
                continue
            area = sum(occ.getMass(2, t) for _, t in gmsh.model.getEntities(2))
            h = math.sqrt(4.0 * area / (math.sqrt(3.0) * target_faces))
            mesh_rng = np.random.default_rng([seed, attempt, 1])
            for _ in range(4):
                V, F, labels, types = _mesh_surfaces(
                    gmsh, h, irregular, np.random.default_rng(mesh_rng.integers(2**32))
                )
                ratio = len(F) / target_faces
                if 1 / FACE_COUNT_SLACK <= ratio <= FACE_COUNT_SLACK:
                    break
                h *= math.sqrt(ratio)
        finally:
            gmsh.finalize()
        V, F = _compact(V, F)
        F = _orient_outward(V, F)
        params.update(attempt=attempt, mesh_size=h, irregular=irregular, noise=noise)
        if noise > 0:
            V = add_normal_noise(V, F, noise, np.random.default_rng([seed, attempt, 2]))
        return Part(
            V=V, F=F, labels=labels, surface_types=types, kind=kind, seed=seed, params=params
        )
    raise RuntimeError(f"seed {seed} ({kind}): every parameter draw failed: {last_error}")


# --------------------------------------------------------------------------------------------
# Noise, I/O
# --------------------------------------------------------------------------------------------


def mean_edge_length(V: np.ndarray, F: np.ndarray) -> float:
    """Mean length of the unique edges of ``F``.

    Parameters
    ----------
    V : (n, 3) float64
    F : (m, 3) int64

    Returns
    -------
    float
    """
    E = np.sort(np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]]), axis=1)
    E = np.unique(E, axis=0)
    return float(np.linalg.norm(V[E[:, 0]] - V[E[:, 1]], axis=1).mean())


def add_normal_noise(
    V: np.ndarray, F: np.ndarray, fraction: float, rng: np.random.Generator | int | None = 0
) -> np.ndarray:
    """Displace vertices along their normals by Gaussian noise.

    Parameters
    ----------
    V : (n, 3) float64
    F : (m, 3) int64
    fraction : float
        Standard deviation of the displacement, as a fraction of the mean edge length.
    rng : numpy Generator or int seed

    Returns
    -------
    (n, 3) float64
        ``V + N(0, (fraction * mean_edge_length)^2) * n_v`` with ``n_v`` the unit
        area-weighted vertex normal (sign irrelevant: the noise is symmetric).
    """
    rng = np.random.default_rng(rng)
    P0, P1, P2 = V[F[:, 0]], V[F[:, 1]], V[F[:, 2]]
    FN = np.cross(P1 - P0, P2 - P0)  # area-weighted (twice the area)
    N = np.zeros_like(V)
    for j in range(3):
        np.add.at(N, F[:, j], FN)
    N /= np.maximum(np.linalg.norm(N, axis=1, keepdims=True), 1e-300)
    sigma = fraction * mean_edge_length(V, F)
    return V + rng.standard_normal(len(V))[:, None] * sigma * N


def write_part(part: Part, out_dir: str | os.PathLike, name: str | None = None) -> Path:
    """Write ``NAME.obj``, ``NAME.facelabels.txt`` and ``NAME.surface_types.txt``.

    Parameters
    ----------
    part : Part
    out_dir : path-like
        Created if missing.
    name : str, optional
        File stem; default ``part.name``.

    Returns
    -------
    Path
        The OBJ file.
    """
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    name = part.name if name is None else name
    obj = out / f"{name}.obj"
    with obj.open("w") as fh:
        fh.write(f"# {part.kind} seed {part.seed} {part.params}\n")
        np.savetxt(fh, part.V, fmt="v %.9g %.9g %.9g")
        np.savetxt(fh, part.F + 1, fmt="f %d %d %d")
    np.savetxt(out / f"{name}.facelabels.txt", part.labels, fmt="%d")
    with (out / f"{name}.surface_types.txt").open("w") as fh:
        fh.writelines(f"{k} {t}\n" for k, t in enumerate(part.surface_types))
    return obj


def read_part(obj: str | os.PathLike) -> tuple[np.ndarray, np.ndarray, np.ndarray, list]:
    """Read a part written by :func:`write_part` (or an ABC part with the same side files).

    Returns
    -------
    V : (n, 3) float64
    F : (m, 3) int64
    labels : (m,) int64
    surface_types : list of str
    """
    import igl

    obj = Path(obj)
    V, F = igl.read_triangle_mesh(str(obj))
    stem = obj.with_suffix("")
    labels = np.loadtxt(f"{stem}.facelabels.txt", dtype=np.int64).reshape(-1)
    types_path = Path(f"{stem}.surface_types.txt")
    types = []
    if types_path.exists():
        types = [line.split()[1] for line in types_path.read_text().splitlines() if line.strip()]
    return np.asarray(V, dtype=np.float64), np.asarray(F, dtype=np.int64), labels, types


def main(argv: list[str] | None = None) -> int:
    """Command line: write parts for a list of seeds."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--out", required=True, help="output directory")
    ap.add_argument("--seeds", type=int, nargs="+", default=list(range(len(KINDS))))
    ap.add_argument("--kind", choices=KINDS, default=None, help="default: cycle by seed")
    ap.add_argument("--target-faces", type=int, default=TARGET_FACES_DEFAULT)
    ap.add_argument("--irregular", type=float, default=0.0)
    ap.add_argument("--noise", type=float, default=0.0, help="fraction of mean edge length")
    args = ap.parse_args(argv)
    for s in args.seeds:
        part = make_part(
            s,
            args.kind,
            target_faces=args.target_faces,
            irregular=args.irregular,
            noise=args.noise,
        )
        suffix = (f"_irr{args.irregular:g}" if args.irregular else "") + (
            f"_noise{args.noise:g}" if args.noise else ""
        )
        path = write_part(part, args.out, part.name + suffix)
        sys.stdout.write(
            f"{path}: {len(part.F)} faces, {len(part.surface_types)} B-Rep faces "
            f"({', '.join(sorted(set(part.surface_types)))})\n"
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
