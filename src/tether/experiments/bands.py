"""Percentile-band figures of sweep results, in the one look of :mod:`tether.viz.style`.

* :func:`bands_against_axis`: a summary metric against a numeric axis (e.g. team size):
  the median as a line, the 25-75 and 10-90 percentile bands shaded, one colour per
  series (the other axes' values);
* :func:`bands_over_time`: a per-step metric against time, the same bands over seeds,
  one colour per combination.
"""

from __future__ import annotations

from collections.abc import Mapping

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402

from tether.viz import style  # noqa: E402
from tether.viz.plots import TIME_LABEL  # noqa: E402

__all__ = ["PERCENTILES", "bands_against_axis", "bands_over_time", "percentiles"]

#: the percentiles drawn: outer band, inner band, median, inner band, outer band
PERCENTILES = (10, 25, 50, 75, 90)
BAND_NOTE = "line: median; bands: 25-75 and 10-90 percentiles"


def percentiles(samples: np.ndarray, axis: int = 0) -> np.ndarray:
    """The :data:`PERCENTILES` of ``samples`` along ``axis`` (NaN ignored), stacked first."""
    with np.errstate(all="ignore"):
        return np.nanpercentile(np.asarray(samples, dtype=float), PERCENTILES, axis=axis)


def _colour(k: int) -> str:
    return style.ROLE_CYCLE[k % len(style.ROLE_CYCLE)]


def _draw(ax: object, x: np.ndarray, q: np.ndarray, colour: str, label: str) -> None:
    ax.fill_between(x, q[0], q[4], color=colour, alpha=0.14, lw=0)  # type: ignore[attr-defined]
    ax.fill_between(x, q[1], q[3], color=colour, alpha=0.30, lw=0)  # type: ignore[attr-defined]
    ax.plot(x, q[2], color=colour, lw=1.5, label=label)  # type: ignore[attr-defined]


def _finish(fig: Figure, xlabel: str, ylabel: str, title: str, legend: bool) -> Figure:
    ax = fig.axes[0]
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.grid(alpha=0.3)
    ax.set_facecolor(style.BACKGROUND)
    ax.set_title(f"{title}\n{BAND_NOTE}", fontsize=9)
    if legend:
        style.place_legend(ax)
    return fig


def bands_against_axis(
    series: Mapping[str, Mapping[float, np.ndarray]], xlabel: str, ylabel: str, title: str
) -> Figure:
    """A metric against a numeric axis: per series, values by axis value -> bands.

    Parameters
    ----------
    series : mapping
        Series label -> {axis value: the metric's values over seeds}.
    """
    fig, ax = plt.subplots(figsize=(6.4, 3.6), layout="constrained")
    for k, (label, by_x) in enumerate(series.items()):
        xs = np.array(sorted(by_x), dtype=float)
        q = np.stack([percentiles(by_x[x]) for x in sorted(by_x)], axis=1)
        _draw(ax, xs, q, _colour(k), label)
        ax.plot(xs, q[2], "o", color=_colour(k), ms=3.5)
    return _finish(fig, xlabel, ylabel, title, legend=len(series) > 1 or bool(next(iter(series))))


def bands_over_time(
    series: Mapping[str, tuple[np.ndarray, np.ndarray]],
    ylabel: str,
    title: str,
    reference: tuple[float, str] | None = None,
) -> Figure:
    """A per-step metric against time: per series, ``(t, values[seed, step])`` -> bands.

    Runs of different lengths are padded with NaN (a band then covers the seeds still
    running).
    """
    fig, ax = plt.subplots(figsize=(6.4, 3.6), layout="constrained")
    for k, (label, (t, values)) in enumerate(series.items()):
        _draw(ax, np.asarray(t, dtype=float), percentiles(values, axis=0), _colour(k), label)
    if reference is not None:
        ax.axhline(reference[0], color=style.CURSOR, ls=":", lw=1, label=reference[1])
    return _finish(fig, TIME_LABEL, ylabel, title, legend=True)
