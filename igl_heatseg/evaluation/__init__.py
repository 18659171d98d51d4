"""Scoring segmentations against ground truth, and comparing parameterizations.

Contract: pure functions of labels (and a mesh where geometry is needed); nothing here changes
a result. Imports any stage below it.
"""

from .metrics import (
    Evaluation,
    contingency_table,
    coverage,
    evaluate_labels,
    purity,
    rand_index,
    read_labels,
    read_truth,
)
from .surfaces import (
    boundary_length,
    boundary_length_ratio,
    face_kinds,
    read_surface_types,
    segment_ratio,
    surface_kind,
    type_accuracy,
)

__all__ = [
    "Evaluation",
    "evaluate_labels",
    "purity",
    "coverage",
    "rand_index",
    "contingency_table",
    "read_labels",
    "read_truth",
    "type_accuracy",
    "boundary_length",
    "boundary_length_ratio",
    "segment_ratio",
    "surface_kind",
    "face_kinds",
    "read_surface_types",
]
