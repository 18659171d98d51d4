"""Tangent pipe joints get their border (``surfaces.joints.tangent_joints``)."""
import igl
import numpy as np
import pytest
from meshes import pipe_bend, revolved

from igl_heatseg.surfaces.joints import tangent_joints
from igl_heatseg.surfaces.model import Surface
from igl_heatseg.surfaces.refine import refine_segmentation


@pytest.mark.parametrize("seed", [0, 1])
@pytest.mark.parametrize("start", [-3.0, 3.0])
def test_a_pipe_bend_segmented_off_its_joint_gets_the_border_at_the_joint(seed, start):
    # before the joint rule the cut and the moves left 300-365 of 6,624 faces (4.6-5.5 %) on
    # the wrong side of the joint, up to a tube radius off it
    V, F, S = pipe_bend(0.05, seed)
    r = refine_segmentation(V, F, (S > start).astype(np.int64), exact=False)
    kinds = np.array([s.kind for s in r.surfaces])[r.labels]
    wrong = ((kinds == "cylinder") & (S > 0)) | ((kinds == "torus") & (S < 0))
    assert wrong.sum() <= 0.005 * len(F)


def _capsule(dome_radius):
    # a cylinder of radius 3 (z from -10 to 0) closed by a spherical dome centred on its axis
    # at height h so that it meets the cylinder's rim: tangent when dome_radius == 3
    h = -np.sqrt(max(dome_radius**2 - 9.0, 0.0))
    top = np.arcsin(3.0 / dome_radius)
    prof = [(3.0, z) for z in np.linspace(-10, 0, 26)]
    prof += [(dome_radius * np.sin(a), h + dome_radius * np.cos(a))
             for a in np.linspace(top, 0.05, 20)[1:]]
    V, F, row = revolved(prof, n=48)
    z = V[F].mean(axis=1)[:, 2]
    cyl = Surface("cylinder", {"point": np.zeros(3), "axis": np.array([0.0, 0, 1]),
                               "radius": 3.0})
    sph = Surface("sphere", {"center": np.array([0.0, 0, h]), "radius": dome_radius})
    return V, F, z, {0: cyl, 1: sph}


def test_a_hemispherical_end_gets_its_border_at_the_rim():
    V, F, z, fits = _capsule(3.0)
    labels = (z > -1.5).astype(np.int64)  # the border 1.5 below the rim
    TT = igl.triangle_triangle_adjacency(F)[0]
    assert tangent_joints(V, F, labels, fits, TT, 0.01) > 0
    assert (labels == (z > 0)).all()


def test_a_dome_meeting_its_cylinder_at_a_crease_is_left_to_the_moves():
    # radius 3.12 on a cylinder of radius 3: they meet at an angle of 16 degrees, not
    # tangentially; the plane through the sphere's centre is no border
    V, F, z, fits = _capsule(3.12)
    labels = (z > -1.5).astype(np.int64)
    before = labels.copy()
    TT = igl.triangle_triangle_adjacency(F)[0]
    assert tangent_joints(V, F, labels, fits, TT, 0.01) == 0
    assert (labels == before).all()


def test_a_joint_fitted_a_fraction_of_an_edge_off_keeps_the_mesh_loop_on_it():
    # the sphere's fitted centre 0.1 above the rim, where the dome's first ring of triangles
    # (up to the next loop of edges at z = 0.24) has centroids at z = 0.08 and 0.16: cut by
    # centroids, every other triangle of that ring would go to the cylinder (a staircase twice
    # the rim's length); the nearer loop of edges is the rim
    V, F, z, fits = _capsule(3.0)
    fits[1].params["center"] = np.array([0.0, 0, 0.1])
    first = (z > 0) & (z < 0.25)
    assert (z[first] < 0.1).any() and (z[first] > 0.1).any()
    labels = (z > -1.5).astype(np.int64)
    TT = igl.triangle_triangle_adjacency(F)[0]
    tangent_joints(V, F, labels, fits, TT, 0.01)
    assert (labels == (z > 0)).all()
