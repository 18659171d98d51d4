"""The result of :func:`~igl_heatseg.cad.build.build_brep`: the sewn shape, the status of
every segment's face, fidelity, timings and tolerances."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

__all__ = ["CadResult"]


@dataclass
class CadResult:
    """Result of :func:`~igl_heatseg.cad.build.build_brep`.

    Attributes
    ----------
    shape : TopoDS_Shape
        A solid when the mesh was closed and the shell closed, else a shell or compound.
    faces : list of dict
        One per segment: ``index``, ``kind``, ``status`` (``"built"`` or ``"faceted"``),
        ``reason`` (None when built), ``built_as`` (the fitted ``kind``, or ``"bspline"`` for
        an analytic segment farther than the tolerance from its surface, or misfit by it, that
        a B-spline over its chart fits better; None when faceted), ``max_dev`` (largest vertex
        distance to the surface built, else to the fitted one), ``why_bspline`` (for those
        B-spline faces, which test sent them there and both fits' deviations; else None),
        ``dropped`` (of a faceted segment: its triangles left out because sewing closed them
        up, two of their corners merged; 0 for a built one; absent when the whole model was
        faceted).
    fidelity : dict
        :func:`igl_heatseg.cad.fidelity.brep_fidelity` of ``shape`` against the mesh.
    timings : dict
        Seconds per stage.
    tolerances : dict
        The modelling, curve and sewing tolerances used.
    faceted_model : bool
        True when the whole build failed and ``shape`` is the fully faceted mesh (of a mesh of
        several parts: every part faceted).
    message : str
    border_faces_moved : (p, 3) int64
        Mesh faces built with a neighbouring segment instead of their own (face, segment of the
        labels given, segment built with;
        :func:`~igl_heatseg.cad.surface_choice.settle`); the faces of a segment are those of
        the labels given with these moves.
    time_limit : dict or None
        With a time limit: ``seconds``, ``reached`` (bool) and ``skipped`` (the builds it left
        out, as text); None without one.
    """

    shape: object
    faces: list = field(default_factory=list)
    fidelity: dict = field(default_factory=dict)
    timings: dict = field(default_factory=dict)
    tolerances: dict = field(default_factory=dict)
    faceted_model: bool = False
    message: str = ""
    border_faces_moved: np.ndarray = field(
        default_factory=lambda: np.zeros((0, 3), dtype=np.int64))
    time_limit: dict | None = None

    @property
    def not_built(self) -> list:
        """Entries of :attr:`faces` that were faceted."""
        return [f for f in self.faces if f["status"] != "built"]

    def to_report(self) -> dict:
        """JSON-ready summary (no OCC objects)."""
        return {
            "faces": [dict(f) for f in self.faces],
            "not_built": [f["index"] for f in self.not_built],
            "fidelity": dict(self.fidelity),
            "timings": {k: round(float(v), 4) for k, v in self.timings.items()},
            "tolerances": dict(self.tolerances),
            "faceted_model": bool(self.faceted_model),
            "message": self.message,
            "border_faces_moved": np.asarray(self.border_faces_moved).tolist(),
            "time_limit": None if self.time_limit is None else dict(self.time_limit),
        }
