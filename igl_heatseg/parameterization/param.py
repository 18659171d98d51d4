"""Former home of the chart parameterization, kept so that old imports keep working.

The code lives in :mod:`~.prepare` (chart checks, edges, certificate, BLAS threads),
:mod:`~.eigenmap` (Hessian eigenmaps), :mod:`~.fallback` (Tutte, repair, guarded SLIM),
:mod:`~.distortion`, :mod:`~.chart` (:func:`parameterize_chart`) and :mod:`~.methods`
(baselines, :data:`METHODS`, :func:`compare_methods`).  Import from those (or from
:mod:`igl_heatseg.parameterization`); this module only re-exports their public names.
"""

from .chart import HLLE_SKIP_CURVATURE, ChartParam, parameterize_chart
from .distortion import distortion
from .eigenmap import DENSE_EIGEN_MAX, EIGEN_SHIFT, NULLSPACE_TOL, gram_correction, hessian_map
from .fallback import SLIM_ITERATIONS, repair_map, tutte_map
from .methods import METHODS, PIPELINE_METHODS, compare_methods, map_chart
from .prepare import BLAS_THREADS, limit_blas_threads, total_abs_curvature

__all__ = [
    "ChartParam",
    "parameterize_chart",
    "map_chart",
    "hessian_map",
    "gram_correction",
    "tutte_map",
    "repair_map",
    "distortion",
    "total_abs_curvature",
    "limit_blas_threads",
    "compare_methods",
    "METHODS",
    "PIPELINE_METHODS",
    "NULLSPACE_TOL",
    "EIGEN_SHIFT",
    "DENSE_EIGEN_MAX",
    "HLLE_SKIP_CURVATURE",
    "BLAS_THREADS",
    "SLIM_ITERATIONS",
]
