"""Environment stepping: tether's vector environment against MPE2.

The measurement is ``benchmarks/envs_throughput.py`` (the environments' own benchmark:
the same random-action loop on both sides, warm-up apart, the sides in turns), run here
as a command at a reduced grid of sizes; its JSON is read back. Without that script in
the tree, or without ``mpe2`` installed, the row says so and measures nothing.
"""

from __future__ import annotations

import importlib.util
import json
import sys
import tempfile
from pathlib import Path

from suite.core import ROOT, Line, command, row

SCRIPT = ROOT / "benchmarks" / "envs_throughput.py"


@row("envs", "environment stepping: agent-steps per second against MPE2")
def envs(quick: bool) -> dict:
    if not SCRIPT.exists():
        return {"lines": [], "skipped": f"{SCRIPT.relative_to(ROOT)} is not in this tree"}
    if importlib.util.find_spec("mpe2") is None:
        return {"lines": [], "skipped": "mpe2 is not installed (pip install mpe2)"}
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "envs.json"
        agents, n_envs = (["3"], ["1"]) if quick else (["3", "35"], ["1", "64"])
        argv = [sys.executable, str(SCRIPT), "--agents", *agents, "--envs", *n_envs,
                "--rounds", "1" if quick else "3", "--budget-s", "0.2" if quick else "1.0",
                "--sides", "tether", "mpe2", "--out", str(out)]  # fmt: skip
        command(argv, timeout_s=1800)
        doc = json.loads(out.read_text())
    lines = []
    for (agents, n_envs), sides in _by_size(doc).items():
        ours, peer = sides.get("tether"), sides.get("mpe2")
        if ours is None:
            continue
        label = f"environment steps, {agents} agents x {n_envs:,} environments (agent-steps/CPU s)"
        lines.append(Line(label, "/s", _rate(ours), higher_is_better=True,
                          peer="MPE2 simple_spread (same loop, in turns)",
                          peer_value=_rate(peer) if peer else None,
                          warmup_s=ours.get("warmup_cpu_s")))  # fmt: skip
    return {"lines": lines, "details": {"envs_throughput": doc.get("rows", doc.get("results"))}}


def _by_size(doc: dict) -> dict[tuple[int, int], dict[str, dict]]:
    """``(agents, envs) -> {side: record}`` from the script's JSON (a flat list of rows
    with a ``side`` each, or rows holding every side under ``sides``)."""
    out: dict[tuple[int, int], dict[str, dict]] = {}
    for rec in doc.get("rows", doc.get("results", [])):
        key = (int(rec["agents"]), int(rec["envs"]))
        if "sides" in rec:
            out.setdefault(key, {}).update(rec["sides"])
        else:
            out.setdefault(key, {})[rec["side"]] = rec
    return out


def _rate(rec: dict) -> float:
    """Agent-steps per CPU second, episode resets included where the script gives it."""
    for key in ("episode_agent_steps_per_s", "agent_steps_per_cpu_s", "agent_steps_per_s"):
        if key in rec:
            return float(rec[key])
    raise KeyError("no agent-steps rate in the envs_throughput.py record")
