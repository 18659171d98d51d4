"""The optional OpenCASCADE dependency (OCP) with an install hint when it is missing."""

from __future__ import annotations

import contextlib
import itertools

__all__ = ["require_ocp", "quiet_occ", "shapes_in"]

INSTALL_HINT = (
    "igl_heatseg.cad needs OpenCASCADE through OCP (cadquery-ocp-novtk 8.0): "
    "pip install 'igl_heatseg[cad]'"
)


def require_ocp() -> None:
    """Raise ImportError with the install hint when OCP cannot be imported."""
    try:
        import OCP  # noqa: F401
    except ImportError as exc:  # pragma: no cover - depends on the environment
        raise ImportError(INSTALL_HINT) from exc


@contextlib.contextmanager
def quiet_occ():
    """Raise OCC's default message printers to failures only while in the block (the STEP
    translators print transfer statistics on stdout; the package logs instead)."""
    from OCP.Message import Message, Message_Gravity

    printers = Message.DefaultMessenger_s().Printers()
    saved = []
    for i in range(1, printers.Length() + 1):
        p = printers.Value(i)
        saved.append((p, p.GetTraceLevel()))
        p.SetTraceLevel(Message_Gravity.Message_Fail)
    try:
        yield
    finally:
        for p, level in saved:
            p.SetTraceLevel(level)


def shapes_in(shapes) -> list:
    """The shapes of an OCC list (``TopTools_ListOfShape``, e.g. an ancestor map's entry) as a
    Python list.

    Reads exactly ``Extent()`` items: letting OCP's iterator run out costs about 30 us per list
    (its StopIteration), which made ``list(lst)`` over the 1,284 edges of an 809-face sewn
    shell take 0.2 s, 6 of a coarse part's 85 s over its rebuilds.

    Parameters
    ----------
    shapes : OCP.collections.List_TopoDS_Shape

    Returns
    -------
    list of TopoDS_Shape

    Examples
    --------
    >>> from OCP.BRepPrimAPI import BRepPrimAPI_MakeBox
    >>> from OCP.TopAbs import TopAbs_EDGE, TopAbs_FACE
    >>> from OCP.TopExp import TopExp
    >>> from OCP.collections import (
    ...     IndexedDataMap_TopoDS_Shape_List_TopoDS_Shape_TopTools_ShapeMapHasher as Map)
    >>> m = Map()
    >>> TopExp.MapShapesAndAncestors_s(BRepPrimAPI_MakeBox(1.0, 1.0, 1.0).Shape(),
    ...                                TopAbs_EDGE, TopAbs_FACE, m)
    >>> len(shapes_in(m.FindFromIndex(1)))     # a box's edge is on two faces
    2
    """
    return list(itertools.islice(shapes, shapes.Extent()))
