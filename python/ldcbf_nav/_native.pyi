"""Type stubs of the native module ``ldcbf_nav._native`` (built from src/lib.rs)."""

from typing import Any, Dict, List, Mapping, Optional, Sequence, Tuple, TypedDict, Union, final

import numpy as np
import numpy.typing as npt

_FloatArray = npt.NDArray[np.float64]
_ArrayLike = npt.ArrayLike

__all__ = [
    "ArgumentError",
    "CONFIG_FIELDS",
    "ConfigError",
    "Controller",
    "QP_SIZES",
    "ScenarioError",
    "default_config",
    "humanoid_config",
    "load_scenario",
    "simulate",
    "solve_qp",
]

CONFIG_FIELDS: List[str]
"""Names of the controller settings (``ldcbf_controller::Config`` fields)."""

QP_SIZES: List[Tuple[int, int]]
"""Compiled solver sizes ``(n, max m)`` of :func:`solve_qp`."""

class ArgumentError(ValueError):
    """A bad argument; ``field`` names the argument or setting."""

    field: str

class ConfigError(ArgumentError):
    """An invalid controller setting; ``field`` names it."""

    requirement: str

class ScenarioError(ArgumentError):
    """A scenario that cannot be used; ``field`` is the dotted path of the field."""

    file: str
    line: Optional[int]

class _Plan(TypedDict):
    """The predicted plan of a cycle."""

    x0: _FloatArray
    """``[px, py, vx, vy, theta]`` predicted at the end of the current step."""
    states: _FloatArray
    """``(N, 5)``: ``x_1 .. x_N`` as rows ``[px, py, vx, vy, theta]``."""
    feet: _FloatArray
    """``(N, 2)``: footsteps ``f_0 .. f_{N-1}``."""
    first_side: str
    """Side of ``f_0`` (the current swing foot): ``"left"`` or ``"right"``."""

class _Info(TypedDict):
    """Diagnostics of one cycle (``ldcbf_controller::CycleInfo``)."""

    qp_status: Optional[str]
    iterations: int
    active_set_size: int
    active_obstacles: int
    obstacles_truncated: bool
    inside_obstacle: bool
    time_clamped: bool
    warm_started: bool
    source: str
    cost: float
    max_violation: float
    min_h0: float
    relax_gait: float
    relax_safety: float
    relax_capture: float

class _StepOutput(TypedDict):
    """What :meth:`Controller.step` returns (``ldcbf_controller::CycleOutput``)."""

    foot_target: _FloatArray
    """Where the current swing foot should land, m (2,)."""
    turning_rate: float
    """Turning rate for the next step, rad/s."""
    status: str
    """``optimal``, ``infeasible``, ``budget_exhausted``, ``numerical_failure`` or ``invalid_input``."""
    input_error: Optional[str]
    """With ``invalid_input``: ``state``, ``stance_foot``, ``time_in_step``, ``goal`` or ``not_configured``."""
    plan: _Plan
    info: _Info

@final
class Controller:
    """The LDCBF footstep MPC (``ldcbf_controller::Controller``).

    ``config``: a dict of settings over :func:`default_config` (missing keys
    keep the default). ``size``: ``"robot"`` (horizon 3, 8 obstacles, foot
    rows possible; the simulator's) or ``"paper"`` (no foot rows).
    """

    def __new__(cls, config: Optional[Mapping[str, Any]] = None, *, size: str = "robot") -> "Controller": ...
    @property
    def config(self) -> Dict[str, Any]:
        """Every setting in use."""
    @property
    def size(self) -> str:
        """``"robot"`` or ``"paper"``."""
    @property
    def horizon(self) -> int:
        """Footsteps planned per cycle (3)."""
    @property
    def obstacle_capacity(self) -> int:
        """Obstacles used per cycle at most (the nearest 8)."""
    def reset(self) -> None:
        """Forgets the warm-start and fallback memory."""
    def step(
        self,
        com_position: _ArrayLike,
        com_velocity: _ArrayLike,
        heading: float,
        turning_rate: float,
        stance_foot: _ArrayLike,
        stance_side: str,
        time_in_step: float,
        goal: _ArrayLike,
        obstacles: Optional[Sequence[_ArrayLike]] = None,
        obstacle_velocities: Optional[_ArrayLike] = None,
        obstacle_velocity_radii: Optional[_ArrayLike] = None,
    ) -> _StepOutput:
        """One control cycle; ``obstacles`` are convex ``(k, 2)`` vertex arrays,
        ``obstacle_velocities`` their velocities ``(n, 2)`` in m/s (None: at rest),
        ``obstacle_velocity_radii`` their velocity uncertainty radii ``(n,)`` in m/s
        (None: all 0, velocities known)."""

def default_config() -> Dict[str, Any]:
    """The controller's defaults (the paper's Table I, a point robot)."""

def humanoid_config() -> Dict[str, Any]:
    """The simulator's default humanoid: body disk 0.25 m, feet 0.22 x 0.10 m, foot rows on."""

def solve_qp(
    P: _ArrayLike,
    q: _ArrayLike,
    G: Optional[_ArrayLike] = None,
    h: Optional[_ArrayLike] = None,
    *,
    max_iter: int = 1000,
    tol_primal: float = 1e-10,
    tol_dependence: float = 1e-12,
) -> Dict[str, Any]:
    """``min 1/2 x'Px + q'x`` s.t. ``Gx <= h`` with the controller's solver.

    Returns ``x``, ``lambda`` (one multiplier per row), ``objective``,
    ``status`` (``solved``, ``infeasible``, ``iteration_limit``,
    ``numerical_error``), ``iterations``, ``active_set`` and ``path``
    (``static`` when ``n`` and ``m`` fit one of the compiled sizes
    :data:`QP_SIZES`, ``dynamic`` otherwise: the run-time-sized instance of
    the same solver, any size). ``max_iter >= 1``; ``tol_primal`` and
    ``tol_dependence`` each in ``(0, 1e-3)`` (else ``ArgumentError``).
    """

DenseResult = Tuple[
    str,
    np.ndarray,
    np.ndarray,
    np.ndarray,
    Optional[np.ndarray],
    float,
    int,
]

def solve_dense(
    P: _ArrayLike,
    q: _ArrayLike,
    G: Optional[_ArrayLike] = None,
    h: Optional[_ArrayLike] = None,
    A: Optional[_ArrayLike] = None,
    b: Optional[_ArrayLike] = None,
    lb: Optional[_ArrayLike] = None,
    ub: Optional[_ArrayLike] = None,
    initvals: Optional[_ArrayLike] = None,
    *,
    max_iter: int = 1000,
    tol_primal: float = 1e-10,
    tol_dependence: float = 1e-12,
) -> DenseResult:
    """``min 1/2 x'Px + q'x`` s.t. ``Gx <= h``, ``Ax = b``, ``lb <= x <= ub``
    (qpsolvers' form), one cold solve.

    Equalities are held as equality rows, finite bounds as simple bounds
    (``-inf``/``+inf`` or an absent array: no bound). A C-contiguous float64
    array is read in place; anything else is converted once (complex
    entries refused). ``initvals``: a primal guess; the rows active or
    violated there enter the active set first. Solved at the smallest
    compiled size that holds ``n`` and the rows (:data:`QP_SIZES`), else by
    the run-time-sized instance.

    Returns ``(status, x, z, y, z_box, objective, iterations)``: ``z`` the
    multipliers of ``G x <= h`` (m,), ``y`` of ``A x = b`` (me,), ``z_box``
    of the bounds (n,; ``> 0`` where the upper bound is active, ``< 0`` the
    lower; None without bounds), with ``P x + q + G'z + A'y + z_box = 0`` at
    a solution. ``status``: ``solved``, ``infeasible`` (the multipliers hold
    the Farkas certificate), ``iteration_limit`` or ``numerical_error``.
    A bad member raises ``ArgumentError`` naming it (shape, non-finite
    entry, ``P`` not symmetric positive (semi)definite).
    """

class QpSolver:
    """Repeated QPs with one ``P`` (an MPC loop): ``P`` is checked and
    factored once; each :meth:`solve` reuses the factor and the row storage
    of the size chosen at the first solve (a compiled size when ``n`` and
    the rows fit one; a new instance when the rows outgrow it) and starts
    from the previous solve's active set (when the row count is unchanged).
    """

    def __init__(
        self,
        P: _ArrayLike,
        *,
        max_iter: int = 1000,
        tol_primal: float = 1e-10,
        tol_dependence: float = 1e-12,
    ) -> None: ...
    @property
    def n(self) -> int:
        """Number of variables."""
    @property
    def path(self) -> Optional[str]:
        """``static`` or ``dynamic``: the instance of the last solve (None before)."""
    def solve(
        self,
        q: _ArrayLike,
        G: Optional[_ArrayLike] = None,
        h: Optional[_ArrayLike] = None,
        A: Optional[_ArrayLike] = None,
        b: Optional[_ArrayLike] = None,
        lb: Optional[_ArrayLike] = None,
        ub: Optional[_ArrayLike] = None,
        *,
        warm_start: Union[bool, _ArrayLike, None] = True,
    ) -> DenseResult:
        """As :func:`solve_dense` with this ``P``. ``warm_start``: ``True``
        (the previous active set), ``False`` (cold) or a primal guess."""

def load_scenario(
    scenario: Union[str, Dict[str, Any]],
    seed: Optional[int] = None,
    sets: Optional[Dict[str, Any]] = None,
) -> Dict[str, Any]: ...
def simulate(
    scenario: Union[str, Dict[str, Any]],
    seed: Optional[int] = None,
    sets: Optional[Dict[str, Any]] = None,
    solver: str = "own",
    mpc_rate: Union[int, str, None] = None,
    trajectory_every: int = 1,
) -> Dict[str, Any]: ...
