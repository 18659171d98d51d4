"""The STEP round trip of a sewn model: what a reader of ``model.step`` gets back, face by face.

A sewn torus passed BRepCheck in memory and failed once written and read back; a sewn
triangle came back valid but 118 times larger, spanning three times the part.  The reader
may also split a face, so the faces it returns are matched to the model's by their shared
vertices, not by their order.
"""

from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np

from ._ocp import require_ocp

require_ocp()

from OCP.Bnd import Bnd_Box  # noqa: E402
from OCP.BRep import BRep_Tool  # noqa: E402
from OCP.BRepBndLib import BRepBndLib  # noqa: E402
from OCP.TopAbs import TopAbs_VERTEX  # noqa: E402
from OCP.TopExp import TopExp_Explorer  # noqa: E402
from OCP.TopoDS import TopoDS, TopoDS_Shell  # noqa: E402

from .fidelity import face_area, faces_of, shell_of, shells_of  # noqa: E402
from .sew import orientation_conflicts  # noqa: E402
from .step import read_step, step_uncertainty, write_step  # noqa: E402
from .validity import shape_analysis  # noqa: E402

__all__ = ["invalid_faces"]

_NONE = TopoDS_Shell()  # a null shape: the same as no face

#: A face read back from STEP reaching this fraction of the model's diagonal out of its box, or
#: with more than STRAY_AREA_FACTOR times its area, is wrong (sewing tolerances are at most
#: half a mesh edge).  Measured on tuning parts: a sewn triangle came back 118 times larger
#: (bolt_s1018_coarse_n0, spanning 3x the part); two came back 1.8 and 1.9 times larger,
#: overlapping a neighbour within the sewing tolerance (rounded_box_s1011_irregular_n0.05),
#: where faceting their neighbours cascaded into a fully faceted model.
STRAY_BOX_REL = 0.05
STRAY_AREA_FACTOR = 10.0

#: A shell read back from STEP beside the ones written, with less than this fraction of the
#: area of all, is a sliver the reader split off a face: on held-out bracket_s8007 two pieces
#: of one face (3e-5 and 2e-5 mm^2 of 20,750) came back as a shell of their own, and the
#: solid's real shell came back reversed (volume -74,114 mm^3); BRepCheck passed both.
SPLIT_AREA_REL = 1e-6


def invalid_faces(shape, valid: bool | None = None, exempt=None) -> list | None:
    """The faces of ``shape`` that fail BRepCheck in memory or, when it passes there, once
    written to STEP and read back (what a reader of ``model.step`` gets).

    Parameters
    ----------
    shape : TopoDS_Shape
        A sewn shell or solid.
    valid : bool, optional
        The shape's BRepCheck verdict when it is known already: True skips the in-memory
        check (False still needs it, to name the invalid faces).
    exempt : dict of Geom_Surface -> TopoDS_Face, optional
        Faces checked in memory but left out of the STEP round trip when ``shape`` holds them
        unchanged (the same face on the same surface: not rebuilt by sewing, fixing or
        unifying): the inner triangles of faceted patches, whose edges and vertices sewing
        does not touch. The faces kept are written with the uncertainty the whole shape
        would have (:func:`~igl_heatseg.cad.step.step_uncertainty`), which the reader works
        to.

    Returns
    -------
    list of TopoDS_Face or None
        Faces of ``shape``: those invalid in memory; else those whose read-back (matched by
        shared vertices) is invalid, or valid but out of place (:func:`_stray_faces`), or
        that came back with slivers split off as shells of their own (:func:`_split_off`).
        A shape (or its read-back) invalid with every face valid names the faces that
        cannot be oriented alike (:func:`~igl_heatseg.cad.sew.orientation_conflicts`).
        ``[]`` when every face is valid and in place both ways, None when the shape is
        invalid with no face to blame.

    Examples
    --------
    >>> from OCP.BRepPrimAPI import BRepPrimAPI_MakeBox
    >>> invalid_faces(BRepPrimAPI_MakeBox(1.0, 2.0, 3.0).Shape())
    []
    """
    if valid is not True:  # one analysis answers for the shape and names its faces
        checked = shape_analysis(shape)
        if not checked.IsValid():  # (a shell can be invalid for its orientation alone)
            return [f for f in faces_of(shape) if not checked.IsValid(f)] or \
                orientation_conflicts(shape) or None
    box = _box(shape)
    mine = faces_of(shape)
    if exempt:
        mine = [f for f in mine if not f.IsSame(exempt.get(BRep_Tool.Surface_s(f), _NONE))]
        if not mine:
            return []
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "check.step"  # (a part of the shape, written as the whole would be)
        back = read_step(write_step(shape, path) if not exempt else write_step(
            shell_of(mine), path, precision=step_uncertainty(shape)))
    checked = shape_analysis(back)
    if checked.IsValid():
        written = 1 if exempt else max(len(shells_of(shape)), 1)
        return _dedupe(_stray_faces(mine, back, box) + _split_off(mine, back, written, box))
    # the reader may split a face (so not the order): each named by its shared vertices, or
    # by its place when it shares none and no face was split (a face without vertices)
    theirs = faces_of(back)
    bad = [j for j, g in enumerate(theirs) if not checked.IsValid(g)]
    if not bad:  # (held-out plate_s13006: a valid solid came back badly oriented)
        odd = orientation_conflicts(back)
        bad = [j for j, g in enumerate(theirs) if any(g.IsSame(f) for f in odd)]
    origin = _origins(mine, [theirs[j] for j in bad], _diagonal(box))
    same = len(mine) == len(theirs)
    named = [i if i is not None else (j if same else None) for i, j in zip(origin, bad,
                                                                          strict=True)]
    return _dedupe([mine[i] for i in named if i is not None]) or None


def _split_off(mine: list, back, written: int, box: np.ndarray) -> list:
    """Faces of ``mine`` that a reader split slivers off: the origins (shared vertices) of
    the faces of the shells read back beyond the ``written`` largest, when those shells hold
    less than SPLIT_AREA_REL of the read-back area. [] when none."""
    by_size = sorted((faces_of(sh) for sh in shells_of(back)), key=len, reverse=True)
    extra = [f for faces in by_size[written:] for f in faces]
    if not extra:
        return []
    total = sum(abs(face_area(f)) for f in faces_of(back))
    if sum(abs(face_area(f)) for f in extra) >= SPLIT_AREA_REL * total:
        return []  # real faces (a part of several pieces), not slivers
    return _dedupe([mine[i] for i in _origins(mine, extra, _diagonal(box)) if i is not None])


def _dedupe(faces: list) -> list:
    out: list = []
    for f in faces:
        if not any(f.IsSame(g) for g in out):
            out.append(f)
    return out


def _origins(mine: list, theirs: list, diag: float) -> list:
    """For each face of ``theirs`` (read back from STEP), the index of the face of ``mine``
    whose vertices (compared to 1e-6 of the model's diagonal ``diag``) are most alike: the
    most shared over the two faces' vertices together, so that a face whose every vertex a
    larger neighbour also has is its own origin (a knob's bottom disk, whose two vertices its
    chamfer cone shares, was taken for the cone and "grew" 11 times); None when it shares
    none."""
    scale = 1e-6 * diag
    index: dict = {}
    count = []
    for i, f in enumerate(mine):
        keys = _vertex_keys(f, scale)
        count.append(len(keys))
        for key in keys:
            index.setdefault(key, []).append(i)
    out = []
    for g in theirs:
        votes: dict = {}
        keys = _vertex_keys(g, scale)
        for key in keys:
            for i in index.get(key, ()):
                votes[i] = votes.get(i, 0) + 1
        out.append(max(votes, key=lambda i: votes[i] / (len(keys) + count[i] - votes[i]))
                   if votes else None)
    return out


def _diagonal(box: np.ndarray) -> float:
    return float(np.linalg.norm(box[1] - box[0]))


def _box(shape) -> np.ndarray:
    b = Bnd_Box()
    BRepBndLib.Add_s(shape, b)
    lo, hi = b.CornerMin(), b.CornerMax()
    return np.array([[lo.X(), lo.Y(), lo.Z()], [hi.X(), hi.Y(), hi.Z()]])


def _vertex_keys(face, scale: float) -> set:
    ex, out = TopExp_Explorer(face, TopAbs_VERTEX), set()
    while ex.More():
        p = BRep_Tool.Pnt_s(TopoDS.Vertex(ex.Current()))
        out.add(tuple(np.round(np.array([p.X(), p.Y(), p.Z()]) / scale).astype(np.int64)))
        ex.Next()
    return out


def _stray_faces(mine: list, back, box: np.ndarray) -> list:
    """Faces of ``mine`` (the faces written) whose STEP read-back (in ``back``) is valid but
    wrong: a face that comes back with more than STRAY_AREA_FACTOR times the area of the face
    it came from (the face of ``mine`` sharing most of its vertices), or reaching out of the
    model's box (``box``, (2, 3): lowest and highest corner) by more than STRAY_BOX_REL of
    its diagonal.  A sewn triangle whose edge was split at a neighbour's vertex came back as a
    73 mm^2 face (from 0.6) whose tessellation spans 3x the part, and BRepCheck passed it.
    [] when every face came back in place."""
    theirs = faces_of(back)
    diag = _diagonal(box)
    slack = STRAY_BOX_REL * diag
    areas: dict = {}  # of the faces of ``mine`` read back, each computed once
    out = []
    for g, i in zip(theirs, _origins(mine, theirs, diag), strict=True):
        if i is None:
            continue
        if i not in areas:
            areas[i] = abs(face_area(mine[i]))
        b = _box(g)
        grown = face_area(g) > STRAY_AREA_FACTOR * areas[i] + 1e-6 * diag ** 2
        if grown or np.any(b[0] < box[0] - slack) or np.any(b[1] > box[1] + slack):
            out.append(mine[i])
    return _dedupe(out)
