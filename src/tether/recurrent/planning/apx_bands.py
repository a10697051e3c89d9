"""genNewSubset of Algorithm 1 (Banfi et al., Sec. IV-B): subsets band by band of utility.

:func:`bands` makes the subsets of at most ``delta`` frontiers (positions in order of
decreasing utility) in the order Algorithm 1 examines them -- decreasing utility,
increasing size, then colex rank -- one band of utility at a time, so that the
utility bound of Step 10 stops the enumeration as well as the DP
(:mod:`tether.recurrent.planning.apx`); :func:`subsets_in_band` makes one band of one
size.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator

import numpy as np

FIRST_BAND = 1 / 64  # width of the first utility band, relative to the best subset
LOWEST_BAND_RATIO = 0.75  # a band (lo, hi] has lo >= this * hi (unless it is the last)
BAND_SUBSETS = 20_000  # a band after a larger one is narrower in proportion


def subsets_in_band(
    uf: np.ndarray, s: int, lo: float, hi: float, fits: np.ndarray | None = None
) -> np.ndarray:
    """Sorted ``s``-subsets of positions with ``lo < U(F) <= hi`` (``uf`` non-increasing).

    Built position by position; a prefix is extended only by the contiguous
    range of next positions for which some completion can land in the band
    (the ``r`` positions right after give the largest completion, the last
    ``r`` positions the smallest). Exact band membership is decided on the
    sums recomputed as Algorithm 1 ranks them. With ``fits`` (``(k, k)`` bool),
    only subsets whose every pair of positions fits are made: a prefix with a pair
    that does not is dropped.
    """
    k = len(uf)
    if s > k:
        return np.empty((0, s), dtype=np.intp)
    csum = np.concatenate([[0.0], np.cumsum(uf)])
    slack = 1e-9 * (1.0 + csum[-1])
    pre = np.empty((1, 0), dtype=np.intp)
    psum = np.zeros(1)
    for t in range(s):
        r = s - t - 1  # positions still to choose after this one
        window = csum[r + 1 :] - csum[: k - r]  # uf[j] + the r next values, j <= k-1-r
        tail = csum[k] - csum[k - r]  # the r smallest values
        start = pre[:, -1] + 1 if t else np.zeros(len(pre), dtype=np.intp)
        stop = np.searchsorted(-window, psum - lo + slack, side="left")
        first = np.searchsorted(-uf[: k - r], psum + tail - hi - slack, side="left")
        first = np.maximum(start, first)
        count = np.maximum(stop - first, 0)
        owner = np.repeat(np.arange(len(pre)), count)
        offset = np.arange(len(owner)) - np.repeat(np.cumsum(count) - count, count)
        nxt = first[owner] + offset
        if fits is not None and t:
            keep = fits[pre[owner, 0], nxt]
            for m in range(1, t):
                keep &= fits[pre[owner, m], nxt]
            owner, nxt = owner[keep], nxt[keep]
        pre = np.column_stack([pre[owner], nxt])
        psum = psum[owner] + uf[nxt]
    util = uf[pre].sum(axis=1)
    return pre[(util > lo) & (util <= hi)]


def bands(
    uf: np.ndarray,
    delta: int,
    rank: Callable[[np.ndarray], np.ndarray],
    fits: np.ndarray | None = None,
) -> Iterator[tuple[np.ndarray, ...]]:
    """genNewSubset: subsets of <= ``delta`` positions, band by band of utility.

    Yields ``(util, size, combos, lo)`` (``combos`` padded with -1 to ``delta``
    columns; ``lo`` the band's lower end: every later subset has ``U <= lo``)
    ordered by decreasing utility, increasing size, then colex rank, i.e. exactly
    the order of a global sort; bands are disjoint utility intervals ``(lo, hi]``,
    the first :data:`FIRST_BAND` times the ``delta``-th utility wide, then of
    doubling width with ``lo >= LOWEST_BAND_RATIO * hi``, narrower when the growth
    of the last bands predicts more than :data:`BAND_SUBSETS` subsets; a consumer
    that stops early (Step 10) never makes the later bands. With ``fits`` (see
    :func:`subsets_in_band`) the subsets with a pair that does not fit are left out
    and the others keep that order.

    Parameters
    ----------
    uf
        Utilities of the positions ``0..k-1``, non-increasing and positive.
    delta
        The largest subset size.
    rank
        Colex ranks of sorted subsets given as rows (``_Ranker.rank`` of APX).
    fits
        Optional ``(k, k)`` boolean: the pairs of positions a subset may hold.
    """
    top = float(uf[:delta].sum())
    floor = float(uf.min())  # no subset has a smaller utility (utilities are > 0)
    # the first band's width scales with the delta-th utility, not the best subset's: one
    # frontier far more useful than the rest (a robot next to it) would put every subset
    # holding it into one band (C(109, 3) = 209 k subsets where the search stopped after
    # 16 k)
    width = float(uf[min(delta, len(uf)) - 1]) * FIRST_BAND
    hi, lo, last = np.inf, top - width, 0
    while True:
        if lo < max(floor, 1e-9 * top):
            lo = -1.0  # the last band: every subset left
        parts = [subsets_in_band(uf, s, lo, hi, fits) for s in range(1, delta + 1)]
        combos = np.full((sum(len(p) for p in parts), delta), -1, dtype=np.intp)
        util, size, ranks, at = [], [], [], 0
        for s, p in enumerate(parts, start=1):
            combos[at : at + len(p), :s] = p
            at += len(p)
            util.append(uf[p].sum(axis=1))
            size.append(np.full(len(p), s))
            ranks.append(rank(p))
        util_a, size_a = np.concatenate(util), np.concatenate(size)
        order = np.lexsort((np.concatenate(ranks), size_a, -util_a))
        yield util_a[order], size_a[order], combos[order], lo
        if lo < 0:
            return
        # widths double (as Algorithm 1's bands), but a band never reaches below
        # LOWEST_BAND_RATIO of its upper end: the number of subsets grows steeply as the
        # utility falls, and Step 10 usually stops inside the band (one band of 1.9 M
        # subsets cost 2 s where the search stopped in its first thousands)
        # ... and narrower in proportion when, at the growth from the last band to this
        # one, it would hold more than BAND_SUBSETS subsets (they crowd at lower
        # utilities: a wide last band was mostly made after the subset that stopped the
        # search)
        width = min(2.0 * width, (1.0 - LOWEST_BAND_RATIO) * lo)
        guess = len(util_a) * max(1.0, len(util_a) / max(1, last))  # next band, same growth
        if guess > BAND_SUBSETS:
            width = min(width, (hi - lo if hi < np.inf else width) * BAND_SUBSETS / guess)
        hi, lo, last = lo, lo - width, len(util_a)
