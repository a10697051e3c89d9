"""The up-front refusals of a uniform placement (``tether.team._check_box_fits``).

A refusal must never hit a team that fits: a square or cubic lattice at exactly the
separation is a valid placement, and its size must pass. A box far too small, or a draw
that would list billions of links, must be refused before any draw.
"""

from __future__ import annotations

import numpy as np
import pytest

from tether.team import MAX_EXPECTED_PAIRS, _check_box_fits


@pytest.mark.parametrize("seed", range(40))
def test_a_lattice_that_fits_is_never_refused(seed: int) -> None:
    rng = np.random.default_rng(seed)
    dim = int(rng.choice([2, 3]))
    sep = float(rng.uniform(0.2, 5.0))
    extent = rng.uniform(1.0, 60.0, size=dim)
    lattice = int(np.prod(np.floor(extent / sep) + 1))  # points sep apart inside the box
    if lattice * (lattice - 1) / 2 > MAX_EXPECTED_PAIRS:
        pytest.skip("a lattice this large trips the pair bound, not the packing bound")
    _check_box_fits(lattice, extent, range_m=sep, separation_m=sep)


@pytest.mark.parametrize("dim", [2, 3])
def test_a_box_far_too_small_is_refused(dim: int) -> None:
    extent = np.full(dim, 10.0)
    lattice = int(np.prod(np.floor(extent / 1.0) + 1))
    with pytest.raises(ValueError, match="do not fit"):
        _check_box_fits(4 * lattice, extent, range_m=1.0, separation_m=1.0)


def test_a_draw_with_billions_of_links_is_refused_and_a_sparse_one_is_not() -> None:
    extent = np.array([37.0, 37.0])
    with pytest.raises(ValueError, match="links within 15 m"):
        _check_box_fits(1_000_000, extent, range_m=15.0, separation_m=0.0)
    _check_box_fits(20, extent, range_m=15.0, separation_m=2.5)  # the paper's team
