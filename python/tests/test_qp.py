"""`ldcbf_nav.solve_qp`: optimality at every compiled size, and the CLI's
`ldcbf-sim qp solve` on the QPs a run exported, bit for bit."""

from __future__ import annotations

import csv
import io

import numpy as np
import pytest

import ldcbf_nav
from conftest import run_cli


def test_small_known_solution():
    # min sum (x_i - 1)^2 over 6 variables with x_0 + x_1 <= 1.
    P, q = 2 * np.eye(6), -2 * np.ones(6)
    G, h = np.array([[1.0, 1.0, 0, 0, 0, 0]]), np.array([1.0])
    s = ldcbf_nav.solve_qp(P, q, G, h)
    assert s["status"] == "solved"
    assert s["iterations"] == 1
    np.testing.assert_allclose(s["x"], [0.5, 0.5, 1, 1, 1, 1], atol=1e-14)
    assert abs(s["objective"] + 5.5) < 1e-12
    np.testing.assert_allclose(s["lambda"], [1.0], atol=1e-14)
    assert list(s["active_set"]) == [0]
    # No rows: the unconstrained minimiser.
    s = ldcbf_nav.solve_qp(P, q)
    np.testing.assert_allclose(s["x"], np.ones(6), atol=1e-14)
    assert s["lambda"].shape == (0,)


def test_infeasible_and_iteration_limit():
    P, q = 2 * np.eye(6), np.zeros(6)
    G = np.zeros((2, 6))
    G[0, 0], G[1, 0] = 1.0, -1.0
    s = ldcbf_nav.solve_qp(P, q, G, np.array([-1.0, -1.0]))  # x0 <= -1 and x0 >= 1
    assert s["status"] == "infeasible"
    G = np.vstack([-np.eye(6)])
    s = ldcbf_nav.solve_qp(P, q, G, -np.ones(6), max_iter=2)  # x >= 1: 6 adds needed
    assert s["status"] == "iteration_limit" and s["iterations"] == 2


@pytest.mark.parametrize("n, m", ldcbf_nav.QP_SIZES + [(2, 8), (7, 3), (50, 200)])
def test_kkt_at_every_compiled_size_and_others(n, m):
    """A random strictly convex QP, feasible by construction, at each compiled
    size's full row count and at sizes solved by the dynamic instance: the
    answer satisfies the KKT conditions."""
    rng = np.random.default_rng(n * 1000 + m)
    A = rng.standard_normal((n, n))
    P = A @ A.T + n * np.eye(n)
    q = rng.standard_normal(n) * 5
    G = rng.standard_normal((m, n))
    h = G @ rng.standard_normal(n) + rng.uniform(0.0, 1.0, m)
    s = ldcbf_nav.solve_qp(P, q, G, h)
    assert s["status"] == "solved", s["status"]
    x, lam = s["x"], s["lambda"]
    scale = 1.0 + np.abs(q).max() + np.abs(P).max()
    assert np.abs(P @ x + q + G.T @ lam).max() <= 1e-8 * scale  # stationarity
    assert (G @ x - h).max() <= 1e-8  # primal feasibility
    assert lam.min() >= 0.0  # dual feasibility
    assert np.abs(lam * (G @ x - h)).max() <= 1e-8 * scale  # complementarity
    assert abs(s["objective"] - (0.5 * x @ P @ x + q @ x)) <= 1e-9 * scale
    assert len(s["active_set"]) == np.count_nonzero(lam)


def test_matches_the_cli_solver_on_exported_qps(tmp_path):
    """`run --export-qps` writes every cycle's QP; `qp solve` prints status,
    iterations and the objective to 17 digits: solve_qp gives the same."""
    qdir = tmp_path / "qps"
    run_cli(
        "run", "paper", "--out", str(tmp_path / "out"), "--no-plots",
        "--set", "time_limit=10", "--export-qps", str(qdir),
    )
    files = sorted(qdir.glob("cycle_*.npz"))
    assert len(files) > 100
    files = files[::4]
    out = run_cli("qp", "solve", *map(str, files)).stdout
    rows = {r["file"]: r for r in csv.DictReader(io.StringIO(out))}
    assert len(rows) == len(files)
    for f in files:
        z = np.load(f)
        s = ldcbf_nav.solve_qp(z["P"], z["q"], z["G"], z["h"])
        r = rows[str(f)]
        assert s["status"] == r["status"], f.name
        assert s["iterations"] == int(r["iterations"]), f.name
        if s["status"] == "solved":
            # "{:.17e}" keeps 18 significant digits: the float reads back exactly.
            assert float(r["objective"]).hex() == s["objective"].hex(), f.name
