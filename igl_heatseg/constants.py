"""Defaults from the paper (Table 1) and named numerical tolerances."""

from __future__ import annotations

import math

__all__ = [
    "THETA_DEFAULT",
    "EPS_DEFAULT",
    "DEGENERATE_FACE_TOL",
    "HEAT_SUM_TOL",
    "TIE_RTOL",
    "OFF_HEADER_MAX_BYTES_PER_ENTRY",
]

#: Dihedral deviation above which an interior edge is sharp (radians). Paper Table 1: pi/20.
THETA_DEFAULT: float = math.pi / 20.0

#: Groups whose initial segment area is below ``EPS_DEFAULT * A_largest`` are dropped. Table 1: 5 %.
EPS_DEFAULT: float = 0.05

#: A face is degenerate (zero area) when ``2*area <= DEGENERATE_FACE_TOL * longest_edge**2``.
#: Scale-free per face: catches collinear and coincident corners, not tiny well-shaped faces
#: (the iron scan has faces of area 1e-14 that are perfectly good triangles at their own scale).
DEGENERATE_FACE_TOL: float = 1e-12

#: Largest allowed deviation of ``sum_i u_i`` from 1 before a heat solve is reported as failed.
HEAT_SUM_TOL: float = 1e-6

#: Two temperatures within this relative distance are a tie, decided for the lower group id.
#: Two factorizations of one system (libigl's LLT, CHOLMOD) round differently (measured: an
#: exact tie came out 5.6e-17 apart), and an exact tie must not be decided by round-off.
TIE_RTOL: float = 1e-12

#: Smallest number of bytes an ASCII OFF file needs per declared vertex or face; a header that
#: declares more entries than ``file_size / this`` cannot be held by the file.
OFF_HEADER_MAX_BYTES_PER_ENTRY: int = 2
