"""Every bound a scenario key declares is enforced, generated from the pydantic models.

For each numeric field of :class:`tether.config.Scenario` and of every built-in
strategy's ``Params`` with a declared bound (``ge``, ``gt``, ``le``, ``lt``), the value
just outside it (the bound itself for a strict one, the next float or integer beyond it
for an inclusive one) is refused with tether's one-line error naming the key, and the
value on the bound of an inclusive one is not refused for that key.

The bounds themselves are a contract with users (the scenario reference shows them), so
they are also recorded in ``tests/data/field_bounds.txt``: a bound removed or loosened in a
model (``sim.collision_distance_m`` accepting -2, a leader speed of 0 that then fails inside
the run) fails :func:`test_the_bounds_are_the_recorded_ones`. A bound changed on purpose is
recorded again with ``python tests/test_field_bounds.py``.
"""

from __future__ import annotations

import copy
import math
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import annotated_types as at
import pytest
from pydantic import BaseModel

from _parameters import STRATEGY_SCENARIOS, _models_in
from tether.config import Scenario, load_scenario, scenario_from_dict, set_dotted
from tether.errors import ScenarioError
from tether.plugins import BUILTINS
from tether.registry import STRATEGIES
from tether.runner import strategy_params


@dataclass(frozen=True)
class Bound:
    """One declared bound: ``key`` (dotted), its kind (``ge``, ``gt``, ``le``, ``lt``)."""

    strategy: str | None  # None: a key of the scenario itself
    key: str
    kind: str
    limit: float
    integer: bool

    @property
    def id(self) -> str:
        where = f"{self.strategy}:" if self.strategy else ""
        return f"{where}{self.key}:{self.kind}"

    def outside(self) -> float:
        """The nearest value that breaks the bound."""
        below = self.kind in ("ge", "gt")
        if self.kind in ("gt", "lt"):
            return self.limit
        if self.integer:
            return self.limit - 1 if below else self.limit + 1
        return math.nextafter(self.limit, -math.inf if below else math.inf)


RECORD = Path(__file__).parent / "data" / "field_bounds.txt"

KINDS = {at.Ge: "ge", at.Gt: "gt", at.Le: "le", at.Lt: "lt"}


def _is_integer(annotation: Any) -> bool:
    return annotation is int or (
        hasattr(annotation, "__args__") and int in annotation.__args__ and float not in
        annotation.__args__
    )  # fmt: skip


def bounds_of(model: type[BaseModel], strategy: str | None, prefix: str = "") -> Iterator[Bound]:
    for name, info in model.model_fields.items():
        for sub in _models_in(info.annotation):
            yield from bounds_of(sub, strategy, f"{prefix}{name}.")
        for meta in info.metadata:
            for cls, kind in KINDS.items():
                if isinstance(meta, cls):
                    limit = getattr(meta, kind)
                    yield Bound(strategy, f"{prefix}{name}", kind, limit,
                                _is_integer(info.annotation))  # fmt: skip


BOUNDS = [
    *bounds_of(Scenario, None),
    *(b for name in sorted(BUILTINS[STRATEGIES]) for b in bounds_of(
        STRATEGIES.get(name).Params, name)),
]  # fmt: skip


def recorded_lines() -> list[str]:
    """One line per bound: ``key kind limit``, sorted."""
    return sorted(f"{b.id.rsplit(':', 1)[0]} {b.kind} {b.limit!r}" for b in BOUNDS)


def test_the_bounds_are_the_recorded_ones() -> None:
    now, recorded = set(recorded_lines()), set(RECORD.read_text().splitlines())
    assert now == recorded, (
        f"bounds changed: not recorded {sorted(now - recorded)[:5]}, recorded but gone "
        f"{sorted(recorded - now)[:5]}; if on purpose: python tests/test_field_bounds.py"
    )


def test_the_walk_finds_the_bounds_users_meet() -> None:
    ids = {b.id for b in BOUNDS}
    assert {"sim.collision_distance_m:ge", "silent:trajectory.speed_mps:gt", "sim.dt_s:gt",
            "team.n_robots:gt"} <= ids  # fmt: skip
    assert len(BOUNDS) > 100


def refusal(bound: Bound, value: float) -> str | None:
    """The one-line error for ``key: value`` (None if it is accepted)."""
    if bound.strategy is None:
        data = load_scenario("silent_demo").model_dump(mode="json")
        set_dotted(data, bound.key, value)
        try:
            scenario_from_dict(data, "s.yaml")
        except ScenarioError as exc:
            return str(exc)
        return None
    base = load_scenario(STRATEGY_SCENARIOS[bound.strategy]).model_dump(mode="json")
    data = copy.deepcopy(base)
    data["strategy"] = {"name": bound.strategy, "params": dict(base["strategy"]["params"])}
    set_dotted(data["strategy"]["params"], bound.key, value)
    scenario = scenario_from_dict(data, "s.yaml")
    try:
        strategy_params(scenario, STRATEGIES.get(bound.strategy))
    except ScenarioError as exc:
        return str(exc)
    return None


@pytest.mark.parametrize("bound", BOUNDS, ids=[b.id for b in BOUNDS])
def test_a_value_beyond_a_declared_bound_is_refused_naming_the_key(bound: Bound) -> None:
    key = bound.key if bound.strategy is None else f"strategy.params.{bound.key}"
    message = refusal(bound, bound.outside())
    assert message is not None, (
        f"{key} = {bound.outside()!r} was accepted ({bound.kind} {bound.limit})"
    )
    assert message.startswith(f"s.yaml: {key}: ") and "\n" not in message, message
    if bound.kind in ("ge", "le"):  # the bound itself is allowed (for this key)
        on = refusal(bound, bound.limit)
        assert on is None or f"{key}: " not in on, on


if __name__ == "__main__":  # record the bounds after a deliberate change
    RECORD.write_text("\n".join(recorded_lines()) + "\n")
    print(f"{RECORD}: {len(BOUNDS)} bounds")
