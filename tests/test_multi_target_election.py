"""The prime-traveler election (Sec. 3.3) by flooding over the message layer."""

from __future__ import annotations

import numpy as np
import pytest

from tether.comm import CommParams, MessageLayer
from tether.continuous.exploration.election import ACTIVE, NO_TOKEN, TRANSIT, Election


def chain(n: int) -> np.ndarray:
    return np.array([(i, i + 1) for i in range(n - 1)])


def lossless(n: int, host: int = 0) -> Election:
    """An election of ``n`` robots over a message layer that loses and delays nothing."""
    return Election(n, MessageLayer(n, CommParams(), np.random.default_rng(0)), host=host)


def run_until_prime(
    election: Election,
    pairs: np.ndarray,
    candidate: np.ndarray,
    crit: np.ndarray,
    max_rounds: int = 500,
) -> tuple[int, int]:
    """Rounds until someone becomes prime; returns (winner, rounds)."""
    wants = np.zeros(election.n, dtype=bool)
    for r in range(1, max_rounds + 1):
        out = election.round(pairs, candidate, crit, candidate, wants)
        if out.became_prime:
            assert len(out.became_prime) == 1
            return out.became_prime[0], r
    raise AssertionError("no prime elected")


@pytest.mark.parametrize("seed", range(10))
def test_the_winner_is_the_candidate_with_the_smallest_criterion(seed: int) -> None:
    rng = np.random.default_rng(seed)
    n = int(rng.integers(4, 15))
    candidate = rng.random(n) < 0.6
    candidate[rng.integers(n)] = True
    crit = rng.uniform(1, 50, n)
    layer = MessageLayer(n, CommParams(), rng)
    winner, rounds = run_until_prime(Election(n, layer), chain(n), candidate, crit)
    cand = np.flatnonzero(candidate)
    assert winner == cand[np.argmin(crit[cand])]
    # the host decides after exactly 2(N - 1) rounds; the result then floods to the winner
    assert 2 * (n - 1) <= rounds <= 2 * (n - 1) + (n - 1) + 1


def test_ties_go_to_the_lower_index() -> None:
    n = 8
    crit = np.full(n, 5.0)
    candidate = np.zeros(n, dtype=bool)
    candidate[[6, 3, 5]] = True
    assert run_until_prime(lossless(n), chain(n), candidate, crit)[0] == 3


def test_a_tie_heard_later_from_a_higher_index_does_not_win() -> None:
    """Host 3 of a row of 7 hears candidate 1 (two hops) before candidate 6 (three hops),
    both with the same criterion: the lower index keeps the election."""
    n = 7
    crit = np.full(n, 5.0)
    candidate = np.zeros(n, dtype=bool)
    candidate[[1, 6]] = True
    assert run_until_prime(lossless(n, host=3), chain(n), candidate, crit)[0] == 1


def test_a_winner_that_is_no_longer_a_traveler_declines_and_a_new_election_follows() -> None:
    n = 6
    e = lossless(n)
    pairs = chain(n)
    crit = np.array([9.0, 9.0, 1.0, 9.0, 2.0, 9.0])
    candidate = np.zeros(n, dtype=bool)
    candidate[[2, 4]] = True
    wants = np.zeros(n, dtype=bool)
    declined, decided = [], []
    for _ in range(200):
        secondary = candidate.copy()
        if decided:
            secondary[2] = False  # robot 2 won, but reached its target before the news came
        out = e.round(pairs, candidate & secondary, crit, secondary, wants)
        declined += out.declined
        decided += out.decided
        if out.became_prime:
            break
    assert decided[0][2] == 2  # it did win the first election
    assert declined == [2]
    assert out.became_prime == [4]  # the host held a new one


@pytest.mark.parametrize(("loss", "delay"), [(0.3, 0), (0.0, 3), (0.4, 2)])
def test_never_two_primes_with_loss_delay_and_changing_candidates(loss: float, delay: int):
    rng = np.random.default_rng(7)
    n = 10
    layer = MessageLayer(n, CommParams(loss, delay), rng)
    e = Election(n, layer)
    edges = np.array([(i, j) for i in range(n) for j in range(i + 1, n)])
    primes_seen = decided = 0
    active = np.zeros(n, dtype=bool)
    for _ in range(3000):
        pairs = edges[rng.random(len(edges)) < 0.35]  # a changing graph
        pairs = np.concatenate([chain(n), pairs])  # kept connected
        secondary = (rng.random(n) < 0.5) & ~active
        wants = active & (rng.random(n) < 0.05)  # the prime reaches its target now and then
        out = e.round(pairs, secondary, rng.uniform(0, 10, n), secondary, wants)
        for _, host, _ in out.decided:
            active[host] = False
            decided += 1
        for w in out.became_prime:
            active[w] = True
            primes_seen += 1
        assert active.sum() <= 1
        acting = (e.token != NO_TOKEN) & (e.token != TRANSIT)
        assert np.count_nonzero(acting) <= 1  # one token; a host whose token is in flight waits
        assert np.count_nonzero(e.token == ACTIVE) == active.sum()
    assert decided > 20 and primes_seen > 3  # elections do complete under loss and delay


def test_the_token_holder_that_travels_again_takes_the_role_at_once() -> None:
    """Algorithm 1, line 8: a prime whose succession found no candidate keeps the token;
    when it takes its next target it knows no prime exists and is prime in that round,
    instead of leaving the role vacant for its own poll of 2(N - 1) rounds. The start-up
    election is not cut short: there the host's own candidacy competes."""
    n = 6
    e = lossless(n)
    pairs = chain(n)
    crit = np.array([5.0, 1.0, 9.0, 9.0, 9.0, 9.0])
    candidate = np.zeros(n, dtype=bool)
    candidate[[0, 1]] = True  # the start-up host 0 has a target too, robot 1 a shorter one
    winner, rounds = run_until_prime(e, pairs, candidate, crit)
    assert winner == 1 and rounds >= 2 * (n - 1)
    candidate[:] = False  # robot 1 reaches its target; nobody else travels
    wants = np.zeros(n, dtype=bool)
    wants[1] = True
    for _ in range(4 * n):
        out = e.round(pairs, candidate, crit, np.ones(n, dtype=bool), wants)
        if out.decided:
            break
    assert out.decided[0][1:] == (1, -1)  # no candidate: robot 1 holds the token idle
    candidate[1], wants[1] = True, False  # it takes its next target
    out = e.round(pairs, candidate, crit, np.ones(n, dtype=bool), wants)
    assert out.became_prime == [1]
    assert out.decided[0][1:] == (1, 1) and e.candidates[out.decided[0][0]] == [1]
    assert e.token[1] == ACTIVE
