"""Charts to the plane: cut to a disk, map by a discrete Hessian energy, certify, pack.

Contract: a chart is ``V (n,3)``, ``F (m,3)``; :func:`cut_to_disk` makes it a disk,
:func:`parameterize_chart` maps it (paper §3.6: Hessian eigenmap, with a certified bijective
fallback), :func:`certify_map` checks bijectivity, :func:`pack_charts` packs an atlas.
Imports only from ``mesh`` and below.
"""

from .atlas import PackedAtlas, atlas_corner_uv, pack_charts
from .bijectivity import Certificate, certify_map
from .chart import ChartParam, parameterize_chart
from .cut import CutError, CutResult, chart_topology, cut_along_paths, cut_to_disk

__all__ = [
    "cut_to_disk",
    "cut_along_paths",
    "chart_topology",
    "CutResult",
    "CutError",
    "parameterize_chart",
    "ChartParam",
    "certify_map",
    "Certificate",
    "pack_charts",
    "PackedAtlas",
    "atlas_corner_uv",
]
