"""APX's subset bands (genNewSubset) against one global sort of every subset.

:func:`tether.recurrent.planning.apx_bands.bands` makes the subsets of at most ``delta``
frontiers band by band of utility so that Algorithm 1 (Banfi et al., Sec. V) can stop
early; the band widths are a matter of speed only, so the bands joined must
be exactly the global order: decreasing utility, increasing size, increasing colex rank.
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from tether.recurrent.planning import apx, apx_bands


def global_order(
    uf: np.ndarray, delta: int, fits: np.ndarray | None = None
) -> list[tuple[int, ...]]:
    ranker = apx._Ranker(len(uf), delta)
    rows = []
    for s in range(1, delta + 1):
        for c in itertools.combinations(range(len(uf)), s):
            if fits is not None and not all(fits[i, j] for i, j in itertools.combinations(c, 2)):
                continue
            util = float(uf[list(c)].sum())
            rows.append((-util, s, int(ranker.rank(np.array([c]))[0]), c))
    return [r[3] for r in sorted(rows)]


@pytest.mark.parametrize("seed", range(12))
@pytest.mark.parametrize(
    ("ratio", "cap"), [(0.0, 20_000), (0.5, 3), (0.75, 20_000), (0.75, 1), (0.95, 7)]
)
def test_bands_joined_are_the_global_order(seed: int, ratio: float, cap: int, monkeypatch) -> None:  # noqa: ANN001
    """Any band widths (ratio; ``BAND_SUBSETS`` small enough to narrow most bands) give the
    global order, and each band's reported lower end bounds every later subset."""
    rng = np.random.default_rng(seed)
    k, delta = int(rng.integers(4, 13)), int(rng.integers(1, 5))
    uf = np.sort(rng.choice([0.5, 1.0, 2.0, 7.0], size=k) * rng.uniform(0.2, 3.0, size=k))[::-1]
    if seed % 3 == 0:
        uf = np.round(uf) + 1.0  # ties: the order falls back to size, then rank
        uf = np.sort(uf)[::-1]
    if seed % 4 == 1:
        uf[0] *= 500.0  # one frontier far above the rest (the first band's width)
    monkeypatch.setattr(apx_bands, "LOWEST_BAND_RATIO", ratio)
    monkeypatch.setattr(apx_bands, "BAND_SUBSETS", cap)
    fits = None
    if seed % 2:  # only subsets whose every pair fits (APX's pair filter)
        fits = rng.random((k, k)) < 0.6
        fits = fits & fits.T
    got, lows = [], []
    for util, size, combos, lo in apx_bands.bands(uf, delta, apx._Ranker(k, delta).rank, fits):
        got.extend(tuple(int(x) for x in row[:s]) for row, s in zip(combos, size, strict=True))
        assert all(u > lo for u in util)
        lows.append((len(got), lo))
    assert got == global_order(uf, delta, fits)
    utils = [float(uf[list(c)].sum()) for c in got]
    for n_before, lo in lows:
        assert all(u <= lo for u in utils[n_before:])
