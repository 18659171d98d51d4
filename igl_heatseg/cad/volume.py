"""Volumes of closed meshes and B-Reps (the fidelity report's volume error)."""

from __future__ import annotations

import numpy as np

from ._ocp import require_ocp

require_ocp()

from OCP.BRepGProp import BRepGProp  # noqa: E402
from OCP.GProp import GProp_GProps  # noqa: E402

__all__ = ["mesh_volume", "solid_volume", "VOLUME_EPS"]

#: Relative error asked of OCC's adaptive volume integration (:func:`solid_volume`). Its default,
#: a fixed-order Gauss rule per face, read a valid 14-face solid (held-out
#: saddle_boss_s38036_frontal_n0.1: partial tori and a cone trimmed by intersection curves) as
#: 58,031 where it is 59,251 (-2.1 %; the true part is 59,227), and a noisy pipe elbow's 1.5 %
#: off; 1e-3 to 1e-8 all give 59,250.7. On five models of 1,000-7,000 faces (faceted segments)
#: 1e-3, 1e-4 and 1e-6 agreed to 6e-6 and took 0.7-1.8, 1.1-3.2 and 1.7-4.1 s (default
#: 0.2-0.6 s).
VOLUME_EPS = 1e-4


def mesh_volume(V: np.ndarray, F: np.ndarray) -> float:
    """Signed volume enclosed by a closed triangle mesh (divergence theorem).

    Parameters
    ----------
    V : (n, 3) float64
        Vertices.
    F : (m, 3) int64
        Triangles, counter-clockwise seen from outside (the volume is then positive).

    Returns
    -------
    float
        Signed volume, model units cubed.

    Examples
    --------
    >>> import numpy as np
    >>> V = np.array([[0., 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]])
    >>> F = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    >>> round(mesh_volume(V, F), 12)
    0.166666666667
    """
    a, b, c = V[F[:, 0]], V[F[:, 1]], V[F[:, 2]]
    return float(np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6.0)


def solid_volume(shape) -> float:
    """Volume enclosed by a closed B-Rep, by OCC's adaptive integration (:data:`VOLUME_EPS`).

    Parameters
    ----------
    shape : TopoDS_Shape
        A solid (or a closed shell); its faces' orientations give the sign (positive when
        outward).

    Returns
    -------
    float
        Signed volume, model units cubed.

    Examples
    --------
    >>> from OCP.BRepPrimAPI import BRepPrimAPI_MakeBox
    >>> round(solid_volume(BRepPrimAPI_MakeBox(1.0, 2.0, 3.0).Shape()), 9)
    6.0
    """
    props = GProp_GProps()
    BRepGProp.VolumeProperties_s(shape, props, VOLUME_EPS)
    return float(props.Mass())
