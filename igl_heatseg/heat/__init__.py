"""Harmonic "temperature" fields: one per seed group, one factorization for all.

Contract: given ``V``, ``F`` (a validated mesh) and a seed group per vertex (``-1`` for
non-seeds), a solver returns the hottest group per vertex and per face (:class:`HeatLabels`).
:class:`HeatSolver` solves every field exactly (the reference); :class:`FastHeatSolver` gives
the same labels from certified local solves (and is :class:`HeatSolver` when groups are few).
Both factor once and solve many times, through :class:`~igl_heatseg.heat.factor.SparseCholesky`.
Imports only from ``mesh`` and below.

Modules: ``factor`` (sparse Cholesky), ``exact`` (the Dirichlet system, the exact solver and
its streaming argmax), and the fast solver's ``patches``, ``certify``, ``refine`` and ``fast``.
"""

from collections.abc import Callable
from typing import Protocol

import numpy as np

from .exact import HeatLabels, HeatSolver, HeatSystem, corner_means, heat_fields
from .factor import SparseCholesky
from .fast import FastHeatSolver

__all__ = [
    "HeatSolver",
    "FastHeatSolver",
    "HeatLabels",
    "HeatLabeler",
    "HeatSystem",
    "SparseCholesky",
    "heat_fields",
    "corner_means",
]


class HeatLabeler(Protocol):
    """What segmentation needs of a heat solver (both solvers satisfy it)."""

    k: int

    def labels(self, progress: Callable[[float], None] | None = None) -> HeatLabels: ...

    def temperature(self, i: int) -> np.ndarray: ...
