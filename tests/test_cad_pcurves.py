"""Pcurves that stray from their edge (as sewing can leave them) are projected again."""

from __future__ import annotations

import math

import numpy as np
import pytest

pytest.importorskip("OCP")

from OCP.BRep import BRep_Builder, BRep_Tool  # noqa: E402
from OCP.BRepGProp import BRepGProp  # noqa: E402
from OCP.BRepPrimAPI import (  # noqa: E402
    BRepPrimAPI_MakeCone,
    BRepPrimAPI_MakeCylinder,
    BRepPrimAPI_MakeSphere,
    BRepPrimAPI_MakeTorus,
)
from OCP.GProp import GProp_GProps  # noqa: E402
from OCP.TopAbs import TopAbs_EDGE  # noqa: E402
from OCP.TopExp import TopExp_Explorer  # noqa: E402
from OCP.TopoDS import TopoDS  # noqa: E402

from igl_heatseg.cad.fidelity import face_area, faces_of, shape_valid  # noqa: E402
from igl_heatseg.cad.pcurves import mend_pcurves, pcurve_deviation, pcurve_through  # noqa: E402


def _volume(shape) -> float:
    props = GProp_GProps()
    BRepGProp.VolumeProperties_s(shape, props)
    return props.Mass()


def _bottom_circle(side):
    """The side face's edge at v = 0 that is not its seam."""
    ex = TopExp_Explorer(side, TopAbs_EDGE)
    while ex.More():
        e = TopoDS.Edge(ex.Current())
        ex.Next()
        if not BRep_Tool.IsClosed_s(e, side):
            a, b = BRep_Tool.Range_s(e, side)
            pc = BRep_Tool.CurveOnSurface_s(e, side, 0.0, 0.0)
            if abs(pc.Value(0.5 * (a + b)).Y()) < 1e-9:
                return e
    raise AssertionError("no bottom circle")


def _spiky_pcurve(a: float, b: float, height: float):
    """(u, v) = (t, spike(t)): the circle's own pcurve at its ends, ``height`` up the axis at
    mid-range (a narrow Gaussian)."""
    T = np.linspace(a, b, 200)
    return pcurve_through(np.c_[T, height * np.exp(-(((T - 0.5 * (a + b)) / 0.2) ** 2))], T)


def test_a_spiked_pcurve_of_a_cylinder_is_projected_again():
    solid = BRepPrimAPI_MakeCylinder(1.0, 2.0).Shape()
    side = faces_of(solid)[0]
    edge = _bottom_circle(side)
    a, b = BRep_Tool.Range_s(edge, side)
    tol = BRep_Tool.Tolerance_s(edge)
    BRep_Builder().UpdateEdge(edge, _spiky_pcurve(a, b, 1.5), side, tol)
    # the spike is invisible at the ends, but the face's domain and the volume are wrong
    assert pcurve_deviation(edge, side) > 1.4
    assert not abs(face_area(side) - 4 * math.pi) < 0.3
    assert not abs(_volume(solid) - 2 * math.pi) < 0.1

    assert mend_pcurves(solid) == (1, 0)
    assert pcurve_deviation(edge, side, 1000) <= max(tol, 1e-6)
    assert face_area(side) == pytest.approx(4 * math.pi, rel=1e-6)
    assert _volume(solid) == pytest.approx(2 * math.pi, rel=1e-6)
    assert shape_valid(solid)
    assert mend_pcurves(solid) == (0, 0)


@pytest.mark.parametrize("make", [
    lambda: BRepPrimAPI_MakeCylinder(1.0, 2.0).Shape(),
    lambda: BRepPrimAPI_MakeCone(2.0, 1.0, 3.0).Shape(),
    lambda: BRepPrimAPI_MakeSphere(1.5).Shape(),
    lambda: BRepPrimAPI_MakeTorus(3.0, 1.0).Shape(),
])
def test_exact_pcurves_are_left_alone(make):
    shape = make()
    before = _volume(shape)
    assert mend_pcurves(shape) == (0, 0)
    assert _volume(shape) == before
    for face in faces_of(shape):
        ex = TopExp_Explorer(face, TopAbs_EDGE)
        while ex.More():
            assert pcurve_deviation(TopoDS.Edge(ex.Current()), face) < 1e-6
            ex.Next()


def test_a_wild_bspline_pcurve_on_a_plane_is_projected_again():
    # UnifySameDomain joined merged edges' pcurves on a plane into one B-spline of degree 11
    # whose poles ran out to 1e12 (a coarse noisy countersunk plate's solid: volume 3e24).
    # Pcurves on planes were not checked; a B-spline one is now (lines and circles are exact).
    solid = BRepPrimAPI_MakeCylinder(1.0, 2.0).Shape()
    cap = next(f for f in faces_of(solid) if abs(face_area(f) - math.pi) < 1e-9
               and _volume_z(f) < 1e-9)
    ex = TopExp_Explorer(cap, TopAbs_EDGE)
    edge = TopoDS.Edge(ex.Current())
    a, b = BRep_Tool.Range_s(edge, cap)
    old = BRep_Tool.CurveOnSurface_s(edge, cap, 0.0, 0.0)
    T = np.linspace(a, b, 200)
    UV = np.array([[old.Value(float(t)).X(), old.Value(float(t)).Y()] for t in T])
    spike = 1.0 + 3.0 * np.exp(-(((T - 0.5 * (a + b)) / 0.2) ** 2))  # out to 4 radii
    tol = BRep_Tool.Tolerance_s(edge)
    BRep_Builder().UpdateEdge(edge, pcurve_through(UV * spike[:, None], T), cap, tol)
    assert pcurve_deviation(edge, cap) > 2.9
    assert not abs(_volume(solid) - 2 * math.pi) < 0.1

    assert mend_pcurves(solid) == (1, 0)
    assert pcurve_deviation(edge, cap, 1000) <= max(tol, 1e-6)
    assert face_area(cap) == pytest.approx(math.pi, rel=1e-6)
    assert _volume(solid) == pytest.approx(2 * math.pi, rel=1e-6)
    assert shape_valid(solid)
    assert mend_pcurves(solid) == (0, 0)


def _volume_z(face) -> float:
    """Height of a planar face's centre of mass."""
    props = GProp_GProps()
    BRepGProp.SurfaceProperties_s(face, props)
    return props.CentreOfMass().Z()
