"""A mesh of several connected parts built one part at a time: the fallback of
:func:`~igl_heatseg.cad.build.build_brep` when the model as a whole stays invalid.

The parts of a multi-part mesh (a truck's 64 shells) share no edge, so a face that no rebuild
mends in one part need not cost the others their surfaces: each part is built on its own (and,
failing, faceted on its own), and the results are put in one compound.
"""

from __future__ import annotations

import numpy as np

from ..mesh.topology import face_components
from ._ocp import require_ocp

require_ocp()

from OCP.BRep import BRep_Builder  # noqa: E402
from OCP.TopoDS import TopoDS_Compound  # noqa: E402

from .fidelity import brep_fidelity  # noqa: E402

__all__ = ["build_by_component"]


def build_by_component(V, F, labels, surfaces, uv, tol: float, build, progress=None):
    """Build each edge-connected part of a mesh on its own and put the results in one compound.

    Parameters
    ----------
    V : (n, 3) float64
    F : (m, 3) int64
    labels : (m,) int64
        Segment of each face, ``0..k-1``; a segment spread over several parts is built in each.
    surfaces : list of Surface, length k
    uv : list of (ids (p,), UV (p, 2)) or None
        Charts by segment (vertex ids into ``V``), as :func:`~.build.build_brep` takes them; a
        segment spread over several parts has its chart made anew in each.
    tol : float
        The modelling tolerance of the whole mesh (model units).
    build : callable
        ``build(V, F, labels, surfaces, uv=..., tol=...)`` for one part, returning an object
        with ``shape``, ``faces``, ``faceted_model`` and ``border_faces_moved``
        (:func:`~igl_heatseg.cad.build.build_brep`, which calls this module, passes itself).
    progress : callable(stage, fraction), optional

    Returns
    -------
    tuple or None
        None for a mesh of one part. Otherwise ``(shape, faces, fidelity, faceted_model,
        message, border_faces_moved)``: the compound; one entry per segment, as ``build`` gives
        them, faceted when any of its parts was; :func:`~igl_heatseg.cad.fidelity.brep_fidelity`
        of the compound against the whole mesh; True only when every part was faceted whole; a
        summary; the parts' moved faces ``(p, 3)`` (face, old and new segment, into ``F`` and
        ``labels``).

    Examples
    --------
    >>> import numpy as np
    >>> from igl_heatseg.surfaces.model import Surface
    >>> V = np.array([[0., 0, 0], [1, 0, 0], [0, 1, 0], [5, 0, 0], [6, 0, 0], [5, 1, 0]])
    >>> F = np.array([[0, 1, 2], [3, 4, 5]])
    >>> z = Surface("plane", {"point": np.zeros(3), "normal": np.array([0., 0, 1])})
    >>> from igl_heatseg.cad.build import build_brep
    >>> shape, faces, fid, whole, _, _ = build_by_component(V, F, np.array([0, 0]), [z], None,
    ...                                                      0.01, build_brep)
    >>> fid["faces"], [f["status"] for f in faces], whole
    (2, ['built'], False)
    """
    count, comp = face_components(F)
    if count < 2:
        return None
    progress = progress or (lambda stage, frac: None)
    builder, compound = BRep_Builder(), TopoDS_Compound()
    builder.MakeCompound(compound)
    faceted: dict = {}
    status = [None] * len(surfaces)
    whole, moved = 0, [np.zeros((0, 3), dtype=np.int64)]
    k = len(surfaces)
    lo, hi = np.full(k, count), np.full(k, -1)
    np.minimum.at(lo, labels, comp)
    np.maximum.at(hi, labels, comp)
    spread = lo != hi  # segments with faces in more than one part (or in none)
    for c in range(count):
        progress("components", c / count)
        faces = np.flatnonzero(comp == c)
        verts, Fl = np.unique(F[faces], return_inverse=True)
        segs, lab = np.unique(labels[faces], return_inverse=True)
        res = build(V[verts], Fl.reshape(-1, 3), lab, [surfaces[a] for a in segs],
                    uv=_charts(uv, segs, verts, spread), tol=tol)
        builder.Add(compound, res.shape)
        whole += bool(res.faceted_model)
        m = np.asarray(res.border_faces_moved, dtype=np.int64).reshape(-1, 3)
        moved.append(np.c_[faces[m[:, 0]], segs[m[:, 1]], segs[m[:, 2]]])
        for entry, a in zip(res.faces, segs.tolist(), strict=True):
            if status[a] is None or entry["status"] != "built":
                status[a] = dict(entry, index=a)
            if entry["status"] != "built":
                faceted[a] = True
    progress("components", 1.0)
    for a in np.flatnonzero(hi < 0).tolist():  # a surface without faces: nothing to build
        status[a] = dict(index=a, kind=surfaces[a].kind, status="faceted",
                         reason="no faces in the mesh", built_as=None, max_dev=None,
                         why_bspline=None)
        faceted[a] = True
    fid = brep_fidelity(compound, V, F)
    message = (f"the model as a whole stayed invalid; built part by part: {whole} of {count} "
               f"parts fully faceted, {len(faceted)} of {len(surfaces)} segments faceted")
    return compound, status, fid, whole == count, message, np.concatenate(moved)


def _charts(uv, segs, verts, spread):
    """The charts of a part's segments ``segs``, their vertex ids renumbered into the part's
    ``verts``; None for a segment ``spread`` over another part too."""
    if uv is None:
        return None
    out = []
    for a in segs.tolist():
        entry = uv[a]
        if entry is None or spread[a]:
            out.append(None)
            continue
        ids, UV = (np.asarray(x) for x in entry)
        out.append((np.searchsorted(verts, ids), UV))
    return out
