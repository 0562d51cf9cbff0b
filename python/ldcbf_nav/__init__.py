"""ldcbf-nav from Python: the LDCBF footstep MPC of a humanoid robot.

* :class:`Controller`: the controller of ``ldcbf-controller``; one
  :meth:`Controller.step` per control cycle, numpy arrays in and out.
* :func:`simulate`: a closed-loop run of the simulator behind ``ldcbf-sim run``
  (same scenarios, same ``--set`` overrides); its logs as numpy columns.
* :func:`load_scenario`: a scenario, validated as ``ldcbf-sim`` loads it.
* :func:`solve_qp`: the controller's dense dual active-set QP solver;
  :func:`solve_dense` the same in qpsolvers' problem form (equalities and
  bounds natively, numpy buffers read in place) and :class:`QpSolver` for
  repeated solves with one ``P`` (factored once, warm-started).
* qpsolvers: when it is installed, ``import ldcbf_nav`` registers the solver
  as ``"ldcbf"`` (:mod:`ldcbf_nav.qpsolvers_backend`).

Frames and units: world frame, metres, seconds, radians (headings
counter-clockwise from the world x axis).

A bad argument raises :class:`ArgumentError` (a :class:`ValueError`), or its
subclasses :class:`ConfigError` (a controller setting) and
:class:`ScenarioError` (a scenario field); the exception's ``field`` attribute
and its message name the argument or setting.
"""

from __future__ import annotations

import importlib.util
import os
from typing import Any, Dict, List, Mapping, Optional, Sequence, Tuple, Union

from . import _native
from ._native import (
    CONFIG_FIELDS,
    QP_SIZES,
    ArgumentError,
    ConfigError,
    Controller,
    QpSolver,
    ScenarioError,
    default_config,
    humanoid_config,
    solve_dense,
    solve_qp,
)

__all__ = [
    "ArgumentError",
    "CONFIG_FIELDS",
    "ConfigError",
    "Controller",
    "QP_SIZES",
    "QpSolver",
    "ScenarioError",
    "default_config",
    "humanoid_config",
    "load_scenario",
    "simulate",
    "solve_dense",
    "solve_qp",
]

__version__ = "0.1.0"

# The exceptions are defined in the extension; show them under the package.
for _exc in (ArgumentError, ConfigError, ScenarioError):
    _exc.__module__ = __name__
del _exc

# qpsolvers' solver "ldcbf" (ldcbf_nav/qpsolvers_backend.py), when qpsolvers
# is installed.
if importlib.util.find_spec("qpsolvers") is not None:
    from .qpsolvers_backend import register as _register

    _register()

ScenarioSpec = Union[str, "os.PathLike[str]", Mapping[str, Any]]


def _spec(scenario: ScenarioSpec) -> Union[str, Dict[str, Any]]:
    """A scenario name or path as a string, or a mapping as a dict."""
    if isinstance(scenario, Mapping):
        return dict(scenario)
    if isinstance(scenario, (str, os.PathLike)):
        return os.fspath(scenario)
    err = ArgumentError(
        f"scenario: expected a scenario name, a path or a dict, got {scenario!r}"
    )
    err.field = "scenario"
    raise err


def _sets(overrides: Mapping[str, Any]) -> Dict[str, Any]:
    """``--set`` keys: ``a__b`` is the dotted key ``a.b``; dotted keys pass as is."""
    return {k.replace("__", "."): v for k, v in overrides.items()}


def load_scenario(
    scenario: ScenarioSpec, *, seed: Optional[int] = None, **overrides: Any
) -> Dict[str, Any]:
    """Loads and validates a scenario as ``ldcbf-sim run`` does.

    ``scenario`` is a shipped scenario's name (``"maze"``: ``scenarios/maze.toml``
    of the current directory, else of the repository the package was built
    from), a path to a TOML file, or a dict with the keys of a scenario file.
    ``seed`` is ``--seed``; every other keyword is a ``--set key=value``
    override (``delta=0.3``, ``time_limit=20``, ``goal=[4, 4]``); a dotted key
    is written ``disturbance__push_time=2.0`` or passed as
    ``**{"disturbance.push_time": 2.0}``.

    Returns a dict: ``name``, ``start`` (2,), ``start_heading``, ``stance``,
    ``goal`` (2,), ``time_limit``, ``success_radius``, ``stuck_window``,
    ``planner``, ``perception``, ``seed``, ``config`` (the controller settings,
    for :class:`Controller`), ``robot`` and ``obstacles`` (a list of ``(k, 2)``
    vertex arrays, counter-clockwise: the true map).
    """
    return _native.load_scenario(_spec(scenario), seed, _sets(overrides))


def simulate(
    scenario: ScenarioSpec,
    *,
    seed: Optional[int] = None,
    solver: str = "own",
    mpc_rate: Union[int, str] = 20,
    trajectory_every: int = 1,
    **overrides: Any,
) -> Dict[str, Any]:
    """Runs a scenario in closed loop, as ``ldcbf-sim run`` (without figures).

    ``scenario``, ``seed`` and the keyword overrides are as in
    :func:`load_scenario`. ``solver`` is ``"own"`` or ``"clarabel"``;
    ``mpc_rate`` a rate in Hz (1..1000) or ``"step"`` (once per step);
    ``trajectory_every`` keeps every n-th 1 kHz plant sample (and the last) in
    ``trajectory``, as ``--trajectory-every``.

    Returns a dict:

    * ``outcome``: ``goal_reached``, ``time_limit``, ``stuck`` or ``diverged``;
    * ``summary``: the content of ``summary.json``;
    * ``cycles``, ``footsteps``, ``trajectory``: the columns of
      ``cycles.csv``, ``footsteps.csv`` and ``trajectory.csv`` as numpy
      arrays (strings as ``str`` arrays, flags as ``bool``), unrounded;
      ``cycles`` also has ``index``, ``goal_x``, ``goal_y`` (the goal given to
      the controller), ``subgoal`` and ``obstacles_seen``;
    * ``subgoals`` (k, 2) and ``scenario`` (as :func:`load_scenario`).
    """
    return _native.simulate(
        _spec(scenario), seed, _sets(overrides), solver, mpc_rate, trajectory_every
    )
