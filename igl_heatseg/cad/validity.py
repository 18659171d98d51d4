"""BRepCheck of whole shapes: the validity verdict the sewing, the build's blame and the
fidelity report share."""

from __future__ import annotations

from ._ocp import require_ocp

require_ocp()

from OCP.BRepCheck import BRepCheck_Analyzer  # noqa: E402

__all__ = ["shape_analysis", "shape_valid"]


def shape_analysis(shape):
    """BRepCheck of a whole shape, its sub-shapes checked on all cores (OCC's parallel mode:
    1.8 -> 1.2 s on a sewn 15,341-face solid, 2 cores).

    Parameters
    ----------
    shape : TopoDS_Shape

    Returns
    -------
    BRepCheck_Analyzer
        ``IsValid()`` for the shape, ``IsValid(sub)`` for one of its faces, edges, ...

    Examples
    --------
    >>> from OCP.BRepPrimAPI import BRepPrimAPI_MakeBox
    >>> from igl_heatseg.cad.fidelity import faces_of
    >>> box = BRepPrimAPI_MakeBox(1.0, 2.0, 3.0).Shape()
    >>> checked = shape_analysis(box)
    >>> checked.IsValid(), all(checked.IsValid(f) for f in faces_of(box))
    (True, True)
    """
    return BRepCheck_Analyzer(shape, True, True)


def shape_valid(shape) -> bool:
    """Whether a whole shape passes BRepCheck (:func:`shape_analysis`).

    Parameters
    ----------
    shape : TopoDS_Shape

    Returns
    -------
    bool

    Examples
    --------
    >>> from OCP.BRepPrimAPI import BRepPrimAPI_MakeBox
    >>> shape_valid(BRepPrimAPI_MakeBox(1.0, 2.0, 3.0).Shape())
    True
    """
    return bool(shape_analysis(shape).IsValid())
