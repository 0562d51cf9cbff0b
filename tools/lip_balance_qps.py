#!/usr/bin/env python3
"""A seeded set of dense QPs of n = 50, m = 100: a condensed LIP balance MPC.

Usage (numpy only):
    python3 tools/lip_balance_qps.py /tmp/lipbal                 # LIPBAL0..99.npz
    python3 tools/lip_balance_qps.py --full /tmp/lipbal_full     # + A, b, lb, ub
    python3 tools/compare_solvers.py --repeat 1000 --daqp-model \\
        --stats stats.csv /tmp/lipbal/*.npz > other.csv

Options: `--count N` (files, default 100), `--seed S` (default 12),
`--reach F` (the initial capture point is uniform in F times the support
rectangle; default 0.85, 0.7 with `--full`), `--prefix NAME` (file names
`NAME<k>.npz`, default LIPBAL), `--full`.
The same arguments give byte-identical files (with the same numpy and BLAS).

The files follow the qpbenchmark npz layout of `tests/data/lipmwalk`
(`min 1/2 x'Px + q'x  s.t.  Gx <= h, Ax = b, lb <= x <= ub`): keys P, q, G, h
as float64 (C order) and A, b, lb, ub; an absent key is stored, as in the
LIPMWALK files, as a 0-d object array holding None (pickle protocol 3, written
with the same bytes as there, so numpy 1.x reads it too). `np.load(f,
allow_pickle=True)` opens them; `ldcbf-sim qp solve` reads P, q, G, h only
(so it must not be given the `--full` files: it would drop A, b, lb, ub).

The model: the linear inverted pendulum (CoM height z_c = 0.8 m, g = 9.81,
omega = sqrt(g / z_c)) on both horizontal axes, state per axis (c, c', c'')
(CoM position, velocity, acceleration), input the CoM jerk j held over each
step (exact discretisation), dt = 0.1 s, horizon N = 25 steps. The decision
variable is the 25 jerks of both axes, interleaved (jx_0, jy_0, jx_1, ...):
n = 50. ZMP z = c - c''/omega^2, capture point xi = c + c'/omega. Condensing
writes the ZMPs and capture points of steps 1..N as T x0 + S U with S block
lower triangular (the jerk of step k moves z and xi from step k + 1 on; every
row of S has a nonzero diagonal, so every ZMP row depends on U, unlike the
first rows of the LIPMWALK files, which are zero).

Constraints (m = 100, the same G in every file): the ZMP of each step 1..N in
the support rectangle of a single stance foot, half-lengths 0.10 m (along the
foot) and 0.05 m (across), centred at the origin and yawed by 0.25 rad
(toe-out), i.e. s_k = R' z_k in [-a, a] per foot axis: rows ordered step by
step, per foot axis first the upper then the lower limit (4 rows per step,
like LIPMWALK's upper/lower pairs). The yaw makes each row mix the x and y
jerks, so G is dense within its block lower-triangular pattern.

Cost (the same P in every file): 1/2 sum_k [ w_xi |xi_k - r|^2 (the last
step weighted 10 w_xi) + (s_k - s_ref)' W (s_k - s_ref) + w_j |j_k|^2 ] with
r the reference point (capture point and CoM at rest over it), s_ref = R' r,
W = diag(0.5, 2.0) (the ZMP kept nearer the middle across the foot than
along it, in the foot frame, which makes P dense: x and y couple through the
yaw), w_xi = 1, w_j = 1e-4 (in (m/s^3)^-2). P = S_xi' Wxi S_xi + S_s' W S_s
+ w_j I is SPD and dense, cond(P) = 1.4e5 (the last jerks move only the last
steps, so they are held mostly by w_j; LIPMWALK's P has cond 320).

What changes from file to file (q and h only; P, G, A, lb, ub are fixed):

* the reference point r: uniform in the inner 40 % of the rectangle (a weight
  shift target);
* the CoM position c over a point e uniform in the inner 50 % of the
  rectangle (+-5 mm), the ZMP z at e +-1 cm (clipped to the rectangle), the
  acceleration c'' = omega^2 (c - z);
* the push: the CoM velocity c' = omega (xi_0 - c), with the initial capture
  point xi_0 uniform in `reach` times the rectangle (foot frame); the speeds
  are then 0 to about 0.45 m/s. The ZMP cannot jump (jerk input), so a capture
  point near the edge is not always recoverable. With the defaults (reach
  0.85, seed 12, 100 files; active sets as DAQP and quadprog both find them)
  35 files have no active row (the unconstrained minimiser is feasible), 58
  have 1 to 10 active rows, and 7 are beyond recovery by ankle torque alone,
  the ZMP pinned to an edge over the whole horizon (25 to 34 active rows).

`--full` exercises the whole format, same n = 50, m = 100 rows of G: A, b
(2 rows) the terminal equality xi_N = r (the capture point at the end of the
horizon on the reference), lb = -ub the jerk limits +-8 m/s^3 on all 50
variables; the default reach is then 0.7, which keeps the terminal equality
reachable (all 100 files of the default seed are feasible; with other seeds
or counts a file may be infeasible, which the solvers report as such). With
the defaults 44 files have no active inequality, 56 have 1 to 11 (rows of G
and bounds), 31 of them with an active jerk bound.

The script prints, per set, how many files have a violated row at the
unconstrained (with `--full`: equality-constrained, bounds ignored) minimiser,
i.e. how many need at least one active inequality at the optimum (strictly
convex QP); the solvers' active-set sizes come from
`compare_solvers.py --stats`.
"""
import argparse
import io
import os
import sys
import zipfile

import numpy as np

N = 25            # steps
DT = 0.1          # s
ZC = 0.8          # m
GRAV = 9.81       # m/s^2
OMEGA = np.sqrt(GRAV / ZC)
HALF = np.array([0.10, 0.05])   # support rectangle half-lengths (foot frame), m
YAW = 0.25                      # rad
W_XI = 1.0
W_XI_TERMINAL = 10.0
W_ZMP = np.array([0.5, 2.0])    # foot frame: along, across
W_JERK = 1e-4
JERK_MAX = 8.0                  # m/s^3, --full only

# A 0-d object array holding None, as stored in the LIPMWALK files (pickle
# protocol 3, numpy.core.multiarray): numpy >= 2 writes protocol 4 and
# numpy._core, which older numpy cannot unpickle.
NONE_NPY = (
    b"\x93NUMPY\x01\x00v\x00{'descr': '|O', 'fortran_order': False, 'shape': (), }"
    + b" " * 63 + b"\n"
    b"\x80\x03cnumpy.core.multiarray\n_reconstruct\nq\x00cnumpy\nndarray\nq\x01K\x00"
    b"\x85q\x02C\x01bq\x03\x87q\x04Rq\x05(K\x01)cnumpy\ndtype\nq\x06X\x02\x00\x00\x00"
    b"O8q\x07\x89\x88\x87q\x08Rq\t(K\x03X\x01\x00\x00\x00|q\nNNNJ\xff\xff\xff\xffJ\xff"
    b"\xff\xff\xffK?tq\x0bb\x89]q\x0cNatq\rb."
)


def rotation(yaw):
    c, s = np.cos(yaw), np.sin(yaw)
    return np.array([[c, -s], [s, c]])


def condensed():
    """T (2N x 6) and S (2N x 2N) of the ZMPs and of the capture points of
    steps 1..N: y = T x0 + S U, x0 = (cx, cx', cx'', cy, cy', cy''),
    U = (jx_0, jy_0, jx_1, ...), y = (yx_1, yy_1, yx_2, ...)."""
    A1 = np.array([[1.0, DT, DT**2 / 2], [0.0, 1.0, DT], [0.0, 0.0, 1.0]])
    B1 = np.array([DT**3 / 6, DT**2 / 2, DT])
    A = np.kron(np.eye(2), A1)                       # (6, 6)
    B = np.kron(np.eye(2), B1.reshape(3, 1))         # (6, 2)
    Cz = np.kron(np.eye(2), [[1.0, 0.0, -1.0 / OMEGA**2]])
    Cxi = np.kron(np.eye(2), [[1.0, 1.0 / OMEGA, 0.0]])
    out = {}
    for name, C in (("z", Cz), ("xi", Cxi)):
        T = np.zeros((2 * N, 6))
        S = np.zeros((2 * N, 2 * N))
        Ak = np.eye(6)
        powers = [np.eye(6)]
        for k in range(1, N + 1):
            Ak = A @ Ak
            powers.append(Ak)
        for k in range(1, N + 1):           # output of step k
            T[2 * (k - 1):2 * k] = C @ powers[k]
            for i in range(k):              # input of step i moves step k >= i + 1
                S[2 * (k - 1):2 * k, 2 * i:2 * i + 2] = C @ powers[k - 1 - i] @ B
        out[name] = (T, S)
    return out


class Mpc:
    """The fixed part: P, G (and A, lb, ub with --full); q, h per state."""

    def __init__(self, full):
        self.full = full
        c = condensed()
        self.Tz, self.Sz = c["z"]
        self.Txi, self.Sxi = c["xi"]
        self.R = rotation(YAW)
        Rt = np.kron(np.eye(N), self.R.T)                # world -> foot frame, per step
        self.Ts, self.Ss = Rt @ self.Tz, Rt @ self.Sz    # s = Ts x0 + Ss U
        wxi = np.full(2 * N, W_XI)
        wxi[-2:] *= W_XI_TERMINAL
        self.wxi = wxi
        self.ws = np.tile(W_ZMP, N)
        P = (self.Sxi.T * wxi) @ self.Sxi + (self.Ss.T * self.ws) @ self.Ss \
            + W_JERK * np.eye(2 * N)
        self.P = 0.5 * (P + P.T)
        # rows: step k, foot axis i, upper then lower
        G = np.empty((4 * N, 2 * N))
        G[0::2] = self.Ss
        G[1::2] = -self.Ss
        self.G = G
        self.hbase = np.repeat(np.tile(HALF, N), 2)
        if full:
            self.A = self.Sxi[-2:].copy()
            self.ub = np.full(2 * N, JERK_MAX)
            self.lb = -self.ub

    def qp(self, x0, r):
        sref = self.R.T @ r
        exi = self.Txi @ x0 - np.tile(r, N)      # capture point error at U = 0
        es = self.Ts @ x0 - np.tile(sref, N)     # foot-frame ZMP error at U = 0
        q = self.Sxi.T @ (self.wxi * exi) + self.Ss.T @ (self.ws * es)
        s0 = self.Ts @ x0
        h = self.hbase.copy()
        h[0::2] -= s0        # Ss U <= a - s0
        h[1::2] += s0        # -Ss U <= a + s0
        out = {"P": self.P, "q": q, "G": self.G, "h": h,
               "A": None, "b": None, "lb": None, "ub": None}
        if self.full:
            out.update(A=self.A, b=r - self.Txi[-2:] @ x0, lb=self.lb, ub=self.ub)
        return out


def draw_state(rng, reach):
    """Reference r and initial state x0 (world frame) of one file."""
    R = rotation(YAW)
    r = R @ (rng.uniform(-0.4, 0.4, 2) * HALF)
    e_f = rng.uniform(-0.5, 0.5, 2) * HALF
    c = R @ e_f + rng.uniform(-0.005, 0.005, 2)
    z = R @ np.clip(e_f + rng.uniform(-0.01, 0.01, 2), -HALF, HALF)
    acc = OMEGA**2 * (c - z)
    xi = R @ (rng.uniform(-reach, reach, 2) * HALF)
    v = OMEGA * (xi - c)
    x0 = np.array([c[0], v[0], acc[0], c[1], v[1], acc[1]])
    return x0, r


def write_npz(path, arrays):
    """Like np.savez (stored, zip64 headers, 1980 timestamps), with the
    LIPMWALK bytes for None members."""
    with zipfile.ZipFile(path, "w", compression=zipfile.ZIP_STORED,
                         allowZip64=True) as zf:
        for key in ("P", "q", "G", "h", "A", "b", "lb", "ub"):
            info = zipfile.ZipInfo(key + ".npy", date_time=(1980, 1, 1, 0, 0, 0))
            info.compress_type = zipfile.ZIP_STORED
            info.external_attr = 0o600 << 16
            if arrays[key] is None:
                data = NONE_NPY
            else:
                buf = io.BytesIO()
                np.lib.format.write_array(
                    buf, np.ascontiguousarray(arrays[key], dtype=np.float64),
                    allow_pickle=False)
                data = buf.getvalue()
            with zf.open(info, "w", force_zip64=True) as f:
                f.write(data)


def needs_active(d):
    """Whether the minimiser without the inequalities (with A x = b when
    present) violates a row of G x <= h or a bound."""
    P, q = d["P"], d["q"]
    n = len(q)
    if d["A"] is None:
        x = np.linalg.solve(P, -q)
    else:
        A, b = d["A"], d["b"]
        K = np.block([[P, A.T], [A, np.zeros((len(b), len(b)))]])
        x = np.linalg.solve(K, np.concatenate([-q, b]))[:n]
    tol = 1e-9
    viol = int(np.sum(d["G"] @ x - d["h"] > tol))
    if d["lb"] is not None:
        viol += int(np.sum(d["lb"] - x > tol) + np.sum(x - d["ub"] > tol))
    return viol


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("outdir")
    ap.add_argument("--count", type=int, default=100, help="files (default 100)")
    ap.add_argument("--seed", type=int, default=12, help="numpy seed (default 12)")
    ap.add_argument("--reach", type=float, default=None,
                    help="initial capture point uniform in REACH times the support "
                    "rectangle (default 0.85, with --full 0.7)")
    ap.add_argument("--prefix", default="LIPBAL",
                    help="file names PREFIX<k>.npz, k = 0..count-1 (default LIPBAL)")
    ap.add_argument("--full", action="store_true",
                    help="also A, b (terminal capture point) and lb, ub (jerk limits)")
    a = ap.parse_args()
    reach = a.reach if a.reach is not None else (0.7 if a.full else 0.85)
    os.makedirs(a.outdir, exist_ok=True)
    rng = np.random.default_rng(a.seed)
    mpc = Mpc(a.full)
    n_active, viol_rows = 0, []
    for k in range(a.count):
        x0, r = draw_state(rng, reach)
        d = mpc.qp(x0, r)
        write_npz(os.path.join(a.outdir, f"{a.prefix}{k}.npz"), d)
        v = needs_active(d)
        n_active += v > 0
        viol_rows.append(v)
    ev = np.linalg.eigvalsh(mpc.P)
    print(f"{a.count} files in {a.outdir}: n = {mpc.P.shape[0]}, m = {mpc.G.shape[0]}"
          + (", A 2 rows, lb/ub on all variables" if a.full else "")
          + f"; cond(P) = {ev[-1] / ev[0]:.3g}; "
          f"{n_active} need an active inequality (rows and bounds violated at the "
          f"unconstrained minimiser: median {np.median(viol_rows):.0f}, "
          f"max {max(viol_rows)})", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
