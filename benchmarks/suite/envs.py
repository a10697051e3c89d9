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
        raise FileNotFoundError(f"{SCRIPT.relative_to(ROOT)} is not in this tree")
    if importlib.util.find_spec("mpe2") is None:
        raise ModuleNotFoundError("mpe2 is not installed: pip install mpe2")
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "envs.json"
        agents, n_envs = (["3"], ["1"]) if quick else (["3", "35"], ["1", "64"])
        argv = [sys.executable, str(SCRIPT), "--agents", *agents, "--envs", *n_envs,
                "--rounds", "1" if quick else "3", "--budget-s", "0.2" if quick else "1.0",
                "--sides", "tether", "mpe2", "--out", str(out)]  # fmt: skip
        command(argv, timeout_s=1800)
        doc = json.loads(out.read_text())
    lines = []
    for res in doc["results"]:
        ours, peer = res["sides"]["tether"], res["sides"].get("mpe2")
        lines.append(
            Line(
                f"environment steps, {res['agents']} agents x {res['envs']:,} environments "
                "(agent-steps per CPU second)",
                "/s",
                ours["agent_steps_per_cpu_s"],
                higher_is_better=True,
                peer="MPE2 simple_spread (same loop, in turns)",
                peer_value=peer["agent_steps_per_cpu_s"] if peer else None,
                warmup_s=ours["warmup_cpu_s"],
            )  # fmt: skip
        )
    return {"lines": lines, "details": {"envs_throughput": doc["results"]}}
