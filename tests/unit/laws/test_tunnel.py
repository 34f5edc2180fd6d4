"""The tunnel the projectile opens (fepen.laws.tunnel, tunnel_kernel.c) and the load of its wall on the body
behind the nose (docs/theory.md §8.7): where a point is in a straight tunnel, the wall pushing a yawed body back
toward its axis and nothing on a centred one, the wall kept where it was pushed, and the smooth onset."""

import math

import numpy as np
import pytest

from fepen.laws import target as tg
from fepen.laws.tunnel import Tunnel

A0 = 0.0118  # the shoulder's radius (m)
XI_SH = 0.03  # the shoulder's distance behind the tip (m)
LAW = tg.TargetLaw(density=2400.0, Y=40e6, E=32.5e9, T=4e6, lam=0.67, sigma_s=300e6, B=1.0,
                   c_over_a=tg.cavity_ratio(40e6, 32.5e9, 4e6), D=2 * A0, onset_speed=10.0)
DOWN = np.array([0.0, -1.0, 0.0])


def straight_tunnel(depth=0.4):
    """A tunnel dug straight down (-y) by a shoulder that went from the face to `depth`."""
    t = Tunnel(XI_SH, A0)
    none = np.zeros((0, 3))
    for y in np.arange(-1e-4, -depth, -0.25 * A0):
        t.at(np.array([0.0, y, 0.0]), DOWN)
        t.commit = True
        tg.point_forces(LAW, none, none, none, np.zeros(0), np.zeros(0), np.zeros(0), np.zeros(0), DOWN, t,
                        np.zeros(0))
    return t


def shank(tilt_deg, omega, centre_y=-0.2, rings=40, per_ring=48, length=0.12):
    """Points on a cylinder of radius A0 behind the shoulder (no nose), its axis tilted by tilt_deg about z at
    the shoulder (the body's shoulder at (0, centre_y, 0)), the body moving down at 300 m/s and turning at
    omega (rad/s) about z. Returns x, v, n, area, body xi, the shoulder and the axis."""
    th = math.radians(tilt_deg)
    axis = np.array([math.sin(th), -math.cos(th), 0.0])  # tail to nose
    e1 = np.array([math.cos(th), math.sin(th), 0.0])
    e2 = np.array([0.0, 0.0, 1.0])
    sh = np.array([0.0, centre_y, 0.0])
    xi = XI_SH + (np.arange(rings) + 0.5) * length / rings
    phi = (np.arange(per_ring) + 0.5) * 2 * math.pi / per_ring
    XI, PHI = np.meshgrid(xi, phi, indexing="ij")
    n = (np.cos(PHI)[..., None] * e1 + np.sin(PHI)[..., None] * e2).reshape(-1, 3)
    x = sh - (XI - XI_SH).reshape(-1, 1) * axis + A0 * n
    w = np.array([0.0, 0.0, omega])
    v = DOWN * 300.0 + np.cross(w, x - sh)
    area = np.full(len(x), 2 * math.pi * A0 * length / (rings * per_ring))
    return x, v, n, area, XI.ravel(), sh, axis


def forces(t, x, v, n, area, xi, sh, axis):
    t.at(sh, axis)
    k = len(x)
    return tg.point_forces(LAW, x, v, n, area, np.full(k, A0), np.full(k, np.inf), np.zeros(k), axis, t, xi)


def test_a_point_is_located_against_the_wall():
    t = straight_tunnel()
    assert t.count > 50
    st = t.stations()
    assert np.allclose(st["direction"][1:], DOWN, atol=1e-12) and np.all(np.diff(st["s"]) > 0)
    assert np.allclose(st["radius"], A0)
    # a centred, aligned body moving along the tunnel: every shank point on the wall, none pushing it
    f, sums = forces(t, *shank(0.0, 0.0))
    assert sums[3] == 0 and np.abs(f).max() == 0.0


@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_a_yawed_body_turning_into_the_wall_is_pushed_back(sign):
    """Tilted by 2 deg and turning further: the tail presses the wall on one side; the wall's force on the
    body points back toward the tunnel's axis there and its moment about the shoulder opposes the turn."""
    t = straight_tunnel()
    x, v, n, area, xi, sh, axis = shank(sign * 2.0, sign * 30.0)
    f, sums = forces(t, x, v, n, area, xi, sh, axis)
    assert sums[3] > 0
    tail = xi > XI_SH + 0.06
    # tilted about the shoulder, the tail lies toward -x for sign > 0 and turns further that way: the wall
    # pushes it back toward +x, the tunnel's axis
    assert sign * f[tail, 0].sum() > 0.0
    assert np.all(sign * f[:, 0] >= 0.0)  # only that side of the wall is pressed
    moment = np.cross(x - sh, f).sum(axis=0)[2]
    assert sign * moment < 0.0  # against the turn


def test_the_force_vanishes_when_the_body_is_centred():
    t = straight_tunnel()
    turning = forces(t, *shank(0.0, 30.0))[1]  # centred but turning: the wall resists the turn
    assert turning[3] > 0
    still = forces(t, *shank(0.0, 0.0))[1]
    assert still[3] == 0 and np.all(still[:3] == 0.0)


def test_the_wall_stays_where_it_was_pushed():
    """A committed step pushes the wall out to the points it loads; pressed again no further, they carry at
    most the load of an open patch at the wall, and once the body turns back they carry nothing."""
    t = straight_tunnel()
    x, v, n, area, xi, sh, axis = shank(3.0, 30.0)
    before = t.stations()["radius"].max()
    t.commit = True
    f0, s0 = forces(t, x, v, n, area, xi, sh, axis)
    after = t.stations()["radius"]
    assert after.max() > before and s0[3] > 0
    back = forces(t, x, -v + 2 * DOWN * 300.0, n, area, xi, sh, axis)[1]  # turning back
    assert back[3] == 0


def test_the_stress_develops_over_the_onset_speed():
    """sigma_s grows linearly in the outward speed up to target.onset_speed, then is whole."""
    t = straight_tunnel()
    x, v, n, area, xi, sh, axis = shank(0.0, 0.0)  # centred: every shank point at the wall
    k = len(x)
    out = []
    for u in (2.0, 5.0, 20.0, 40.0):  # the body moving sideways into the wall at u (and down at 300 m/s)
        vs = v + np.array([u, 0.0, 0.0])
        t.at(sh, axis)
        f, sig = tg.normal_stress(LAW, x, vs, n, area, np.full(k, A0), np.full(k, np.inf), np.zeros(k), axis, t, xi)
        i = int(np.argmax(sig))
        vn = float(vs[i] @ n[i])
        out.append((sig[i] - LAW.B * LAW.density * vn * vn) / LAW.sigma_s)
    assert out[0] == pytest.approx(0.2, rel=0.05) and out[1] == pytest.approx(0.5, rel=0.05)
    assert out[2] == pytest.approx(1.0, rel=1e-9) and out[3] == pytest.approx(1.0, rel=1e-9)


def test_the_sector_is_atan2s_sector_everywhere_and_at_every_edge():
    """tunnel_locate takes a point's sector from a polynomial angle (error 1e-5 rad) and from libm's atan2 only
    within 1e-4 rad of an edge: the same sector as atan2's alone, on a million random offsets about random axes
    and on offsets 1e-12 to 1e-3 rad either side of every edge (and on the axes the basis switches at)."""
    from fepen import native

    lib = native.kernel("target")
    rng = np.random.default_rng(7)
    S = 16

    def sectors(r, t):
        r, t = np.ascontiguousarray(r, dtype=float), np.ascontiguousarray(t, dtype=float)
        q, qe = np.zeros(len(r), np.int32), np.zeros(len(r), np.int32)
        lib.tunnel_sectors(len(r), r.ctypes.data, t.ctypes.data, S, q.ctypes.data, qe.ctypes.data)
        return q, qe

    t = rng.normal(size=(1_000_000, 3))
    t /= np.linalg.norm(t, axis=1)[:, None]
    q, qe = sectors(rng.normal(size=t.shape) * 10.0 ** rng.uniform(-4, 1, size=(len(t), 1)), t)
    assert np.array_equal(q, qe) and len(set(qe)) == S
    # edges: offsets at angle 2 pi j / S - pi + eps about the y axis (e1 = z, e2 = y x z = x) and about z (e1 = x)
    for axis, e1, e2 in (((0.0, 1.0, 0.0), (0, 0, 1), (1, 0, 0)), ((0.0, 0.0, 1.0), (1, 0, 0), (0, 1, 0))):
        eps = np.concatenate([s * 10.0 ** np.arange(-12.0, -2.5, 0.25) for s in (-1, 1)] + [[0.0]])
        ang = (2 * math.pi * np.arange(S + 1) / S - math.pi)[:, None] + eps[None, :]
        r = np.cos(ang).ravel()[:, None] * np.array(e1) + np.sin(ang).ravel()[:, None] * np.array(e2)
        q, qe = sectors(r * 0.0118, np.tile(axis, (len(r), 1)))
        assert np.array_equal(q, qe)
