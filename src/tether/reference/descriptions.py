"""Descriptions of the scenario keys whose models carry none in their fields.

Keyed by ``module.Model.field``. A field's own ``description`` takes precedence, so a
description here can move into its model's ``Field(description=...)`` at any time;
``tests/test_reference.py`` fails on an entry that names no field or that its field
already describes.
"""

from __future__ import annotations

_CONNECTIVITY = "tether.continuous.connectivity.strategy_params.ConnectivityStrategyParams"
#: the parameters connectivity and multi_target share
_CONTINUOUS = "tether.continuous.connectivity.strategy_params.ContinuousParams"
_ESTIMATOR = "tether.continuous.connectivity.estimation.EstimatorParams"
_ESTIMATOR_CONFIG = "tether.continuous.connectivity.strategy_params.EstimatorConfig"
_EXTERNAL = "tether.continuous.connectivity.external.ExternalForce"
_MULTI = "tether.continuous.exploration.params.MultiTargetParams"
_TARGETS = "tether.continuous.exploration.params.TargetsConfig"
_MESSAGES = "tether.continuous.exploration.params.MessagesConfig"
_START = "tether.continuous.exploration.params.StartConfig"
_GEN = "tether.continuous.exploration.targets"

KEY_DESCRIPTIONS: dict[str, str] = {
    # the connectivity force (Table 2) and the robot model
    f"{_CONTINUOUS}.preset": "Table 2's column: outdoor (empty space, town), office, "
    "experiment (Sec. 4.2); sets the radii's defaults",
    f"{_CONTINUOUS}.rs_inner_m": "R's: the range factor starts falling from 1",
    f"{_CONTINUOUS}.rs_m": "Rs: the range factor reaches 0 (the link range)",
    f"{_CONTINUOUS}.ro_m": "Ro: the obstacle factor is 0 within this of an obstacle",
    f"{_CONTINUOUS}.ro_outer_m": "R'o: the obstacle factor reaches 1",
    f"{_CONTINUOUS}.rc_m": "Rc: the collision factor is 0 within this of another robot",
    f"{_CONTINUOUS}.rc_outer_m": "R'c: the collision factor reaches 1",
    f"{_CONTINUOUS}.lambda2_min": "lambda2 at which the potential is infinite",
    f"{_CONTINUOUS}.lambda2_null": "lambda2 above which the potential is zero",
    f"{_CONTINUOUS}.potential_gain_n": "k_V, the gain of the connectivity potential",
    f"{_CONTINUOUS}.mass_kg": "M, each robot's mass in eq. (1)",
    f"{_CONTINUOUS}.damping_ns_per_m": "b, the linear damping of eq. (1)",
    f"{_CONTINUOUS}.speed_damping_n": "beta, the damping that bounds the speed below max_speed_mps",
    f"{_CONTINUOUS}.max_step_fraction": "a sub-step moves no robot more than this fraction "
    "of the narrowest transition band",
    f"{_CONTINUOUS}.guard": "a step leaving the safe set: counted (detect), vetoed "
    "(enforce), or not checked (off)",
    f"{_CONTINUOUS}.keep_fraction": "enforce: a step keeps this fraction of the margin "
    "lambda2 - lambda2_min",
    f"{_CONTINUOUS}.eigensolver": "lambda2 and the Fiedler vector: exact, or the "
    "decentralized estimator",
    f"{_CONTINUOUS}.fiedler_method": "exact eigenpair: auto (certified small solver, LAPACK "
    "when it cannot certify) or lapack (LAPACK every sub-step)",
    f"{_CONTINUOUS}.estimator": "the decentralized estimator and its message layer",
    f"{_CONNECTIVITY}.external": "the external force f_i of eq. (1)",
    # the estimator of Yang et al. (2010)
    f"{_ESTIMATOR}.k1": "k1, gain of the deflation term (k1 > k3)",
    f"{_ESTIMATOR}.k2": "k2, gain of the Laplacian term",
    f"{_ESTIMATOR}.k3": "k3, gain of the normalization term (k3 / k2 caps the estimate)",
    f"{_ESTIMATOR}.gamma": "gamma, the consensus filters' gain",
    f"{_ESTIMATOR}.kp": "kP, proportional gain of the PI average consensus",
    f"{_ESTIMATOR}.ki": "kI, integral gain of the PI average consensus",
    f"{_ESTIMATOR}.step_scale": "scales the Euler step of one communication round",
    f"{_ESTIMATOR_CONFIG}.rounds_per_substep": "communication rounds per integrator sub-step",
    f"{_ESTIMATOR_CONFIG}.warmup_rounds": "rounds before the first step",
    f"{_ESTIMATOR_CONFIG}.loss_probability": "each message is lost with this probability",
    f"{_ESTIMATOR_CONFIG}.delay_rounds": "messages arrive this many rounds late",
    f"{_ESTIMATOR_CONFIG}.failures": "robot -> round from which it neither sends nor receives",
    # the external force
    f"{_EXTERNAL}.kind": "none, constant, goal (pull to operator goals) or random",
    f"{_EXTERNAL}.magnitude_n": "bound on each robot's external force",
    f"{_EXTERNAL}.hold_s": "random: a force is redrawn after this long",
    f"{_EXTERNAL}.planar": "random: forces stay horizontal in 3-D",
    f"{_EXTERNAL}.forces": "constant: one force vector for all robots, or one per robot (N)",
    f"{_EXTERNAL}.robots": "goal: the robots pulled to goals",
    f"{_EXTERNAL}.goals": "goal: one goal point per robot in robots (m)",
    f"{_EXTERNAL}.gain_n_per_m": "goal: force per metre to the goal",
    # multi-target exploration (Table 2's traveling column and the open choices)
    f"{_MULTI}.targets": "the target generator and its parameters",
    f"{_MULTI}.r_grid_m": "Rgrid, the cell of the A* planning grid",
    f"{_MULTI}.sigma": "sigma of rho, eqs. (14)-(15) (>= 1)",
    f"{_MULTI}.v_cruise_mps": "v_cruise, the travelers' cruise speed along their paths",
    f"{_MULTI}.xc_frac": "x_c of eq. (9) as a fraction of v_cruise",
    f"{_MULTI}.xm_frac": "x_M of eq. (9) as a fraction of v_cruise",
    f"{_MULTI}.rz_m": "Rz, the radius of an anchor's ball around its target",
    f"{_MULTI}.kp_n_per_m": "position gain of the traveling force, eq. (3)",
    f"{_MULTI}.kv_ns_per_m": "velocity gain of the traveling force, eq. (3)",
    f"{_MULTI}.kz_n": "k_z, gain of the anchor force, eq. (7)",
    f"{_MULTI}.k_lambda_per_s": "k_Lambda, gain of the efficiency consensus, eq. (13)",
    f"{_MULTI}.alpha_lambda": "alpha of the tracking error, eq. (11)",
    f"{_MULTI}.stall_timeout_s": "a prime without progress for this long drops its target "
    "(null: never)",
    f"{_MULTI}.help_max_hops": "a help request travels this many links at most",
    f"{_MULTI}.max_travel_force_n": "the traveling and helper forces saturate here",
    f"{_MULTI}.election_criterion": "the prime is the candidate with the shortest remaining "
    "path, or nearest its target",
    f"{_MULTI}.messages": "faults of the message layer of the election and consensus",
    f"{_MULTI}.start": "where the team starts when team.init is not positions",
    f"{_MULTI}.reference_filter": "robots follow eq. (1) through the 4th-order reference "
    "filter of eq. (16)",
    f"{_TARGETS}.kind": "the target generator: fixed, paper_random or schedule",
    f"{_TARGETS}.params": "the generator's parameters (see its table)",
    f"{_MESSAGES}.rounds_per_step": "communication rounds per control step",
    f"{_MESSAGES}.loss_probability": "each message is lost with this probability",
    f"{_MESSAGES}.delay_rounds": "messages arrive this many rounds late",
    f"{_START}.center_m": "the first robot's position (default: random in the bounds)",
    f"{_START}.height_m": "3-D: [low, high] of the first robot's height",
    f"{_START}.margin_m": "the first robot this far inside the world's bounds",
    # target generators
    f"{_GEN}.FixedParams.queues": "one target list per robot",
    f"{_GEN}.FixedParams.timeout_s": "a target not reached this long after it is taken is "
    "dropped (null: never)",
    f"{_GEN}.FixedQueue.robot": "the robot that visits these targets",
    f"{_GEN}.FixedQueue.targets": "the target points, visited in this order (m)",
    f"{_GEN}.FixedQueue.stay_s": "Delta t, time to stay at each target",
    f"{_GEN}.ScheduleParams.targets": "targets with the times they appear",
    f"{_GEN}.ScheduleParams.timeout_s": "a target not reached this long after it is taken is "
    "dropped (null: never)",
    f"{_GEN}.ScheduledTarget.robot": "the robot that visits it",
    f"{_GEN}.ScheduledTarget.position_m": "the target point",
    f"{_GEN}.ScheduledTarget.at_s": "when the target appears",
    f"{_GEN}.ScheduledTarget.stay_s": "Delta t, time to stay at the target",
    f"{_GEN}.PaperRandomParams.stay_s": "Delta t, time to stay at each target",
    f"{_GEN}.PaperRandomParams.clearance_m": "targets at least this far from obstacles",
    f"{_GEN}.PaperRandomParams.timeout_s": "a target not reached this long after it is taken "
    "is dropped (null: never)",
}
