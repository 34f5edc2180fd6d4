"""What a shot will cost, known before work starts (fepen.runs.budget, issue 43 item 5): a mesh too coarse for
the body, past mesh.max_cells or past the machine's memory is refused in one line naming mesh.size; a
deformable shot at any allowed mesh.size stays under 4 GB before its first step or is refused; the rigid step
is bounded below at low speed (a shot at 1 m/s in a thousand steps, not 185,000) and unchanged above it; a
run.rigid_step past fifty times the shot's own steps is refused."""

import math

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from fepen import scene
from fepen.errors import InputError
from fepen.runs import budget, setup
from fepen.scene import SCHEMA

DEFAULT = scene.load(None, ["effects.fidelity=rigid"])
BUILT = setup.projectile(DEFAULT)


def test_a_mesh_coarser_than_half_the_calibre_is_refused_naming_mesh_size():
    shape = BUILT.shape
    budget.check_mesh(shape, 0.5 * shape.diameter, None, False, 1e6, 1)  # the coarsest allowed
    for size in (0.012, 0.02, 0.05):  # once an internal gmsh error, or a key the user never set
        with pytest.raises(InputError) as err:
            budget.check_mesh(shape, size, None, False, 1e6, 1)
        assert err.value.key == "mesh.size" and "half the calibre" in err.value.message


def test_a_mesh_past_max_cells_is_refused_with_the_size_that_fits():
    with pytest.raises(InputError) as err:
        budget.check_mesh(BUILT.shape, 2e-4, None, False, 1e6, 1)  # once 7.8 GB in gmsh, silently
    assert err.value.key == "mesh.size" and "mesh.max_cells" in err.value.message
    fits = float(err.value.message.split("mesh.size >= ")[1].split(" m")[0])
    assert budget.expected_cells(BUILT.shape, fits * 1.01, None, False) <= 1e6 < budget.expected_cells(
        BUILT.shape, fits * 0.95, None, False)


def test_a_mesh_past_the_machines_memory_is_refused_whatever_max_cells(monkeypatch):
    monkeypatch.setattr(budget, "available_bytes", lambda: 2.0e9)
    with pytest.raises(InputError) as err:
        budget.check_mesh(BUILT.shape, 8e-4, None, False, 1e9, 2)
    assert err.value.key == "mesh.size" and "2.0 GB available" in err.value.message
    assert budget.check_mesh(BUILT.shape, 2.5e-3, None, False, 1e9, 2)["bytes"] < 2.0e9


def test_a_finer_nose_adds_cells_and_its_absence_adds_none():
    plain = budget.expected_cells(BUILT.shape, 2.5e-3, None, False)
    assert budget.expected_cells(BUILT.shape, 2.5e-3, 2.5e-3, False) == plain
    assert budget.expected_cells(BUILT.shape, 2.5e-3, 5e-4, False) >= 22030  # measured: 22,030 cells


SIZE = SCHEMA["mesh.size"]


@settings(max_examples=60, deadline=None)
@given(size=st.floats(SIZE.lo, SIZE.hi), nose=st.none() | st.floats(SCHEMA["mesh.nose_size"].lo,
                                                                     SCHEMA["mesh.nose_size"].hi),
       charge=st.booleans())
def test_every_allowed_mesh_size_is_refused_or_under_4_gb_before_the_first_step(size, nose, charge):
    """With the default mesh.max_cells, on one or two processes: refused (InputError naming mesh.size) or
    expected under 4 GB before the first time step (the estimate is checked against a measured run in
    tests/system/test_data_safety.py)."""
    for processes in (1, 2):
        try:
            cost = budget.check_mesh(BUILT.shape, size, nose, charge, SCHEMA["mesh.max_cells"].default, processes)
        except InputError as err:
            assert err.key == "mesh.size"
            continue
        assert cost["bytes"] < 4.0e9


def old_step(mass, v0, diameter, law):
    """The step of every fepen before this rule."""
    t_stop = mass * v0 / (law.sigma_s * math.pi * 0.25 * diameter ** 2)
    return min(budget.STEP_FRACTION * diameter / v0, t_stop / budget.STOP_STEPS)


@pytest.mark.parametrize("v0", [200.0, 584.3, 1000.0, 3000.0])
def test_the_rigid_step_is_unchanged_above_the_crater_speed(v0):
    law = setup.target_law(DEFAULT)
    assert budget.default_step(0.367, v0, 0.0236, law) == pytest.approx(old_step(0.367, v0, 0.0236, law), rel=1e-15)


@pytest.mark.parametrize("v0", [0.1, 1.0, 10.0])
def test_the_rigid_step_is_bounded_below_at_vanishing_speed(v0):
    """At 1 m/s the old step was 18 ns (185,000 steps, 88 s); the crater's time scale bounds it now."""
    law = setup.target_law(DEFAULT)
    t_stop, t_crater = budget.time_scales(0.367, v0, 0.0236, law)
    assert t_crater > t_stop
    step = budget.default_step(0.367, v0, 0.0236, law)
    assert step == pytest.approx(t_crater / budget.STOP_STEPS) and step > 10 * old_step(0.367, v0, 0.0236, law)


def test_a_rigid_step_fifty_times_finer_than_the_shots_own_is_refused():
    law = setup.target_law(DEFAULT)
    own = budget.default_step(0.367, 584.3, 0.0236, law)
    budget.check_rigid_step(own / 40, BUILT.shape, BUILT.shell_density, 584.3, law)
    with pytest.raises(InputError) as err:
        budget.check_rigid_step(1e-12, BUILT.shape, BUILT.shell_density, 584.3, law)
    assert err.value.key == "run.rigid_step" and "at least" in err.value.message


def test_a_rigid_end_time_past_the_step_budget_is_refused():
    """A rigid run with run.end_time goes on to that time: 1 s of the default shot was 164,500 steps (50 s here,
    150 s on CI) of a body that had stopped and drifted back. The budget counts the steps the run will take."""
    law = setup.target_law(DEFAULT)
    mass = BUILT.shell_density * budget.meshed_volume(BUILT.shape, False)
    own = budget.default_step(mass, 584.3, BUILT.shape.diameter, law)
    limit = budget.MAX_RIGID_STEPS * own
    budget.check_rigid_step(None, BUILT.shape, BUILT.shell_density, 584.3, law, 0.99 * limit)
    with pytest.raises(InputError) as err:
        budget.check_rigid_step(None, BUILT.shape, BUILT.shell_density, 584.3, law, 1.01 * limit)
    assert err.value.key == "run.end_time" and f"{limit:.3g} s" in err.value.message
    # a coarser step of the user's own buys a longer end time in proportion
    budget.check_rigid_step(2 * own, BUILT.shape, BUILT.shell_density, 584.3, law, 1.9 * limit)
