"""The ``tether`` command line: a thin layer over :mod:`tether.runner`.

Every command is one call of the Python API; errors in the user's input are
printed as one line (file, field, fix) with exit code 2, never a traceback.
"""

from __future__ import annotations

import os
import signal
import sys
import warnings
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Annotated

import typer
from rich.console import Console

from tether.config import MAX_SEED, Scenario
from tether.errors import TetherError, TetherWarning
from tether.interrupts import Stopped, stop_on_signals
from tether.terminal.help import flow, summary
from tether.terminal.usage import usage_error_class, usage_line
from tether.terminal.words import count

app = typer.Typer(
    add_completion=False,
    no_args_is_help=False,
    help="tether: multi-robot teams that stay connected. Run `tether run` for a demo.",
    context_settings={"help_option_names": ["-h", "--help"]},
)
out = Console()
err = Console(stderr=True)

DEFAULT_SCENARIO = "silent_demo"


def say(message: str) -> None:
    """One line of output as written: no markup, no colouring, never wrapped to the terminal."""
    out.print(message, markup=False, highlight=False, soft_wrap=True)


@contextmanager
def noting(note: str) -> Iterator[None]:
    """Tell the user, if the block is stopped (Ctrl-C, SIGTERM), what the stop left behind."""
    try:
        yield
    except Stopped as exc:
        exc.note = note
        raise


def _version(value: bool) -> None:
    if value:
        from tether import __version__
        from tether.runfolder import git_hash

        say(f"tether {__version__} (commit {git_hash()})")
        raise typer.Exit()


@app.callback()
def _options(
    version: Annotated[
        bool,
        typer.Option("--version", callback=_version, is_eager=True, help="Print the version."),
    ] = False,
) -> None:
    """tether: multi-robot teams that stay connected. Run `tether run` for a demo."""


def _seed(value: int | None) -> int | None:
    if value is not None and not 0 <= value <= MAX_SEED:
        raise typer.BadParameter("must be an integer from 0 to 2**63 - 1")
    return value


ScenarioArg = Annotated[
    str, typer.Argument(help="Scenario YAML file, or the name of a built-in scenario.")
]
SetOpt = Annotated[
    list[str] | None,
    typer.Option("--set", "-s", help="Override a scenario key, e.g. strategy.params.d0_m=5"),
]
PluginOpt = Annotated[
    list[str] | None,
    typer.Option(
        "--plugin",
        "-p",
        help="Import your own plug-in first: a module name or a .py file (repeatable).",
    ),
]

QuietOpt = Annotated[
    bool, typer.Option("--quiet", "-q", help="No progress bar (or progress lines).")
]
QuickOpt = Annotated[
    bool,
    typer.Option(
        "--quick", help="The experiment at its quick size (the sweep block's `quick` entry)."
    ),
]
#: the sweep folder without --out (``-quick`` appended for the quick size)
DEFAULT_SWEEP_DIR = "runs/sweep"


def _load(scenario: str, overrides: list[str] | None, quick: bool = False):
    from tether.quicksize import load_scenario_at

    return load_scenario_at(scenario, quick=quick, overrides=overrides)


def _load_plugins(plugins: list[str] | None) -> None:
    """Import the ``--plugin`` modules and files, before any scenario is read."""
    from tether.plugins import load_plugins

    load_plugins(plugins)


def _check_sweep_block(
    scenario: str, overrides: list[str] | None, sc: Scenario, quick: bool = False
) -> int:
    """Every combination of the sweep block builds, and the quick size's keys and values
    are valid (what ``validate`` checks beyond ``build``); the number of combinations."""
    from tether.experiments.plan import check_combinations
    from tether.runner import check_sweep, strategy_class

    n_combos = check_combinations(sc)
    if not quick and "quick" in sc.sweep:
        small = _load(scenario, overrides, quick=True)
        check_sweep(small, strategy_class(small))
    return n_combos


@app.command()
def run(
    scenario: ScenarioArg = DEFAULT_SCENARIO,
    out_dir: Annotated[
        Path | None, typer.Option("--out", "-o", help="Run folder (default: runs/<name>-...)")
    ] = None,
    seed: Annotated[
        int | None, typer.Option(callback=_seed, help="Override the scenario's seed (0 or more).")
    ] = None,
    set_: SetOpt = None,
    no_figures: Annotated[bool, typer.Option("--no-figures", help="Skip the PNG figures.")] = False,
    animate_: Annotated[bool, typer.Option("--animate", help="Then `tether animate` it.")] = False,
    view_: Annotated[bool, typer.Option("--view", help="Then `tether view` it.")] = False,
    plugin: PluginOpt = None,
    quiet: QuietOpt = False,
) -> None:
    """Run one scenario and write its run folder (scenario, Parquet records, summary, figures).

    Example: tether run scenarios/silent_paper.yaml --set strategy.params.d0_m=5
    """
    _load_plugins(plugin)
    from tether.progress import StepProgress
    from tether.runner import run as run_scenario
    from tether.runner import strategy_class
    from tether.terminal.notes import run_notes

    sc = _load(scenario, set_)
    say(f"running {sc.name} ({sc.strategy.name}, {count(sc.team.n_robots, 'robot')}) ...")
    placing = f"building the world and placing {count(sc.team.n_robots, 'robot')}"
    steps = None if quiet else StepProgress(out, say, sc.sim.max_steps, preparing=placing)
    try:
        with noting("no run folder was written"):
            outcome = run_scenario(
                sc, out_dir=out_dir, seed=seed, progress=steps,
                figures=False if no_figures else None,
                check=lambda: _check_sweep_block(scenario, set_, sc),  # what validate refuses
            )  # fmt: skip
    finally:
        if steps is not None:
            steps.stop()
    s = outcome.summary
    keys = [
        "steps",
        "sim_time_s",
        "wall_time_s",
        "connected_all_steps",
        "min_lambda2",
        "min_links",
        "collisions",
        "final_explored_fraction",
        "out_of_comm_mean_steps",
        "planning_time_mean_s",
        "planning_time_max_s",
        "min_lambda2_weighted",
        "min_robot_distance_m",
        "min_obstacle_clearance_m",
        "controller_success",
        "safe_set_exits",
        "guard_interventions",
        "max_speed_mps",
        "targets_reached",
    ]
    for k in keys:
        if s.get(k) is not None:  # None: not measured in this run (no obstacles, ...)
            v = s[k]
            say(f"  {k:<24} {v:.4g}" if isinstance(v, float) else f"  {k:<24} {v}")
    for note in run_notes(outcome.path, s, sc, strategy_class(sc)):
        say(f"note: {note}")
    say(f"results: {outcome.path}")
    if animate_:
        animate(outcome.path)
    if view_:
        view(outcome.path)


@app.command()
def sweep(
    scenario: ScenarioArg,
    out_dir: Annotated[
        Path | None,
        typer.Option(
            "--out", "-o", help="Sweep folder (default: runs/sweep, runs/sweep-quick with --quick)."
        ),
    ] = None,
    seeds: Annotated[
        int | None,
        typer.Option(min=1, help="Seeds per combination (default: the sweep block's, else 1)."),
    ] = None,
    executor: Annotated[
        str, typer.Option(help="Where trials run: processes (all cores), serial or dask.")
    ] = "processes",
    workers: Annotated[
        int | None,
        typer.Option(min=1, help="Processes (processes, local dask); default: all cores."),
    ] = None,
    address: Annotated[
        str | None, typer.Option(help="Dask scheduler address, e.g. tcp://host:8786.")
    ] = None,
    set_: SetOpt = None,
    quick: QuickOpt = False,
    plugin: PluginOpt = None,
    quiet: QuietOpt = False,
) -> None:
    """Run the scenario's `sweep:` combinations x seeds (resumable) into one table of trials.

    With --quick, the experiment at the size its sweep block's `quick` entry gives (its
    own scenario hash, so never mixed with the full size's trials).

    Example: tether sweep scenarios/silent_paper.yaml --out runs/fig5 --seeds 20
    """
    _load_plugins(plugin)
    from tether.experiments.progress import progress_for
    from tether.experiments.sweep import run_sweep
    from tether.quicksize import QUICK_SUFFIX

    sc = _load(scenario, set_, quick)
    if out_dir is None:
        out_dir = Path(DEFAULT_SWEEP_DIR + (QUICK_SUFFIX if quick else ""))
    resume = f"finished trials are kept in {out_dir}; the same command resumes the sweep"
    checking = "checking every combination of the sweep (its world and team)"
    progress = None if quiet else progress_for(out, say, preparing=checking)
    try:
        with noting(resume):
            result = run_sweep(sc, out_dir, seeds=seeds, executor=executor, workers=workers,
                               address=address, progress=progress)  # fmt: skip
    finally:
        if progress is not None:
            progress.stop()
    out.print(
        f"{result.n_runs} runs ({result.n_skipped} already done); table: {result.table}",
        markup=False,
        highlight=False,
    )
    for fig in result.figures:
        out.print(f"figure: {fig}", markup=False, highlight=False)


@app.command()
def report(
    sweep_dirs: Annotated[
        list[Path], typer.Argument(help="Sweep folder(s) written by `tether sweep`.")
    ],
    paper: Annotated[
        str | None,
        typer.Option(
            "--paper",
            help="recurrent: the recurrent paper's Figs. 4-6 and tables from the sweep "
            "folders of its campaigns (paper/recurrent_*).",
        ),
    ] = None,
    out_dir: Annotated[
        Path | None,
        typer.Option("--out", "-o", help="With --paper: where to write (default: first folder)."),
    ] = None,
) -> None:
    """Write a Markdown report of a sweep: figures with percentile bands and statistics.

    Writes SWEEP_DIR/report.md and SWEEP_DIR/figures/. Example: tether report runs/fig5

    With --paper recurrent, several folders (the sweeps of paper/recurrent_fig4,
    recurrent_fig5_6, recurrent_fig5_6_utility, recurrent_relay_binding) make the
    paper's figures and tables: OUT/recurrent_paper.md, .json and OUT/figures/.
    """
    command = " ".join(["tether report", *map(str, sweep_dirs)])
    if paper is not None:
        from tether.recurrent.report import write_paper_report

        command += f" --paper {paper}" + (f" --out {out_dir}" if out_dir else "")
        path = write_paper_report(paper, sweep_dirs, out_dir, command=command)
    else:
        from tether.experiments.report import write_report

        if len(sweep_dirs) != 1 or out_dir is not None:
            raise TetherError(
                "tether report: give one sweep folder (several, and --out, only with --paper)"
            )
        path = write_report(sweep_dirs[0], command=command)
    out.print(f"report: {path}", markup=False, highlight=False, soft_wrap=True)


@app.command()
def validate(
    scenario: ScenarioArg, set_: SetOpt = None, quick: QuickOpt = False, plugin: PluginOpt = None
) -> None:
    """Check a scenario (schema, strategy parameters, map, initial team, memory) without running.

    Runs exactly the checks `tether run` runs before simulating (tether.runner.build),
    and builds every combination of the `sweep:` block as `tether sweep` does, so a
    scenario that validates is one that runs. The sweep's quick size, if any, is checked
    too (its keys and values); --quick checks the quick size as fully as the full one.
    """
    _load_plugins(plugin)
    from tether.limits import format_bytes
    from tether.progress import Working
    from tether.runfolder import check_writable
    from tether.runner import build, strategy_class, strategy_params
    from tether.usercode import code_references

    sc = _load(scenario, set_, quick)
    with Working(f"checking {scenario}: its world, {count(sc.team.n_robots, 'robot')}, "
                 "strategy and sweep", out, say):  # fmt: skip
        need = build(sc).memory_bytes
        calls = code_references(strategy_params(sc, strategy_class(sc)), "strategy.params.")
        n_combos = _check_sweep_block(scenario, set_, sc, quick)
    check_writable(sc.output.dir)  # where `tether run` would write (without --out)
    size = ", quick size" if quick else ""
    swept = f", sweep of {count(n_combos, 'combination')}{size}" if n_combos else size
    say(
        f"{scenario}: ok ({sc.strategy.name}, {count(sc.team.n_robots, 'robot')}{swept}); "
        f"memory about {format_bytes(need)}"
    )
    for field, spec in calls:  # code the scenario names (only ever from loaded modules)
        say(f"  calls {spec} ({field})")


@app.command("list")
def list_(plugin: PluginOpt = None) -> None:
    """List the built-in scenarios, campaigns, strategies, scenes and link models.

    Each with what it is, and where its name goes (a command or a scenario key); with
    installed plug-in packages' and those of --plugin.
    """
    _load_plugins(plugin)
    from tether.plugins import IGNORED
    from tether.terminal.listing import listing_lines

    for line in listing_lines():
        say(line)
    for line in IGNORED:
        say(f"ignored plug-in: {line}")


RunDirArg = Annotated[Path, typer.Argument(help="A run folder written by `tether run`.")]


@app.command()
def animate(
    run_dir: RunDirArg,
    out_file: Annotated[Path | None, typer.Option("--out", "-o", help="GIF or MP4 file.")] = None,
    fmt: Annotated[str | None, typer.Option("--format", help="gif or mp4 (ffmpeg).")] = None,
    fps: Annotated[float, typer.Option(help="Frames per second.")] = 10.0,
    duration: Annotated[float | None, typer.Option(help="Longest length (s); default 20.")] = None,
    stride: Annotated[int | None, typer.Option(min=1, help="Every N-th recorded step.")] = None,
    width: Annotated[int, typer.Option(min=64, max=8192, help="Width in pixels.")] = 720,
) -> None:
    """Animate a run folder as a GIF (or an MP4 where ffmpeg exists).

    Example: tether animate runs/silent_demo --fps 20 --format mp4
    """
    from tether.viewing.commands import animate_command

    animate_command(
        run_dir,
        out_file,
        fmt=fmt,
        fps=fps,
        duration_s=duration,
        stride=stride,
        width_px=width,
        say=say,
    )


@app.command()
def view(
    run_dir: RunDirArg,
    out_file: Annotated[Path | None, typer.Option("--out", "-o", help="HTML file.")] = None,
    max_mb: Annotated[float, typer.Option(help="Size budget; long runs are thinned.")] = 8.0,
    serve: Annotated[bool, typer.Option(help="Also serve it on 127.0.0.1.")] = False,
    port: Annotated[
        int, typer.Option(min=0, max=65535, help="Port for --serve (0: any free one).")
    ] = 8000,
) -> None:
    """Write a self-contained, offline HTML 3-D replay of a run folder."""
    from tether.viewing.commands import view_command

    view_command(run_dir, out_file, max_mb=max_mb, serve=serve, port=port, say=say)


@app.command("export")
def export_(
    run_dir: RunDirArg,
    fmt: Annotated[str, typer.Option("--format", help="mcap or rosbag2.")] = "mcap",
    out_path: Annotated[Path | None, typer.Option("--out", "-o", help="File or folder.")] = None,
) -> None:
    """Export a run folder as ROS 2 messages (Foxglove, RViz, ros2 bag play)."""
    from tether.viewing.commands import export_command

    export_command(run_dir, out_path, fmt=fmt, say=say)


_python_showwarning = warnings.showwarning


def _show_warning(message, category, filename, lineno, file=None, line=None) -> None:  # noqa: ANN001
    """A :class:`TetherWarning` as one ``warning: ...`` line; others as Python shows them."""
    if issubclass(category, TetherWarning):
        err.print(f"warning: {message}", highlight=False, markup=False, soft_wrap=True)
    else:
        _python_showwarning(message, category, filename, lineno, file, line)


def main(argv: list[str] | None = None) -> None:
    """Entry point: run the app, turning user errors into one line on stderr.

    Exit codes: 0 success, 2 bad input (one ``error:`` line naming the file or
    option, the field and the fix; usage errors too), 1 an internal error (one
    line with a hint; ``TETHER_DEBUG=1`` shows the traceback), 130 interrupted by
    Ctrl-C and 143 by SIGTERM (one line; a run folder being written is removed).
    """
    warnings.showwarning = _show_warning
    args = sys.argv[1:] if argv is None else list(argv)
    try:
        with stop_on_signals(), warnings.catch_warnings():
            if not os.environ.get("TETHER_DEBUG"):  # one line on stderr: no numpy warning
                warnings.simplefilter("ignore", RuntimeWarning)
            code = app(args=args or ["--help"], prog_name="tether", standalone_mode=False)
        if isinstance(code, int) and code == 130:  # typer's KeyboardInterrupt, no handler
            raise Stopped(signal.SIGINT)
    except Stopped as exc:  # Ctrl-C or SIGTERM: what the command was doing is undone
        err.print(str(exc), highlight=False, markup=False, soft_wrap=True)
        sys.exit(exc.code)
    except TetherError as exc:
        err.print(f"error: {exc}", highlight=False, markup=False, soft_wrap=True)
        sys.exit(2)
    except (typer.Exit, SystemExit) as exc:
        code = getattr(exc, "exit_code", getattr(exc, "code", 0))
        sys.exit(code or 0)
    except (typer.Abort, KeyboardInterrupt):
        err.print(str(Stopped(signal.SIGINT)), highlight=False, markup=False)
        sys.exit(130)
    except Exception as exc:  # usage errors, and anything unexpected
        if isinstance(exc, usage_error_class()):
            err.print(usage_line(exc), highlight=False, markup=False, soft_wrap=True)
            sys.exit(2)
        if type(exc).__name__ == "Abort":  # click's own Abort (Ctrl-C at a prompt)
            sys.exit(130)
        if os.environ.get("TETHER_DEBUG"):
            details = getattr(exc, "details", None)  # e.g. the traceback of a failed trial
            if details:
                print(details, file=sys.stderr)
            raise
        message = " ".join(str(exc).split())
        err.print(
            f"error: internal error {type(exc).__name__}: {message} "
            "(set TETHER_DEBUG=1 for the traceback and please report it)",
            highlight=False,
            markup=False,
            soft_wrap=True,
        )
        sys.exit(1)


for _command in app.registered_commands:  # help paragraphs flow to the terminal's width
    _command.help = flow(_command.callback.__doc__)
    _command.short_help = summary(_command.callback.__doc__)

if __name__ == "__main__":
    main()
