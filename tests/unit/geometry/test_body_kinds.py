"""The two body kinds, the exact solid of revolution (Shape) and the CAD body (CadBody), each give their own answer
through one method or one function registered per kind (issue 60, item 5): no caller asks which kind it holds."""

import numpy as np
import pytest

from fepen.geometry import gmsh_model, mesh_cache, revolution
from fepen.geometry.cad import CadBody
from fepen.geometry.shape import Shape

SHAPE = Shape(0.0236, 0.144, "ogive", cavity_diameter=0.012, cavity_length=0.06)
CAD = CadBody(0.0236, 0.144, "/x/body.step", 0.001, "abc")


def test_the_exact_volume_and_mass_are_the_shape_s_and_unknown_for_a_cad_body():
    assert SHAPE.exact_volume(False) == SHAPE.shell_volume() and SHAPE.exact_volume(True) == SHAPE.outer_volume()
    assert SHAPE.exact_mass(7850.0) == SHAPE.mass(7850.0)
    assert SHAPE.exact_mass(7850.0, 1700.0) == SHAPE.mass(7850.0, 1700.0)
    assert CAD.exact_volume(False) is None and CAD.exact_volume(True) is None
    assert CAD.exact_mass(7850.0, 1700.0) is None
    assert CAD.cavity_length == 0.0 and SHAPE.cavity_length == 0.06


def test_only_a_cad_body_is_meshed_for_a_rigid_run():
    assert not SHAPE.needs_volume_mesh("rigid")
    assert SHAPE.needs_volume_mesh("plastic") and SHAPE.needs_volume_mesh("elastic")
    assert all(CAD.needs_volume_mesh(f) for f in ("rigid", "elastic", "plastic"))


def test_the_nose_zone_of_each_kind():
    y_c, r_c = revolution.nose_zone(SHAPE, np.zeros((0, 3)), np.zeros(0))
    assert y_c == SHAPE.nose_length and r_c == pytest.approx(SHAPE.radius)
    # a CAD body's from its surface points: the foremost point within 1e-3 of the largest radius
    X = np.array([[0.0, 0.0, 0.0], [0.005, 0.01, 0.0], [0.0118, 0.03, 0.0], [0.0, 0.05, 0.0118]])
    radius = np.hypot(X[:, 0], X[:, 2])
    assert revolution.nose_zone(CAD, X, radius) == (0.03, 0.0118)


def test_a_probe_point_is_inside_the_exact_outline_or_a_cad_body_s_cylinder():
    from fepen.runs import probes

    near_tip = (0.011, 0.001, 0.0)  # inside the calibre's cylinder, outside the ogive's nose
    assert "past the outside's radius" in probes.outside_radially(SHAPE, near_tip[1], near_tip[0], False, 1e-9)
    assert probes.outside_radially(CAD, near_tip[1], near_tip[0], False, 1e-9) is None
    assert "past the body's" in probes.outside_radially(CAD, 0.05, 0.012, False, 1e-9)
    z0, z1, rc = SHAPE.cavity_sections()[-1]
    assert "in the cavity" in probes.outside_radially(SHAPE, 0.5 * (z0 + z1), 0.5 * rc, False, 1e-9)
    assert probes.outside_radially(SHAPE, 0.5 * (z0 + z1), 0.5 * rc, True, 1e-9) is None


@pytest.mark.parametrize("registry", ["gmsh model", "cache record", "cached extent", "load points", "rigid body",
                                      "nose zone", "probe outline"])
def test_every_per_kind_behaviour_is_registered_for_both_kinds(registry):
    """A behaviour registered per kind (functools.singledispatch) has an entry for each kind and refuses any
    other type rather than guessing."""
    from fepen.runs import probes, rigid
    from fepen.solver import surface

    fn = {"gmsh model": gmsh_model._build, "cache record": mesh_cache.record,
          "cached extent": mesh_cache._verify_extent, "load points": surface.facet_points,
          "rigid body": rigid.body_points, "nose zone": revolution.nose_zone,
          "probe outline": probes.outside_radially}[registry]
    assert {Shape, CadBody} <= set(fn.registry)
    assert fn.registry[Shape] is not fn.registry[CadBody]
    with pytest.raises(TypeError):
        fn(object(), *([None] * (fn.registry[Shape].__code__.co_argcount - 1)))

