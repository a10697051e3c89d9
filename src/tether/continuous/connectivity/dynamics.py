"""Integration of eq. (1) for a stiff barrier: step rules that follow the force, and a guard.

The robot model (:mod:`tether.continuous.connectivity.robot`) is stepped by
semi-implicit Euler, :func:`~tether.continuous.connectivity.robot.damped_step`. The
connectivity potential of App. A grows without bound as lambda2 falls to ``lambda2_min``
(and the anchor potential of eq. (6) at the rim of its ball), so the force is stiff
exactly where it matters: an explicit step that is too long there overshoots into the
barrier, meets a huge force and throws the robot back with more energy than it had.
Inside each control period ``dt`` the step ``h`` is therefore chosen by two rules and
checked a posteriori:

1. **Displacement rule.** No robot moves more than ``max_step_m`` in one sub-step (a
   tenth of the narrowest transition band of the weights): ``h |v| + h^2 |f| / m <=
   max_step_m``, so the sampled force sees every band a robot enters
   (:func:`displacement_step`).
2. **Stiffness rule.** ``h omega <= stiffness_target``, with ``omega^2`` the largest
   stiffness per unit mass seen on the previous sub-step. After every candidate step the
   secant stiffness of the force along the motion is measured
   (:func:`substep_terms`): for robot ``i``, ``|f_i(q+) - f_i(q)| / (m r_i)`` where
   ``r_i`` is the largest displacement of ``i`` and its neighbours (whose motion changes
   ``f_i``). A candidate with ``h omega > stiffness_max`` is rejected and retried with
   ``h = stiffness_target / omega`` (at most halved), unless its local error is below
   ``tolerance_m``: the distance ``h^2 |f_i(q+) - f_i(q)| / (2 m)`` between the Euler step
   and the trapezoidal one (a tenth of ``max_step_m``). A force that jumps (a closest
   obstacle point that switches, a saturation) has an unbounded secant however short the
   step; the error test accepts its short steps, and bounds the chatter there to
   ``tolerance_m``. This is error control, not a veto: it looks at the force, never at
   lambda2, so a controller that would break connectivity still does, only resolved in
   time. The step never grows by more than ``growth`` per sub-step.

For the oscillator ``m x'' = -k x`` symplectic Euler is stable for ``h omega < 2`` and its
energy error per step is ``O((h omega)^2)``; ``stiffness_target = 0.3`` was chosen by the
passivity measurement in ``docs/continuous.md`` (with ``f_i = 0`` the energy of a team
released near the barrier never rises by more than ``1e-3`` of its start energy).

Guard
-----
``guard`` says what happens when a step would leave the safe set (the weighted lambda2 of
App. A at or below ``lambda2_min + lambda2_tolerance``, which holds exactly when the team
is disconnected, two robots are within ``Rc`` or a robot or a used line of sight is
within ``Ro`` of an obstacle):

* ``detect`` (the default): nothing is vetoed; every such sub-step is counted
  (``safe_set_exits``), so the result is the controller's own;
* ``enforce``: a safety net: a candidate must keep ``keep_fraction`` of the margin
  ``lambda2 - lambda2_min`` (and exceed it by ``lambda2_tolerance``); otherwise ``h`` is
  halved, and if no step is admissible, or the guard has rejected ``guard_budget``
  candidates in this period, the team brakes to rest for the rest of the period (a
  stall). Every rejection is a ``guard_intervention``;
* ``off``: no check (the estimator then never computes the exact lambda2).

A run whose guard intervened, whose step rule had to give up (``tolerance_misses``) or
whose team left the safe set is not a success of the controller (``controller_success``
in the summary).

Energy
------
With ``E = sum m |v|^2 / 2 + V(lambda2)`` the exact solution obeys ``dE = f_ext . dq -
B |v|^2 dt``. The residual of a sub-step, ``dE - f_ext . dq + h B |v+|^2``, is the energy
the integrator made or lost: its positive parts are summed as ``energy_added_j``, all of
it as ``energy_net_j`` (negative: the integrator dissipated); with the exact eigensolver,
where ``V`` is known.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import cache
from typing import Any, Literal, Protocol

import numpy as np

from tether import jit
from tether.continuous.connectivity.robot import RobotModel, damped_step, dissipation, stay_inside

Guard = Literal["enforce", "detect", "off"]
GUARDS: tuple[str, ...] = ("enforce", "detect", "off")


@dataclass(frozen=True)
class IntegratorParams:
    """The robot, the step rules and the guard (see the module docstring)."""

    robot: RobotModel = field(default_factory=RobotModel)
    max_step_m: float = 0.1
    tolerance_m: float = 1e-3
    stiffness_target: float = 0.3
    stiffness_max: float = 0.6
    growth: float = 2.0
    guard: Guard = "detect"
    keep_fraction: float = 0.5
    guard_budget: int = 100
    lambda2_tolerance: float = 1e-9
    max_retries: int = 30
    max_substeps: int = 10_000

    def __post_init__(self) -> None:
        if not (self.max_step_m > 0 and self.tolerance_m >= 0):
            raise ValueError("need max_step_m > 0 and tolerance_m >= 0")
        if not 0 < self.stiffness_target <= self.stiffness_max < 2:
            raise ValueError("need 0 < stiffness_target <= stiffness_max < 2")
        if not self.growth > 1:
            raise ValueError("growth must be > 1")
        if self.guard not in GUARDS:
            raise ValueError(f"guard must be one of {', '.join(GUARDS)}")
        if not 0 <= self.keep_fraction < 1:
            raise ValueError("keep_fraction must be in [0, 1)")

    @property
    def mass_kg(self) -> float:
        return self.robot.mass_kg


class System(Protocol):
    """What the integrator needs of a strategy.

    ``evaluate(q) -> (lambda2, cache)``: the exact weighted lambda2 of a configuration
    (``inf`` when it is not computed) and whatever the forces need; ``forces(q, v, cache)
    -> (f, f_conservative, h_move)``: the total force, its part that derives from the
    connectivity potential, and the displacement rule's step; ``accept(q, v, cache) ->
    bool``: a candidate became the state (advance stateful parts such as the estimator;
    True if the forces must then be evaluated again); ``neighbours(cache)``: the ``(m,
    2)`` pairs whose motion changes each other's force; ``potential(lambda2)``: ``V``.
    """

    def evaluate(self, q: np.ndarray) -> tuple[float, Any]: ...
    def forces(self, q: np.ndarray, v: np.ndarray, cache: Any) -> tuple: ...
    def accept(self, q: np.ndarray, v: np.ndarray, cache: Any) -> bool: ...
    def neighbours(self, cache: Any) -> np.ndarray: ...
    def potential(self, lambda2: float) -> float: ...


@dataclass
class IntegrationStats:
    """What happened inside one control period (or summed over a run)."""

    substeps: int = 0
    rejections: int = 0  # candidates the stiffness rule rejected (error control)
    guard_interventions: int = 0  # candidates the guard rejected, plus stalls
    stalls: int = 0  # periods in which the guard found no admissible step
    tolerance_misses: int = 0  # sub-steps accepted after max_retries without the rule met
    safe_set_exits: int = 0  # accepted sub-steps outside the safe set (detect)
    box_contacts: int = 0
    energy_added_j: float = 0.0
    energy_net_j: float = 0.0
    speed_limit_work_j: float = 0.0
    max_speed_mps: float = 0.0
    max_accel_mps2: float = 0.0
    min_lambda2: float = float("inf")
    min_step_s: float = float("inf")

    @property
    def stalled(self) -> bool:
        return self.stalls > 0

    def add(self, other: IntegrationStats) -> None:
        """Accumulate ``other`` (counts and energies add, extremes combine)."""
        for name in ("substeps", "rejections", "guard_interventions", "stalls",
                     "tolerance_misses", "safe_set_exits", "box_contacts", "energy_added_j",
                     "energy_net_j", "speed_limit_work_j"):  # fmt: skip
            setattr(self, name, getattr(self, name) + getattr(other, name))
        for name in ("max_speed_mps", "max_accel_mps2"):
            setattr(self, name, max(getattr(self, name), getattr(other, name)))
        for name in ("min_lambda2", "min_step_s"):
            setattr(self, name, min(getattr(self, name), getattr(other, name)))


@dataclass
class StepMemory:
    """The step rule's memory from sub-step to sub-step (and period to period): the last
    step the rules chose and the step they predict next."""

    h_s: float = float("inf")
    next_s: float = float("inf")
    jump_n: float = 0.0  # recent force jumps, halved at every sub-step


@cache
def _kernels() -> Any:
    """:mod:`~tether.continuous.connectivity.dynamics_kernels`, imported on first use (numba
    only when kernels run; an import statement in a per-sub-step function costs
    microseconds per call)."""
    from tether.continuous.connectivity import dynamics_kernels

    return dynamics_kernels


def displacement_step(v: np.ndarray, force: np.ndarray, mass: float, delta_m: float) -> float:
    """The largest ``h`` with ``h |v_i| + h^2 |f_i| / m <= delta_m`` for every robot."""
    if jit.enabled():
        displacement_kernel = _kernels().displacement_kernel
        return float(displacement_kernel(np.ascontiguousarray(v, dtype=float),
                                         np.ascontiguousarray(force, dtype=float), mass,
                                         delta_m))  # fmt: skip
    vmax = float(np.max(np.sqrt((v * v).sum(axis=1)), initial=0.0))
    fmax = float(np.max(np.sqrt((force * force).sum(axis=1)), initial=0.0))
    disc = vmax * vmax + 4.0 * delta_m * fmax / mass
    denom = vmax + np.sqrt(disc)
    return float("inf") if denom <= 0 else 2.0 * delta_m / denom


def robot_step(
    q: np.ndarray,
    v: np.ndarray,
    force: np.ndarray,
    h: float,
    robot: RobotModel,
    box: np.ndarray | None = None,
    margin_m: float = 0.0,
) -> tuple[np.ndarray, np.ndarray, int, float, float]:
    """:func:`~tether.continuous.connectivity.robot.damped_step` then the box: ``(q+, v+, contacts,
    dissipated, speed_limit)`` (:func:`~tether.continuous.connectivity.robot.dissipation`)."""
    if jit.enabled():
        step_kernel = _kernels().step_kernel
        corners = np.zeros((0, q.shape[1])) if box is None else np.ascontiguousarray(box, float)
        return step_kernel(np.ascontiguousarray(q, dtype=float),
                           np.ascontiguousarray(v, dtype=float),
                           np.ascontiguousarray(force, dtype=float), float(h), robot.mass_kg,
                           robot.damping_ns_per_m, robot.max_speed_mps, robot.speed_damping_n,
                           corners, float(margin_m))  # fmt: skip
    q_new, v_new = damped_step(q, v, force, h, robot)
    diss, limit = dissipation(v, force, h, robot)
    if box is None:
        return q_new, v_new, 0, diss, limit
    q_box, v_box = stay_inside(q, q_new, v_new, box, margin_m)
    return q_box, v_box, int(np.count_nonzero(q_box != q_new)), diss, limit


def _sequential_sum(x: np.ndarray) -> float:
    """The sum of ``x`` in C order, one term after the other (the kernels' order)."""
    return float(np.cumsum(x.ravel())[-1]) if x.size else 0.0


def substep_terms(
    q: np.ndarray,
    v: np.ndarray,
    q1: np.ndarray,
    v1: np.ndarray,
    f: np.ndarray,
    f1: np.ndarray,
    f_c: np.ndarray,
    pairs: np.ndarray,
    h: float,
    mass_kg: float,
) -> tuple[float, float, float, float, float, float]:
    """What one candidate step tells: ``(omega2, jump, work, kinetic, max_speed, max_accel)``.

    ``omega2``: the secant stiffness per unit mass (module docstring, rule 2); ``jump``: the
    largest change ``|f_i(q+) - f_i(q)|`` of a robot's force; ``work``:
    ``(f - f_c) . dq``, the work of the forces that do not derive from the connectivity
    potential; ``kinetic``: the change of kinetic energy; the largest speed and
    acceleration ``|v+ - v| / h`` of a robot.
    """
    if jit.enabled():
        terms_kernel = _kernels().terms_kernel
        c = np.ascontiguousarray
        return terms_kernel(c(q, dtype=float), c(v, dtype=float), c(q1, dtype=float),
                            c(v1, dtype=float), c(f, dtype=float), c(f1, dtype=float),
                            c(f_c, dtype=float), c(pairs, dtype=np.int64), float(h),
                            float(mass_kg))  # fmt: skip
    m = mass_kg
    d = q1 - q
    g = f1 - f
    dq = np.sqrt((d * d).sum(axis=1))
    df = np.sqrt((g * g).sum(axis=1))
    work = _sequential_sum((f - f_c) * d)
    kinetic = _sequential_sum(0.5 * m * (v1 * v1 - v * v))
    a = v1 - v
    speed = float(np.max(np.sqrt((v1 * v1).sum(axis=1)), initial=0.0))
    accel = float(np.max(np.sqrt((a * a).sum(axis=1)) / h, initial=0.0))
    reach = dq.copy()
    if len(pairs):
        np.maximum.at(reach, pairs[:, 0], dq[pairs[:, 1]])
        np.maximum.at(reach, pairs[:, 1], dq[pairs[:, 0]])
    moved = reach > 0
    omega2 = float(np.max(df[moved] / (m * reach[moved]), initial=0.0))
    if np.any(df[~moved] > 0):
        omega2 = float("inf")
    return omega2, float(np.max(df, initial=0.0)), work, kinetic, speed, accel


def integrate(
    q: np.ndarray,
    v: np.ndarray,
    dt_s: float,
    system: System,
    params: IntegratorParams,
    lambda2_min: float,
    current: tuple[float, Any] | None = None,
    box: np.ndarray | None = None,
    box_margin_m: float = 0.0,
    memory: StepMemory | None = None,
) -> tuple[np.ndarray, np.ndarray, tuple[float, Any], IntegrationStats]:
    """Advance eq. (1) by ``dt_s`` with adaptive sub-steps (see the module docstring).

    Parameters
    ----------
    q, v
        ``(n, dim)`` positions and velocities.
    dt_s
        The control period to cover.
    system
        The strategy's forces and evaluation (:class:`System`).
    params, lambda2_min
        The robot, the step rules and the guard; the barrier's lambda2.
    current
        ``system.evaluate(q)`` if already known (reused from the previous period).
    box, box_margin_m
        ``(2, dim)`` lower and upper corners of the world, kept ``box_margin_m`` away
        (:func:`~tether.continuous.connectivity.robot.stay_inside`); ``None`` for unbounded space.
    memory
        The step rule's memory, carried from period to period (updated in place).

    Returns
    -------
    q, v, the evaluation at the final ``q``, the period's statistics.
    """
    stats = IntegrationStats()
    memory = memory if memory is not None else StepMemory()
    robot, guard = params.robot, params.guard
    tol = params.lambda2_tolerance
    ev = current if current is not None else system.evaluate(q)
    f, f_c, h_move = system.forces(q, v, ev[1])
    t = 0.0
    while t < dt_s * (1 - 1e-12) and stats.substeps < params.max_substeps:
        lam = ev[0]
        h = min(dt_s - t, h_move, params.growth * memory.h_s, memory.next_s)
        floor = lambda2_min + params.keep_fraction * (lam - lambda2_min)
        accepted = guarded = False
        for _ in range(params.max_retries + 1):
            h_try = h
            q1, v1, contacts, diss, limit = robot_step(q, v, f, h_try, robot, box,
                                                       box_margin_m)  # fmt: skip
            ev1 = system.evaluate(q1)
            guarded = guard == "enforce" and not (ev1[0] > floor and ev1[0] > lambda2_min + tol)
            if guarded:
                stats.guard_interventions += 1
                if stats.guard_interventions >= params.guard_budget:
                    break  # the guard has held the team long enough this period: brake
                h *= 0.5
                continue
            f1, f_c1, h_move1 = system.forces(q1, v1, ev1[1])
            terms = substep_terms(q, v, q1, v1, f, f1, f_c, system.neighbours(ev1[1]), h_try,
                                  robot.mass_kg)  # fmt: skip
            finite = bool(np.isfinite(f1).all())  # an undefined force is never accepted
            omega2, jump = (terms[0], terms[1]) if finite else (math.inf, math.inf)
            # the longest steps that would meet each test (the error's with a margin)
            h_stiff = params.stiffness_target / math.sqrt(omega2) if omega2 > 0 else math.inf
            h_err = 0.9 * math.sqrt(2.0 * robot.mass_kg * params.tolerance_m / jump) \
                if jump > 0 else math.inf  # fmt: skip
            error_m = 0.5 * h_try * h_try * jump / robot.mass_kg
            if h_try * h_try * omega2 <= params.stiffness_max**2 or error_m <= params.tolerance_m:
                accepted = True
                break
            stats.rejections += 1
            h = min(0.5 * h_try, max(h_stiff, h_err)) if math.isfinite(jump) else 0.5 * h_try
        if guarded:  # enforce: no admissible step; stop and brake, never cross the invariant
            stats.stalls += 1
            v = np.zeros_like(v)
            break
        if not accepted:  # the rule could not be met: take the shortest step tried, say so
            if not np.all(np.isfinite(f1)):
                raise FloatingPointError(f"non-finite force after {params.max_retries} retries")
            stats.tolerance_misses += 1
        _, _, work, kinetic, speed, accel = terms
        if math.isfinite(lam) and math.isfinite(ev1[0]):
            residual = kinetic + system.potential(ev1[0]) - system.potential(lam) - work + diss
            if math.isfinite(residual):
                stats.energy_added_j += max(residual, 0.0)
                stats.energy_net_j += residual
        stats.speed_limit_work_j += limit
        stats.max_speed_mps = max(stats.max_speed_mps, speed)
        stats.max_accel_mps2 = max(stats.max_accel_mps2, accel)
        stats.box_contacts += contacts
        stats.min_lambda2 = min(stats.min_lambda2, ev1[0])
        if guard == "detect" and not ev1[0] > lambda2_min + tol:
            stats.safe_set_exits += 1
        stats.substeps += 1
        stats.min_step_s = min(stats.min_step_s, h_try)
        if h_try < dt_s - t:  # a step the rules chose, not the rest of the period
            memory.h_s = h_try
        # a force that jumps once often jumps back (a kink of the potential: a switch of
        # the closest obstacle point, of the eigenvector of a repeated lambda2): the next
        # step is sized for the largest recent jump, not for this step's alone
        memory.jump_n = max(jump, 0.5 * memory.jump_n)
        h_recent = 0.9 * math.sqrt(2.0 * robot.mass_kg * params.tolerance_m / memory.jump_n) \
            if memory.jump_n > 0 else math.inf  # fmt: skip
        memory.next_s = max(h_stiff, h_recent)
        if system.accept(q1, v1, ev1[1]):
            f1, f_c1, h_move1 = system.forces(q1, v1, ev1[1])
        q, v, ev, f, f_c, h_move = q1, v1, ev1, f1, f_c1, h_move1
        t += h_try
    return q, v, ev, stats
