"""The compiled message rounds against their references: the same rounds, bit for bit.

The election's merge and the consensus update (``continuous/exploration/round_kernels.py``), the
message layer's delivery and mailbox re-alignment (``comm_kernels.py``) run when
``tether.jit`` is on; with it off the numpy references run. Both must deliver the same
messages (loss draws, delays, failures included) and reach the same states.
"""

from __future__ import annotations

import numpy as np
import pytest

from tether import jit
from tether.comm import CommParams, MessageLayer
from tether.continuous.exploration.consensus import EfficiencyConsensus
from tether.continuous.exploration.election import Election

pytest.importorskip("numba")


def random_links(rng: np.random.Generator, n: int) -> np.ndarray:
    """A random connected-ish link set: a chain plus random chords, some dropped."""
    pairs = {(i, i + 1) for i in range(n - 1) if rng.random() < 0.9}
    for _ in range(n):
        i, j = sorted(rng.choice(n, 2, replace=False))
        pairs.add((int(i), int(j)))
    out = np.array(sorted(pairs), dtype=np.intp).reshape(-1, 2)
    return out[rng.permutation(len(out))]


def play(on: bool, seed: int, comm: CommParams, rounds: int = 120) -> list:
    """Election and consensus rounds over changing links; everything they produce."""
    rng = np.random.default_rng(seed)
    n = int(rng.integers(5, 16))
    with jit.using(on):
        election = Election(n, MessageLayer(n, comm, np.random.default_rng(seed + 1)))
        consensus = EfficiencyConsensus(n, MessageLayer(n, comm, np.random.default_rng(seed + 2)),
                                        5.0)  # fmt: skip
        history = []
        links = random_links(rng, n)
        for r in range(rounds):
            if r % 7 == 0:  # the links change now and then; the same array object otherwise
                links = random_links(rng, n)
            candidate = rng.random(n) < 0.5
            crit = np.round(rng.uniform(0, 20, n), 1)  # ties happen
            wants = rng.random(n) < 0.05
            out = election.round(links, candidate, crit, candidate, wants)
            prime = int(rng.integers(-1, n))
            consensus.round(links, 0.1, prime, float(rng.random()))
            history.append((election.msg.copy(), election.token.copy(), out.decided,
                            out.became_prime, out.declined, out.opened,
                            consensus.estimate.copy(), election.layer.sent,
                            election.layer.delivered, consensus.layer.sent,
                            consensus.layer.delivered))  # fmt: skip
    return history


@pytest.mark.parametrize("seed", range(4))
@pytest.mark.parametrize(
    "comm",
    [CommParams(), CommParams(0.3), CommParams(0.2, 2), CommParams(0.1, 0, {1: 30, 3: 60})],
    ids=["perfect", "loss", "loss+delay", "failures"],
)
def test_compiled_rounds_equal_the_reference(seed: int, comm: CommParams) -> None:
    fast, ref = play(True, seed, comm), play(False, seed, comm)
    assert len(fast) == len(ref)
    for a, b in zip(fast, ref, strict=True):
        for x, y in zip(a, b, strict=True):
            if isinstance(x, np.ndarray):
                np.testing.assert_array_equal(x, y)
            else:
                assert x == y


def test_exchange_inbox_is_the_same() -> None:
    """Mailboxes, ages and counters of one layer, round by round, with loss and failures."""
    rng = np.random.default_rng(3)
    n = 9
    comm = CommParams(0.25, 0, {4: 5})
    layers = {on: MessageLayer(n, comm, np.random.default_rng(8)) for on in (True, False)}
    for r in range(40):
        links = random_links(rng, n)
        values = rng.normal(size=(n, 3))
        inbox = {}
        for on, layer in layers.items():
            with jit.using(on):
                inbox[on] = layer.exchange(links if r % 3 else links.copy(), values)
        for field in ("receiver", "sender", "values", "age"):
            np.testing.assert_array_equal(getattr(inbox[True], field), getattr(inbox[False], field))
        assert layers[True].sent == layers[False].sent
        assert layers[True].delivered == layers[False].delivered
