"""The charged projectile, tied variant: shell and charge as two materials of one mesh, bonded through
their shared interface nodes; the bodies' mass-averaged accelerations in history.csv. (The frictional
interface: tests/test_interface.py.)"""

import numpy as np
import pytest
from mpi4py import MPI

from fepen import scene
from fepen.runs.deformable import DeformableRun

#: one pytest-xdist worker runs this module (make test: -n 2 --dist loadgroup), so that its module-scoped
#: runs are made once, not once per worker
pytestmark = pytest.mark.xdist_group("test_charge")

TIED = ["effects.charge=true", "charge.contact=tied", "mesh.size=0.004", "impact.velocity=800",
        "impact.obliquity_deg=0", "impact.attack_deg=0", "run.fields=false", "run.checkpoint_interval=0"]


def charged_run(comm, end="1.5e-4"):
    import tempfile

    out = comm.bcast(tempfile.mkdtemp(prefix="fepen-charge-") if comm.rank == 0 else None, root=0)
    sim = DeformableRun(scene.load(None, [*TIED, f"run.end_time={end}"]), out, comm)
    summary = sim.run()
    return summary, np.array(sim.rows), sim


@pytest.fixture(scope="module")
def tied_150us():
    """The serial tied run to 150 us, made once for the tests that read it (each reads, none changes it)."""
    return charged_run(MPI.COMM_SELF)


def test_tied_charge_accelerations_balance_the_target_force(tied_150us):
    """shell_acc_g and charge_acc_g: mass-weighted, they give the whole projectile's deceleration by the
    target (momentum balance, to round-off) at every recorded time; both bodies decelerate, and the charge,
    softer and lighter, oscillates about the shell's deceleration."""
    summary, rows, sim = tied_150us
    m_shell, m_charge = sim.solver.body_mass
    assert m_shell + m_charge == pytest.approx(0.367, abs=1e-3)  # the paper's 367 g, charge included
    assert 0.01 < m_charge < 0.05
    cols = sim.columns
    decel = rows[:, cols.index("decel_g")]
    a_s, a_c = rows[:, cols.index("shell_acc_g")], rows[:, cols.index("charge_acc_g")]
    mixed = (m_shell * a_s + m_charge * a_c) / (m_shell + m_charge)
    assert np.max(np.abs(mixed + decel)) < 1e-6 * np.abs(decel).max()
    late = rows[:, 0] > 5e-5
    assert np.all(a_s[late] < 0) and np.all(a_c[late] < 0)
    assert np.std(a_c[late]) > np.std(a_s[late])
    assert summary["energy_error"] < 1e-3
    header = (sim.out / "history.csv").read_text().splitlines()[0].split(",")
    assert header[-2:] == ["shell_acc_g", "charge_acc_g"]


@pytest.mark.mpi
def test_tied_charge_is_the_same_on_any_rank_count():
    _, world, _ = charged_run(MPI.COMM_WORLD, "6e-5")
    _, alone, _ = charged_run(MPI.COMM_SELF, "6e-5")
    assert world.shape == alone.shape
    cols = [1, 2, 5, -2, -1]
    assert np.max(np.abs(world[:, cols] - alone[:, cols])) <= 1e-10 * np.abs(alone[:, cols]).max()


def test_lowpass_keeps_the_pulse_and_removes_the_ringing():
    """The documented filter (zero-phase Butterworth, 10 kHz): a smooth 1 ms deceleration pulse (sin^2) with
    50 kHz ringing of a third of its height comes out as the pulse within 1 % of its peak, its peak at the
    same time (zero phase), the ringing attenuated below 1 % (away from the record's ends)."""
    from fepen.post.signals import lowpass

    t = np.arange(0.0, 2e-3, 1e-6)
    pulse = np.where(t < 1e-3, np.sin(np.pi * t / 1e-3) ** 2, 0.0) * 6e4
    ring = 2e4 * np.sin(2 * np.pi * 5e4 * t)
    out = lowpass(t, pulse + ring, 1e4)
    inner = (t > 2e-4) & (t < 1.8e-3)
    assert np.max(np.abs(out - pulse)[inner]) < 0.01 * 6e4
    assert abs(t[np.argmax(out)] - 5e-4) < 5e-6
    assert np.max(np.abs(lowpass(t, ring, 1e4))[inner]) < 0.01 * 2e4


def test_charge_section_stresses_follow_the_inertia_of_the_fill(tied_150us):
    """charge_sections.csv: while the projectile decelerates, the charge is pushed against the front of the
    cavity: along the axis its mean axial stress is compressive and falls in magnitude from front to rear,
    and at the front it stays below the inertia of a free charge column, rho_c |a_c| L_charge (the tied
    walls carry part of it in shear), and above a tenth of it."""
    summary, rows, sim = tied_150us
    d = np.genfromtxt(sim.out / "charge_sections.csv", delimiter=",", names=True)
    late = d["t_s"] > 5e-5
    axial = np.array([d[f"axis{k}_axial_Pa"][late].mean() for k in range(5)])
    assert np.all(axial < 0) and np.all(np.diff(np.abs(axial)) < 0)
    a_c = abs(rows[rows[:, 0] > 5e-5, sim.columns.index("charge_acc_g")].mean()) * 9.80665
    column = 1850.0 * a_c * sim.pm.shape.cavity_length
    assert 0.1 * column < abs(axial[0]) < column
    assert len(d.dtype.names) == 1 + 2 * (3 * 4 + 5)
