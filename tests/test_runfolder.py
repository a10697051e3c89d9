"""Run folders commit like a database: atomic files, summary.json last, never two runs mixed."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from tether import runfolder
from tether.config import load_scenario, scenario_from_dict
from tether.errors import OutputError
from tether.runner import run


def tiny(max_steps: int = 5, figures: bool = True):
    data = load_scenario("silent_demo").model_dump(mode="json")
    data["sim"]["max_steps"] = max_steps
    data["output"]["figures"] = figures
    return scenario_from_dict(data, "tiny.yaml")


def files_of(path: Path) -> dict[str, bytes]:
    return {str(p.relative_to(path)): p.read_bytes() for p in path.rglob("*") if p.is_file()}


def writes_of_a_run(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> list[str]:
    """The file names a successful run writes, in order."""
    order: list[str] = []
    real = runfolder.atomic_write

    def spy(path: Path, write) -> None:  # noqa: ANN001
        order.append(path.name)
        real(path, write)

    monkeypatch.setattr(runfolder, "atomic_write", spy)
    run(tiny(), out_dir=tmp_path / "spy")
    monkeypatch.setattr(runfolder, "atomic_write", real)
    return order


def test_summary_is_written_last_and_every_file_is_committed(tmp_path, monkeypatch):
    order = writes_of_a_run(tmp_path, monkeypatch)
    assert order[-1] == "summary.json"
    assert order.count("summary.json") == 1
    committed = {Path(name).name for name in files_of(tmp_path / "spy")}
    assert committed == set(order)  # nothing unwritten, nothing stray
    assert {"steps.parquet", "robots.parquet", "links.parquet", "events.parquet",
            "scenario.yaml", "links.png", "snapshot.png"} <= committed  # fmt: skip


def test_a_failure_at_any_write_leaves_the_previous_run_untouched(tmp_path, monkeypatch):
    """Inject a failure at each write in turn: the folder holds the old run or nothing."""
    n_writes = len(writes_of_a_run(tmp_path, monkeypatch))
    out = tmp_path / "out"
    run(tiny(figures=False), out_dir=out, seed=7)
    before = files_of(out)
    real = runfolder.atomic_write
    for k in range(n_writes):
        calls = {"n": 0}

        def failing(path: Path, write, k=k, calls=calls) -> None:  # noqa: ANN001
            calls["n"] += 1
            if calls["n"] == k + 1:
                raise OSError(f"disk full at write {k}")
            real(path, write)

        monkeypatch.setattr(runfolder, "atomic_write", failing)
        with pytest.raises(OutputError, match=rf"run folder \(disk full at write {k}\)"):
            run(tiny(), out_dir=out, seed=3)
        monkeypatch.setattr(runfolder, "atomic_write", real)
        assert files_of(out) == before, f"failure at write {k} changed the committed run"
        assert [p.name for p in tmp_path.iterdir() if "staging" in p.name] == []
        fresh = tmp_path / f"fresh{k}"
        monkeypatch.setattr(runfolder, "atomic_write", failing)
        calls["n"] = 0
        with pytest.raises(OutputError):
            run(tiny(), out_dir=fresh, seed=3)
        monkeypatch.setattr(runfolder, "atomic_write", real)
        assert not fresh.exists()  # no folder without summary.json, and none with it


def test_atomic_write_never_leaves_half_a_file(tmp_path):
    target = tmp_path / "table.bin"
    target.write_bytes(b"old complete content")

    def half(tmp: str) -> None:
        with open(tmp, "wb") as fh:
            fh.write(b"new but")
        raise RuntimeError("killed mid-write")

    with pytest.raises(RuntimeError):
        runfolder.atomic_write(target, half)
    assert target.read_bytes() == b"old complete content"
    assert [p.name for p in tmp_path.iterdir()] == ["table.bin"]  # no temporary left


def test_reusing_an_output_folder_replaces_the_run_as_a_whole(tmp_path):
    out = tmp_path / "run"
    run(tiny(figures=True), out_dir=out, seed=1)
    assert (out / "figures" / "snapshot.png").exists()
    run(tiny(figures=False), out_dir=out, seed=2)
    assert not (out / "figures").exists()  # the first run's figures did not survive
    summary = json.loads((out / "summary.json").read_text())
    assert summary["seed"] == 2


@pytest.mark.parametrize("kind", ["file", "user folder"])
def test_an_output_path_that_is_not_a_run_folder_is_refused(tmp_path, kind):
    out = tmp_path / "mine"
    if kind == "file":
        out.write_text("precious")
    else:
        out.mkdir()
        (out / "notes.txt").write_text("precious")
    with pytest.raises(OutputError, match="mine"):
        run(tiny(), out_dir=out)
    assert "precious" in (out.read_text() if kind == "file" else (out / "notes.txt").read_text())


def test_a_parent_removed_by_a_concurrent_abort_is_made_again(tmp_path, monkeypatch):
    """In a sweep, one trial's abort can remove the combination folder it made while another
    trial of that combination is between making it and making its staging folder (a CI
    failure: "cannot create the run folder (No such file or directory)")."""
    import tempfile as tempfile_module

    from tether.runfolder import RunFolder

    real = tempfile_module.mkdtemp
    removed: list[bool] = []

    def racing_mkdtemp(*args, **kwargs):  # noqa: ANN002, ANN003, ANN202
        if not removed:  # the other trial's abort runs right now
            removed.append(True)
            kwargs["dir"].rmdir()
        return real(*args, **kwargs)

    monkeypatch.setattr(tempfile_module, "mkdtemp", racing_mkdtemp)
    folder = RunFolder(tmp_path / "combo" / "seed-2")
    assert removed and folder.staging.is_dir()
    assert folder.staging.parent == tmp_path / "combo"
