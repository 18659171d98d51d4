"""Machined parts with exact per-face B-Rep labels, reproducible from a seed.

Each part is built with gmsh's OpenCASCADE kernel, its surface is meshed, and every triangle
keeps the id of the B-Rep face (gmsh surface entity) it was meshed on.  The output mirrors the
ABC files in ``shared/data``: ``NAME.obj``, ``NAME.facelabels.txt`` (one label per OBJ face,
``0..k-1``) and ``NAME.surface_types.txt`` (``k Type`` per line; types as in ABC: Plane,
Cylinder, Cone, Sphere, Torus, BSpline, Extrusion, Revolution, Other).

Families (:data:`KINDS`):

* prismatic: ``rounded_box`` (filleted box: cylinders, sphere corners), ``plate`` (chamfers,
  boss with fillet, counterbores), ``bracket`` (L, chamfer, fillet, slot), ``block`` (pocket,
  drilled blind holes), ``countersunk_plate`` (countersunk and chamfered holes: cones; slot,
  groove), ``housing`` (thin filleted shell, bosses, openings), ``ribbed_bracket`` (thin gusset
  ribs, fillets);
* revolved: ``flange`` (hub fillet torus, keyway, bolt circle), ``knob`` (spherical dome,
  cylindrical or spherical flutes), ``domed_cap`` (sphere, fillet tori, chamfer cone),
  ``saddle_boss`` (boss on a cylinder: freeform saddle fillet), ``pipe_elbow`` (cylinders and
  tori joined tangentially, optional flange);
* fasteners and transmission: ``bolt`` (chamfered hex head, shank, under-head fillet, optional
  annular V thread grooves), ``nut`` (hex with 30-degree corner chamfers, countersunk bore),
  ``gear`` (involute spur gear: extruded spline flanks), ``sprocket`` (roller seats, chamfered
  teeth, hub).

Surfaces gmsh reports as ``Unknown`` (some trimmed OCC surfaces, extruded splines) are typed
from the exact surface's principal curvatures (:func:`_surface_type`).

Tessellations: the default gmsh Frontal-Delaunay mesh aimed at ``target_faces``;
``irregular`` in [0, 1) modulates the target edge length in space by up to that fraction (random
smooth field) and switches gmsh to MeshAdapt, so triangle sizes and shapes vary; ``cad_facets``
> 0 replaces the gmsh mesh with OpenCASCADE's own STL tessellation (about that many segments per
circle, long slivers on planes), like a CAD export.  ``noise`` moves every vertex along its
(area-weighted) vertex normal by a Gaussian with standard deviation ``noise * mean edge
length``.

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
KINDS = (
    "rounded_box",
    "plate",
    "bracket",
    "flange",
    "block",
    "knob",
    "domed_cap",
    "countersunk_plate",
    "saddle_boss",
    "bolt",
    "nut",
    "gear",
    "sprocket",
    "pipe_elbow",
    "housing",
    "ribbed_bracket",
)

#: Default number of triangles aimed at (the result is within FACE_COUNT_SLACK of it).
TARGET_FACES_DEFAULT = 15000

#: Accepted ratio between the triangle count and the target before remeshing with a new size.
FACE_COUNT_SLACK = 1.35

#: Triangles per 2*pi of curvature gmsh aims at on curved faces (small fillets get rows).
CURVATURE_ELEMENTS = 12

#: Smallest triangle size allowed by curvature refinement, as a fraction of the target size.
MIN_SIZE_RATIO = 3.0

#: OpenCASCADE's angular deflection that gives ``n`` segments per full circle is ``STL_TURN / n``
#: (measured: BRepMesh puts two segments per deflection step on a circle).
STL_TURN = 4.0 * math.pi

#: Linear deflection (model units) of the coarse CAD tessellation: large enough that the angle
#: decides on parts ~100 units across (a 12-gon on R = 50 has a 1.7 sagitta), small enough that
#: BRepMesh still gives conforming face triangulations (at 1000 it left gaps along edges).
STL_LINEAR_DEFLECTION = 5.0

#: Accepted range of ``cad_facets`` (segments per full circle) for the coarse tessellation.
MIN_CAD_FACETS, MAX_CAD_FACETS = 6, 96

#: Parameter grid (per direction) on which gmsh ``Unknown`` surfaces are typed by curvature.
CURVATURE_SAMPLES = 5

#: Principal curvature below which a direction is flat (1/model units; parts are ~100 units).
CURVATURE_ZERO = 1e-7

#: Relative spread of a principal curvature below which it counts as constant.
CURVATURE_REL_TOL = 1e-6

#: Tolerance (model units, parts are ~100 units) for selecting edges by their bounding box.
BBOX_TOL = 1e-4

#: Attempts with fresh random parameters when OpenCASCADE rejects a fillet or boolean (each
#: attempt has its own generator, so raising this changes no part an earlier attempt made;
#: the sprocket of seed 31001 needs 9).
MAX_ATTEMPTS = 16

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
    """The tag of the model's only solid; raises if there are several or stray surfaces."""
    vols = occ.getEntities(3)
    if len(vols) != 1:
        raise RuntimeError(f"expected one solid, got {len(vols)}")
    stray = {t for _, t in occ.getEntities(2)} - set(_faces_of(occ, vols[0][1]))
    if stray:
        raise RuntimeError(f"surfaces {sorted(stray)} do not bound the solid")
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


# --------------------------------------------------------------------------------------------
# More recipes: revolved parts, fasteners, gears, pipes, thin-walled parts
# --------------------------------------------------------------------------------------------


def _faces_of(occ, vol: int) -> list[int]:
    """Surface tags bounding the volume ``vol``."""
    _, surfs = occ.getSurfaceLoops(vol)
    return sorted({int(t) for loop in surfs for t in loop})


def _curves_of(occ, vol: int) -> list[int]:
    """Curve tags on the boundary of the volume ``vol``."""
    out = set()
    for s in _faces_of(occ, vol):
        _, curves = occ.getCurveLoops(s)
        out.update(int(abs(t)) for loop in curves for t in loop)
    return sorted(out)


def _select_circle(occ, vol: int, z: float, r: float) -> list[int]:
    """Curves of ``vol`` in the plane ``z`` whose bounding box is a disk of radius ``r``."""
    return [
        c
        for c in _curves_of(occ, vol)
        if _near((q := _bbox(occ, 1, c))[2], z)
        and _near(q[5], z)
        and _near(q[3] - q[0], 2 * r)
        and _near(q[4] - q[1], 2 * r)
    ]


def _select_plane(occ, vol: int, z: float) -> list[int]:
    """Surfaces of ``vol`` lying in the horizontal plane ``z``."""
    return [
        f
        for f in _faces_of(occ, vol)
        if _near(_bbox(occ, 2, f)[2], z) and _near(_bbox(occ, 2, f)[5], z)
    ]


def _prism(occ, xy: np.ndarray, z0: float, h: float) -> int:
    """Extrude the closed polygon ``xy`` (n, 2) from ``z0`` up by ``h``; return the volume."""
    pts = [occ.addPoint(float(x), float(y), z0) for x, y in xy]
    lines = [occ.addLine(pts[i], pts[(i + 1) % len(pts)]) for i in range(len(pts))]
    surf = occ.addPlaneSurface([occ.addCurveLoop(lines)])
    out = occ.extrude([(2, surf)], 0, 0, h)
    return next(t for d, t in out if d == 3)


def _hexagon(s: float, phase: float = 0.0) -> np.ndarray:
    """Corners of a regular hexagon of width across flats ``s`` centred at the origin."""
    a = phase + np.arange(6) * np.pi / 3
    rc = s / math.sqrt(3.0)
    return np.stack([rc * np.cos(a), rc * np.sin(a)], axis=1)


def _chamfered_disk(occ, r, z0, h, c_bot, c_top, angle_deg=30.0) -> int:
    """Cylinder ``r`` from ``z0`` to ``z0 + h``, its circular edges chamfered into cones.

    ``c_bot``/``c_top`` are the radial chamfer widths (0: none); the cones make ``angle_deg``
    with the end planes.
    """
    cyl = occ.addCylinder(0, 0, z0, 0, 0, h, r)
    t = math.tan(math.radians(angle_deg))
    for z, c in ((z0 + h, c_top), (z0, c_bot)):
        if c > 0:
            edges, faces = _select_circle(occ, cyl, z, r), _select_plane(occ, cyl, z)
            cyl = occ.chamfer([cyl], edges, faces, [c, c * t])[0][1]
    return cyl


def _hex_chamfer_tool(occ, s, z0, h, both=True) -> int:
    """The revolved body whose intersection with a hex prism chamfers its corners (30 deg)."""
    rc = s / math.sqrt(3.0) + 0.5
    c = rc - 0.475 * s
    return _chamfered_disk(occ, rc, z0, h, c if both else 0.0, c)


def _v_groove(occ, r: float, depth: float, zc: float, width: float) -> int:
    """Ring tool cutting a V groove of ``depth`` and ``width`` at height ``zc`` into a shaft ``r``.

    The revolved triangle leaves two cone faces on the shaft.
    """
    pts = [
        occ.addPoint(r - depth, 0, zc),
        occ.addPoint(r + 1.0, 0, zc - width / 2 - 1.0 * width / (2 * depth)),
        occ.addPoint(r + 1.0, 0, zc + width / 2 + 1.0 * width / (2 * depth)),
    ]
    lines = [occ.addLine(pts[i], pts[(i + 1) % 3]) for i in range(3)]
    tri = occ.addPlaneSurface([occ.addCurveLoop(lines)])
    out = occ.revolve([(2, tri)], 0, 0, 0, 0, 0, 1, 2 * math.pi)
    occ.remove([(2, tri)], recursive=True)  # the profile is not part of the ring's boundary
    return next(t for d, t in out if d == 3)


def _seam_outward(occ, tool: int, x: float, y: float, a: float) -> int:
    """Turn a vertical-axis cylinder or sphere about its axis so its seam faces direction ``a``.

    OCC puts the seam of a cylinder or sphere on its local +x side; a tool cutting a flute or
    seat into the rim of a part should have it on the outer side, in air, or the cut face is
    split in two along the seam.
    """
    occ.rotate([(3, tool)], x, y, 0, 0, 0, 1, a)
    return tool


def _countersunk_bore(occ, r, z0, z1, sink_bot, sink_top) -> list[int]:
    """Tools of a through bore ``r`` with 90-degree countersinks of added radius ``sink_*``."""
    tools = [_vertical_hole(occ, 0, 0, z0 - 1, z1 + 1, r)]
    if sink_top > 0:
        tools.append(occ.addCone(0, 0, z1 - sink_top, 0, 0, sink_top + 1, r, r + sink_top + 1))
    if sink_bot > 0:
        tools.append(occ.addCone(0, 0, z0 + sink_bot, 0, 0, -sink_bot - 1, r, r + sink_bot + 1))
    return tools


def _nut(occ, rng) -> dict:
    s = rng.uniform(60, 80)
    h = rng.uniform(0.5, 0.85) * s
    phase = rng.uniform(0, math.pi / 3)
    body = _prism(occ, _hexagon(s, phase), 0, h)
    both = bool(rng.integers(0, 4))  # one nut in four is chamfered on the top only
    tool = _hex_chamfer_tool(occ, s, 0, h, both)
    body = occ.intersect([(3, body)], [(3, tool)])[0][0][1]
    rb = rng.uniform(0.25, 0.32) * s
    sink = rng.uniform(1.0, 2.5)
    _cut(occ, body, _countersunk_bore(occ, rb, 0, h, sink, sink))
    return dict(across_flats=s, height=h, phase=phase, bore=rb, countersink=sink)


def _bolt(occ, rng) -> dict:
    s = rng.uniform(28, 38)
    k = rng.uniform(0.6, 0.75) * s * 0.6
    d = rng.uniform(0.55, 0.65) * s
    L = rng.uniform(55, 75)
    # shank along -z from the head's underside at z = 0; head from 0 to k
    head = _prism(occ, _hexagon(s, rng.uniform(0, math.pi / 3)), 0, k)
    head = occ.intersect([(3, head)], [(3, _hex_chamfer_tool(occ, s, 0, k, False))])[0][0][1]
    shank = _chamfered_disk(occ, d / 2, -L, L + 0.5 * k, rng.uniform(1.0, 2.0), 0.0, 45.0)
    b = _fuse(occ, head, shank)
    rf = rng.uniform(0.6, 1.2)
    under = _select_circle(occ, b, 0, d / 2)
    b = occ.fillet([b], under, [rf])[0][1]
    n_threads = int(rng.integers(0, 2)) * int(rng.integers(4, 9))
    pitch = rng.uniform(2.0, 3.0)
    tools = []
    z_start = -L + 3.0
    for i in range(n_threads):  # annular V grooves (not helical), two cone faces each
        tools.append(_v_groove(occ, d / 2, 0.3 * pitch, z_start + pitch * (i + 0.5), 0.8 * pitch))
    if tools:
        _cut(occ, b, tools)
    return dict(
        across_flats=s, head_h=k, shank_d=d, length=L, fillet=rf, grooves=n_threads, pitch=pitch
    )


def _knob(occ, rng) -> dict:
    R, H = rng.uniform(30, 42), rng.uniform(25, 40)
    dome = rng.uniform(0.2, 0.45) * R
    Rs = (R * R + dome * dome) / (2 * dome)  # sphere through the rim, apex ``dome`` above
    body = occ.addCylinder(0, 0, 0, 0, 0, H, R)
    cap = occ.addSphere(0, 0, H + dome - Rs, Rs)
    clip = occ.addCylinder(0, 0, H, 0, 0, dome + 1, R)
    cap = occ.intersect([(3, cap)], [(3, clip)])[0][0][1]
    b = _fuse(occ, body, cap)
    n = int(rng.integers(6, 13))
    spherical = bool(rng.integers(0, 2))
    rf = rng.uniform(0.25, 0.4) * 2 * math.pi * R / n
    tools = []
    for i in range(n):
        a = 2 * math.pi * i / n
        c = R + 0.45 * rf
        x, y = c * math.cos(a), c * math.sin(a)
        if spherical:  # dimples near the top rim
            t = occ.addSphere(x, y, H - rng.uniform(0.35, 0.5) * H, rf)
        else:  # vertical flutes, stopping short of the base
            t = occ.addCylinder(x, y, 0.25 * H, 0, 0, H + dome, rf)
        tools.append(_seam_outward(occ, t, x, y, a))
    rb = rng.uniform(4, 7)
    tools.append(_drilled_blind_hole(occ, 0, 0, 0, -rng.uniform(0.4, 0.6) * H, rb))
    ch = rng.uniform(1.0, 2.0)
    b = _chamfer_bottom(occ, b, R, ch)
    _cut(occ, b, tools)
    return dict(R=R, H=H, dome=dome, sphere_r=Rs, flutes=n, spherical=spherical, flute_r=rf,
                bore=rb, chamfer=ch)


def _chamfer_bottom(occ, b, R, ch) -> int:
    edges, faces = _select_circle(occ, b, 0, R), _select_plane(occ, b, 0)
    return occ.chamfer([b], edges, faces, [ch])[0][1]


def _domed_cap(occ, rng) -> dict:
    R1, T1 = rng.uniform(40, 52), rng.uniform(6, 10)
    R2, H2 = rng.uniform(0.5, 0.7) * R1, rng.uniform(20, 35)
    dome = rng.uniform(0.3, 0.8) * R2
    Rs = (R2 * R2 + dome * dome) / (2 * dome)
    flange = occ.addCylinder(0, 0, 0, 0, 0, T1, R1)
    body = occ.addCylinder(0, 0, T1, 0, 0, H2, R2)
    cap = occ.addSphere(0, 0, T1 + H2 + dome - Rs, Rs)
    clip = occ.addCylinder(0, 0, T1 + H2, 0, 0, dome + 1, R2)
    cap = occ.intersect([(3, cap)], [(3, clip)])[0][0][1]
    b = _fuse(occ, _fuse(occ, flange, body), cap)
    rf1 = rng.uniform(2, 5)
    b = occ.fillet([b], _select_circle(occ, b, T1, R2), [rf1])[0][1]
    rf2 = rng.uniform(2, 5)
    b = occ.fillet([b], _select_circle(occ, b, T1 + H2, R2), [rf2])[0][1]
    ch = rng.uniform(1, 2.5)
    b = occ.chamfer([b], _select_circle(occ, b, T1, R1), _select_plane(occ, b, T1), [ch])[0][1]
    # cavity from below, bolt holes through the flange
    rc = R2 - rng.uniform(3, 5)
    tools = [occ.addCylinder(0, 0, -1, 0, 0, T1 + H2 * rng.uniform(0.5, 0.8) + 1, rc)]
    n, rh = int(rng.choice([3, 4, 6])), rng.uniform(2.5, 4)
    rbc = 0.5 * (R2 + rf1 + R1 - ch)
    for i in range(n):
        a = 2 * math.pi * i / n
        tools.append(_vertical_hole(occ, rbc * math.cos(a), rbc * math.sin(a), -1, T1 + 1, rh))
    _cut(occ, b, tools)
    return dict(R_flange=R1, T_flange=T1, R_body=R2, H_body=H2, dome=dome, sphere_r=Rs,
                fillet_base=rf1, fillet_dome=rf2, chamfer=ch, cavity_r=rc, n_holes=n)


def _countersunk_plate(occ, rng) -> dict:
    L, W, T = rng.uniform(90, 120), rng.uniform(55, 80), rng.uniform(10, 16)
    b = occ.addBox(-L / 2, -W / 2, 0, L, W, T)
    rc = rng.uniform(3, 8)
    vert = _select(occ, 1, lambda q: _near(q[5] - q[2], T) and _near(q[0], q[3]))
    b = occ.fillet([b], vert, [rc])[0][1]
    tools = []
    rh = rng.uniform(3, 4.5)
    m = rc + rh + rng.uniform(3, 6)
    for sx in (-1, 1):  # countersunk holes (90-degree cones) on one end
        x, y = sx * (L / 2 - m), W / 2 - m
        tools.append(_vertical_hole(occ, x, y, -1, T + 1, rh))
        cs = rng.uniform(2.5, 4)
        tools.append(occ.addCone(x, y, T - cs, 0, 0, cs + 1, rh, rh + cs + 1))
    for sx in (-1, 1):  # plain holes chamfered both sides (45 degrees)
        x, y = sx * (L / 2 - m), -W / 2 + m
        tools.append(_vertical_hole(occ, x, y, -1, T + 1, rh))
        c = rng.uniform(0.8, 1.5)
        tools.append(occ.addCone(x, y, T - c, 0, 0, c + 1, rh, rh + c + 1))
        tools.append(occ.addCone(x, y, c, 0, 0, -c - 1, rh, rh + c + 1))
    ws = rng.uniform(6, 10)  # rounded through slot along x
    x0, x1 = -L / 2 + m + rh + ws, L / 2 - m - rh - ws
    tools += _rounded_slot(occ, x0 * 0.6, x1 * 0.6, 0, -1, T + 1, ws)
    gw, gd = rng.uniform(6, 12), rng.uniform(0.25, 0.4) * T  # open groove across the bottom
    tools.append(occ.addBox(-gw / 2 + rng.uniform(-5, 5), -W / 2 - 1, -1, gw, W + 2, gd + 1))
    _cut(occ, b, tools)
    return dict(L=L, W=W, T=T, corner_fillet=rc, hole_r=rh, slot_w=ws, groove=(gw, gd))


def _saddle_boss(occ, rng) -> dict:
    R, L = rng.uniform(18, 26), rng.uniform(90, 110)
    body = occ.addCylinder(-L / 2, 0, 0, L, 0, 0, R)
    rb, hb = rng.uniform(0.4, 0.65) * R, rng.uniform(1.4, 1.8) * R
    xb = rng.uniform(-0.15, 0.15) * L
    boss = occ.addCylinder(xb, 0, 0, 0, 0, hb, rb)
    b = _fuse(occ, body, boss)
    rf = rng.uniform(1.5, 3)
    saddle = _select(
        occ, 1, lambda q: q[5] > R * 0.5 and q[2] > 0 and q[5] < R + 1e-3 and q[3] - q[0] < 3 * rb
    )
    filleted = False
    try:
        b = occ.fillet([b], saddle, [rf])[0][1]
        filleted = True
    except Exception:  # OCC may refuse the saddle fillet: keep the sharp junction
        pass
    ch = rng.uniform(1, 2)

    def at_end(q):
        return _near(q[0], q[3]) and (_near(q[0], -L / 2) or _near(q[0], L / 2))

    ends = [c for c in _curves_of(occ, b) if at_end(_bbox(occ, 1, c))]
    endf = [f for f in _faces_of(occ, b) if at_end(_bbox(occ, 2, f))]
    if len(ends) == 2 and len(endf) == 2:
        b = occ.chamfer([b], ends, endf, [ch])[0][1]
    rbore = rng.uniform(0.45, 0.65) * R
    tools = [occ.addCylinder(-L / 2 - 1, 0, 0, L + 2, 0, 0, rbore)]
    tools.append(occ.addCylinder(xb, 0, 0, 0, 0, hb + 1, rng.uniform(0.4, 0.6) * rb))
    _cut(occ, b, tools)
    return dict(R=R, L=L, boss_r=rb, boss_h=hb, boss_x=xb, fillet=rf if filleted else 0.0,
                chamfer=ch, bore=rbore)


def _involute(rb: float, r: float) -> tuple[float, float]:
    """Polar angle and radius of the involute of the base circle ``rb`` at radius ``r``."""
    t = math.sqrt(max(r * r / (rb * rb) - 1.0, 0.0))
    return t - math.atan(t), r


def _gear_profile(occ, z: int, m: float, z0: float) -> int:
    """Plane surface of a spur gear (``z`` teeth, module ``m``, 20-degree involute) at ``z0``.

    Flanks are splines through points of the involute, tips and roots circle arcs, with a
    radial line from the root circle to the base circle on each flank.
    """
    rp = m * z / 2
    rbase = rp * math.cos(math.radians(20))
    ra, rr = rp + m, rp - 1.25 * m
    r0 = max(rbase, rr * 1.0001)
    half = math.pi / (2 * z) + _involute(rbase, rp)[0]  # half tooth angle at the base circle
    radii = np.linspace(r0, ra, 6)
    center = occ.addPoint(0, 0, z0)

    def pt(r, a):
        return occ.addPoint(r * math.cos(a), r * math.sin(a), z0)

    teeth = []  # per tooth: (root start point, curves, root end point)
    for k in range(z):
        ak = 2 * math.pi * k / z
        pr = [pt(r, ak - half + _involute(rbase, r)[0]) for r in radii]
        pl = [pt(r, ak + half - _involute(rbase, r)[0]) for r in radii[::-1]]
        rs, re = pt(rr, ak - half), pt(rr, ak + half)
        curves = [
            occ.addLine(rs, pr[0]),
            occ.addSpline(pr),
            occ.addCircleArc(pr[-1], center, pl[0]),
            occ.addSpline(pl),
            occ.addLine(pl[-1], re),
        ]
        teeth.append((rs, curves, re))
    loop = []
    for k, (_, curves, re) in enumerate(teeth):
        loop += curves
        loop.append(occ.addCircleArc(re, center, teeth[(k + 1) % z][0]))
    return occ.addPlaneSurface([occ.addCurveLoop(loop)])


def _gear(occ, rng) -> dict:
    z = int(rng.integers(14, 31))
    m = rng.uniform(76, 88) / z
    T = rng.uniform(12, 25)
    surf = _gear_profile(occ, z, m, 0.0)
    b = next(t for d, t in occ.extrude([(2, surf)], 0, 0, T) if d == 3)
    rp = m * z / 2
    hub = bool(rng.integers(0, 2))
    rh = rng.uniform(0.35, 0.5) * rp
    if hub:
        hh = rng.uniform(6, 12)
        b = _fuse(occ, b, occ.addCylinder(0, 0, T, 0, 0, hh, rh))
    else:
        hh = 0.0
    rbore = rng.uniform(0.35, 0.6) * rh
    tools = [_vertical_hole(occ, 0, 0, -1, T + hh + 1, rbore)]
    kw = rng.uniform(0.25, 0.35) * rbore
    tools.append(occ.addBox(rbore - 1.0, -kw / 2, -1, 0.3 * rbore + 1.0, kw, T + hh + 2))
    _cut(occ, b, tools)
    return dict(teeth=z, module=m, width=T, pitch_r=rp, hub=hub, hub_r=rh, hub_h=hh,
                bore=rbore, keyway=kw)


def _sprocket(occ, rng) -> dict:
    z = int(rng.integers(12, 25))
    rp = rng.uniform(36, 44)
    p = 2 * rp * math.sin(math.pi / z)
    rs, ra = 0.31 * p, rp + 0.3 * p
    T = rng.uniform(0.45, 0.6) * p
    c = rng.uniform(0.12, 0.2) * p  # tooth side chamfer (radial width)
    b = _chamfered_disk(occ, ra, 0, T, c, c, rng.uniform(55, 65))
    tools = []
    for a in 2 * np.pi * np.arange(z) / z:
        x, y = rp * math.cos(a), rp * math.sin(a)
        tools.append(_seam_outward(occ, occ.addCylinder(x, y, -1, 0, 0, T + 2, rs), x, y, a))
    b = _cut(occ, b, tools)
    rh, hh = rng.uniform(0.35, 0.45) * rp, rng.uniform(8, 14)
    b = _fuse(occ, b, occ.addCylinder(0, 0, T, 0, 0, hh, rh))
    rf = rng.uniform(1.5, 3)
    b = occ.fillet([b], _select_circle(occ, b, T, rh), [rf])[0][1]
    rbore = rng.uniform(0.4, 0.6) * rh
    tools = [_vertical_hole(occ, 0, 0, -1, T + hh + 1, rbore)]
    n, rl = int(rng.choice([0, 4, 5, 6])), rng.uniform(3.5, 6)
    rlc = 0.5 * (rh + rf + rp - rs)
    for i in range(n):  # lightening holes
        a = 2 * math.pi * (i + 0.5) / n
        tools.append(_vertical_hole(occ, rlc * math.cos(a), rlc * math.sin(a), -1, T + 1, rl))
    _cut(occ, b, tools)
    return dict(teeth=z, pitch_r=rp, pitch=p, seat_r=rs, tip_r=ra, width=T, chamfer=c,
                hub_r=rh, hub_h=hh, fillet=rf, bore=rbore, lightening=n)


def _tube_path(occ, Rb, r, L1, L2, angle) -> list[int]:
    """Solids of a straight leg, a torus bend of ``angle`` and a second leg, radius ``r``."""
    leg1 = occ.addCylinder(Rb, -L1, 0, 0, L1, 0, r)
    bend = occ.addTorus(0, 0, 0, Rb, r, -1, angle)
    ex, ey = Rb * math.cos(angle), Rb * math.sin(angle)
    tx, ty = -math.sin(angle), math.cos(angle)
    leg2 = occ.addCylinder(ex, ey, 0, L2 * tx, L2 * ty, 0, r)
    return [leg1, bend, leg2]


def _pipe_elbow(occ, rng) -> dict:
    r, t = rng.uniform(10, 15), rng.uniform(2, 4)
    Rb = rng.uniform(1.8, 3.0) * r
    angle = math.radians(float(rng.choice([45, 60, 90, 90, 120])))
    L1, L2 = rng.uniform(25, 45), rng.uniform(25, 45)
    outer = _tube_path(occ, Rb, r, L1, L2, angle)
    out, _ = occ.fuse([(3, outer[0])], [(3, outer[1]), (3, outer[2])])
    b = out[0][1]
    flanged = bool(rng.integers(0, 2))
    rfl, tfl = r + rng.uniform(6, 10), rng.uniform(4, 7)
    if flanged:  # a flange disk at the end of the first leg
        b = _fuse(occ, b, occ.addCylinder(Rb, -L1, 0, 0, tfl, 0, rfl))
    inner = _tube_path(occ, Rb, r - t, L1 + 1, L2 + 1, angle)
    _cut(occ, b, inner)
    return dict(r=r, wall=t, bend_r=Rb, angle=math.degrees(angle), L1=L1, L2=L2,
                flange=(rfl, tfl) if flanged else None)


def _housing(occ, rng) -> dict:
    L, W, H = rng.uniform(80, 110), rng.uniform(55, 75), rng.uniform(30, 45)
    t = rng.uniform(2.5, 4)
    rv, rt = rng.uniform(6, 12), rng.uniform(2, 5)
    outer = occ.addBox(-L / 2, -W / 2, 0, L, W, H)
    vert = _select(occ, 1, lambda q: _near(q[5] - q[2], H) and _near(q[0], q[3]))
    outer = occ.fillet([outer], vert, [rv])[0][1]
    top = _select(occ, 1, lambda q: _near(q[2], H) and _near(q[5], H))
    outer = occ.fillet([outer], top, [rt])[0][1]
    inner = occ.addBox(-L / 2 + t, -W / 2 + t, -1, L - 2 * t, W - 2 * t, H - t + 1)
    ivert = _select(
        occ, 1, lambda q: _near(q[5] - q[2], H - t + 1) and _near(q[0], q[3]) and q[2] < 0
    )
    inner = occ.fillet([inner], ivert, [max(rv - t, 1.0)])[0][1]
    b = _cut(occ, outer, [inner])
    # corner bosses inside, a round opening on the top and one on a side
    rb = rng.uniform(4, 6)
    m = t + rb + max(rv - t, 1.0) * 0.4
    tools = []
    for sx in (-1, 1):
        for sy in (-1, 1):
            x, y = sx * (L / 2 - m), sy * (W / 2 - m)
            b = _fuse(occ, b, occ.addCylinder(x, y, 0, 0, 0, H - t + 0.01, rb))
            tools.append(_vertical_hole(occ, x, y, -1, H - t - 2, rng.uniform(1.5, 2.5)))
    ro = rng.uniform(0.15, 0.25) * W
    tools.append(_vertical_hole(occ, rng.uniform(-0.15, 0.15) * L, 0, H - t - 1, H + 1, ro))
    rs = rng.uniform(0.1, 0.18) * H
    tools.append(occ.addCylinder(-L / 2 - 1, 0, 0.45 * H, t + 2, 0, 0, rs))
    _cut(occ, b, tools)
    return dict(L=L, W=W, H=H, wall=t, fillet_vert=rv, fillet_top=rt, boss_r=rb,
                top_hole=ro, side_hole=rs)


def _ribbed_bracket(occ, rng) -> dict:
    L, W, T = rng.uniform(80, 110), rng.uniform(45, 65), rng.uniform(6, 10)
    Hw = rng.uniform(50, 75)
    base = occ.addBox(0, -W / 2, 0, L, W, T)
    wall = occ.addBox(0, -W / 2, 0, T, W, Hw)
    b = _fuse(occ, base, wall)
    rf = rng.uniform(2, 4)
    corner = _select(
        occ, 1, lambda q: _near(q[0], T) and _near(q[3], T) and _near(q[2], T) and _near(q[5], T)
    )
    b = occ.fillet([b], corner, [rf])[0][1]
    n = int(rng.choice([1, 2, 3]))
    tr = rng.uniform(2.0, 3.5)  # thin ribs
    lr, hr = rng.uniform(0.45, 0.7) * L, rng.uniform(0.5, 0.8) * Hw
    ys = [0.0] if n == 1 else list(np.linspace(-W / 2 + tr / 2 + 3, W / 2 - tr / 2 - 3, n))
    for y in ys:  # gussets: right triangles in the xz plane, thickness tr along y
        c = T - 0.5  # tucked into the corner fillet
        tri = [(c, c), (c + lr, c), (c, c + hr)]
        pts = [occ.addPoint(x, y - tr / 2, z) for x, z in tri]
        lines = [occ.addLine(pts[i], pts[(i + 1) % 3]) for i in range(3)]
        surf = occ.addPlaneSurface([occ.addCurveLoop(lines)])
        rib = next(t for d, t in occ.extrude([(2, surf)], 0, tr, 0) if d == 3)
        b = _fuse(occ, b, rib)
    rc = rng.uniform(4, 8)
    outer = _select(occ, 1, lambda q: _near(q[0], L) and _near(q[3], L) and _near(q[5] - q[2], T))
    b = occ.fillet([b], outer, [rc])[0][1]
    rh = rng.uniform(3, 4.5)
    tools = []
    for y in (-W / 4, W / 4) if n != 2 else (0.0,):
        tools.append(_vertical_hole(occ, L - rc - rh - 3, y, -1, T + 1, rh))
    for y in (-W / 3, W / 3):
        tools.append(occ.addCylinder(-1, y, 0.8 * Hw, T + 2, 0, 0, rh))
    _cut(occ, b, tools)
    return dict(L=L, W=W, T=T, wall_H=Hw, ribs=n, rib_t=tr, rib=(lr, hr), fillet=rf,
                corner_fillet=rc, hole_r=rh)


_RECIPES = {
    "rounded_box": _rounded_box,
    "plate": _plate,
    "bracket": _bracket,
    "flange": _flange,
    "block": _block,
    "knob": _knob,
    "domed_cap": _domed_cap,
    "countersunk_plate": _countersunk_plate,
    "saddle_boss": _saddle_boss,
    "bolt": _bolt,
    "nut": _nut,
    "gear": _gear,
    "sprocket": _sprocket,
    "pipe_elbow": _pipe_elbow,
    "housing": _housing,
    "ribbed_bracket": _ribbed_bracket,
}


# --------------------------------------------------------------------------------------------
# Meshing
# --------------------------------------------------------------------------------------------


def _surface_type(gmsh, s: int) -> str:
    """ABC type name of surface ``s``; gmsh's ``Unknown`` surfaces are typed from curvature.

    gmsh reports some OCC surfaces (e.g. cylinders trimmed by booleans, extruded splines) as
    ``Unknown``.  Those are classified from the principal curvatures of the exact CAD surface
    on a grid of parameters: both zero -> Plane; one zero and the other constant -> Cylinder;
    both equal and constant -> Sphere; one zero with one fixed ruling direction -> Extrusion;
    anything else -> Other.
    """
    name = gmsh.model.getType(2, s)
    if name in _TYPE_NAMES:
        return _TYPE_NAMES[name]
    lo, hi = gmsh.model.getParametrizationBounds(2, s)
    a = (np.arange(CURVATURE_SAMPLES) + 0.5) / CURVATURE_SAMPLES
    uu, vv = np.meshgrid(lo[0] + a * (hi[0] - lo[0]), lo[1] + a * (hi[1] - lo[1]))
    uv = np.stack([uu.ravel(), vv.ravel()], axis=1).ravel()
    k1, k2, d1, d2 = gmsh.model.getPrincipalCurvatures(s, uv)
    k = np.sort(np.abs(np.stack([k1, k2], axis=1)), axis=1)
    D = np.stack([np.reshape(d1, (-1, 3)), np.reshape(d2, (-1, 3))], axis=1)
    zero = k < CURVATURE_ZERO
    if zero.all():
        return "Plane"
    if zero[:, 0].all():
        if np.ptp(k[:, 1]) <= CURVATURE_REL_TOL * k[:, 1].mean():
            return "Cylinder"
        # ruling = direction of the zero curvature; parallel rulings -> extrusion surface
        idx = np.argmin(np.abs(np.stack([k1, k2], axis=1)), axis=1)
        rul = D[np.arange(len(idx)), idx]
        rul /= np.maximum(np.linalg.norm(rul, axis=1, keepdims=True), 1e-300)
        if np.abs(rul @ rul[0]).min() > 1 - CURVATURE_REL_TOL:
            return "Extrusion"
        return "Other"
    if np.ptp(k) <= CURVATURE_REL_TOL * k.mean():
        return "Sphere"
    return "Other"


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
    return _collect_triangles(gmsh)


def _tessellate_cad(gmsh, facets: int) -> tuple:
    """OpenCASCADE's own (STL export) tessellation of the current model, ``facets`` per circle.

    ``BRepMesh`` with an angular deflection and a linear deflection too large to matter: curved
    faces get about ``facets`` segments per full turn, planes the fewest triangles that cover
    them (long slivers), like a CAD STL export.  The per-face triangulations share the edge
    discretization; their duplicate edge nodes are merged, and the zero-area triangles that
    sphere poles leave (two corners on the pole) are dropped.
    """
    gmsh.model.mesh.clear()
    gmsh.option.setNumber("Mesh.StlAngularDeflection", STL_TURN / facets)
    gmsh.option.setNumber("Mesh.StlLinearDeflectionRelative", 0)
    gmsh.option.setNumber("Mesh.StlLinearDeflection", STL_LINEAR_DEFLECTION)
    gmsh.model.mesh.importStl()
    gmsh.model.mesh.removeDuplicateNodes()
    V, F, labels, types = _collect_triangles(gmsh)
    # sphere poles come out as triangles with a repeated (merged) corner: drop them
    keep = (F[:, 0] != F[:, 1]) & (F[:, 1] != F[:, 2]) & (F[:, 2] != F[:, 0])
    return V, F[keep], labels[keep], types


def _collect_triangles(gmsh) -> tuple:
    """V, F, label per triangle (surfaces in tag order) and surface types of the current mesh."""
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
        types.append(_surface_type(gmsh, s))
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


def _mesh_part(gmsh, target_faces, irregular, cad_facets, mesh_rng) -> tuple:
    """Mesh the current (synchronized) model; return V, F, labels, types and the mesh size."""
    if cad_facets:
        return (*_tessellate_cad(gmsh, cad_facets), float("nan"))
    area = sum(gmsh.model.occ.getMass(2, t) for _, t in gmsh.model.getEntities(2))
    h = math.sqrt(4.0 * area / (math.sqrt(3.0) * target_faces))
    for _ in range(4):
        V, F, labels, types = _mesh_surfaces(
            gmsh, h, irregular, np.random.default_rng(mesh_rng.integers(2**32))
        )
        ratio = len(F) / target_faces
        if 1 / FACE_COUNT_SLACK <= ratio <= FACE_COUNT_SLACK:
            break
        h *= math.sqrt(ratio)
    return V, F, labels, types, h


def make_part(
    seed: int,
    kind: str | None = None,
    *,
    target_faces: int = TARGET_FACES_DEFAULT,
    irregular: float = 0.0,
    noise: float = 0.0,
    cad_facets: int = 0,
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
    cad_facets : int
        0 (default): gmsh surface mesh aimed at ``target_faces``.  Otherwise a coarse CAD-export
        tessellation instead (OpenCASCADE's STL tessellation, about ``cad_facets`` segments per
        full circle, e.g. 12 to 24; slivers on planes); ``target_faces`` and ``irregular`` are
        then ignored and the triangle count follows from the part (0.2k-2.5k for these
        families: below the 5k-40k of the gmsh meshes, as CAD exports are).

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
    if cad_facets != 0 and not MIN_CAD_FACETS <= cad_facets <= MAX_CAD_FACETS:
        raise ValueError(
            f"cad_facets must be 0 or in [{MIN_CAD_FACETS}, {MAX_CAD_FACETS}], got {cad_facets}"
        )
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
            try:
                V, F, labels, types, h = _mesh_part(gmsh, target_faces, irregular, cad_facets,
                                                    np.random.default_rng([seed, attempt, 1]))
            except Exception as exc:  # gmsh could not mesh this draw: draw again
                last_error = exc
                logger.info("seed %d %s attempt %d: meshing failed: %s", seed, kind, attempt, exc)
                continue
        finally:
            gmsh.finalize()
        V, F = _compact(V, F)
        F = _orient_outward(V, F)
        params.update(
            attempt=attempt, mesh_size=h, irregular=irregular, noise=noise, cad_facets=cad_facets
        )
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
    ap.add_argument(
        "--cad-facets", type=int, default=0, help="coarse CAD tessellation, segments per circle"
    )
    args = ap.parse_args(argv)
    for s in args.seeds:
        part = make_part(
            s,
            args.kind,
            target_faces=args.target_faces,
            irregular=args.irregular,
            noise=args.noise,
            cad_facets=args.cad_facets,
        )
        suffix = (
            (f"_irr{args.irregular:g}" if args.irregular else "")
            + (f"_cad{args.cad_facets}" if args.cad_facets else "")
            + (f"_noise{args.noise:g}" if args.noise else "")
        )
        path = write_part(part, args.out, part.name + suffix)
        sys.stdout.write(
            f"{path}: {len(part.F)} faces, {len(part.surface_types)} B-Rep faces "
            f"({', '.join(sorted(set(part.surface_types)))})\n"
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
