"""Harmonic "temperature" fields: one per seed group, one factorization for all.

Contract: given ``V``, ``F`` (a validated mesh) and a seed group per vertex (``-1`` for
non-seeds), a solver returns the hottest group per vertex and per face (:class:`HeatLabels`).
:class:`HeatSolver` solves every field exactly (the reference); :class:`FastHeatSolver` gives
the same labels from certified local solves. Both factor once and solve many times.
Imports only from ``mesh`` and below.
"""

from .exact import HeatLabels, HeatSolver, corner_means, heat_fields
from .fast import FastHeatSolver

__all__ = ["HeatSolver", "FastHeatSolver", "HeatLabels", "heat_fields", "corner_means"]
