"""Charts to the plane: cut to a disk, map by a discrete Hessian energy, certify, pack.

Contract: a chart is ``V (n,3)``, ``F (m,3)``; :func:`cut_to_disk` makes it a disk,
:func:`parameterize_chart` maps it (paper §3.6: Hessian eigenmap, with certified bijective
fallbacks, the lowest-energy certified map kept unless the Hessian map is within a margin),
:func:`certify_map` checks bijectivity, :func:`parameterize_pieces` cuts a chart further
while no map of it is near-isometric, :func:`pack_charts` packs an atlas.
Imports only from ``mesh`` and below.

Modules: ``cut`` and ``wedges`` (cutting), ``hessian`` (energies), ``prepare`` (chart checks,
certificate orientation), ``eigenmap`` (Hessian maps), ``fallback`` (Tutte, repair, SLIM),
``distortion``, ``chart`` (:func:`parameterize_chart`), ``split`` (cuts for distortion and
for packing), ``spikes`` (spikes peeled off for packing),
``methods`` (baselines, :func:`~.methods.compare_methods`), ``bijectivity``, ``atlas`` and
``outline_pack`` (packing); ``param`` only re-exports old names.
"""

from .atlas import PackedAtlas, atlas_corner_uv, pack_charts
from .bijectivity import Certificate, certify_map
from .chart import ChartParam, parameterize_chart
from .cut import CutError, CutResult, chart_topology, cut_along_paths, cut_to_disk
from .split import parameterize_pieces

__all__ = [
    "cut_to_disk",
    "cut_along_paths",
    "chart_topology",
    "CutResult",
    "CutError",
    "parameterize_chart",
    "parameterize_pieces",
    "ChartParam",
    "certify_map",
    "Certificate",
    "pack_charts",
    "PackedAtlas",
    "atlas_corner_uv",
]
