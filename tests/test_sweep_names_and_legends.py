"""Sweep folders named in characters a shell takes as they are, legends beside crowded
plots, reports that keep constant metrics, and a colour bar for link margins."""

from __future__ import annotations

import re

import matplotlib

matplotlib.use("Agg")
import numpy as np  # noqa: E402
from hypothesis import example, given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402

from tether.config import load_scenario, sweep_label  # noqa: E402
from tether.experiments.plan import trials_of  # noqa: E402
from tether.viz.plots import pyplot, series_over_time, snapshot  # noqa: E402

SAFE = re.compile(r"[A-Za-z0-9._+\-=,~]+")
scalars = st.one_of(st.integers(-10**6, 10**6), st.floats(allow_nan=False, allow_infinity=False),
                    st.booleans(), st.text(max_size=30))  # fmt: skip
values = st.one_of(scalars, st.lists(scalars, max_size=4),
                   st.dictionaries(st.text(max_size=5), scalars, max_size=3))  # fmt: skip
keys = st.from_regex(r"[a-z]{1,6}", fullmatch=True)  # distinct leaves: one part per key


@settings(max_examples=300, deadline=None)
@given(st.dictionaries(keys, values, min_size=1, max_size=8))
@example({"a": "x" * 70, "b": "y" * 20, "c": 123456.789, "d": "z" * 78, "e": "w" * 78})
def test_labels_use_only_safe_characters_and_keep_numbers_whole(combo) -> None:
    label = sweep_label({f"strategy.params.{k}": v for k, v in combo.items()})
    assert SAFE.fullmatch(label), label
    parts = [re.sub(r"~[0-9a-f]{10}$", "", p) for p in label.split(",")]  # a long label's hash
    for key, value in combo.items():
        if isinstance(value, int | float):
            shown = [p for p in parts if p.startswith(f"{key}=")]
            assert shown in ([], [f"{key}={value}"]), (shown, value)  # whole, or left out


def test_labels_tell_combinations_apart() -> None:
    combos = [{"t": "a b"}, {"t": "a_b"}, {"t": "a'b"}, {"t": [1, 2]}, {"t": [1, 3]},
              {"t": {"k": 1}}, {"t": {"k": 2}}, {"t": 1.5}, {"t": "1.5x"}]  # fmt: skip
    labels = [sweep_label(c) for c in combos]
    assert len(set(labels)) == len(labels), labels


def test_zipped_axes_are_named_by_their_first_axis(tmp_path) -> None:
    """Fig. 9 zips a scene with its parameters, range, preset, targets and start."""
    folders = {t.run_dir.rsplit("/", 2)[-2] for _, t in trials_of(
        load_scenario("paper/continuous_fig9"), tmp_path, 1)}  # fmt: skip
    assert len(folders) == 18  # 6 team sizes x 3 scenes
    for name in folders:
        assert re.fullmatch(r"n_robots=\d+,scene=(empty|town|office)~[0-9a-f]{8}", name), name


def _overlaps(a, b) -> bool:
    return not (a.x1 <= b.x0 or b.x1 <= a.x0 or a.y1 <= b.y0 or b.y1 <= a.y0)


def test_a_crowded_legend_goes_beside_the_plot_a_small_one_inside() -> None:
    t = np.arange(50.0)
    crowded = {f"n_robots={k},trajectory=h0123abcd,d0_m={k / 2}": (t, t * k) for k in range(12)}
    fig = series_over_time(crowded, "time (s)", "links")
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    (legend,) = fig.legends
    assert fig.axes[0].get_legend() is None
    assert not _overlaps(legend.get_window_extent(renderer), fig.axes[0].get_window_extent())
    pyplot().close(fig)
    fig = series_over_time({"a": (t, t), "b": (t, 2 * t)}, "time (s)", "links")
    assert fig.axes[0].get_legend() is not None and not fig.legends
    pyplot().close(fig)


def test_snapshots_have_a_link_margin_colour_bar() -> None:
    pos = np.array([[0.0, 0.0], [5.0, 0.0], [9.0, 1.0]])
    fig = snapshot([pos], [np.array([[0, 1], [1, 2]])], ["t = 0 s"], range_m=10.0)
    labels = [ax.get_ylabel() for ax in fig.axes]
    assert "link margin, 1 - d / range" in labels
    pyplot().close(fig)
