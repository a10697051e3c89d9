"""What a run writes, described: every summary key, Parquet column and event.

The core keys and columns every run has are here; each built-in strategy's own are in
:mod:`tether.reference.strategy_outputs`. ``tests/test_reference.py`` runs every
built-in strategy and fails on a key or column it writes that is not described here,
and on a described one (without a ``when``) that it no longer writes.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Output:
    """The description of one summary key, column or event field (short, SI units)."""

    description: str
    #: the condition under which it is written; empty: in every run (of its strategy)
    when: str = ""


#: keys of ``summary.json`` in every run (:func:`tether.record.summarize`, the runner)
CORE_SUMMARY: dict[str, Output] = {
    "scenario": Output("the scenario's name"),
    "strategy": Output("the strategy's name"),
    "seed": Output("the seed the run used"),
    "n_robots": Output("number of robots"),
    "dim": Output("dimension of the workspace (2 or 3)"),
    "sim_time_s": Output("simulated time"),
    "steps": Output("steps simulated (the initial state is step 0)"),
    "wall_time_s": Output("wall-clock time of the simulation"),
    "cpu_time_s": Output("processor time of the simulation"),
    "connected_all_steps": Output(
        "the true interaction graph, fixed nodes included, was connected at every step"
    ),
    "min_lambda2": Output(
        "least lambda2 of the unweighted interaction graph (null above 500 nodes)"
    ),
    "min_links": Output("fewest links of the interaction graph at a step"),
    "max_links": Output("most links of the interaction graph at a step"),
    "collisions": Output("robot pairs closer than collision_distance_m, summed over steps"),
    "collision_distance_m": Output("sim.collision_distance_m of the run"),
    "min_distance_m": Output("least distance between two linked nodes over the run"),
    "provenance": Output("tether version, git commit, Python, platform and CPU count"),
    "scene_files": Output(
        "each file the world read: its path as given, stand-in, SHA-256 and copy in files/",
        when="the scene read files (a map, a point file)",
    ),
}

#: columns of ``steps.parquet`` in every run: one row per step
CORE_STEPS: dict[str, Output] = {
    "step": Output("step number (0: the initial state)"),
    "t_s": Output("simulated time of the step"),
    "connected": Output("the true interaction graph is connected"),
    "n_components": Output("connected components of the interaction graph"),
    "n_links": Output("links of the interaction graph"),
    "lambda2": Output("lambda2 of the unweighted interaction graph (NaN above 500 nodes)"),
    "min_distance_m": Output("least distance between two linked nodes"),
    "collisions": Output("robot pairs closer than sim.collision_distance_m"),
}

#: columns of ``robots.parquet`` in every run: one row per (recorded step, robot)
CORE_ROBOTS: dict[str, Output] = {
    "step": Output("step number (every output.record_every-th step)"),
    "robot": Output("robot index, 0 to n_robots - 1"),
    "x_m": Output("x position"),
    "y_m": Output("y position"),
    "z_m": Output("z position", when="3-D worlds"),
}

#: columns of ``links.parquet``: one row per (recorded step, link)
CORE_LINKS: dict[str, Output] = {
    "step": Output("step number (every output.record_every-th step)"),
    "i": Output("node index of one end (>= n_robots: a fixed node, the base station)"),
    "j": Output("node index of the other end (i < j)"),
}

#: columns of ``events.parquet`` every event has; the others depend on its ``kind``
CORE_EVENTS: dict[str, Output] = {
    "step": Output("step at which the event happened"),
    "kind": Output("what happened (the table of event kinds)"),
    "robot": Output("the robot it concerns (-1: none)", when="events of the kinds that name one"),
    "t_s": Output("simulated time of the event", when="events of the kinds that carry it"),
}


@dataclass(frozen=True)
class Event:
    """One kind of event: what it means, which strategies write it, its own fields."""

    description: str
    strategies: tuple[str, ...]
    fields: dict[str, str]


_TARGET = "the target's id"
_CONT = ("multi_target",)
_CONT_MISSION = ("multi_target", "continuous_exploration")  # the mission keeps these
_EXPL = ("recurrent", "utility", "unconstrained", "silent_exploration")

#: every kind of event a built-in strategy writes, with its own columns
EVENTS: dict[str, Event] = {
    "stall": Event(
        "the guard found no admissible step and the team braked to rest",
        ("connectivity", *_CONT_MISSION),
        {"substeps": "sub-steps taken in the control period"},
    ),
    "target_added": Event(
        "a target was added (by its generator, or from Python while the team runs)",
        _CONT,
        {
            "target": _TARGET,
            "position_m": "the target's position",
            "stay_s": "how long the robot stays at it",
            "appear_s": "when it appears",
        },
    ),
    "target_taken": Event(
        "a robot took up a target and planned its path",
        _CONT_MISSION,
        {"target": _TARGET, "position_m": "the target's position", "path_m": "path length"},
    ),
    "target_reached": Event("a robot reached a target", _CONT_MISSION, {"target": _TARGET}),
    "target_dropped": Event(
        "a target was given up",
        _CONT_MISSION,
        {"target": _TARGET, "reason": "unreachable, expired or stalled"},
    ),
    "role": Event("a robot changed role", _CONT, {"old": "role before", "new": "role after"}),
    "replan": Event("a traveler planned its path again", _CONT, {"path_m": "new path length"}),
    "election_open": Event(
        "an election of the prime traveler was opened", _CONT, {"epoch": "the election's number"}
    ),
    "election": Event(
        "an election was decided",
        _CONT,
        {
            "epoch": "the election's number",
            "winner": "the new prime traveler",
            "candidates": "the robots that stood",
        },
    ),
    "election_declined": Event("a robot declined to become the prime traveler", _CONT, {}),
    "help_requested": Event(
        "a stalled prime asked its neighbours for help",
        _CONT_MISSION,
        {"hops": "links it travels"},
    ),
    "help_ended": Event("a prime's help request ended", _CONT, {}),
    "plan": Event(
        "the base station planned (or tried to plan) a configuration",
        ("recurrent",),
        {
            "n_ready": "ready robots",
            "n_vertices": "vertices of the exploration graph",
            "n_edges": "edges of the exploration graph",
            "n_frontiers": "frontiers with a utility",
            "issued": "the plan was sent to the robots",
            "planning_time_s": "wall-clock planning time",
            "solver_time_s": "time in the configuration solver",
            "utility": "summed utility of the configuration",
            "size": "vertices of the configuration",
            "n_fake": "robots sent to fake frontiers",
            "n_assigned": "robots given a goal",
            "method": "apx, ilp-highs or ilp-scip",
            "proven_optimal": "the utility is proven optimal",
            "timed_out": "the ILP's time limit ran out",
            "fallback": "the configuration is APX's (the ILP found nothing better)",
            "apx_delta": "the delta APX ran with, when lowered to bound memory",
            "apx_delta_capped": "delta was lowered for this plan",
        },
    ),
    "abort": Event(
        "a robot could not reach its goal; its branch was preempted",
        ("recurrent",),
        {"preempted": "the robots stopped with it"},
    ),
    "recovery": Event(
        "a robot failed; the branches that depended on it were preempted",
        ("recurrent",),
        {"preempted": "the robots stopped", "homing": "those sent back to the base station"},
    ),
    "failure": Event("a robot failed", _EXPL, {}),
    "return": Event(
        "a robot headed back to the base station",
        ("utility", "unconstrained", "silent_exploration"),
        {},
    ),
}
