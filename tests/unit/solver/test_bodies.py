"""Per-body energies, momenta and the tied-interface force (fepen.solver.diagnostics: bodies,
tied_interface_force, the plastic work's split) on a two-material Taylor rod: a Johnson–Cook copper front
(material 0, heating: the shell's kind) tied through shared nodes to a bilinear rear (material 1: the
charge's kind), struck on a rigid wall so that both halves yield."""

import math

import numpy as np
import pytest
from mpi4py import MPI

from fepen import dolfinx_api as dx
from fepen import scene
from fepen.laws import materials as M
from fepen.runs import setup
from fepen.solver import diagnostics, explicit, kernels
from fepen.solver import rigid_wall as rigidwall

D, L, V0 = 0.00762, 0.0254, 146.0
COPPER = dict(E=124e9, nu=0.34, density=8960.0)


def two_part_rod():
    """The rod, its cells ahead of mid-length material 0 (Johnson–Cook copper, heating), those
    behind material 1 (bilinear, 60 MPa, 300 MPa tangent), its solver on the rigid wall, struck at V0."""
    sc = scene.load(None, ["projectile.nose=flat", "projectile.cavity_diameter=0", "target.kind=rigid-wall",
                           f"projectile.diameter={D}", f"projectile.length={L}", "mesh.size=0.0015"])
    pm = setup.mesh(sc, MPI.COMM_SELF)
    msh = pm.mesh
    n_cells = msh.topology.index_map(3).size_local
    corners = msh.geometry.x[dx.geometry_dofs(msh)[:n_cells]]
    cells = (corners[:, :, 1].mean(axis=1) > 0.5 * L).astype(np.int64)  # nose tip at y = 0, axis +y
    front = M.johnson_cook(COPPER["E"], COPPER["nu"], COPPER["density"], 90e6, 292e6, 0.31, 0.025, 1.09, 1356.0,
                           294.0, specific_heat=383.0)
    rear = M.bilinear(COPPER["E"], COPPER["nu"], COPPER["density"], 60e6, 3e8)
    s = explicit.ExplicitSolver(msh, [front, rear], cells, 0.8)
    s.external = rigidwall.RigidWall(s)
    s.set_initial(velocity=lambda X: np.tile([0.0, -V0, 0.0], (len(X), 1)))
    return s


def run_with_rows(s, end: float):
    """Step to ``end``; at every step (t, the rear body's (material 1's) momentum (world), the tie's force on
    it)."""
    rows = []

    def row():
        e = diagnostics.energies(s)
        b = diagnostics.bodies(s, e)
        rows.append([s.t, *b.momentum[1], *diagnostics.tied_interface_force(s, 1)[:2]])

    row()
    while s.t < end:
        s.step()
        row()
    return np.array(rows)


@pytest.fixture(scope="module")
def heated():
    s = two_part_rod()
    return s, run_with_rows(s, 30e-6)


def test_bodies_add_up_to_the_whole_rod(heated):
    """The bodies' kinetic energies, momenta, elastic energies and plastic work sum to the whole rod's (to
    round-off), each body's elastic energy is the kernels' formula restricted to its cells, and both halves
    carry a share of the kinetic energy and momentum in proportion to their masses at the start (uniform v)."""
    s, _ = heated
    e = diagnostics.energies(s)
    b = diagnostics.bodies(s, e)
    n = s.n_owned
    v = s.velocity_at_step()
    p = np.sum(s.mass[:n, None] * v[:n], axis=0)
    assert np.sum(b.kinetic) == pytest.approx(e.kinetic, rel=1e-13)
    assert np.sum(b.momentum, axis=0) == pytest.approx(p[:2], rel=1e-12, abs=1e-12 * np.abs(p).max())
    assert np.sum(b.internal) == pytest.approx(e.elastic + e.plastic, rel=1e-13)
    # the whole elastic energy by the kernels the solver's energies used before the split
    G = np.array([m.shear_modulus for m in s.materials])[s.mat]
    J = np.empty(s.n_cells)
    kernels.cell_jacobians(s.positions(), s.dofs, s.orient, s.vol0, s.mat, J)
    whole = (kernels.volumetric_energy(s.node.vol, s.node.vol0, s.cell.bulk, n)
             + kernels.deviatoric_energy(s.s, J, s.vol0, G))
    assert e.elastic == pytest.approx(whole, rel=1e-12)
    assert e.plastic > 0.3 * e.initial_kinetic and min(e.plastic_by_body) > 0.01 * e.plastic  # both halves yield


def test_the_split_of_plastic_work_agrees_with_the_bilinear_closed_form(heated):
    """The heating front's plastic work is heat / β, the rear's the rest; the rear's closed form
    ∫ σ_y dε_p over its reference volume (computed from its cells' ε_p, independently of the running sums)
    agrees with that rest within 0.1 % (the solver's sum is over the current volume, which changes by far less
    in the bilinear rear's yielding)."""
    s, _ = heated
    e = diagnostics.energies(s)
    beta = s.materials[0].params[M.BETA]
    assert e.plastic_by_body[0] == pytest.approx(e.heat / beta, rel=1e-12)
    closed = diagnostics._bilinear_plastic(s)[1]
    assert e.plastic_by_body[1] == pytest.approx(closed, rel=1e-3)


def test_without_heating_the_split_uses_the_closed_form():
    """effects.thermal off: no heat to tell the front's share; the bilinear rear's is its closed form, the
    front takes the rest; elastic materials do none (a pure function of the sums)."""
    jc = M.johnson_cook(1e11, 0.3, 8000.0, 1e8, 1e8, 0.3, 0.0, 1.0, 1800.0, 294.0, thermal=False)
    jc_hot = M.johnson_cook(1e11, 0.3, 8000.0, 1e8, 1e8, 0.3, 0.0, 1.0, 1800.0, 294.0, taylor_quinney=0.9)
    bl = M.bilinear(1e10, 0.3, 1850.0, 45e6, 6e8)
    el = M.elastic(1e11, 0.3, 8000.0)
    assert diagnostics._plastic_by_material([jc, bl], 10.0, 0.0, [0.0, 3.0]) == [7.0, 3.0]
    assert diagnostics._plastic_by_material([jc_hot, bl], 10.0, 8.1, [0.0, 3.0]) == pytest.approx([9.0, 1.0])
    assert diagnostics._plastic_by_material([el, bl], 10.0, 0.0, [0.0, 3.0]) == [0.0, 10.0]
    assert diagnostics._plastic_by_material([jc], 10.0, 9.0, [0.0]) == [10.0]


def test_the_tie_force_is_the_rate_of_the_rear_body_momentum(heated):
    """Only the front touches the wall: the rear's momentum changes by the impulse of the force across the
    tie alone. Central differences make v^{n+1} − v^n = Δt_n (a^n + a^{n+1}) / 2 at every node, so with a row
    at every step the trapezoid sum of the force is the momentum change to round-off (1e-9 of the change);
    the tie decelerates the rear (the force along +y, its −y momentum falls by more than a tenth)."""
    s, rows = heated
    t, p, f = rows[:, 0], rows[:, 1:3], rows[:, 3:5]
    impulse = np.concatenate([np.zeros((1, 2)), np.cumsum(0.5 * np.diff(t)[:, None] * (f[1:] + f[:-1]), axis=0)])
    change = p - p[0]
    assert np.max(np.abs(impulse - change)) < 1e-9 * np.abs(change).max()
    m_rear = s.node.body_mass[1]
    assert change[-1, 1] > 0.1 * m_rear * V0 and np.mean(f[:, 1]) > 0.0
    assert math.isclose(float(p[0, 1]), -m_rear * V0, rel_tol=1e-12)
