"""Each built-in strategy's own summary keys and Parquet columns, described.

:data:`STRATEGY_OUTPUTS` maps a strategy to the keys it adds to ``summary.json``
(:meth:`tether.sim.Strategy.metrics`), ``steps.parquet`` (``step_values``) and
``robots.parquet`` (``robot_values``).
"""

from __future__ import annotations

from dataclasses import dataclass, field

from tether.recurrent.exploration.metrics import THRESHOLDS, RobotState
from tether.reference.outputs import Output


@dataclass(frozen=True)
class StrategyOutputs:
    """What one strategy adds to the run folder."""

    summary: dict[str, Output] = field(default_factory=dict)
    steps: dict[str, Output] = field(default_factory=dict)
    robots: dict[str, Output] = field(default_factory=dict)


_WAYPOINTS = "the leader follows waypoints"
_ESTIMATOR = "eigensolver: estimator"
_FILTER = "reference_filter: true"

SILENT = StrategyOutputs(
    summary={
        "leader_reached_goal": Output("the leader reached the end of its path"),
        "leader_travel_m": Output("distance the leader travelled"),
        "leader_blocked_steps": Output("steps in which the constraints held the leader back"),
        "path_length_m": Output("length of the leader's path", when=_WAYPOINTS),
        "path_progress": Output("fraction of its path the leader covered", when=_WAYPOINTS),
    }
)

CONNECTIVITY = StrategyOutputs(
    summary={
        "min_lambda2_weighted": Output("least lambda2 of the weighted graph, every sub-step"),
        "min_robot_distance_m": Output("least distance between two linked robots"),
        "min_obstacle_clearance_m": Output("least distance of a robot to an obstacle point"),
        "guard": Output("the guard mode: detect, enforce or off"),
        "controller_success": Output(
            "no guard intervention, no safe-set exit, no tolerance miss (null: guard off)"
        ),
        "guard_interventions": Output("candidate sub-steps the guard rejected"),
        "safe_set_exits": Output("accepted sub-steps that left the safe set"),
        "stalls": Output("control periods in which the team braked to rest"),
        "substeps": Output("integrator sub-steps taken"),
        "rejected_substeps": Output("candidate sub-steps the step rules rejected"),
        "tolerance_misses": Output("sub-steps at which the step rules gave up"),
        "min_substep_s": Output("shortest sub-step"),
        "max_speed_mps": Output("largest robot speed"),
        "speed_bound_mps": Output("the robots' top speed"),
        "max_accel_mps2": Output("largest commanded acceleration"),
        "energy_added_j": Output("energy the integrator added (positive residuals summed)"),
        "energy_net_j": Output("the integrator's energy residual, summed (negative: lost)"),
        "speed_limit_work_j": Output("energy taken by the speed-limiting damping"),
        "box_contacts": Output("sub-steps at which a robot met the world's box"),
        "eigensolver": Output("exact or estimator"),
        "estimator_lambda2_rel_error_max": Output(
            "largest relative error of a robot's lambda2 estimate", when=_ESTIMATOR
        ),
        "estimator_lambda2_rel_error_mean": Output(
            "mean relative error of the robots' lambda2 estimates", when=_ESTIMATOR
        ),
        "estimator_vector_error_max": Output(
            "largest error of an estimated Fiedler vector component", when=_ESTIMATOR
        ),
        "message_delivery_ratio": Output("fraction of messages delivered", when=_ESTIMATOR),
    },
    steps={
        "max_speed_mps": Output("largest robot speed in the control period"),
        "max_accel_mps2": Output("largest commanded acceleration in the control period"),
        "substeps": Output("sub-steps in the control period"),
        "rejected_substeps_total": Output("rejected candidate sub-steps so far"),
        "guard_interventions_total": Output("guard interventions so far"),
        "safe_set_exits_total": Output("safe-set exits so far"),
        "energy_added_j_total": Output("energy the integrator added so far"),
    },
)

_MULTI_TARGET_OWN = StrategyOutputs(
    summary={
        "targets_total": Output("targets the run used"),
        "targets_reached": Output("targets reached"),
        "targets_dropped": Output("targets given up (unreachable, expired, stalled)"),
        "targets_pending": Output("targets neither reached nor dropped at the end"),
        "replans": Output("paths planned again"),
        "completion_time_s": Output("when every target was reached (null: dropped or pending)"),
        "explorers": Output("robots that had targets"),
        "mean_explorer_distance_m": Output("mean distance travelled by the explorers"),
        "max_explorer_stretch_m": Output("largest distance between two explorers"),
        "mean_lambda2_weighted": Output("mean lambda2 of the weighted graph"),
        "elections": Output("elections of the prime traveler decided"),
        "max_simultaneous_primes": Output("most prime travelers at one step"),
        "prime_vacant_steps": Output("control periods with travelers but no prime"),
        "longest_prime_vacancy_steps": Output("longest run of such periods"),
        "anchor_outside_steps": Output("control periods an anchor spent outside its ball"),
        "help_requests": Output("help requests of stalled primes"),
        "helper_robot_s": Output("robot-seconds spent helping"),
        "reference_filter_max_deviation_m": Output(
            "largest distance between a robot and its filtered reference", when=_FILTER
        ),
        "reference_filter_max_speed_mps": Output("largest reference speed", when=_FILTER),
        "reference_filter_max_accel_mps2": Output("largest reference acceleration", when=_FILTER),
    },
    steps={
        "lambda2_weighted": Output("lambda2 of the weighted graph"),
        "prime": Output("the prime traveler (-1: none)"),
        "n_travelers": Output("prime and secondary travelers"),
        "n_anchors": Output("anchors"),
        "prime_efficiency": Output("the prime's efficiency, eq. (9) (NaN: no prime travels)"),
    },
    robots={
        "role": Output("connector, prime, secondary or anchor"),
        **{
            f"{axis}_ref_m": Output(f"{axis} of the filtered reference", when=_FILTER)
            for axis in "xyz"
        },
    },
)

MULTI_TARGET = StrategyOutputs(
    summary={**CONNECTIVITY.summary, **_MULTI_TARGET_OWN.summary},
    steps={**CONNECTIVITY.steps, **_MULTI_TARGET_OWN.steps},
    robots=_MULTI_TARGET_OWN.robots,
)

_EXPLORATION = StrategyOutputs(
    summary={
        "final_explored_fraction": Output(
            "fraction of the free space reachable from the base station known there at the end"
        ),
        "out_of_comm_mean_steps": Output("steps without a link to the base station, mean"),
        "out_of_comm_max_steps": Output("steps without a link to the base station, largest"),
        "out_of_comm_per_robot_steps": Output("steps without a link to the base station, each"),
        **{
            f"time_to_{round(100 * level)}pct_s": Output(
                f"time until {round(100 * level)} % was explored (null: never)"
            )
            for level in THRESHOLDS
        },
        **{
            f"time_{name}_frac": Output(f"share of the live robots' steps spent {name}")
            for name in RobotState.NAMES[: RobotState.FAILED]
        },
        "out_of_comm_episodes": Output("episodes a robot spent without a link to the station"),
        "out_of_comm_longest_steps": Output("longest such episode"),
        "out_of_comm_episode_mean_steps": Output("mean length of such an episode"),
        "robots_failed": Output("robots that failed"),
        "failures": Output("each failed robot and the step it failed at"),
        "timing_s": Output("processor time of each part of the simulator"),
        "base_m": Output("the base station's position"),
        "map_cells": Output("cells of the map along each axis"),
        "resolution_m": Output("the map's cell size"),
        "mission": Output(
            "the mission metrics shared by every paradigm (tether.mission.metrics): time to "
            "50/90/99 %, path length, coverage spread, overlap, time linked to the base "
            "station, information latency, the coverage goal and why the run stopped"
        ),
    },
    steps={
        "explored_fraction": Output("fraction of the reachable free space known at the station"),
        "team_explored_fraction": Output("fraction of it some robot has sensed"),
        "n_connected": Output("robots linked to the base station"),
    },
    robots={
        "connected": Output("linked to the base station"),
        "state": Output("0 moving, 1 relaying, 2 waiting, 3 returning, 4 failed"),
    },
)

_PLANNING_TIME = {
    "planning_time_mean_s": Output("mean planning time"),
    "planning_time_max_s": Output("longest planning time"),
    "planning_time_total_s": Output("total planning time"),
}

RECURRENT = StrategyOutputs(
    summary={
        **_EXPLORATION.summary,
        "plans": Output("plans issued"),
        "plan_attempts": Output("plans attempted"),
        **_PLANNING_TIME,
        "constraint_violations": Output("plans that broke a constraint (with check: true)"),
        "exploration_finished": Output("no frontier was left"),
        "plans_not_proven_optimal": Output("issued plans not proven optimal"),
        "plans_timed_out": Output("issued plans whose ILP ran out of time"),
        "plans_apx_delta_capped": Output("issued plans whose delta was lowered"),
        "plans_after_failures": Output("plans issued after the first failure"),
        "robots_preempted_by_failures": Output("robots stopped by failures' recoveries"),
    },
    steps=_EXPLORATION.steps,
    robots=_EXPLORATION.robots,
)

UTILITY = StrategyOutputs(
    summary={
        **_EXPLORATION.summary,
        "plans": Output("goals chosen"),
        "returns_to_bs": Output("returns to the base station"),
        **_PLANNING_TIME,
    },
    steps=_EXPLORATION.steps,
    robots=_EXPLORATION.robots,
)

UNCONSTRAINED = UTILITY

SILENT_EXPLORATION = StrategyOutputs(
    summary={
        **_EXPLORATION.summary,
        "leader": Output("the exploring robot"),
        "frontiers_chosen": Output("frontiers the leader headed for"),
        "leader_blocked_steps": Output("steps the steering law held the leader back"),
        "leader_returned": Output("the leader had no frontier left and headed home"),
    },
    steps=_EXPLORATION.steps,
    robots=_EXPLORATION.robots,
)

_CONTROLLER_KEYS = (
    "controller_success", "min_lambda2_weighted", "guard", "guard_interventions",
    "safe_set_exits", "tolerance_misses", "stalls", "max_speed_mps", "speed_bound_mps",
    "min_robot_distance_m", "min_obstacle_clearance_m",
)  # fmt: skip
_TARGET_KEYS = (
    "targets_total", "targets_reached", "targets_dropped", "targets_pending", "replans",
    "elections", "help_requests",
)  # fmt: skip

CONTINUOUS_EXPLORATION = StrategyOutputs(
    summary={
        **_EXPLORATION.summary,
        **{k: CONNECTIVITY.summary[k] for k in _CONTROLLER_KEYS},
        **{k: MULTI_TARGET.summary[k] for k in _TARGET_KEYS},
        "frontiers_given": Output("frontier targets given to the explorers"),
        "frontiers_explored_before_reached": Output(
            "targets dropped because the team explored their frontier before they were reached"
        ),
        "targets_dropped_by_reason": Output("dropped targets per reason"),
        "control_periods": Output("control periods of the continuous controller"),
    },
    steps=_EXPLORATION.steps,
    robots=_EXPLORATION.robots,
)

#: strategy name -> what it adds to the run folder
STRATEGY_OUTPUTS: dict[str, StrategyOutputs] = {
    "silent": SILENT,
    "connectivity": CONNECTIVITY,
    "multi_target": MULTI_TARGET,
    "recurrent": RECURRENT,
    "utility": UTILITY,
    "unconstrained": UNCONSTRAINED,
    "silent_exploration": SILENT_EXPLORATION,
    "continuous_exploration": CONTINUOUS_EXPLORATION,
}
