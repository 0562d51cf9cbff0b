#!/usr/bin/env python3
"""A seeded set of non-condensed LIP walking MPC QPs: P only positive semidefinite.

Usage (numpy only):
    python3 tools/lip_mpc_qps.py /tmp/lipmpc                  # LIPMPC0..99.npz
    python3 tools/lip_mpc_qps.py --horizon 64 /tmp/lipmpc64   # n = 384

Options: `--count N` (files, default 100), `--seed S` (default 21),
`--horizon N` (steps, default 8), `--prefix NAME` (file names `NAME<k>.npz`,
default LIPMPC). The same arguments give byte-identical files (with the same
numpy). `tests/data/lipmpc/` holds the first 6 files of the defaults.

The files follow the qpbenchmark npz layout of `tests/data/lipmwalk`
(`min 1/2 x'Px + q'x  s.t.  Gx <= h, Ax = b, lb <= x <= ub`), written by
`lip_balance_qps.write_npz`; every member is present.

The model: the linear inverted pendulum (CoM height z_c = 0.8 m, g = 9.81,
omega = sqrt(g / z_c)) on both horizontal axes, state per axis (c, c') (CoM
position and velocity), input the ZMP p held over each tick of dt = 0.1 s
(exact discretisation: c'' = omega^2 (c - p)). The horizon has N ticks; the
footsteps change every 4 ticks (0.4 s steps), alternating left and right.

Variables (not condensed): per tick k = 0..N-1 the ZMP u_k = (px, py), then
the state x_{k+1} = (cx, cx', cy, cy'): n = 6 N, in that order.

Equality rows (A x = b, 4 N): the dynamics x_{k+1} = Ad x_k + Bd u_k, with
the measured state x_0 on the right-hand side of the first four.

Cost: 1/2 sum_k [ w_v |c'_{k+1} - v_ref|^2 + w_u |u_k - f_k|^2 ] with f_k
the centre of tick k's foot, w_v = 1, w_u = 0.1. The CoM positions carry no
weight, so P is diagonal with 2 N zeros on it: positive semidefinite, not
definite (the dynamics rows make the minimiser unique).

Inequality rows (G x <= h, 2 N): the lateral capture point
xi_y = c_y + c'_y / omega of every tick within +-0.4 m of the walking line.

Bounds (lb, ub) on every variable: the ZMP inside the foot's rectangle
(half-lengths 0.10 m along x, 0.05 m across); the velocities within
+-1.5 m/s; the positions within +-10 m.

What changes from file to file (q, h, b, lb, ub): the forward reference
speed v_ref = (vx, 0) with vx uniform in [0.1, 0.5] m/s (the feet are placed
for it), the initial CoM position (x = 0, laterally halfway to the first foot
+-2 cm) and velocity (forward uniform in [0, 0.3] m/s, lateral uniform in
+-0.1 m/s), and which foot comes first.

The script prints how many files have a violated inequality row or bound at
the minimiser under the dynamics alone.
"""
import argparse
import os
import sys

import numpy as np

from lip_balance_qps import write_npz

DT = 0.1          # s
ZC = 0.8          # m
GRAV = 9.81       # m/s^2
OMEGA = np.sqrt(GRAV / ZC)
TICKS_PER_STEP = 4
FOOT_Y = 0.1      # m, lateral offset of a foot from the walking line
HALF = np.array([0.10, 0.05])   # foot rectangle half-lengths (x, y), m
W_V = 1.0
W_U = 0.1
XI_MAX = 0.4      # m
V_MAX = 1.5       # m/s
C_MAX = 10.0      # m


def dynamics():
    """Ad (4 x 4) and Bd (4 x 2) of x = (cx, cx', cy, cy'), u = (px, py)."""
    ch, sh = np.cosh(OMEGA * DT), np.sinh(OMEGA * DT)
    a = np.array([[ch, sh / OMEGA], [OMEGA * sh, ch]])
    b = np.array([1.0 - ch, -OMEGA * sh])
    Ad = np.kron(np.eye(2), a)
    Bd = np.kron(np.eye(2), b.reshape(2, 1))
    return Ad, Bd


class Mpc:
    """The fixed part (P, A, G) for a horizon of N ticks."""

    def __init__(self, N):
        self.N = N
        n = 6 * N
        Ad, Bd = dynamics()
        self.Ad = Ad
        A = np.zeros((4 * N, n))
        for k in range(N):
            u, x = 6 * k, 6 * k + 2          # columns of u_k, x_{k+1}
            A[4 * k:4 * k + 4, x:x + 4] = np.eye(4)
            A[4 * k:4 * k + 4, u:u + 2] = -Bd
            if k > 0:
                A[4 * k:4 * k + 4, x - 6:x - 2] = -Ad
        self.A = A
        pdiag = np.zeros(n)
        for k in range(N):
            pdiag[6 * k:6 * k + 2] = W_U
            pdiag[6 * k + 3] = W_V       # cx'
            pdiag[6 * k + 5] = W_V       # cy'
        self.P = np.diag(pdiag)
        G = np.zeros((2 * N, n))
        for k in range(N):
            cy = 6 * k + 2 + 2
            G[2 * k, cy] = 1.0
            G[2 * k, cy + 1] = 1.0 / OMEGA
            G[2 * k + 1] = -G[2 * k]
        self.G = G
        self.h = np.full(2 * N, XI_MAX)

    def qp(self, vx, x0, left_first):
        N, n = self.N, 6 * self.N
        q = np.zeros(n)
        lb, ub = np.empty(n), np.empty(n)
        for k in range(N):
            step = k // TICKS_PER_STEP
            side = 1.0 if (step % 2 == 0) == left_first else -1.0
            # the foot of step s sits where the CoM is at its middle
            f = np.array([vx * DT * TICKS_PER_STEP * (step + 0.5), side * FOOT_Y])
            u, x = 6 * k, 6 * k + 2
            q[u:u + 2] = -W_U * f
            q[x + 1] = -W_V * vx
            lb[u:u + 2], ub[u:u + 2] = f - HALF, f + HALF
            lb[x:x + 4] = [-C_MAX, -V_MAX, -C_MAX, -V_MAX]
            ub[x:x + 4] = [C_MAX, V_MAX, C_MAX, V_MAX]
        b = np.zeros(4 * N)
        b[:4] = self.Ad @ x0
        return {"P": self.P, "q": q, "G": self.G, "h": self.h.copy(),
                "A": self.A, "b": b, "lb": lb, "ub": ub}


def draw(rng):
    vx = rng.uniform(0.1, 0.5)
    left_first = bool(rng.integers(2))
    y0 = (FOOT_Y if left_first else -FOOT_Y) * 0.5 + rng.uniform(-0.02, 0.02)
    x0 = np.array([0.0, rng.uniform(0.0, 0.3), y0, rng.uniform(-0.1, 0.1)])
    return vx, x0, left_first


def needs_active(d):
    """Rows of G and bounds violated at the minimiser under A x = b alone
    (P + A'A is definite here, so the KKT matrix is regular)."""
    P, q, A, b = d["P"], d["q"], d["A"], d["b"]
    n, me = len(q), len(b)
    K = np.block([[P, A.T], [A, np.zeros((me, me))]])
    x = np.linalg.solve(K, np.concatenate([-q, b]))[:n]
    tol = 1e-9
    return int(np.sum(d["G"] @ x - d["h"] > tol)
               + np.sum(d["lb"] - x > tol) + np.sum(x - d["ub"] > tol))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("outdir")
    ap.add_argument("--count", type=int, default=100, help="files (default 100)")
    ap.add_argument("--seed", type=int, default=21, help="numpy seed (default 21)")
    ap.add_argument("--horizon", type=int, default=8, help="ticks N (default 8)")
    ap.add_argument("--prefix", default="LIPMPC",
                    help="file names PREFIX<k>.npz, k = 0..count-1 (default LIPMPC)")
    a = ap.parse_args()
    if a.horizon < 1:
        ap.error("--horizon must be >= 1")
    os.makedirs(a.outdir, exist_ok=True)
    rng = np.random.default_rng(a.seed)
    mpc = Mpc(a.horizon)
    active = []
    for k in range(a.count):
        vx, x0, left_first = draw(rng)
        d = mpc.qp(vx, x0, left_first)
        write_npz(os.path.join(a.outdir, f"{a.prefix}{k}.npz"), d)
        active.append(needs_active(d))
    n = mpc.P.shape[0]
    print(f"{a.count} files in {a.outdir}: n = {n}, {mpc.A.shape[0]} equality rows, "
          f"{mpc.G.shape[0]} rows of G, bounds on all {n} variables; rank(P) = "
          f"{np.linalg.matrix_rank(mpc.P)}; {sum(v > 0 for v in active)} need an "
          f"active inequality (median {np.median(active):.0f}, max {max(active)} "
          f"violated at the minimiser under the dynamics alone)", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
