"""The CoM reference from the ZMP reference: Kajita's preview control of the
cart-table model (Kajita et al., "Biped walking pattern generation by using
preview control of zero-moment point", ICRA 2003).

Per horizontal axis, the state is the CoM's position, velocity and
acceleration ``(c, c', c'')`` (m, m/s, m/s^2, W); the input is the jerk; the
output is the ZMP ``p = c - (H / g) c''``. Each preview period the jerk is
``-K x + sum_j f_j p_ref(t + j dt)`` over ``horizon`` s of the future ZMP
reference, the gains from the discrete Riccati equation with weight 1 on the
ZMP error and ``jerk_weight`` on the jerk, the reference held at its last
sample beyond the horizon. The state is integrated exactly
(a constant jerk per period), so the reference is smooth (C2) at any
sampling rate in between.
"""

from typing import Tuple

import numpy as np
import scipy.linalg


class Preview:
    """A ZMP preview controller for CoM height ``H`` (m), gravity ``g``
    (m/s^2), period ``dt`` (s), looking ``horizon`` (s) ahead."""

    def __init__(self, H: float, g: float, dt: float, horizon: float = 1.2, jerk_weight: float = 1e-6) -> None:
        self.dt = dt
        self.n = max(1, round(horizon / dt))
        A = np.array([[1.0, dt, dt * dt / 2.0], [0.0, 1.0, dt], [0.0, 0.0, 1.0]])
        B = np.array([[dt**3 / 6.0], [dt * dt / 2.0], [dt]])
        C = np.array([[1.0, 0.0, -H / g]])
        Q = C.T @ C
        R = np.array([[jerk_weight]])
        P = scipy.linalg.solve_discrete_are(A, B, Q, R)
        S = R + B.T @ P @ B
        self.K = np.linalg.solve(S, B.T @ P @ A).ravel()
        Ac = A - B @ self.K[None, :]
        f = np.zeros(self.n)
        X = C.T.copy()
        for j in range(self.n):
            f[j] = np.linalg.solve(S, B.T @ X).item()
            X = Ac.T @ X
        # The reference is taken to stay at its last sample beyond the horizon:
        # that sample also carries the gains of the rest (which sum, with the
        # others, to K[0], so that a constant ZMP is tracked exactly).
        f[-1] += self.K[0] - f.sum()
        #: Preview gains of the future ZMP samples ``t + dt, t + 2 dt, ...``.
        self.f = f
        self.A, self.B, self.C = A, B, C
        #: State: rows position, velocity, acceleration; columns x, y.
        self.x = np.zeros((3, 2))
        self.jerk = np.zeros(2)
        #: The state at the start of the current period (``sample``'s origin).
        self.start = self.x.copy()

    def reset(self, com: np.ndarray, velocity: np.ndarray = np.zeros(2)) -> None:
        """Restarts at the CoM ``com`` (x, y) with ``velocity``, no acceleration."""
        self.x = np.zeros((3, 2))
        self.x[0] = com
        self.x[1] = velocity
        self.start = self.x.copy()
        self.jerk = np.zeros(2)

    def update(self, zmp_future: np.ndarray) -> None:
        """Advances one period; ``zmp_future`` (n, 2): the ZMP reference at
        ``t + dt, ..., t + n dt`` (m, W)."""
        self.jerk = -self.K @ self.x + self.f @ zmp_future
        self.x = self.A @ self.x + self.B @ self.jerk[None, :]

    def sample(self, s: float) -> Tuple[np.ndarray, np.ndarray]:
        """The CoM position and velocity (x, y) ``s`` seconds (0 <= s <= dt)
        into the period just started (before the next ``update``)."""
        c0, v0, a0 = self.start
        return (
            c0 + v0 * s + a0 * s * s / 2.0 + self.jerk * s**3 / 6.0,
            v0 + a0 * s + self.jerk * s * s / 2.0,
        )

    def advance(self, zmp_future: np.ndarray) -> None:
        """``update``, keeping the period's start state for ``sample``."""
        self.start = self.x.copy()
        self.update(zmp_future)

    def zmp(self) -> np.ndarray:
        """The model's ZMP now (x, y, m)."""
        return (self.C @ self.x).ravel()
