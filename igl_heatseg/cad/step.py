"""STEP files (AP214) through OpenCASCADE's STEPControl."""

from __future__ import annotations

import logging
import os

import numpy as np

from igl_heatseg.errors import MeshError

from ._ocp import quiet_occ, require_ocp

require_ocp()

from OCP.IFSelect import IFSelect_ReturnStatus  # noqa: E402
from OCP.Interface import Interface_MSG, Interface_Static  # noqa: E402
from OCP.ShapeAnalysis import ShapeAnalysis_ShapeTolerance  # noqa: E402
from OCP.STEPControl import STEPControl_AsIs, STEPControl_Reader, STEPControl_Writer  # noqa: E402

logger = logging.getLogger(__name__)

__all__ = ["write_step", "read_step", "step_uncertainty"]

_UNITS = {"mm": "MM", "m": "M", "cm": "CM", "in": "INCH", "inch": "INCH", "um": "UM"}


def step_uncertainty(shape) -> float:
    """The uncertainty OpenCASCADE writes in a shape's STEP file by default (and its reader
    then works to): 1.5 x the average tolerance of the shape's vertices, edges and faces,
    rounded down to 1, 2 or 5 x 10^k (``STEPControl_ActorWrite::UsedTolerance``).

    Parameters
    ----------
    shape : TopoDS_Shape

    Returns
    -------
    float
        Model units.

    Examples
    --------
    >>> from OCP.BRepPrimAPI import BRepPrimAPI_MakeBox
    >>> round(step_uncertainty(BRepPrimAPI_MakeBox(1.0, 2.0, 3.0).Shape()), 12)  # of 1.5e-7
    1e-07
    """
    tol = Interface_MSG.Intervalled_s(ShapeAnalysis_ShapeTolerance().Tolerance(shape, 0) * 1.5)
    return float(tol) if tol > 0 else 1e-7


def write_step(shape, path, unit: str = "mm", precision: float | None = None) -> str:
    """Write a shape as an AP214 STEP file.

    Parameters
    ----------
    shape : TopoDS_Shape
    path : str or PathLike
    unit : str
        Length unit of the model coordinates: ``"mm"`` (default), ``"cm"``, ``"m"``,
        ``"in"`` or ``"um"``.
    precision : float, optional
        The uncertainty written in the file (model units), which readers work to; default:
        :func:`step_uncertainty` of ``shape``. (A part of a model written with the whole
        model's uncertainty reads back as it would within the whole.)

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
    if precision is None:  # (a global setting: set on every call)
        Interface_Static.SetIVal_s("write.precision.mode", 0)
    elif np.isfinite(precision) and precision > 0:
        Interface_Static.SetIVal_s("write.precision.mode", 2)
        Interface_Static.SetRVal_s("write.precision.val", float(precision))
    else:
        raise MeshError(f"precision must be a positive number, got {precision!r}")
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
