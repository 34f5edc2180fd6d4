"""The rigid projectile on plain arrays: exact mass properties of tetrahedra, quaternions, and the RK4
rigid-body motion under the sum of the load points' forces (docs/theory.md §9).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


def _kernel():
    """rigid_points and force_moment in C (fepen/laws/rigid_kernel.c, fepen.native's "rigid_body"), or None when
    they do not build or FEPEN_KERNEL=python (the numpy expressions below, the reference) is set."""
    from fepen import native

    return native.kernel("rigid_body")


def tet_mass_properties(p: np.ndarray, rho: np.ndarray):
    """Mass, centre of mass and inertia tensor about the centre of a set of tetrahedra.

    Args:
        p: node coordinates (n, 4, 3). rho: density per cell (n,).

    Returns:
        (mass, centre (3,), inertia (3, 3)).
    """
    d = np.einsum("ij,ij->i", np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), p[:, 3] - p[:, 0])
    V = np.abs(d) / 6.0
    m = rho * V
    first = np.einsum("i,ij->j", m, p.mean(axis=1))
    s = p.sum(axis=1)
    second = np.einsum("i,iajk->jk", m / 20.0, np.einsum("iaj,iak->iajk", p, p)) \
        + np.einsum("i,ij,ik->jk", m / 20.0, s, s)
    return float(m.sum()), first, second


def inertia_about_centre(mass: float, first: np.ndarray, second: np.ndarray):
    """From Σ m, Σ m x and Σ ∫ρ x⊗x (about the origin): centre and inertia tensor about the centre."""
    c = first / mass
    S = second - mass * np.outer(c, c)
    return c, np.trace(S) * np.eye(3) - S


def quat_to_matrix(q: np.ndarray) -> np.ndarray:
    """Rotation matrix of a unit quaternion (w, x, y, z) (its entries as Python floats: the same IEEE double
    arithmetic as numpy's scalars, at a fraction of the cost)."""
    w, x, y, z = q.tolist() if isinstance(q, np.ndarray) else q
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def matrix_to_quat(R: np.ndarray) -> np.ndarray:
    """Unit quaternion (w, x, y, z) of a rotation matrix (Shepperd's method)."""
    t = np.trace(R)
    if t > 0:
        s = 2.0 * np.sqrt(1.0 + t)
        q = [0.25 * s, (R[2, 1] - R[1, 2]) / s, (R[0, 2] - R[2, 0]) / s, (R[1, 0] - R[0, 1]) / s]
    else:
        i = int(np.argmax(np.diag(R)))
        j, k = (i + 1) % 3, (i + 2) % 3
        s = 2.0 * np.sqrt(1.0 + R[i, i] - R[j, j] - R[k, k])
        q = np.zeros(4)
        q[0] = (R[k, j] - R[j, k]) / s
        q[1 + i] = 0.25 * s
        q[1 + j] = (R[j, i] + R[i, j]) / s
        q[1 + k] = (R[k, i] + R[i, k]) / s
        return q / np.linalg.norm(q)
    q = np.array(q)
    return q / np.linalg.norm(q)


def quat_mul(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Hamilton product a ⊗ b (on Python floats, as quat_to_matrix)."""
    w1, x1, y1, z1 = a.tolist() if isinstance(a, np.ndarray) else a
    w2, x2, y2, z2 = b.tolist() if isinstance(b, np.ndarray) else b
    return np.array([w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2, w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
                     w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2, w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2])


@dataclass
class RigidState:
    """c, V, L: world-frame centre, velocity, angular momentum; q: body rotation quaternion."""

    c: np.ndarray
    q: np.ndarray
    V: np.ndarray
    L: np.ndarray

    def as_array(self) -> np.ndarray:
        return np.concatenate([self.c, self.q, self.V, self.L])

    @staticmethod
    def from_array(y: np.ndarray) -> RigidState:
        return RigidState(y[0:3].copy(), y[3:7].copy(), y[7:10].copy(), y[10:13].copy())


class RigidBody:
    """A rigid body with surface load points.

    Args:
        mass, centre0, inertia: mass properties in the reference frame (centre0: reference centre).
        points: reference positions of the load points (k, 3). normals: their reference normals (k, 3).
    """

    def __init__(self, mass: float, centre0: np.ndarray, inertia: np.ndarray, points: np.ndarray,
                 normals: np.ndarray):
        self.mass = mass
        self.centre0 = np.asarray(centre0, float)
        self.I_body = np.asarray(inertia, float)
        self.I_body_inv = np.linalg.inv(self.I_body)
        self.r0 = np.ascontiguousarray(np.asarray(points, float) - self.centre0)  # body-frame arms
        self.N0 = np.ascontiguousarray(normals, dtype=float)
        self.lib = _kernel()
        self._r0_at, self._N0_at = self.r0.ctypes.data, self.N0.ctypes.data  # the arrays live as long as self
        #: (R, ω) of the state last passed to derivative (force functions may use them)
        self.frame: tuple[np.ndarray, np.ndarray] | None = None
        self._last: list | None = None  # [state's bytes, R, ω, points or None] of the last state asked (at)
        self.angular_impulse_step = np.zeros(3)  # the last step's angular impulse of the load about O (N m s)

    def at(self, s: RigidState) -> list:
        """[key, R, ω, points or None] of state s, kept for the last state asked: a step's end state is asked
        by the stop rules, then by the history row, then by the next step's first stage, which so compute its
        rotation, angular velocity and load points once instead of three times (the same expressions on the
        same numbers: bitwise the same values). Keyed on the state's numbers, not on the object."""
        key = s.c.tobytes() + s.q.tobytes() + s.V.tobytes() + s.L.tobytes()
        last = self._last
        if last is not None and last[0] == key:
            return last
        R = quat_to_matrix(s.q)
        self._last = last = [key, R, self._omega(s.L, R), None]
        return last

    def _omega(self, L: np.ndarray, R: np.ndarray) -> np.ndarray:
        return R @ (self.I_body_inv @ (R.T @ L))

    def omega(self, s: RigidState, R: np.ndarray | None = None) -> np.ndarray:
        """World angular velocity ω = R I_b^{-1} R^T L."""
        return self.at(s)[2] if R is None else self._omega(s.L, R)

    def points(self, s: RigidState, R: np.ndarray | None = None, w: np.ndarray | None = None):
        """World positions, velocities and normals of the load points, and their arms about the centre
        (R, w: the state's rotation and angular velocity when already known; the arrays are shared with the
        cache of ``at``: read them, never write)."""
        if R is None and w is None:
            last = self.at(s)
            if last[3] is None:
                last[3] = self._points(s, last[1], last[2])
            return last[3]
        R = quat_to_matrix(s.q) if R is None else R
        w = self.omega(s, R) if w is None else w
        return self._points(s, R, w)

    def _points(self, s: RigidState, R: np.ndarray, w: np.ndarray):
        if self.lib is not None:
            k = len(self.r0)
            out = np.empty((4, k, 3))
            a = out.ctypes.data
            step = 24 * k
            small = np.concatenate([R.ravel(), s.c, s.V, w])
            b = small.ctypes.data
            self.lib.rigid_points(k, self._r0_at, self._N0_at, b, b + 72, b + 96, b + 120, a, a + step,
                                  a + 2 * step, a + 3 * step)
            return out[0], out[1], out[2], out[3]
        arm = self.r0 @ R.T
        skew = np.array([[0.0, -w[2], w[1]], [w[2], 0.0, -w[0]], [-w[1], w[0], 0.0]])  # w × r = skew r
        return s.c + arm, s.V + arm @ skew.T, self.N0 @ R.T, arm

    def force_moment(self, arm: np.ndarray, f: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Σ f and Σ arm × f over the load points."""
        if self.lib is not None:
            FM = np.empty(6)
            f = np.ascontiguousarray(f, dtype=float)
            self.lib.force_moment(len(f), arm.ctypes.data, f.ctypes.data, FM.ctypes.data)
            return FM[:3], FM[3:]
        # Σ arm × f as three dot products (np.cross on (k, 3) arrays costs more than the sum)
        return f.sum(axis=0), np.array([arm[:, 1] @ f[:, 2] - arm[:, 2] @ f[:, 1],
                                        arm[:, 2] @ f[:, 0] - arm[:, 0] @ f[:, 2],
                                        arm[:, 0] @ f[:, 1] - arm[:, 1] @ f[:, 0]])

    def to_world(self, s: RigidState, X: np.ndarray) -> np.ndarray:
        """World position of reference points X (k, 3)."""
        return s.c + (np.asarray(X, float) - self.centre0) @ self.at(s)[1].T

    def derivative(self, s: RigidState, force_fn):
        """Time derivative of the state, and the force and moment; force_fn(s, x, v, n) -> forces (k, 3) on
        the load points at world positions x, velocities v, normals n (self.frame holds the state's rotation
        and angular velocity meanwhile)."""
        x, v, n, arm = self.points(s)
        _, R, w, _ = self._last
        self.frame = (R, w)
        F, M = self.force_moment(arm, force_fn(s, x, v, n))
        dq = 0.5 * quat_mul([0.0, *w.tolist()], s.q)
        return np.concatenate([s.V, dq, F / self.mass, M]), F, M

    def power(self, s: RigidState, F: np.ndarray, M: np.ndarray, w: np.ndarray | None = None) -> float:
        """Power F·V + M·ω of the external force and moment (W); w: the state's ω when already known."""
        return float(F @ s.V + M @ (self.omega(s) if w is None else w))

    def rk4_step(self, s: RigidState, dt: float, force_fn):
        """One classical Runge–Kutta step, in numpy: the oracle of the rigid run's compiled step (fepen/runs/
        rigid_batch.c's rigid_step, which RigidRun takes where the C kernels build; tests/unit/runs/
        test_rigid_step.py holds the two together, bitwise), and the step where they do not build.

        Returns:
            (new state, force and moment at the start, work of the external force and moment over the step
            by the same RK4 weights on the stage powers: dt/6 (P1 + 2 P2 + 2 P3 + P4)).
        """
        y0 = s.as_array()
        work = 0.0
        angular = np.zeros(3)
        k = []
        state = s
        for i, (c, w) in enumerate(((0.0, 1.0), (0.5, 2.0), (0.5, 2.0), (1.0, 1.0))):
            if i:
                state = RigidState.from_array(y0 + c * dt * k[-1])
            ki, F, M = self.derivative(state, force_fn)
            if i == 0:
                F0, M0 = F, M
            work += w * self.power(state, F, M, self.frame[1])
            angular += w * (M + np.cross(state.c, F))  # the moment about O
            k.append(ki)
        y = y0 + dt / 6.0 * (k[0] + 2 * k[1] + 2 * k[2] + k[3])
        new = RigidState.from_array(y)
        new.q /= np.linalg.norm(new.q)
        self.angular_impulse_step = dt / 6.0 * angular  # the step's angular impulse about O, the same weights
        return new, F0, M0, dt / 6.0 * work

    def remove_mass(self, s: RigidState, dm: float) -> tuple[RigidState, float]:
        """Take dm (kg) off the body uniformly (mass and inertia scaled alike; the centre and the velocities
        unchanged, so the removed material leaves at the body's own velocity and exerts no thrust).

        Returns:
            (the state with the angular momentum scaled to keep ω, the kinetic energy the removed mass carries
            away (J)).
        """
        f = (self.mass - dm) / self.mass
        ke = self.kinetic_energy(s)
        self.mass -= dm
        self.I_body = self.I_body * f
        self.I_body_inv = self.I_body_inv / f
        self._last = None  # ω of every state changed
        new = RigidState(s.c.copy(), s.q.copy(), s.V.copy(), s.L * f)
        return new, ke - self.kinetic_energy(new)

    def kinetic_energy(self, s: RigidState) -> float:
        return 0.5 * self.mass * float(s.V @ s.V) + 0.5 * float(self.omega(s) @ s.L)
