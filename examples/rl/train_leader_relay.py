"""Train a small policy on a connectivity task and compare it with the paper's controller.

The task (``leader_relay.yaml`` beside this file): four robots follow a leader along an
L-shaped path and must keep their sensing graph connected. The learner is PPO from
Stable-Baselines3 on :func:`tether.envs.team_env` (one centralised policy commanding
every robot); the baseline is the scenario's own strategy (``silent``) acting through
the same environment (:class:`tether.envs.ScriptedPolicy`). Both are scored by the same
reward terms on the same evaluation seeds, which training never sees.

Needs the ``rl`` extra (``pip install ".[rl]"``; a CPU build of PyTorch is enough)::

    python examples/rl/train_leader_relay.py                  # about 5 minutes on 2 cores
    python examples/rl/train_leader_relay.py --timesteps 20000 --out runs/rl_quick

It writes into ``--out``: ``curve.json`` (the learning curve and the baseline),
``curve.png`` (the figure), ``learned_policy.zip`` (the PPO model) and ``episode/``, the
learned policy's first evaluation episode as a run folder (``tether view`` reads it).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

import tether.envs as te

HERE = Path(__file__).resolve().parent
SCENARIO = HERE / "leader_relay.yaml"
#: environment options of training and evaluation alike
OPTIONS: dict[str, Any] = {"max_neighbours": 3}
#: evaluation seeds: far from every training seed (training counts up from 0)
EVAL_SEED0 = 100_000


def evaluate(policy: Callable[[Any, np.ndarray], np.ndarray], seeds: list[int]) -> dict:
    """Mean episode metrics of ``policy(env, observation) -> action`` over ``seeds``."""
    env = te.team_env(str(SCENARIO), **OPTIONS)
    rows = []
    for seed in seeds:
        obs, _ = env.reset(seed=seed)
        done = False
        while not done:
            obs, _, terminated, truncated, _ = env.step(policy(env, obs))
            done = terminated or truncated
        ep = env.episode
        m = ep.metrics()
        rows.append(
            {
                "return": m["episode_return"],
                "path_progress": m["task_path_progress"],
                "connected_steps": float(np.mean([r.connected for r in ep.records])),
                "always_connected": float(all(r.connected for r in ep.records)),
                "steps": ep.step_count,
                "collisions": m["term_collisions"],
            }
        )
    return {key: float(np.mean([r[key] for r in rows])) for key in rows[0]}


def scripted(env: Any, obs: np.ndarray) -> np.ndarray:
    """The ``silent`` strategy's actions (the paper's controller)."""
    return env.scripted_action()


def learned(model: Any) -> Callable[[Any, np.ndarray], np.ndarray]:
    def act(env: Any, obs: np.ndarray) -> np.ndarray:
        return model.predict(obs, deterministic=True)[0]

    return act


def record_episode(model: Any, seed: int, out: Path) -> dict:
    """The learned policy's episode of ``seed`` as a run folder."""
    env = te.team_env(str(SCENARIO), record=True, **OPTIONS)
    obs, _ = env.reset(seed=seed)
    done = False
    while not done:
        obs, _, terminated, truncated, _ = env.step(model.predict(obs, deterministic=True)[0])
        done = terminated or truncated
    return env.write_run(out)


def plot(curve: dict, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    steps = [p["timesteps"] for p in curve["learned"]]
    base = curve["scripted"]
    fig, axes = plt.subplots(1, 4, figsize=(14, 3.2), constrained_layout=True)
    for ax, key, label in zip(
        axes,
        ("return", "path_progress", "connected_steps", "steps"),
        (
            "episode return",
            "leader path done (fraction)",
            "steps connected (fraction)",
            "episode length (steps)",
        ),
        strict=True,
    ):
        ax.plot(steps, [p[key] for p in curve["learned"]], "o-", label="PPO (learned)")
        ax.axhline(base[key], color="k", ls="--", label="silent (scripted)")
        ax.set_xlabel("training steps (thousands)")
        ax.xaxis.set_major_formatter(lambda x, _: f"{x / 1000:g}")
        ax.set_title(label, fontsize=10)
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=8)
    fig.suptitle(f"leader_relay: mean over {curve['eval_episodes']} evaluation seeds", fontsize=10)
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(argv: list[str] | None = None) -> dict:
    ap = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    ap.add_argument("--timesteps", type=int, default=300_000)
    ap.add_argument("--evals", type=int, default=10, help="points on the learning curve")
    ap.add_argument("--eval-episodes", type=int, default=20)
    ap.add_argument("--n-envs", type=int, default=4)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--out", type=Path, default=Path("runs/rl_leader_relay"))
    ap.add_argument("--figure", type=Path, help="also write the figure here")
    ap.add_argument("--json", type=Path, help="also write curve.json here")
    ap.add_argument("--replot", type=Path, help="only draw --figure from a curve.json")
    args = ap.parse_args(argv)
    if args.replot is not None:
        saved = json.loads(args.replot.read_text())
        plot(saved, args.figure or args.replot.with_suffix(".png"))
        return saved

    import torch
    from stable_baselines3 import PPO
    from stable_baselines3.common.callbacks import BaseCallback
    from stable_baselines3.common.env_util import make_vec_env

    torch.set_num_threads(1)
    if args.out.exists() and any(args.out.iterdir()):
        raise SystemExit(f"{args.out}: exists and is not empty; pass another --out")
    args.out.mkdir(parents=True, exist_ok=True)
    seeds = list(range(EVAL_SEED0, EVAL_SEED0 + args.eval_episodes))
    t0 = time.process_time()
    baseline = evaluate(scripted, seeds)
    print(f"scripted silent on {len(seeds)} seeds: {baseline}", flush=True)

    # training episodes: copy k of the vector env starts at seed k, then counts up
    venv = make_vec_env(
        lambda: te.team_env(str(SCENARIO), **OPTIONS), n_envs=args.n_envs, seed=args.seed
    )
    model = PPO(
        "MlpPolicy",
        venv,
        n_steps=512,
        batch_size=256,
        learning_rate=3e-4,
        gamma=0.99,
        ent_coef=0.0,
        policy_kwargs={"net_arch": [64, 64]},
        seed=args.seed,
        verbose=0,
        device="cpu",
    )
    curve: list[dict] = []
    every = max(args.timesteps // args.evals, 1)

    def point() -> None:
        row = {"timesteps": int(model.num_timesteps), **evaluate(learned(model), seeds)}
        row["cpu_s"] = time.process_time() - t0
        curve.append(row)
        print(
            f"{row['timesteps']:>8} steps: return {row['return']:7.2f}, path "
            f"{row['path_progress']:.3f}, connected {row['connected_steps']:.3f} "
            f"({row['cpu_s']:.0f} s)",
            flush=True,
        )

    class Curve(BaseCallback):
        def _on_step(self) -> bool:
            if self.num_timesteps >= every * len(curve):
                point()
            return True

    point()  # the untrained policy
    model.learn(total_timesteps=args.timesteps, callback=Curve())
    if curve[-1]["timesteps"] != model.num_timesteps:
        point()
    model.save(args.out / "learned_policy.zip")
    summary = record_episode(model, seeds[0], args.out / "episode")
    result = {
        "command": "python examples/rl/train_leader_relay.py "
        + " ".join(argv if argv is not None else sys.argv[1:]),
        "scenario": SCENARIO.name,
        "options": OPTIONS,
        "algorithm": "PPO (stable-baselines3), MlpPolicy 64x64, centralised team_env",
        "timesteps": args.timesteps,
        "eval_seeds": [seeds[0], seeds[-1]],
        "eval_episodes": len(seeds),
        "scripted": baseline,
        "learned": curve,
        "cpu_s": time.process_time() - t0,
        "recorded_episode": {"steps": summary["steps"], "seed": seeds[0]},
    }
    (args.out / "curve.json").write_text(json.dumps(result, indent=1) + "\n")
    plot(result, args.out / "curve.png")
    if args.figure is not None:
        plot(result, args.figure)
    if args.json is not None:
        args.json.write_text(json.dumps(result, indent=1) + "\n")
    final = curve[-1]
    print(
        f"learned after {final['timesteps']} steps: return {final['return']:.2f} "
        f"(scripted {baseline['return']:.2f}), connected {final['connected_steps']:.3f} "
        f"(scripted {baseline['connected_steps']:.3f}); wrote {args.out}"
    )
    return result


if __name__ == "__main__":
    main()
