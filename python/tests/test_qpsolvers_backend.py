"""The solver through qpsolvers (`solver="ldcbf"`, registered by `import
ldcbf_nav`), `solve_dense` and the reusable `QpSolver`."""

from __future__ import annotations

import numpy as np
import pytest

import ldcbf_nav

qpsolvers = pytest.importorskip("qpsolvers")
from qpsolvers import Problem, ProblemError, solve_problem, solve_qp  # noqa: E402


def kkt_ok(sol, tol=1e-9):
    """qpsolvers' own residuals of a found solution below `tol`."""
    assert sol.found
    assert sol.primal_residual() < tol
    assert sol.dual_residual() < tol
    assert abs(sol.duality_gap()) < tol


def random_problem(n, m, me, seed, bounds=True):
    """A strictly convex QP, feasible by construction, with equalities and a
    box around a known feasible point."""
    rng = np.random.default_rng(seed)
    M = rng.standard_normal((n, n))
    P = M @ M.T + n * np.eye(n)
    q = 10 * rng.standard_normal(n)
    x0 = rng.standard_normal(n)
    G = rng.standard_normal((m, n))
    h = G @ x0 + rng.uniform(0.0, 0.5, m)
    A = rng.standard_normal((me, n)) if me else None
    b = A @ x0 if me else None
    lb = x0 - rng.uniform(0.05, 0.5, n) if bounds else None
    ub = x0 + rng.uniform(0.05, 0.5, n) if bounds else None
    return Problem(P, q, G, h, A, b, lb, ub)


def test_registered():
    assert "ldcbf" in qpsolvers.available_solvers
    assert "ldcbf" in qpsolvers.dense_solvers


@pytest.mark.parametrize("n, m, me", [(6, 10, 0), (6, 10, 2), (16, 20, 3), (50, 100, 5)])
def test_equalities_and_bounds(n, m, me):
    """Equalities, inequalities and both bounds natively: qpsolvers'
    residuals (which read y, z and z_box) below 1e-9, and the box
    multipliers signed as qpsolvers defines them."""
    prob = random_problem(n, m, me, seed=n + m + me)
    sol = solve_problem(prob, solver="ldcbf")
    kkt_ok(sol)
    assert sol.y.shape == (me,) and sol.z.shape == (m,) and sol.z_box.shape == (n,)
    assert sol.z.min() >= 0.0
    at_lb = np.isclose(sol.x, prob.lb, atol=1e-9)
    at_ub = np.isclose(sol.x, prob.ub, atol=1e-9)
    assert (sol.z_box[~at_lb & ~at_ub] == 0.0).all()
    assert (sol.z_box[at_lb] <= 0.0).all() and (sol.z_box[at_ub] >= 0.0).all()
    assert at_lb.any() or at_ub.any(), "the box should bind somewhere"
    # solve_qp gives the same x.
    x = solve_qp(*prob.unpack(), solver="ldcbf")
    assert np.array_equal(x, sol.x)


def test_one_sided_and_infinite_bounds():
    prob = random_problem(8, 4, 1, seed=3)
    lb = prob.lb.copy()
    lb[::2] = -np.inf
    for lo, up in ((lb, None), (None, prob.ub), (lb, np.full(8, np.inf))):
        p = Problem(prob.P, prob.q, prob.G, prob.h, prob.A, prob.b, lo, up)
        kkt_ok(solve_problem(p, solver="ldcbf"))


def test_warm_start_from_initvals():
    """initvals = the solution: the same x, in no more iterations; a wrong
    guess still ends at the solution."""
    prob = random_problem(20, 40, 2, seed=7)
    cold = solve_problem(prob, solver="ldcbf")
    warm = solve_problem(prob, solver="ldcbf", initvals=cold.x)
    kkt_ok(warm)
    assert np.abs(warm.x - cold.x).max() < 1e-10
    assert warm.extras["iterations"] <= cold.extras["iterations"]
    assert cold.extras["iterations"] > 2
    wrong = solve_problem(prob, solver="ldcbf", initvals=np.full(20, 1e3))
    kkt_ok(wrong)
    assert np.abs(wrong.x - cold.x).max() < 1e-10


def test_infeasible():
    """x_0 <= -1 and x_0 >= 1: not found, x None (as qpsolvers expects)."""
    P, q = np.eye(3), np.ones(3)
    G = np.array([[1.0, 0, 0], [-1.0, 0, 0]])
    h = np.array([-1.0, -1.0])
    sol = solve_problem(Problem(P, q, G, h), solver="ldcbf")
    assert sol.found is False and sol.x is None
    assert sol.extras["status"] == "infeasible"
    assert solve_qp(P, q, G, h, solver="ldcbf") is None
    # Bounds against an equality.
    A, b = np.array([[1.0, 1.0, 1.0]]), np.array([10.0])
    sol = solve_problem(
        Problem(P, q, None, None, A, b, -np.ones(3), np.ones(3)), solver="ldcbf"
    )
    assert sol.found is False and sol.extras["status"] == "infeasible"


def test_unbounded_below():
    """qpsolvers' unbounded case (q in the null space of a rank-one P): no
    solution is returned, either as ProblemError or as not found."""
    v = np.array([5.4, -1.2, -1e-2, 1e4])
    P = np.outer(v, v)
    q = np.array([-1.0, -2, 0, 3e-4])
    try:
        sol = solve_problem(Problem(P, q), solver="ldcbf")
    except ProblemError:
        return
    assert sol.found is False and sol.x is None


def test_refused_inputs():
    scipy_sparse = pytest.importorskip("scipy.sparse")
    P = scipy_sparse.csc_matrix(np.eye(3))
    with pytest.raises(ProblemError, match="sparse"):
        solve_qp(P, np.ones(3), solver="ldcbf")
    with pytest.raises(ProblemError, match="positive definite"):
        solve_qp(np.diag([1.0, -1.0, 1.0]), np.ones(3), solver="ldcbf")
    with pytest.raises(ProblemError, match="symmetric"):
        solve_qp(np.array([[2.0, 1.0], [0.0, 2.0]]), np.ones(2), solver="ldcbf")
    with pytest.raises(ProblemError, match="`h`"):
        solve_qp(np.eye(2), np.ones(2), np.eye(2), np.array([1.0, np.nan]), solver="ldcbf")


def test_complex_p_is_refused():
    P = np.eye(3) * (1 + 1j)
    with pytest.raises(ldcbf_nav.ArgumentError, match="complex") as e:
        ldcbf_nav.solve_qp(P, np.ones(3))
    assert e.value.field == "P"
    with pytest.raises(ldcbf_nav.ArgumentError, match="complex"):
        ldcbf_nav.solve_dense(np.eye(3), [1j, 0, 0])


def test_non_contiguous_and_other_dtypes_read_the_same():
    prob = random_problem(16, 30, 0, seed=5, bounds=False)
    ref = ldcbf_nav.solve_dense(prob.P, prob.q, prob.G, prob.h)
    GF = np.asfortranarray(prob.G)
    for args in (
        (prob.P, prob.q, GF, prob.h),
        (prob.P.astype(np.float32).astype(np.float64), prob.q, prob.G, prob.h),
        (prob.P.tolist(), list(prob.q), prob.G[:, :], prob.h),
    ):
        r = ldcbf_nav.solve_dense(*args)
        assert r[0] == "solved"
    r = ldcbf_nav.solve_dense(prob.P, prob.q, GF, prob.h)
    assert np.array_equal(r[1], ref[1])


def test_qp_solver_object():
    """QpSolver: P factored once; solves equal solve_dense's; the warm start
    from the previous active set takes fewer iterations in sequence."""
    probs = [random_problem(16, 30, 0, seed=s, bounds=False) for s in range(5)]
    P = probs[0].P
    s = ldcbf_nav.QpSolver(P)
    assert s.n == 16 and s.path is None
    cold_iters = warm_iters = 0
    for p in probs:
        ref = ldcbf_nav.solve_dense(P, p.q, p.G, p.h)
        cold = s.solve(p.q, p.G, p.h, warm_start=False)
        assert cold[0] == ref[0] == "solved"
        assert np.array_equal(cold[1], ref[1]) and cold[6] == ref[6]
        cold_iters += cold[6]
    assert s.path == "static"
    # Solving the same problem twice: the second starts from the first's
    # active set.
    for p in probs:
        s.solve(p.q, p.G, p.h, warm_start=False)
        warm = s.solve(p.q, p.G, p.h)
        ref = ldcbf_nav.solve_dense(P, p.q, p.G, p.h)
        assert np.abs(warm[1] - ref[1]).max() < 1e-10
        warm_iters += warm[6]
    assert warm_iters < cold_iters
    # More rows than the first sizing: a new instance, same answers.
    big = random_problem(16, 200, 0, seed=9, bounds=False)
    r = s.solve(big.q, big.G, big.h)
    assert r[0] == "solved" and s.path == "dynamic"
    with pytest.raises(ldcbf_nav.ArgumentError, match="q"):
        s.solve(np.ones(3))
    with pytest.raises(ldcbf_nav.ArgumentError, match="P"):
        ldcbf_nav.QpSolver(-np.eye(3))
