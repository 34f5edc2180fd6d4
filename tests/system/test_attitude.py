"""The attitude and the third dimension in history.csv (issue 46, acceptance 1), both fidelities, checked by
the angular-momentum balance: the angular momentum about the impact point O, H + x_c × M v_c (H about the
centre of mass, the history's angular_momentum_*; x_c its centre_*; v_c its velocity), grows by exactly the
target's angular impulse about O, which the run integrates every step (angular_impulse_*), to round-off.

The balance is checked in its integral form: a row's moment (moment_*) is the target's at that instant, and
the load changes every step as points enter and leave it, so rows sampled every microsecond alias its rate;
the integral over every step does not. The final axis angle of summary.json is the history's last axis angle."""

import json

import numpy as np
import pytest
from mpi4py import MPI

from fepen import scene
from fepen.io import results
from fepen.runs.deformable import DeformableRun
from fepen.runs.rigid import RigidRun


def accelerometer_check(out, fidelity):
    """The filtered axial accelerometer at the centre of mass's station against the body-average deceleration
    (accelerations.csv, rigid: history.csv's decel_g filtered alike): their filtered peaks within 2 %; the
    raw channel carries the ringing a deformable body's node feels, the filter removes it."""
    from fepen.post import signals

    p = np.genfromtxt(out / "probes.csv", delimiter=",", names=True)
    h = results.read(out).history()
    decel = signals.lowpass(h["t_s"], h["decel_g"], 1.0e4)
    k = int(np.argmax(np.abs(decel)))
    assert decel[k] > 1.0e4  # tens of thousands of g: C3's nose entering
    for name, tol in (("cg", 0.02), ("tail", 0.02)):
        axial = -p[f"{name}_axial_g"]  # along the axis, negative while slowing: turned
        j = int(np.argmax(np.abs(axial)))
        assert axial[j] == pytest.approx(decel[k], rel=tol), (name, axial[j], decel[k])
        # measured (plastic, 5 mm): cg +0.48 %, tail +0.25 %; rigid: the centre's exactly, the tail's 1e-3 off
    if fidelity == "rigid":  # out of the plane of turning, the rigid body's axial channel is the deceleration
        # (history.csv's digits)
        np.testing.assert_allclose(-p["cg_axial_g_raw"], h["decel_g"], rtol=1e-5, atol=1e-5 * abs(decel[k]))
    else:  # a node rings: its raw peak is far above the filtered one
        assert np.abs(p["cg_axial_g_raw"]).max() > 1.5 * decel[k]


def balance(out):
    """max over rows of |H_O(t) − H_O(0) − angular impulse(t)| per component, the impulse's peak, the history."""
    h = results.read(out).history()
    m = json.loads((out / "summary.json").read_text())["mass_kg"]
    xc = np.stack([h["centre_x_mm"], -h["centre_y_mm"], h["centre_z_mm"]], 1) * 1e-3  # the scene's frame
    v = np.stack([h["vx_m_s"], -h["vy_m_s"], h["vz_m_s"]], 1)
    H = np.stack([h[f"angular_momentum_{c}_N_m_s"] for c in "xyz"], 1)
    A = np.stack([h[f"angular_impulse_{c}_N_m_s"] for c in "xyz"], 1)
    H_O = H + np.cross(xc, m * v)
    return np.abs(H_O - H_O[0] - A).max(axis=0), np.abs(A).max(axis=0), h


#: accelerometers at the centre of mass's station (78.7 mm behind C3's tip; the cavity holds the axis there, so
#: in the wall): out of the plane of fire, where the turning (about z) adds nothing along the axis, and in it,
#: where it does (α × r along the axis), and at the tail
ACCELEROMETERS = """
[[output.probes]]
name = "cg"
point = [0.0, 0.0787, 0.0095]
kind = "accelerometer"
[[output.probes]]
name = "side"
point = [0.0095, 0.0787, 0.0]
kind = "accelerometer"
[[output.probes]]
name = "tail"
point = [0.0, 0.14, 0.0]
kind = "accelerometer"
"""


@pytest.mark.parametrize("fidelity", ["rigid", "plastic"])
def test_the_angular_momentum_about_O_grows_by_the_targets_angular_impulse(tmp_path, fidelity):
    sets = ["effects.fidelity=rigid"] if fidelity == "rigid" else [
        "mesh.size=0.005", "run.fields=false", "run.end_time=4e-4", "run.checkpoint_interval=0"]
    run = RigidRun if fidelity == "rigid" else DeformableRun
    (tmp_path / "probes.toml").write_text(ACCELEROMETERS)
    out = tmp_path / "out"
    summary = run(scene.load(str(tmp_path / "probes.toml"), sets), out, MPI.COMM_SELF).run()
    accelerometer_check(out, fidelity)
    err, peak, h = balance(out)
    if fidelity == "rigid":  # the rate form, filtered: the row's moment is the rate of the angular momentum
        from fepen.post import signals

        t, L, M = h["t_s"], h["angular_momentum_z_N_m_s"], h["moment_z_N_m"]
        rate = signals.lowpass(t, np.gradient(L, t), 5e3)
        # measured: 0.24 % of the moment's peak at 5 kHz (1.2 % at 10 kHz; 21 % unfiltered: the load changes
        # within a step as points enter, and a row samples it at one instant), away from the filter's ends by
        # two of its periods (the body still rocks in the elastic tunnel when the run ends at 5 m/s)
        inner = (t > t[0] + 2 / 5e3) & (t < t[-1] - 2 / 5e3)
        assert np.abs(rate - signals.lowpass(t, M, 5e3))[inner].max() < 0.01 * np.abs(M).max()
    # C3 turns in its plane: the turning component, z, carries the impulse (0.1 N m s rigid to its stop)
    assert peak[2] > 0.01
    if fidelity == "plastic":
        assert np.all(err < 1e-5 * peak[2]), (err, peak)  # measured: 2e-7
    else:  # the body's moment about O is exact in the rates, x_c × M v after an RK4 step only to its truncation:
        # 1.1e-4 of the peak at the default step (6.0 us), all of it in the last 20 us, where the stopping body
        # rocks on the wall's spring (a period of 74 us); 3.3e-7 at half the step. Its results do not move (the
        # final axis 11.00 against 11.02 deg at 2 us)
        assert np.all(err < 5e-4 * peak[2]), (err, peak)
        half = RigidRun(scene.load(str(tmp_path / "probes.toml"), [*sets, "run.rigid_step=3e-6"]), tmp_path / "half",
                        MPI.COMM_SELF)
        half.run()
        err2 = balance(tmp_path / "half")[0]
        assert np.all(err2 < 1e-5 * peak[2]), (err2, peak)
        assert json.loads((tmp_path / "half" / "summary.json").read_text())["final_axis_angle_deg"] == \
            pytest.approx(summary["final_axis_angle_deg"], abs=0.1)
    # the angular velocity turns the body the way its axis turns: with y out of the target and z = x × y, the
    # axis (sin θ, −cos θ, 0) turns toward +x (θ grows) under ω_z = dθ/dt > 0
    assert h["axis_angle_deg"][-1] == pytest.approx(summary["final_axis_angle_deg"], abs=1e-6)
    assert np.all(h["yaw_deg"] >= 0.0) and np.all(h["yaw_deg"] <= 180.0)
    # the in-plane turn is the integral of ω_z (trapezoids over the rows; the axis stays in the plane)
    from scipy.integrate import cumulative_trapezoid

    turned = np.degrees(cumulative_trapezoid(h["angular_velocity_z_rad_s"], h["t_s"], initial=0.0))
    theta = h["axis_angle_deg"] - h["axis_angle_deg"][0]
    assert np.abs(theta - turned).max() < 0.02 * np.abs(theta).max() + 0.05, np.abs(theta - turned).max()
    assert np.abs(theta).max() > 0.1  # it turned (C3: 0.45 deg rigid, 0.56 plastic, the tunnel holding it)
