"""Solver interface for the dense dual active-set solver of ldcbf-nav.

Written as a `qpsolvers <https://github.com/qpsolvers/qpsolvers>`__ backend
module (the layout of ``qpsolvers/solvers/daqp_.py``): ``ldcbf_solve_problem``
and ``ldcbf_solve_qp``, ready to be proposed upstream as
``qpsolvers/solvers/ldcbf_.py``. Until then :func:`register` (called by
``import ldcbf_nav`` when qpsolvers is installed) adds ``"ldcbf"`` to
``qpsolvers.available_solvers`` and ``qpsolvers.dense_solvers``, so that
``qpsolvers.solve_qp(..., solver="ldcbf")`` and ``solve_problem`` work.

The solver is a dense dual active-set method (Goldfarb-Idnani family) on the
Cholesky factor of ``P``, written for the footstep MPC of ldcbf-nav
(``controller/src/qp/``, ``no_std``, no heap). Equalities ``A x = b`` are
held as equality rows and the box ``lb <= x <= ub`` as simple bounds, both
natively; ``initvals`` warm-starts the solve from the rows active (or
violated) at that primal guess. It takes dense matrices: a
``scipy.sparse`` matrix is refused with :class:`qpsolvers.ProblemError`
(densify it with ``.toarray()``; the solver is meant for small dense
problems).

**Warm-start:** this solver interface supports warm starting 🔥
"""

import time
import warnings
from typing import Optional

import numpy as np
from qpsolvers.exceptions import ProblemError
from qpsolvers.problem import Problem
from qpsolvers.solution import Solution

from ._native import ArgumentError, solve_dense


def ldcbf_solve_problem(
    problem: Problem,
    initvals: Optional[np.ndarray] = None,
    verbose: bool = False,
    **kwargs,
) -> Solution:
    """Solve a quadratic program using ldcbf-nav's dual active-set solver.

    Parameters
    ----------
    problem :
        Quadratic program to solve (dense matrices).
    initvals :
        Warm-start guess vector for the primal solution: the rows active or
        violated at this point enter the active set first.
    verbose :
        Set to `True` to print out extra information.

    Returns
    -------
    :
        Solution to the QP; ``found`` is False when the problem is
        infeasible (a Farkas certificate was found), when the iteration
        limit is reached or on a numerical error (for instance a problem
        unbounded below); ``extras`` holds ``status`` and ``iterations``.

    Raises
    ------
    ProblemError :
        If a matrix is sparse, if ``P`` is not symmetric positive
        (semi)definite, or if a member has a wrong shape or a non-finite
        entry (the message names the member).

    Notes
    -----
    Keyword arguments set the solver settings:

    .. list-table::
       :widths: 30 70
       :header-rows: 1

       * - Name
         - Description
       * - ``max_iter``
         - Maximum number of iterations (adds plus drops), default 1000.
       * - ``tol_primal``
         - Primal feasibility tolerance on rows scaled to unit norm, in
           ``(0, 1e-3)``, default ``1e-10``.
       * - ``tol_dependence``
         - Linear-dependence tolerance of a new active row, in
           ``(0, 1e-3)``, default ``1e-12``.
    """
    build_start_time = time.perf_counter()
    if problem.has_sparse:
        raise ProblemError(
            "ldcbf takes dense matrices; problem has sparse matrices "
            "(convert them with .toarray())"
        )
    P, q, G, h, A, b, lb, ub = problem.unpack()
    solve_start_time = time.perf_counter()
    try:
        status, x, z, y, z_box, obj, iterations = solve_dense(
            P, q, G, h, A, b, lb, ub, initvals, **kwargs
        )
    except ArgumentError as error:
        raise ProblemError(str(error)) from error
    solve_end_time = time.perf_counter()
    solution = Solution(problem)
    solution.extras = {"status": status, "iterations": iterations}
    solution.found = status == "solved"
    if solution.found:
        solution.x = x
        solution.obj = obj
        solution.z = z
        solution.y = y
        solution.z_box = z_box
    elif verbose:
        warnings.warn(f"ldcbf: {status} after {iterations} iterations")
    solution.build_time = solve_start_time - build_start_time
    solution.solve_time = solve_end_time - solve_start_time
    return solution


def ldcbf_solve_qp(
    P: np.ndarray,
    q: np.ndarray,
    G: Optional[np.ndarray] = None,
    h: Optional[np.ndarray] = None,
    A: Optional[np.ndarray] = None,
    b: Optional[np.ndarray] = None,
    lb: Optional[np.ndarray] = None,
    ub: Optional[np.ndarray] = None,
    initvals: Optional[np.ndarray] = None,
    verbose: bool = False,
    **kwargs,
) -> Optional[np.ndarray]:
    r"""Solve a quadratic program using ldcbf-nav's dual active-set solver.

    The quadratic program is defined as:

    .. math::

        \begin{split}\begin{array}{ll}
            \underset{x}{\mbox{minimize}} &
                \frac{1}{2} x^T P x + q^T x \\
            \mbox{subject to}
                & G x \leq h                \\
                & A x = b                   \\
                & lb \leq x \leq ub
        \end{array}\end{split}

    Parameters and settings are those of :func:`ldcbf_solve_problem`.

    Returns
    -------
    :
        Primal solution to the QP, if found, otherwise ``None``.
    """
    problem = Problem(P, q, G, h, A, b, lb, ub)
    solution = ldcbf_solve_problem(problem, initvals, verbose, **kwargs)
    return solution.x if solution.found else None


def register() -> None:
    """Adds ``"ldcbf"`` to qpsolvers' solver tables (once).

    ``qpsolvers.available_solvers``, ``qpsolvers.dense_solvers`` and the
    table ``solve_problem`` dispatches on, as qpsolvers' own
    ``solvers/__init__.py`` does for each solver it finds installed.
    """
    import qpsolvers
    from qpsolvers import solvers

    solvers.solve_function["ldcbf"] = ldcbf_solve_problem
    for table in (solvers.available_solvers, solvers.dense_solvers):
        if "ldcbf" not in table:
            table.append("ldcbf")
    # qpsolvers re-exports the same list objects; keep them in step if a
    # version ever copies them.
    for name in ("available_solvers", "dense_solvers"):
        table = getattr(qpsolvers, name, None)
        if isinstance(table, list) and "ldcbf" not in table:
            table.append("ldcbf")
