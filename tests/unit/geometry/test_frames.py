"""The striking attitude in three dimensions (fepen.geometry.frames, docs/theory.md §7): the axis at the attack
from the velocity in whichever plane, the in-plane case exactly the turn about z it always was, and the rates
turning the nose the way their keys say."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from fepen.geometry import frames

NOSE = np.array([0.0, -1.0, 0.0])  # the reference body's axis, tail to nose


def velocity_direction(alpha):
    return np.array([math.sin(alpha), -math.cos(alpha), 0.0])


@given(alpha=st.floats(0.0, 1.5), attack=st.floats(-1.5, 1.5), plane=st.floats(-math.pi, math.pi))
@settings(max_examples=200, deadline=None)
def test_the_axis_is_at_the_attack_from_the_velocity_in_its_plane(alpha, attack, plane):
    R = frames.striking_rotation(alpha, attack, plane)
    assert R @ R.T == pytest.approx(np.eye(3), abs=1e-12) and np.linalg.det(R) == pytest.approx(1.0, abs=1e-12)
    a, d = R @ NOSE, velocity_direction(alpha)
    assert math.acos(min(1.0, float(a @ d))) == pytest.approx(abs(attack), abs=1e-7)
    # the plane: the axis's move off the velocity lies along cos φ (z × d) + sin φ z
    off = a - (a @ d) * d
    if abs(attack) > 1e-3:
        want = math.cos(plane) * np.cross([0.0, 0.0, 1.0], d) + math.sin(plane) * np.array([0.0, 0.0, 1.0])
        assert off / np.linalg.norm(off) == pytest.approx(math.copysign(1.0, attack) * want, abs=1e-7)


def test_in_the_plane_of_fire_the_turn_is_about_z_by_alpha_plus_attack():
    """φ = 0 is the turn every earlier fepen made, to the last bit (its results do not move)."""
    alpha, attack = math.radians(10.5), math.radians(0.1)
    th = alpha + attack
    old = np.array([[math.cos(th), -math.sin(th), 0.0], [math.sin(th), math.cos(th), 0.0], [0.0, 0.0, 1.0]])
    assert np.array_equal(frames.striking_rotation(alpha, attack, 0.0), old)
    # and the general path agrees with it to round-off
    tiny = frames.striking_rotation(alpha, attack, 1e-300)
    assert tiny == pytest.approx(old, abs=1e-15)


def test_out_of_the_plane_by_90_deg_the_nose_turns_toward_plus_z():
    R = frames.striking_rotation(0.0, math.radians(2.0), math.radians(90.0))
    a = R @ NOSE
    assert a[0] == pytest.approx(0.0, abs=1e-15) and a[2] == pytest.approx(math.sin(math.radians(2.0)), rel=1e-12)


@pytest.mark.parametrize("alpha, attack, plane", [(0.0, 0.0, 0.0), (0.3, 0.05, 1.2), (0.1, -0.2, -2.0)])
def test_the_rates_turn_the_nose_as_their_keys_say(alpha, attack, plane):
    """da/dt = ω × a: the pitch rate moves the nose within the plane of fire (no z), toward +x where the axis
    points down; the yaw rate moves it out of the plane, toward +z, at |ω| (it is normal to the axis)."""
    R = frames.striking_rotation(alpha, attack, plane)
    a = R @ NOSE
    pitch = np.cross(frames.striking_rate(R, 3.0, 0.0), a)
    assert pitch[2] == pytest.approx(0.0, abs=1e-12) and pitch[0] > 0.0
    yaw = np.cross(frames.striking_rate(R, 0.0, 3.0), a)
    assert yaw[2] > 0.0 and np.linalg.norm(yaw) == pytest.approx(3.0, rel=1e-12)
    assert yaw @ a == pytest.approx(0.0, abs=1e-12)
