"""STEP files (AP214) through OpenCASCADE's STEPControl."""

from __future__ import annotations

import logging
import os

from igl_heatseg.errors import MeshError

from ._ocp import quiet_occ, require_ocp

require_ocp()

from OCP.IFSelect import IFSelect_ReturnStatus  # noqa: E402
from OCP.Interface import Interface_Static  # noqa: E402
from OCP.STEPControl import STEPControl_AsIs, STEPControl_Reader, STEPControl_Writer  # noqa: E402

logger = logging.getLogger(__name__)

__all__ = ["write_step", "read_step"]

_UNITS = {"mm": "MM", "m": "M", "cm": "CM", "in": "INCH", "inch": "INCH", "um": "UM"}


def write_step(shape, path, unit: str = "mm") -> str:
    """Write a shape as an AP214 STEP file.

    Parameters
    ----------
    shape : TopoDS_Shape
    path : str or PathLike
    unit : str
        Length unit of the model coordinates: ``"mm"`` (default), ``"cm"``, ``"m"``,
        ``"in"`` or ``"um"``.

    Returns
    -------
    str
        The path written.

    Examples
    --------
    >>> import os, tempfile
    >>> from OCP.BRepPrimAPI import BRepPrimAPI_MakeBox
    >>> p = write_step(BRepPrimAPI_MakeBox(1.0, 2.0, 3.0).Shape(),
    ...                os.path.join(tempfile.mkdtemp(), "box.step"))
    >>> from igl_heatseg.cad.fidelity import faces_of
    >>> len(faces_of(read_step(p)))
    6
    """
    if unit.lower() not in _UNITS:
        raise MeshError(f"unit must be one of {sorted(_UNITS)}, got {unit!r}")
    path = os.fspath(path)
    writer = STEPControl_Writer()
    Interface_Static.SetCVal_s("write.step.schema", "AP214IS")
    Interface_Static.SetCVal_s("write.step.unit", _UNITS[unit.lower()])
    with quiet_occ():
        done = writer.Transfer(shape, STEPControl_AsIs)
        if done != IFSelect_ReturnStatus.IFSelect_RetDone:
            raise RuntimeError("STEP transfer of the shape failed")
        if writer.Write(path) != IFSelect_ReturnStatus.IFSelect_RetDone:
            raise OSError(f"could not write STEP file {path}")
    logger.info("wrote %s", path)
    return path


def read_step(path):
    """Read a STEP file into one shape (all roots transferred).

    Parameters
    ----------
    path : str or PathLike

    Returns
    -------
    TopoDS_Shape
    """
    path = os.fspath(path)
    if not os.path.exists(path):
        raise MeshError(f"STEP file {path} does not exist")
    reader = STEPControl_Reader()
    with quiet_occ():
        if reader.ReadFile(path) != IFSelect_ReturnStatus.IFSelect_RetDone:
            raise MeshError(f"could not read STEP file {path}")
        reader.TransferRoots()
        return reader.OneShape()
