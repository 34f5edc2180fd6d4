"""The stop rules (fepen.runs.events, events_kernel.c) on plain numbers: one definition for the rigid, the
batched rigid and the deformable runs."""

import numpy as np
import pytest

from fepen.runs import events

AXIS = np.array([0.0, -1.0, 0.0])  # nose down, into the target


def outcome(y_min=-0.01, y_max=0.2, v=(0.0, -10.0, 0.0), m=0.4, ke0=0.5 * 0.4 * 800.0**2, thickness=None,
            until_stopped=True, entered=False):
    return events.penetration(y_min, y_max, np.array(v), AXIS, m, ke0, thickness, until_stopped, entered)[0]


def test_embedded_when_the_centre_stops_advancing_or_its_energy_is_spent():
    assert outcome() is None
    assert outcome(v=(0.0, 1e-3, 0.0)) == "embedded"  # moving back along the axis
    assert outcome(v=(20.0, 0.0, 0.0)) == "embedded"  # sideways only: V·a = 0
    # the end of the path: |V| = END_SPEED, above the energy rule's 800 sqrt(STOP_ENERGY) = 2.5 m/s
    v = events.END_SPEED
    assert 800.0 * np.sqrt(events.STOP_ENERGY) < v
    assert outcome(v=(0.0, -v * (1 - 1e-9), 0.0)) == "embedded"
    assert outcome(v=(0.0, -v * (1 + 1e-6), 0.0)) is None
    # the energy rule where it comes first: a shot at 3000 m/s, ½ M V² = STOP_ENERGY KE0 at 9.5 m/s
    v = 3000.0 * np.sqrt(events.STOP_ENERGY)
    fast = 0.5 * 0.4 * 3000.0**2
    assert outcome(v=(0.0, -v * (1 - 1e-9), 0.0), ke0=fast) == "embedded"
    assert outcome(v=(0.0, -v * (1 + 1e-6), 0.0), ke0=fast) is None
    assert outcome(v=(0.0, 1e-3, 0.0), until_stopped=False) is None  # a run with an end time never embeds


def test_perforation_needs_a_finite_target_and_every_point_beyond_its_rear_face():
    assert outcome(y_min=-1.1, y_max=-1.0) is None
    assert outcome(y_min=-0.3, y_max=-0.2001, thickness=0.2) == "perforated"
    assert outcome(y_min=-0.3, y_max=-0.1999, thickness=0.2) is None


def test_ricochet_needs_every_point_above_the_face_and_the_centre_moving_away():
    assert outcome(y_min=1e-6, v=(0.0, 3.0, 0.0), entered=True) == "ricochet"
    assert outcome(y_min=1e-6, v=(0.0, 3.0, 0.0), entered=False) is None  # never entered: not a ricochet
    assert outcome(y_min=1e-6, v=(0.0, -30.0, 0.0), entered=True) is None


@pytest.mark.parametrize("until_stopped", [True, False])
def test_stop_rules_remember_entry_and_respect_the_end_time(until_stopped):
    r = events.StopRules(thickness=None, until_stopped=until_stopped)
    rest = np.zeros(3)
    assert r.penetration(0.01, 0.2, rest, AXIS, 1.0, 1.0) is None  # not entered yet: never embedded
    assert not r.entered
    assert r.penetration(-0.01, 0.2, rest, AXIS, 1.0, 1.0) == ("embedded" if until_stopped else None)
    assert r.entered
    state = r.state()
    fresh = events.StopRules(thickness=None, until_stopped=until_stopped)
    fresh.restore(state)
    assert fresh == r


def test_rebound_after_leaving_the_wall_for_long_enough():
    r = events.StopRules(thickness=None, until_stopped=True)
    assert r.rebound(0.0, 0) is None  # never touched
    assert r.rebound(1e-6, 5) is None
    assert r.rebound(2e-6, 0) is None  # left at 2 us
    assert r.rebound(2e-6 + 0.99 * events.REBOUND_FREE_S, 0) is None
    assert r.rebound(2e-6 + 1.01 * events.REBOUND_FREE_S, 0) == "rebound"
