"""The swing foot's references between footsteps, in W (m, rad, s): its
horizontal path to the latest target, its height, and a smooth 0 -> 1 ramp
(the CoM's reference is ``preview.py``'s, the step's timing ``walker.py``'s).
"""

import math

import numpy as np


def smoothstep(s: float) -> float:
    """Quintic 0 -> 1 on s in [0, 1], zero velocity and acceleration at both ends."""
    s = min(max(s, 0.0), 1.0)
    return s * s * s * (10.0 + s * (-15.0 + 6.0 * s))


def swing_height(phase: float, height: float, lift: float = 0.0) -> float:
    """The swing sole's height (m) at ``phase`` in [0, 1] of the step, the foot
    lifting at ``lift`` and landing at 1: ``height`` midway, zero velocity at
    lift-off and touchdown."""
    s = (phase - lift) / (1.0 - lift)
    return height * 0.5 * (1.0 - math.cos(2.0 * math.pi * min(max(s, 0.0), 1.0)))


class Swing:
    """The swing foot's horizontal path (W, m): a minimum-jerk (quintic)
    motion to the latest target, re-planned each tick from the current
    position, velocity and acceleration, moving between the fractions
    ``begin`` and ``end`` of the step and ending at rest."""

    def __init__(self, start: np.ndarray, begin: float, end: float) -> None:
        #: The fractions of the step between which the foot moves horizontally.
        self.begin, self.end = begin, end
        self.x = np.array(start, dtype=float)
        self.v = np.zeros(2)
        self.a = np.zeros(2)

    def advance(self, target: np.ndarray, phase: float, dt: float, duration: float) -> np.ndarray:
        """Moves ``dt`` (s) along the re-planned path at ``phase`` (the fraction
        of the step of ``duration`` s done before this tick); returns (x, y)."""
        if phase < self.begin or phase >= self.end:
            return self.x.copy()
        tau = (self.end - phase) * duration
        if tau <= dt:
            self.x, self.v, self.a = np.array(target, dtype=float), np.zeros(2), np.zeros(2)
            return self.x.copy()
        d = np.asarray(target, dtype=float) - self.x
        v0, a0 = self.v, self.a
        c3 = (20.0 * d - 12.0 * v0 * tau - 3.0 * a0 * tau**2) / (2.0 * tau**3)
        c4 = (-30.0 * d + 16.0 * v0 * tau + 3.0 * a0 * tau**2) / (2.0 * tau**4)
        c5 = (12.0 * d - 6.0 * v0 * tau - a0 * tau**2) / (2.0 * tau**5)
        t = dt
        self.x = self.x + v0 * t + 0.5 * a0 * t**2 + c3 * t**3 + c4 * t**4 + c5 * t**5
        self.v = v0 + a0 * t + 3.0 * c3 * t**2 + 4.0 * c4 * t**3 + 5.0 * c5 * t**4
        self.a = a0 + 6.0 * c3 * t + 12.0 * c4 * t**2 + 20.0 * c5 * t**3
        return self.x.copy()
