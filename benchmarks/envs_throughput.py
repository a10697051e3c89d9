"""Agent-steps per second: tether's vector environment against MPE2 (and VMAS on the CPU).

For every team size (3, 12, 35 agents) and number of environments (1, 64, 1,024) each
simulator runs the same random-action loop: draw a uniformly random action for every
agent of every environment, step every environment, and start every environment again
after an episode of 300 steps. What is timed, on each side:

* warm-up, apart: construction, the first reset and the first steps (numba's
  compilation or cache load for tether, torch's first calls for VMAS);
* steady stepping: rounds of up to 300 steps (never across an episode's end), the median
  round reported;
* a reset of every environment (the start of an episode), the median reported; the
  *episode* rate charges one reset to every 300 steps.

The sides are measured in turns, round after round (tether, MPE2, VMAS, tether, ...), so
that the machine's other load falls on all alike. The clock is the processor time of
this process (the 2-core machine is shared); wall-clock rates are recorded too.

* tether: ``tether.envs.vector_env`` of ``silent_demo`` with ``team.n_robots`` agents:
  moves, sensed links (range, line of sight, occlusion by robot bodies), components,
  lambda2 and the bottleneck margin of every copy, the leader's path progress and the
  observations of the 6 nearest neighbours, in one compiled call per step for all copies;
* MPE2: ``simple_spread_v3.parallel_env(N=agents, continuous_actions=True)``, one
  environment object per copy (MPE2 has no vector form);
* VMAS: ``vmas.make_env("simple_spread", num_envs=envs, device="cpu", n_agents=agents)``
  if ``vmas`` imports.

Every side runs on one thread (numba's kernels are serial; torch and BLAS pinned to one)::

    python benchmarks/envs_throughput.py                      # all sizes, 3 rounds
    python benchmarks/envs_throughput.py --agents 3 --envs 1 64 --rounds 5

:func:`rows` returns one row per side and size (for a suite runner); :func:`main` runs
them, prints a Markdown table and writes ``benchmarks/results/envs_throughput.json``.
"""

from __future__ import annotations

import os

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("MKL_NUM_THREADS", "1")
os.environ.setdefault("NUMBA_NUM_THREADS", "1")

import argparse
import json
import statistics
import time
from collections.abc import Callable, Sequence
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path
from typing import Any

import numpy as np

from tether.config import load_scenario
from tether.runfolder import machine

ROOT = Path(__file__).resolve().parents[1]
#: index of the ``connected`` term in ``infos["terms"]`` (tether.envs.options.TERMS)
CONNECTED = 2
#: steps of one episode, on every side
EPISODE_STEPS = 300
#: an environment's own step limit, beyond any episode of the loop (which resets every episode)
NEVER_ENDS = 10 * EPISODE_STEPS


class Side:
    """One simulator at one size: ``warm()`` once, then ``reset()`` and ``step()``."""

    name = "side"

    def __init__(self, agents: int, envs: int, seed: int = 0) -> None:
        self.agents, self.envs, self.seed = agents, envs, seed
        self.episodes = 0

    def warm(self) -> None:
        """Build, reset, step a few times (compilation, caches)."""
        self.build()
        self.reset()
        for _ in range(3):
            self.step()

    def build(self) -> None: ...

    def reset(self) -> None: ...

    def step(self) -> None: ...

    def stats(self) -> dict[str, Any]:
        """Side-specific numbers of the timed rounds."""
        return {}


class Tether(Side):
    name = "tether"

    def build(self) -> None:
        import tether.envs as te

        data = load_scenario("silent_demo").model_dump(mode="json")
        data["team"]["n_robots"] = self.agents
        data["sim"]["max_steps"] = NEVER_ENDS
        self.env = te.vector_env(data, self.envs)
        self.rng = np.random.default_rng(self.seed)
        self.shape = self.env.action_space.shape
        self.connected: list[float] = []

    def reset(self) -> None:
        self.env.reset(seed=self.seed + self.episodes * self.envs)
        self.episodes += 1

    def actions(self) -> np.ndarray:
        return self.rng.uniform(-1.0, 1.0, self.shape)

    def step(self) -> None:
        *_, infos = self.env.step(self.actions())
        self.connected.append(float(infos["terms"][:, CONNECTED].mean()))

    def stats(self) -> dict[str, Any]:
        """The share of copy-steps whose team was connected (lambda2 computed)."""
        return {"connected_fraction": float(np.mean(self.connected)) if self.connected else None}


class TetherConnected(Tether):
    """tether with teams that stay connected: lambda2 is computed at every step.

    Each copy's robots share one random velocity (uniform in [-1, 1]^2) and add their
    own uniform jitter of +-0.01, so the team drifts as a whole and its links hold.
    """

    name = "tether_connected"

    def actions(self) -> np.ndarray:
        common = self.rng.uniform(-1.0, 1.0, (self.shape[0], 1, self.shape[2]))
        return common + self.rng.uniform(-0.01, 0.01, self.shape)


class Mpe2(Side):
    name = "mpe2"

    def build(self) -> None:
        from mpe2 import simple_spread_v3

        self.copies = [
            simple_spread_v3.parallel_env(
                N=self.agents, continuous_actions=True, max_cycles=NEVER_ENDS
            )
            for _ in range(self.envs)
        ]
        self.rng = np.random.default_rng(self.seed)
        env = self.copies[0]
        self.shape = (self.agents, *env.action_space(env.possible_agents[0]).shape)

    def reset(self) -> None:
        for k, env in enumerate(self.copies):
            env.reset(seed=self.seed + self.episodes * self.envs + k)
        self.episodes += 1

    def step(self) -> None:
        rng, shape = self.rng, self.shape
        for env in self.copies:
            a = rng.random(shape, dtype=np.float32)  # Box(0, 1, (5,)) per agent
            env.step({name: a[i] for i, name in enumerate(env.agents)})


class Vmas(Side):
    name = "vmas"

    def build(self) -> None:
        import torch
        import vmas

        torch.set_num_threads(1)
        self.torch = torch
        self.env = vmas.make_env(
            "simple_spread",
            num_envs=self.envs,
            device="cpu",
            continuous_actions=True,
            seed=self.seed,
            n_agents=self.agents,
        )
        self.gen = torch.Generator().manual_seed(self.seed)

    def reset(self) -> None:
        self.env.reset()
        self.episodes += 1

    def step(self) -> None:
        torch = self.torch
        self.env.step(
            [torch.rand(self.envs, 2, generator=self.gen) * 2 - 1 for _ in range(self.agents)]
        )


SIDES: dict[str, type[Side]] = {
    "tether": Tether,
    "tether_connected": TetherConnected,
    "mpe2": Mpe2,
    "vmas": Vmas,
}
_MODULES = {
    "tether": "tether.envs",
    "tether_connected": "tether.envs",
    "mpe2": "mpe2",
    "vmas": "vmas",
}


def available(name: str) -> bool:
    """Whether side ``name``'s simulator imports here."""
    try:
        __import__(_MODULES[name])
    except ImportError:
        return False
    return True


def timed(fn: Callable[[], Any]) -> tuple[float, float]:
    """(wall, processor) seconds of ``fn()``."""
    wall, cpu = time.perf_counter(), time.process_time()
    fn()
    return time.perf_counter() - wall, time.process_time() - cpu


def _steps(side: Side, k: int) -> None:
    for _ in range(k):
        side.step()


def measure_size(
    agents: int, envs: int, names: Sequence[str], rounds: int, budget_s: float
) -> list[dict[str, Any]]:
    """One row per side at ``agents`` x ``envs``, measured in interleaved rounds."""
    live: list[tuple[Side, int, dict[str, Any]]] = []
    for name in names:
        side = SIDES[name](agents, envs)
        warm_wall, warm_cpu = timed(side.warm)
        _, one = timed(side.step)
        steps = max(1, min(EPISODE_STEPS, int(budget_s / max(one, 1e-6))))
        row = {
            "side": name,
            "agents": agents,
            "envs": envs,
            "warmup_wall_s": warm_wall,
            "warmup_cpu_s": warm_cpu,
            "steps_per_round": steps,
            "rounds": [],
        }
        live.append((side, steps, row))
    for _ in range(rounds):  # interleaved: every side once per round
        for side, steps, row in live:
            reset_wall, reset_cpu = timed(side.reset)
            wall, cpu = timed(lambda s=side, k=steps: _steps(s, k))
            row["rounds"].append(
                {
                    "reset_wall_s": reset_wall,
                    "reset_cpu_s": reset_cpu,
                    "step_wall_s": wall / steps,
                    "step_cpu_s": cpu / steps,
                }
            )
    out = []
    for side, _, row in live:
        row.update(side.stats())
        rs = row["rounds"]
        for clock in ("wall", "cpu"):
            step_s = statistics.median(r[f"step_{clock}_s"] for r in rs)
            reset_s = statistics.median(r[f"reset_{clock}_s"] for r in rs)
            suffix = "" if clock == "cpu" else "_wall"
            row[f"step_s{suffix}"] = step_s
            row[f"reset_s{suffix}"] = reset_s
            work = agents * envs
            row[f"agent_steps_per_s{suffix}"] = work / max(step_s, 1e-12)
            row[f"episode_agent_steps_per_s{suffix}"] = (
                work * EPISODE_STEPS / max(EPISODE_STEPS * step_s + reset_s, 1e-12)
            )
        out.append(row)
    return out


def rows(
    agents: Sequence[int] = (3, 12, 35),
    envs: Sequence[int] = (1, 64, 1024),
    sides: Sequence[str] = ("tether", "mpe2", "vmas"),
    rounds: int = 3,
    budget_s: float = 1.0,
    progress: Callable[[list[dict[str, Any]]], None] | None = None,
) -> list[dict[str, Any]]:
    """Every row (a side at a size) of the benchmark; sides that do not import are left out.

    Rates are agent-steps per processor second: ``agent_steps_per_s`` while stepping,
    ``episode_agent_steps_per_s`` with one reset per episode of :data:`EPISODE_STEPS`
    (``..._wall`` on the wall clock).
    """
    names = [s for s in sides if available(s)]
    out: list[dict[str, Any]] = []
    for a in agents:
        for e in envs:
            size = measure_size(a, e, names, rounds, budget_s)
            out.extend(size)
            if progress is not None:
                progress(size)
    return out


def table(results: list[dict[str, Any]]) -> str:
    """A Markdown table: every side's episode rate (agent-steps per processor second),
    and each tether side's ratio to each other simulator."""
    names = [n for n in SIDES if any(r["side"] == n for r in results)]
    ours = [n for n in names if n.startswith("tether")]
    others = [n for n in names if n not in ours]
    ratios = [(a, b) for a in ours for b in others]
    head = (
        "| agents | envs | "
        + " | ".join(names)
        + "".join(f" | {a} / {b}" for a, b in ratios)
        + " |"
    )
    lines = [head, "|" + " ---: |" * (2 + len(names) + len(ratios))]
    sizes = sorted({(r["agents"], r["envs"]) for r in results})
    for agents, envs in sizes:
        rate = {
            r["side"]: r["episode_agent_steps_per_s"]
            for r in results
            if (r["agents"], r["envs"]) == (agents, envs)
        }
        cells = [f"{rate[n]:,.0f}" if n in rate else "-" for n in names]
        cells += [
            f"{rate[a] / rate[b]:,.1f}x" if a in rate and b in rate else "-" for a, b in ratios
        ]
        lines.append(f"| {agents} | {envs:,} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def main(argv: Sequence[str] | None = None) -> list[dict[str, Any]]:
    ap = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    ap.add_argument("--agents", type=int, nargs="+", default=[3, 12, 35])
    ap.add_argument("--envs", type=int, nargs="+", default=[1, 64, 1024])
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--budget-s", type=float, default=1.0, help="stepping time per round")
    ap.add_argument("--sides", nargs="+", default=list(SIDES), choices=list(SIDES))
    ap.add_argument("--out", type=Path, default=ROOT / "benchmarks/results/envs_throughput.json")
    ap.add_argument("--table-of", type=Path, help="only print the table of a results JSON")
    args = ap.parse_args(argv)
    if args.table_of is not None:
        saved = json.loads(args.table_of.read_text())["rows"]
        print(table(saved))
        return saved
    skipped = [s for s in args.sides if not available(s)]
    if skipped:
        print(f"not installed, left out: {', '.join(skipped)}", flush=True)
    load_before = os.getloadavg()
    done: list[dict[str, Any]] = []

    def progress(size: list[dict[str, Any]]) -> None:
        done.extend(size)
        print(table(size).splitlines()[-1], flush=True)

    results = rows(args.agents, args.envs, args.sides, args.rounds, args.budget_s, progress)
    command = (
        "python benchmarks/envs_throughput.py"
        f" --agents {' '.join(map(str, args.agents))} --envs {' '.join(map(str, args.envs))}"
        f" --rounds {args.rounds} --budget-s {args.budget_s} --sides {' '.join(args.sides)}"
    )
    versions = {}
    for dist in ("numpy", "numba", "pettingzoo", "gymnasium", "mpe2", "vmas", "torch"):
        try:
            versions[dist] = version(dist)
        except PackageNotFoundError:
            versions[dist] = None
    doc = {
        "command": command,
        "clock": "processor time of this process (rates without _wall); wall clock (_wall)",
        "episode_steps": EPISODE_STEPS,
        "not_installed": skipped,
        "load_average_before": load_before,
        "load_average_after": os.getloadavg(),
        "machine": machine(),
        "versions": versions,
        "rows": results,
        "table": table(results),
    }
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(doc, indent=1) + "\n")
    print(doc["table"])
    print(f"load average before {load_before}, after {doc['load_average_after']}")
    print(f"wrote {args.out}")
    return results


if __name__ == "__main__":
    main()
