"""Closed loop from Python: the ldcbf-nav controller walks a linear inverted
pendulum (LIP) written in numpy through a shipped scenario.

    python examples/lip_loop.py [SCENARIO] [--time-limit S]

The scenario (default ``paper``) gives the start, the goal, the obstacles and
the controller's settings (``ldcbf_nav.load_scenario``); the plant is the 3D
LIP of the controller's model: over a stance on the foot ``f`` the CoM ``p``
obeys ``p'' = beta^2 (p - f)`` with ``beta = sqrt(g / H)``, integrated here in
closed form over each 50 ms control period. Every ``T`` seconds the swing foot
lands at the last commanded ``foot_target``, the stance side flips and the last
commanded turning rate takes effect. Exit status 0 when the CoM reaches the
goal without the body touching an obstacle.
"""

from __future__ import annotations

import argparse
import math
import sys

import numpy as np

import ldcbf_nav


def signed_distance(p: np.ndarray, poly: np.ndarray) -> float:
    """Signed distance from ``p`` to a counter-clockwise convex polygon, m
    (negative inside)."""
    a = poly
    b = np.roll(poly, -1, axis=0)
    e = b - a
    t = np.clip(np.einsum("ij,ij->i", p - a, e) / np.einsum("ij,ij->i", e, e), 0.0, 1.0)
    d = np.min(np.linalg.norm(p - (a + t[:, None] * e), axis=1))
    inside = np.all(e[:, 0] * (p[1] - a[:, 1]) - e[:, 1] * (p[0] - a[:, 0]) >= 0.0)
    return -d if inside else d


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("scenario", nargs="?", default="paper")
    ap.add_argument("--time-limit", type=float, default=None, help="s (default: the scenario's)")
    args = ap.parse_args()

    sc = ldcbf_nav.load_scenario(args.scenario)
    cfg = sc["config"]
    ctl = ldcbf_nav.Controller(cfg)
    obstacles = sc["obstacles"]
    goal = sc["goal"]
    body = sc["robot"]["body_radius"]
    time_limit = args.time_limit or sc["time_limit"]

    beta = math.sqrt(cfg["gravity"] / cfg["com_height"])
    dt = 0.05  # control period: 20 Hz, as in the paper
    per_step = round(cfg["step_duration"] / dt)  # control cycles per step
    ch, sh = math.cosh(beta * dt), math.sinh(beta * dt)

    # At rest over the stance foot, at the start of a step.
    p = sc["start"].copy()
    v = np.zeros(2)
    heading, omega = sc["start_heading"], 0.0
    foot, side = p.copy(), sc["stance"]
    k, steps, t = 0, 0, 0.0
    min_clearance = math.inf
    statuses: dict = {}
    out = None
    while t < time_limit:
        out = ctl.step(p, v, heading, omega, foot, side, k * dt, goal, obstacles)
        statuses[out["status"]] = statuses.get(out["status"], 0) + 1
        if out["status"] == "invalid_input":
            print(f"t = {t:.2f} s: the controller rejected the state ({out['input_error']})")
            break
        # The LIP over one control period, in closed form.
        d = p - foot
        p, v = foot + d * ch + v * (sh / beta), d * (beta * sh) + v * ch
        heading += omega * dt
        t += dt
        k += 1
        if k == per_step:  # step end: land the swing foot
            foot = out["foot_target"].copy()
            side = "right" if side == "left" else "left"
            omega = out["turning_rate"]
            k, steps = 0, steps + 1
        if obstacles:
            min_clearance = min(min_clearance, min(signed_distance(p, o) for o in obstacles) - body)
        if np.linalg.norm(p - goal) <= sc["success_radius"]:
            break

    reached = bool(np.linalg.norm(p - goal) <= sc["success_radius"])
    print(f"scenario {sc['name']}: {'goal reached' if reached else 'goal NOT reached'}"
          f" after {t:.2f} s, {steps} steps, final distance {np.linalg.norm(p - goal):.3f} m")
    print(f"minimum body clearance (at the 50 ms samples) {min_clearance:.3f} m; cycles by status {statuses}")
    return 0 if reached and min_clearance >= -1e-9 else 1


if __name__ == "__main__":
    sys.exit(main())
