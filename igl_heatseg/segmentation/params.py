"""One layer that resolves and checks the segmentation parameters, and the one eps rule.

Every entry point above the segmentation (the pipeline, the command line, the viewer, the
baselines) passes ``theta=None, eps=None`` for "this mode's default" down to
:func:`resolve_params`, which is the only place the defaults are chosen and the ranges checked.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike

from ..constants import EPS_DEFAULT, THETA_DEFAULT
from ..errors import MeshError

__all__ = [
    "MODES",
    "SOLVERS",
    "ROBUST_THETA",
    "ROBUST_EPS",
    "MODE_DEFAULTS",
    "check_segment_params",
    "resolve_params",
    "check_solver",
    "eps_keep",
]

#: Segmentation modes: the paper's (default, faithful) and robust mode (noise, blends).
MODES: tuple[str, ...] = ("paper", "robust")

#: Heat solvers by name (``fast``: certified local solves; ``exact``: one global solve a group).
SOLVERS: tuple[str, ...] = ("fast", "exact")

#: Robust mode's crease threshold on filtered normals (radians): measured on the ABC parts.
ROBUST_THETA: float = 0.7

#: Robust mode's eps, a fraction of the component's area (not of its largest segment).
ROBUST_EPS: float = 0.0015

#: (theta, eps) defaults of each mode, and what eps is measured against (:func:`eps_keep`).
MODE_DEFAULTS: dict[str, tuple[float, float, str]] = {
    "paper": (THETA_DEFAULT, EPS_DEFAULT, "largest"),
    "robust": (ROBUST_THETA, ROBUST_EPS, "component"),
}


def check_segment_params(theta: float, eps: float) -> None:
    """Raise :class:`~igl_heatseg.errors.MeshError` unless ``0 < theta <= pi``, ``0 <= eps <= 1``.

    Examples
    --------
    >>> check_segment_params(0.3, 0.05)
    >>> check_segment_params(4.0, 0.05)
    Traceback (most recent call last):
    ...
    igl_heatseg.errors.MeshError: theta must be in (0, pi] radians, got 4.0
    """
    ok_t = isinstance(theta, (int, float, np.floating)) and not isinstance(theta, bool)
    if not (ok_t and 0 < theta <= math.pi):
        raise MeshError(f"theta must be in (0, pi] radians, got {theta!r}")
    ok_e = isinstance(eps, (int, float, np.floating)) and not isinstance(eps, bool)
    if not (ok_e and 0 <= eps <= 1):
        raise MeshError(f"eps must be in [0, 1], got {eps!r}")


def check_solver(solver: str) -> None:
    """Raise :class:`~igl_heatseg.errors.MeshError` unless ``solver`` is one of :data:`SOLVERS`."""
    if solver not in SOLVERS:
        raise MeshError(f"solver must be one of {list(SOLVERS)}, got {solver!r}")


def resolve_params(
    mode: str = "paper", theta: float | None = None, eps: float | None = None
) -> tuple[float, float]:
    """The ``(theta, eps)`` a mode runs with: ``None`` takes the mode's default; both checked.

    Parameters
    ----------
    mode : {"paper", "robust"}
    theta, eps : float or None

    Returns
    -------
    theta, eps : float

    Raises
    ------
    MeshError
        Unknown mode or a value out of range.

    Examples
    --------
    >>> resolve_params("robust")
    (0.7, 0.0015)
    >>> resolve_params("paper", eps=0.1)[1]
    0.1
    """
    if mode not in MODE_DEFAULTS:
        raise MeshError(f"mode must be one of {list(MODES)}, got {mode!r}")
    t0, e0, _ = MODE_DEFAULTS[mode]
    theta = t0 if theta is None else theta
    eps = e0 if eps is None else eps
    check_segment_params(theta, eps)
    return float(theta), float(eps)


def eps_keep(
    areas: ArrayLike,
    component: ArrayLike | None,
    eps: float,
    reference: str = "largest",
) -> np.ndarray:
    """The eps round (paper §3.4): which initial groups keep their seeds.

    A group is kept when its area is at least ``eps`` times the reference area of its
    connected component: the component's largest initial segment (``"largest"``, the paper's
    rule) or the component's whole area (``"component"``, robust mode; the largest group of a
    component is then always kept). Groups of zero area are dropped.

    Parameters
    ----------
    areas : (k,) array_like of float
        Area of each initial group's segment.
    component : (k,) array_like of int, optional
        Connected component of each group (default: all in one).
    eps : float
        Area fraction in ``[0, 1]``.
    reference : {"largest", "component"}

    Returns
    -------
    keep : (k,) bool

    Examples
    --------
    >>> eps_keep([4.0, 1.0, 0.1], None, 0.05).tolist()
    [True, True, False]
    >>> eps_keep([4.0, 0.1, 0.1], [0, 0, 1], 0.05).tolist()
    [True, False, True]
    """
    a = np.asarray(areas, dtype=np.float64)
    c = np.zeros(len(a), dtype=np.int64) if component is None else np.asarray(component, np.int64)
    ncomp = int(c.max()) + 1 if len(c) else 0
    largest = np.zeros(ncomp)
    np.maximum.at(largest, c, a)
    if reference == "largest":
        keep = a >= eps * largest[c]
    elif reference == "component":
        total = np.bincount(c, weights=a, minlength=ncomp)
        keep = (a >= eps * total[c]) | (a == largest[c])
    else:
        raise MeshError(f"reference must be 'largest' or 'component', got {reference!r}")
    return keep & (a > 0)
