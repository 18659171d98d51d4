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

__all__ = [
    "Evaluation",
    "evaluate_labels",
    "purity",
    "coverage",
    "rand_index",
    "contingency_table",
    "read_labels",
    "read_truth",
]
