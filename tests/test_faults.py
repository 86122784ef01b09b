"""Faults of storage and files: a full disk, a failed or refused write, damaged or read-only stores, outputs
that are not regular files, temporary files of a killed run, two kinds of run in one folder. Each ends in
one line with the right exit code, keeps what was stored, and a rerun gives the uninterrupted result."""

import json
import os
import shutil
import subprocess
import uuid

import numpy as np
import pytest
import zarr
from typer.testing import CliRunner

from drillstring.cli import app
from drillstring.stochastic import montecarlo as mc

runner = CliRunner()
_ENV = {"COLUMNS": "120", "FORCE_COLOR": None, "TTY_COMPATIBLE": None, "TTY_INTERACTIVE": None}
#: Run information that differs between an interrupted and an uninterrupted study; everything else of the
#: summary (statistics, dispersion, convergence, failures, inputs) must be equal.
_RUN_KEYS = {"wall_time", "wall_time_this_run", "realizations_this_run", "realization_wall_time_total",
             "sessions", "files", "workers"}
_ARRAYS = ("status", "nominal_status", "weight_on_hook", "weight_on_bit", "input_values", "rate_of_penetration",
           "bit_speed", "radial_displacement", "nominal_rate_of_penetration", "nominal_radial_displacement", "time")


def _invoke(*args):
    return runner.invoke(app, [str(a) for a in args], env=_ENV)


@pytest.fixture(scope="module")
def case_file(coarse_case, tmp_path_factory):
    """The coarse reference case (conftest) as a case file: a 1 s realization takes a fraction of a second."""
    path = tmp_path_factory.mktemp("cases") / "coarse.toml"
    path.write_text(coarse_case.to_toml(), encoding="utf-8")
    return path


def _study(case_file, out, *extra):
    return _invoke("study", case_file, "--samples", "3", "--t-end", "1", "--workers", "1", "--out", out, "--json",
                   *extra)


@pytest.fixture(scope="module")
def uninterrupted(case_file, tmp_path_factory):
    """An uninterrupted study: its folder and its summary."""
    out = tmp_path_factory.mktemp("whole") / "study"
    result = _study(case_file, out)
    assert result.exit_code == 0, result.output
    return out, json.loads(result.stdout)


def _same_result(summary: dict, uninterrupted_summary: dict) -> None:
    differ = [k for k in uninterrupted_summary if k not in _RUN_KEYS and summary.get(k) != uninterrupted_summary[k]]
    assert not differ, differ


def _same_store(store, reference_store) -> None:
    a, b = zarr.open_group(str(store), mode="r"), zarr.open_group(str(reference_store), mode="r")
    for name in _ARRAYS:
        np.testing.assert_array_equal(a[name][...], b[name][...], err_msg=name)


def _one_line(result, code: int, *expected: str) -> str:
    assert result.exit_code == code, result.output
    lines = result.stderr.strip().splitlines()
    lines = [line for line in lines if "━" not in line and not line.startswith("realizations ")]  # progress bar
    assert len(lines) == 1 and lines[0].startswith("error: "), result.stderr
    for text in expected:
        assert text in lines[0], (text, lines[0])
    assert "Traceback" not in result.output
    return lines[0]


def _no_leftovers(folder) -> None:
    left = [p for p in folder.rglob("*") if p.name.endswith((".tmp", ".partial"))]
    assert not left, left


# --- outputs that are not regular files ------------------------------------------------------------------


def test_simulate_refuses_devices_and_fifos_and_leaves_them(case_file, tmp_path):
    fifo = tmp_path / "fifo"
    os.mkfifo(fifo)
    _one_line(_invoke("simulate", case_file, "--t-end", "0.1", "--out", "/dev/null", "--plot", tmp_path / "a.png"), 2,
              "--out = /dev/null: is a character device, not a regular file")
    _one_line(_invoke("simulate", case_file, "--t-end", "0.1", "--out", tmp_path / "a.nc", "--plot", fifo), 2,
              f"--plot = {fifo}: is a FIFO, not a regular file")
    assert os.path.exists("/dev/null") and not os.path.isfile("/dev/null")
    assert fifo.is_fifo()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["fifo"]


def test_study_output_that_is_a_fifo_is_refused_not_replaced(case_file, tmp_path, uninterrupted):
    """A FIFO where the study writes a file: refused in one line (exit 2), left as it was; the store is
    intact and the rerun, once it is gone, writes everything."""
    out = tmp_path / "study"
    shutil.copytree(uninterrupted[0] / "study.zarr", out / "study.zarr")
    os.mkfifo(out / "summary.json")
    _one_line(_study(case_file, out), 2, f"{out / 'summary.json'} is a FIFO, not a regular file")
    assert (out / "summary.json").is_fifo()
    _same_store(out / "study.zarr", uninterrupted[0] / "study.zarr")
    _no_leftovers(out)
    (out / "summary.json").unlink()
    result = _study(case_file, out)
    assert result.exit_code == 0, result.output
    _same_result(json.loads(result.stdout), uninterrupted[1])


# --- temporary files of a killed run ----------------------------------------------------------------------


def _dead_pid() -> int:
    proc = subprocess.Popen(["true"])
    proc.wait()
    return proc.pid


def test_temporaries_of_a_killed_run_are_removed_by_the_next(case_file, tmp_path, uninterrupted):
    out = tmp_path / "study"
    shutil.copytree(uninterrupted[0], out)
    dead = _dead_pid()
    stale = [out / f".statistics.nc.{dead}.140000.tmp", out / f".report.html.{dead}.1.tmp"]
    live = out / f".envelopes.png.{os.getppid()}.1.tmp"  # a writer still running: kept
    partial = out / "study.zarr" / "rate_of_penetration" / "c" / "1" / f"0.{uuid.uuid4().hex}.partial"
    for path in stale + [live, partial]:
        path.write_bytes(b"half")
    result = _study(case_file, out)
    assert result.exit_code == 0, result.output
    assert not any(p.exists() for p in stale + [partial])
    assert live.exists()
    _same_result(json.loads(result.stdout), uninterrupted[1])


# --- one kind of run per folder ---------------------------------------------------------------------------


def test_a_second_kind_of_run_in_a_folder_is_refused(case_file, tmp_path, uninterrupted):
    out = tmp_path / "study"
    shutil.copytree(uninterrupted[0], out)
    before = (out / "report.html").read_bytes()
    result = _invoke("map", case_file, "--top-speed", "100", "--weight-on-bit", "100 kN", "--t-end", "1",
                     "--workers", "1", "--out", out)
    _one_line(result, 2, f"{out} holds a study ({out / 'study.zarr'})", "use another --out folder for this map")
    assert (out / "report.html").read_bytes() == before
    assert not (out / "map.zarr").exists() and not (out / "map.zarr.lock").exists()


def test_a_folder_where_another_kind_runs_is_refused(case_file, tmp_path):
    """A map running in the folder (its lock held by a live process) refuses a study there."""
    out = tmp_path / "busy"
    out.mkdir()
    holder = subprocess.Popen(["sleep", "60"])
    try:
        (out / "map.zarr.lock").write_text(json.dumps({"pid": holder.pid, "host": os.uname().nodename}) + "\n")
        _one_line(_study(case_file, out), 2, f"{out} holds a map")
        assert sorted(p.name for p in out.iterdir()) == ["map.zarr.lock"]
    finally:
        holder.kill()
        holder.wait()


# --- failed writes: disk full, permission ------------------------------------------------------------------


def test_write_refused_midway_stops_in_one_line_and_resumes(case_file, tmp_path, uninterrupted, monkeypatch):
    """A write refused by the system (EACCES) after the first realization: one line, exit 1, what was
    stored is intact (finished rows equal the uninterrupted study's), no temporary file; the same command
    then resumes to the uninterrupted result."""
    from drillstring.stochastic.store import TaskStore

    original = TaskStore.write_many
    calls = []

    def refused(self, outcomes):
        calls.append(1)
        if len(calls) >= 3:  # nominal run, realization 0, then refused (the disk stays refused)
            raise PermissionError(13, "Permission denied", str(self.path / "rate_of_penetration" / "c" / "1" / "0"))
        return original(self, outcomes)

    monkeypatch.setattr(TaskStore, "write_many", refused)
    monkeypatch.setattr(mc.StudyStore, "flush_interval", 0.0)  # one write per realization: refused after the first
    out = tmp_path / "study"
    line = _one_line(_study(case_file, out), 1, "cannot write", "Permission denied",
                     f"finished realizations are kept in {out / 'study.zarr'}", "run the same command again")
    assert "give write permission" in line
    group = zarr.open_group(str(out / "study.zarr"), mode="r")
    reference = zarr.open_group(str(uninterrupted[0] / "study.zarr"), mode="r")
    assert list(group["status"][...]) == [1, 0, 0]
    np.testing.assert_array_equal(group["rate_of_penetration"][0], reference["rate_of_penetration"][0])
    _no_leftovers(out)
    monkeypatch.setattr(TaskStore, "write_many", original)
    result = _study(case_file, out)
    assert result.exit_code == 0, result.output
    _same_result(json.loads(result.stdout), uninterrupted[1])
    _same_store(out / "study.zarr", uninterrupted[0] / "study.zarr")


@pytest.fixture
def small_filesystem(tmp_path):
    """A 240 KiB tmpfs mounted for the test (skipped where mounting is not permitted), and a function that
    resizes it."""
    where = tmp_path / "small"
    where.mkdir()
    try:
        subprocess.run(["mount", "-t", "tmpfs", "-o", "size=240k", "tmpfs", str(where)], check=True,
                       capture_output=True, timeout=20)
    except (OSError, subprocess.SubprocessError):
        pytest.skip("cannot mount a small filesystem here (needs mount privileges)")

    def resize(size: str) -> None:
        subprocess.run(["mount", "-o", f"remount,size={size}", str(where)], check=True, capture_output=True,
                       timeout=20)

    yield where, resize
    subprocess.run(["umount", "-l", str(where)], capture_output=True, timeout=20)


def test_full_disk_stops_in_one_line_and_resumes_when_there_is_room(case_file, small_filesystem, uninterrupted):
    """A study on a filesystem too small for its store: one line (ENOSPC), exit 1, no half-written file;
    with room, the same command resumes to the uninterrupted result. Then a disk that fills while the
    figures are written: the same."""
    where, resize = small_filesystem
    out = where / "study"
    _one_line(_study(case_file, out), 1, f"cannot write {out / 'study.zarr'}: No space left on device",
              "free some space and run the same command again to resume")
    _no_leftovers(where)
    group = zarr.open_group(str(out / "study.zarr"), mode="r")
    reference = zarr.open_group(str(uninterrupted[0] / "study.zarr"), mode="r")
    for i in np.nonzero(group["status"][...] == 1)[0]:  # what was stored is whole
        np.testing.assert_array_equal(group["rate_of_penetration"][i], reference["rate_of_penetration"][i])
    resize("480k")  # the store (400 KiB in pages) fits, the figures and reports do not
    _one_line(_study(case_file, out), 1, "No space left on device", f"finished realizations are kept in {out}")
    _no_leftovers(where)
    assert not (out / "summary.json").exists() and not (out / "report.html").exists()
    _same_store(out / "study.zarr", uninterrupted[0] / "study.zarr")
    resize("12m")  # the interactive page alone is about 5 MB
    result = _study(case_file, out)
    assert result.exit_code == 0, result.output
    _same_result(json.loads(result.stdout), uninterrupted[1])


def test_simulate_on_a_full_disk_is_one_line(case_file, small_filesystem):
    where, _ = small_filesystem
    (where / "filler").write_bytes(b"x" * (230 * 1024))
    _one_line(_invoke("simulate", case_file, "--t-end", "1", "--out", where / "run.nc", "--plot", where / "run.png"),
              1, "No space left on device")
    _no_leftovers(where)
    assert sorted(p.name for p in where.iterdir()) == ["filler"]


# --- damaged stores ---------------------------------------------------------------------------------------


def _damage(store, name: str, chunk: str, how: str) -> None:
    path = store / name / "c" / chunk
    if how == "delete":
        path.unlink()
    else:
        data = path.read_bytes()
        path.write_bytes(data[: len(data) // 2])


@pytest.mark.parametrize("name, chunk, how, recomputed", [
    ("rate_of_penetration", "1/0", "delete", "realization 1 will be recomputed"),
    ("rate_of_penetration", "2/0", "truncate", "realization 2 will be recomputed"),
    ("status", "0", "truncate", "all 3 realizations will be recomputed"),
    ("weight_on_hook", "0", "delete", "all 3 realizations will be recomputed"),
    ("input_values", "0/0", "truncate", "all 3 realizations will be recomputed"),
    ("nominal_rate_of_penetration", "0", "delete", "the nominal run will be recomputed"),
    ("nominal_status", "0", "truncate", "the nominal run will be recomputed"),
    ("time", "0", "truncate", "rewritten"),
])
def test_damaged_chunk_is_named_recomputed_and_the_study_equals_the_whole_one(case_file, tmp_path, uninterrupted,
                                                                              name, chunk, how, recomputed):
    out = tmp_path / "study"
    shutil.copytree(uninterrupted[0], out)
    (out / "summary.json").unlink()
    _damage(out / "study.zarr", name, chunk, how)
    result = _study(case_file, out)
    assert result.exit_code == 0, result.output
    notes = [line for line in result.stderr.splitlines() if line.startswith("note: ")]
    assert len(notes) == 1, result.stderr
    state = "missing" if how == "delete" else "unreadable"
    assert f"{out / 'study.zarr'} was damaged ({name} c/{chunk} ({state}" in notes[0]
    assert recomputed in notes[0]
    _same_result(json.loads(result.stdout), uninterrupted[1])
    _same_store(out / "study.zarr", uninterrupted[0] / "study.zarr")
    text = (out / "summary.json").read_text()
    assert "NaN" not in text
    _same_result(json.loads(text), uninterrupted[1])


@pytest.mark.parametrize("name, chunk, how", [
    ("weight_on_hook", "0", "delete"), ("input_values", "0/0", "delete"), ("nominal_bit_speed", "0", "delete"),
    ("rate_of_penetration", "1/0", "delete"), ("bit_speed", "0/0", "truncate"),
])
def test_a_damaged_store_is_never_read_as_data(uninterrupted, tmp_path, name, chunk, how):
    from drillstring.stochastic.analysis import load_study
    from drillstring.stochastic.store import StoreError

    store = tmp_path / "study.zarr"
    shutil.copytree(uninterrupted[0] / "study.zarr", store)
    _damage(store, name, chunk, how)
    with pytest.raises(StoreError) as raised:
        load_study(store)
    message = str(raised.value)
    assert f"{store} is damaged ({name} c/{chunk} (" in message and "run the same study command again" in message
    assert "\n" not in message


def test_strict_json_writes_undefined_values_as_null():
    from drillstring.files import strict_json

    text = strict_json({"a": float("nan"), "b": [1.0, float("inf")], "c": {"d": -float("inf"), "e": 2}})
    assert json.loads(text) == {"a": None, "b": [1.0, None], "c": {"d": None, "e": 2}}
    assert "NaN" not in text and "Infinity" not in text


# --- read-only store ---------------------------------------------------------------------------------------


@pytest.fixture
def read_only(tmp_path):
    """A function making a folder read-only (permissions; for the superuser, a read-only bind mount), or
    skipping the test where neither works."""
    mounts = []

    def make(folder):
        for path in [folder, *folder.rglob("*")]:
            path.chmod(0o555 if path.is_dir() else 0o444)
        probe = folder / ".probe"
        try:
            probe.write_text("x")
        except OSError:
            return
        probe.unlink()
        try:
            subprocess.run(["mount", "--bind", str(folder), str(folder)], check=True, capture_output=True, timeout=20)
            mounts.append(folder)
            subprocess.run(["mount", "-o", "remount,bind,ro", str(folder)], check=True, capture_output=True,
                           timeout=20)
        except (OSError, subprocess.SubprocessError):
            pytest.skip("cannot make a read-only folder here")

    def undo():
        while mounts:
            subprocess.run(["umount", "-l", str(mounts.pop())], capture_output=True, timeout=20)
        for path in [tmp_path, *tmp_path.rglob("*")]:
            try:
                path.chmod(0o755 if path.is_dir() else 0o644)
            except OSError:
                pass

    make.undo = undo
    yield make
    undo()


def test_read_only_store_on_rerun_is_one_line(case_file, tmp_path, uninterrupted, read_only, monkeypatch):
    from drillstring.stochastic import montecarlo

    out = tmp_path / "study"
    original = montecarlo.run_realization

    def interrupted(case, settings, index):
        if index == 2:
            raise KeyboardInterrupt
        return original(case, settings, index)

    monkeypatch.setattr(montecarlo, "run_realization", interrupted)
    assert _study(case_file, out).exit_code == 130
    monkeypatch.setattr(montecarlo, "run_realization", original)
    read_only(out / "study.zarr")
    _one_line(_study(case_file, out), 2, f"study store {out / 'study.zarr'} is read-only",
              "make it writable", "run the same command again")
    group = zarr.open_group(str(out / "study.zarr"), mode="r")
    assert list(group["status"][...]) == [1, 1, 0]
    read_only.undo()
    result = _study(case_file, out)
    assert result.exit_code == 0, result.output
    _same_result(json.loads(result.stdout), uninterrupted[1])
    _same_store(out / "study.zarr", uninterrupted[0] / "study.zarr")


def test_a_damaged_map_store_is_named_and_its_points_recomputed(case_file, tmp_path):
    """The same machinery for every kind of store: a deleted chunk of a map's output (one chunk for all
    points) is named, the points are recomputed and the map equals the uninterrupted one."""
    args = ("map", case_file, "--top-speed", "90,110", "--weight-on-bit", "100 kN", "--t-end", "1", "--workers",
            "1", "--json")
    whole = _invoke(*args, "--out", tmp_path / "whole")
    assert whole.exit_code == 0, whole.output
    out = tmp_path / "damaged"
    shutil.copytree(tmp_path / "whole", out)
    (out / "map.zarr" / "mean_rate_of_penetration" / "c" / "0").unlink()
    again = _invoke(*args, "--out", out)
    assert again.exit_code == 0, again.output
    notes = [line for line in again.stderr.splitlines() if line.startswith("note: ")]
    assert len(notes) == 1 and "mean_rate_of_penetration c/0 (missing)" in notes[0], again.stderr
    assert "all 2 points will be recomputed" in notes[0]
    damaged, reference = (zarr.open_group(str(folder / "map.zarr"), mode="r") for folder in (out, tmp_path / "whole"))
    outputs = [name for name in reference.attrs["layout"] if name != "wall_time"]
    assert "mean_rate_of_penetration" in outputs and "status" in outputs
    for name in outputs:
        np.testing.assert_array_equal(damaged[name][...], reference[name][...], err_msg=name)
