"""The tunnel the projectile opens (fepen.laws.tunnel, tunnel_kernel.c) and the load of its wall on the body
behind the nose (docs/theory.md §8.7): where a point is in a straight tunnel, the wall pushing a yawed body back
toward its axis and nothing on a centred one, an elastic wall up to its reload limit that gives back what it
took, and a wall that yields past it and keeps its set."""

import math

import numpy as np
import pytest

from fepen.laws import target as tg
from fepen.laws.tunnel import Tunnel

A0 = 0.0118  # the shoulder's radius (m)
XI_SH = 0.03  # the shoulder's distance behind the tip (m)
CA = tg.cavity_ratio(40e6, 32.5e9, 4e6)
LAW = tg.TargetLaw(density=2400.0, Y=40e6, E=32.5e9, T=4e6, lam=0.67, sigma_s=300e6, B=1.0, c_over_a=CA, D=2 * A0,
                   wall_shear2=tg.wall_modulus(32.5e9, 0.2, CA), reload=tg.reload_fraction(40e6, 0.67, CA))
K = LAW.wall_shear2 / A0  # the wall's stiffness (Pa/m)
LIMIT = LAW.reload * LAW.sigma_s  # its reload limit at rest (Pa)
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
    assert sign * f[:, 0].sum() > 0.0 and abs(f[:, 2].sum()) < 1e-9 * abs(f[:, 0].sum())  # back, not across
    moment = np.cross(x - sh, f).sum(axis=0)[2]
    assert sign * moment < 0.0  # against the turn


def test_the_force_vanishes_when_the_body_is_centred():
    """A centred body carries nothing from the wall, turning or not: the wall is a spring, pressed only where the
    body stands in it (before, a rigid-plastic wall loaded a centred body by its speed into the wall)."""
    t = straight_tunnel()
    for omega in (0.0, 30.0):
        still = forces(t, *shank(0.0, omega))[1]
        assert still[3] == 0 and np.all(still[:3] == 0.0)


def sideways(delta, u=0.0):
    """The centred shank moved sideways (+x) by delta, at rest but for an outward speed u along +x."""
    x, v, n, area, xi, sh, axis = shank(0.0, 0.0)
    return x + [delta, 0.0, 0.0], np.tile([u, 0.0, 0.0], (len(x), 1)), n, area, xi, sh + [delta, 0.0, 0.0], axis


def stresses(t, x, v, n, area, xi, sh, axis):
    t.at(sh, axis)
    k = len(x)
    return tg.normal_stress(LAW, x, v, n, area, np.full(k, A0), np.full(k, np.inf), np.zeros(k), axis, t, xi)


def test_the_wall_is_a_spring_up_to_its_reload_limit():
    """A body pressed sideways into a straight tunnel at rest: every point facing the push carries (2G/a) times
    its push into the wall (its distance from the tunnel's axis less a0), up to the wall's reload limit
    (reload sigma_s), and the points turned away carry nothing; pushing outward at u adds the wall's inertia
    B rho u^2 to the limit."""
    t = straight_tunnel()
    for delta in (1e-5, 5e-5, 2e-3):
        x, v, n, area, xi, sh, axis = sideways(delta)
        _, sig = stresses(t, x, v, n, area, xi, sh, axis)
        push = np.hypot(A0 * n[:, 0] + delta, A0 * n[:, 2]) - A0 * (1.0 + 1e-9)  # less round-off's width
        expect = np.where(push > 0.0, np.minimum(K * push, LIMIT), 0.0)
        assert np.allclose(sig, expect, rtol=1e-9, atol=1e-9 * LIMIT), delta
        assert np.all(sig[n[:, 0] < -0.5] == 0.0)  # the side turned away is free
    assert K * 1e-5 < LIMIT < K * 2e-3  # the two regimes were both met
    x, v, n, area, xi, sh, axis = sideways(2e-3, u=20.0)
    _, sig = stresses(t, x, v, n, area, xi, sh, axis)
    assert sig.max() == pytest.approx(LIMIT + LAW.density * 20.0**2, rel=1e-4)  # u: 20 m/s along e_r, nearly x


def lateral_work(t, deltas, commit):
    """The work of the wall's sideways force on the shank moved through ``deltas`` at rest (trapezoids),
    committing each step when asked (a run's first stages: the wall yields where pressed past its limit)."""
    work, last = 0.0, None
    for d in deltas:
        x, v, n, area, xi, sh, axis = sideways(d)
        t.commit = commit
        fx = forces(t, x, v, n, area, xi, sh, axis)[1][0]
        if last is not None:
            work += 0.5 * (fx + last[1]) * (d - last[0])
        last = (d, fx)
    return work


def test_the_elastic_wall_gives_back_what_it_took():
    """Pressed within its reload limit and let go, the wall gives back the work it took (to 1e-9): it
    dissipates nothing in its elastic range, and stays where it was."""
    t = straight_tunnel()
    radius0 = t.stations()["radius"].copy()
    d = np.linspace(0.0, 0.9 * LIMIT / K, 400)  # the most-pressed point to 90 % of the limit
    w_in = lateral_work(t, d, commit=True)
    w_out = lateral_work(t, d[::-1], commit=True)
    assert w_in < 0.0 and w_out == pytest.approx(-w_in, rel=1e-9)
    assert np.array_equal(t.stations()["radius"], radius0)


def test_the_wall_yields_past_its_limit_and_keeps_its_set():
    """Pressed past its limit (committed each step, as a run's first stages do) the wall yields: the tunnel
    widens where it was pressed by the push less the elastic part at the limit, and on release the body gets
    back less than it gave (the plastic work); back on the axis it is free."""
    t = straight_tunnel()
    d = np.linspace(0.0, 4.0 * LIMIT / K, 400)
    w_in = lateral_work(t, d, commit=True)
    widened = t.stations()["radius"].max() - A0
    assert widened == pytest.approx(3.0 * LIMIT / K, rel=0.02)
    w_out = lateral_work(t, d[::-1], commit=True)
    assert 0.0 < w_out < -w_in
    x, v, n, area, xi, sh, axis = sideways(0.0)  # back on the axis: the wider tunnel holds it nowhere
    assert forces(t, x, v, n, area, xi, sh, axis)[1][3] == 0


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


RC = 3.0  # the curved tunnel's radius of curvature (m)


def curved_tunnel(depth=0.5):
    """A tunnel dug along a circular arc of radius RC in the x-y plane: from the face straight down, bending toward
    +x (its centre at (RC, 0, 0)), the shoulder's axis along the arc's tangent; returns it and the arc's angle at
    its end."""
    t = Tunnel(XI_SH, A0)
    none = np.zeros((0, 3))
    for s in np.arange(1e-4, depth, 0.2 * A0):
        th = s / RC
        t.at(np.array([RC - RC * math.cos(th), -RC * math.sin(th), 0.0]), np.array([math.sin(th), -math.cos(th), 0.0]))
        t.commit = True
        tg.point_forces(LAW, none, none, none, np.zeros(0), np.zeros(0), np.zeros(0), np.zeros(0), DOWN, t,
                        np.zeros(0))
    return t, s / RC


def on_the_arc(th_end, offset, tilt_deg, rings=30, per_ring=24, length=0.12):
    """A shank of radius A0 whose shoulder is on the arc at its end, moved sideways by offset (m, toward +x across
    the path) and tilted by tilt_deg about z: its points, their xi, the shoulder and the axis."""
    sh = np.array([RC - RC * math.cos(th_end), -RC * math.sin(th_end), 0.0])
    tangent = np.array([math.sin(th_end), -math.cos(th_end), 0.0])
    across = np.array([math.cos(th_end), math.sin(th_end), 0.0])
    sh = sh + offset * across
    c, s = math.cos(math.radians(tilt_deg)), math.sin(math.radians(tilt_deg))
    axis, e1 = c * tangent + s * across, -s * tangent + c * across
    xi = XI_SH + (np.arange(rings) + 0.5) * length / rings
    phi = (np.arange(per_ring) + 0.5) * 2 * math.pi / per_ring
    XI, PHI = np.meshgrid(xi, phi, indexing="ij")
    n = (np.cos(PHI)[..., None] * e1 + np.sin(PHI)[..., None] * np.array([0.0, 0.0, 1.0])).reshape(-1, 3)
    return sh - (XI - XI_SH).reshape(-1, 1) * axis + A0 * n, XI.ravel(), sh, axis


def probe(t, x, xi, sh, axis):
    from fepen import native

    t.at(sh, axis)
    k = len(x)
    x, xi = np.ascontiguousarray(x, dtype=float), np.ascontiguousarray(xi, dtype=float)
    clear, located = np.zeros(k, np.int32), np.zeros(k, np.int32)
    delta, rho = np.full(k, np.nan), np.full(k, np.nan)
    native.kernel("target").tunnel_probe(t.buf.ctypes.data, k, x.ctypes.data, xi.ctypes.data, clear.ctypes.data,
                                         located.ctypes.data, delta.ctypes.data, rho.ctypes.data)
    return clear.astype(bool), located.astype(bool), delta, rho


@pytest.mark.parametrize("offset, tilt", [(0.0, 0.0), (2e-4, 0.0), (-5e-4, 1.0), (1e-3, -2.0), (1e-9, 0.3)])
def test_the_clear_test_skips_no_point_the_wall_would_load(offset, tilt):
    """tunnel_clear lets the law's loops skip a point without a square root or a division: every point it calls
    clear is one tunnel_locate finds in the tunnel and not pressed past wall_push's round-off width, on a curved
    tunnel with the body centred, moved off its axis and tilted (and a point it does not call clear is left to
    the locate, which decides)."""
    t, th = curved_tunnel()
    x, xi, sh, axis = on_the_arc(th, offset, tilt)
    clear, located, delta, _ = probe(t, x, xi, sh, axis)
    assert located.all()
    assert np.all(delta[clear] - 1e-9 * A0 <= 0.0)
    if offset or tilt:  # off the axis: one side clear of the wall, the other pressed into it (a point turned far
        # across the path from its ring's centre is located at its own place, and the clear test leaves it be)
        assert clear.sum() > 0.2 * len(x) and (delta - 1e-9 * A0 > 0.0).sum() > 0.2 * len(x)


@pytest.mark.parametrize("tilt", [0.0, 1.0, -3.0])
def test_a_point_is_measured_against_the_curved_axis(tilt):
    """A point's distance from the axis of a tunnel dug along an arc of radius RC, located where its ring lies,
    against its exact distance from the arc: within twice the chords' sag (spacing^2 / 8 RC: the stations' centres
    joined by straight lines, the distance taken across the interpolated direction, not the chord's) and the
    ring's reach along the path (a point of a ring tilted by psi lies A0 sin psi along the path from the ring's
    centre, where the axis has turned by A0 sin psi / RC: A0 (A0 sin psi) / RC),
    docs/theory.md §8.7. Behind the last station only: ahead of it the tunnel ends at the shoulder where it is."""
    t, th = curved_tunnel()
    x, xi, sh, axis = on_the_arc(th, 0.0, tilt)
    _, located, _, rho = probe(t, x, xi, sh, axis)
    assert located.all()
    exact = np.hypot(np.hypot(x[:, 0] - RC, x[:, 1]) - RC, x[:, 2])
    st = t.stations()
    gap = math.hypot(*(sh - st["centre"][-1]))  # from the last station to the shoulder
    behind = xi - XI_SH > gap
    assert behind.sum() > len(x) // 2
    chord = np.diff(st["s"]).max()
    bound = chord**2 / (4 * RC) + A0 * A0 * math.sin(math.radians(abs(tilt))) / RC + 1e-12
    assert np.abs(rho - exact)[behind].max() <= bound
    assert bound < 1e-3 * A0  # at most a dozen micrometres


@pytest.mark.parametrize("delta", [0.0, 5e-12, 2e-11, 1e-10, 1e-9, 1e-8])
def test_the_clear_test_at_the_round_off_width(delta):
    """A centred body moved sideways by delta in a straight tunnel of its own radius: pressed by delta on one side,
    which the wall loads only past wall_push's round-off width (1e-9 of the radius, 1.2e-11 m). The clear test
    calls clear exactly what the locate leaves unpressed there too, from 0 to a thousand widths."""
    t = straight_tunnel()
    x, _, _, _, xi, sh, axis = sideways(delta)
    clear, located, d, _ = probe(t, x, xi, sh, axis)
    assert located.all()
    pressed = d - 1e-9 * A0 > 0.0
    assert not np.any(clear & pressed)
    assert pressed.any() == (delta > 1.5e-11)  # pressed only past the width
    assert clear.sum() >= len(x) // 2 - 48  # the far side and the flanks are clear
