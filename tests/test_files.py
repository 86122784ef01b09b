"""Output files: atomic writes, output paths checked before computing, folder locks."""

import os
import subprocess
import sys
import threading

import pytest

from drillstring import files


def test_atomic_output_replaces_whole_or_leaves_the_old_file(tmp_path):
    target = tmp_path / "sub" / "out.txt"
    files.write_text_atomic(target, "first")
    assert target.read_text() == "first"
    with pytest.raises(RuntimeError, match="midway"):
        with files.atomic_output(target) as temporary:
            temporary.write_text("half of the sec")
            assert target.read_text() == "first"  # not visible before completion
            raise RuntimeError("failed midway")
    assert target.read_text() == "first"
    assert sorted(p.name for p in target.parent.iterdir()) == ["out.txt"]  # no temporary left
    files.write_text_atomic(target, "second")
    assert target.read_text() == "second"


def test_output_file_problems(tmp_path, unwritable_folder):
    (tmp_path / "a_file").write_text("x")
    assert files.output_file_problem(tmp_path / "new.nc") is None
    assert files.output_file_problem(tmp_path / "deeper" / "still" / "new.nc") is None  # folders made later
    assert files.output_file_problem(tmp_path / "a_file") is None  # overwritten
    assert files.output_file_problem(tmp_path) == "is a folder; give a file name"
    assert files.output_file_problem(tmp_path / "a_file" / "x.nc") == f"{tmp_path / 'a_file'} is a file, not a folder"
    problem = files.output_file_problem(unwritable_folder / "x.nc")
    assert problem is not None and problem.startswith(f"cannot write in {unwritable_folder} (")
    problem = files.output_file_problem(unwritable_folder / "sub" / "x.nc")
    assert problem is not None and problem.startswith(f"cannot write in {unwritable_folder} (")
    assert sorted(p.name for p in tmp_path.iterdir() if p.name != "read-only") == ["a_file"]  # checks leave nothing


def test_output_folder_problems(tmp_path, unwritable_folder):
    (tmp_path / "a_file").write_text("x")
    assert files.output_folder_problem(tmp_path) is None
    assert files.output_folder_problem(tmp_path / "new" / "deeper") is None
    assert files.output_folder_problem(tmp_path / "a_file") == "is a file, not a folder"
    assert files.output_folder_problem(tmp_path / "a_file" / "sub") == f"{tmp_path / 'a_file'} is a file, not a folder"
    problem = files.output_folder_problem(unwritable_folder)
    assert problem is not None and problem.startswith(f"cannot write in {unwritable_folder} (")
    assert not (tmp_path / "new").exists()


HOLD = """
import sys, time
from drillstring.files import FileLock
with FileLock(sys.argv[1], shared=sys.argv[2] == "shared"):
    print("held", flush=True)
    time.sleep(120)
"""


def _holder(path, mode="exclusive"):
    proc = subprocess.Popen([sys.executable, "-c", HOLD, str(path), mode], stdout=subprocess.PIPE, text=True)
    assert proc.stdout.readline().strip() == "held"
    return proc


def test_exclusive_lock_refuses_others_until_released(tmp_path):
    path = tmp_path / "x.lock"
    proc = _holder(path)
    try:
        with pytest.raises(files.LockedError, match=f"in use by pid {proc.pid} on host .*started"):
            files.FileLock(path).acquire()
        with pytest.raises(files.LockedError, match=f"pid {proc.pid}"):  # readers too
            files.FileLock(path, shared=True).acquire()
    finally:
        proc.terminate()
        proc.wait()
    # terminated: its record stays, the kernel released the lock -> stale, taken over with a note
    with files.FileLock(path) as lock:
        assert lock.note is not None and f"stale lock (pid {proc.pid} on host" in lock.note
    assert not path.exists()  # a clean release leaves nothing
    with files.FileLock(path) as lock:
        assert lock.note is None


def test_shared_locks_coexist_and_keep_writers_out(tmp_path):
    path = tmp_path / "x.lock"
    proc = _holder(path, "shared")
    try:
        with files.FileLock(path, shared=True) as lock:
            assert lock.note is None
        with pytest.raises(files.LockedError, match="another process .reading or writing it."):
            files.FileLock(path).acquire()
    finally:
        proc.terminate()
        proc.wait()
    with files.FileLock(path, shared=True):
        pass
    assert not path.exists()  # the last reader removes the empty lock file


def test_lock_is_reentrant_in_one_thread_only(tmp_path):
    path = tmp_path / "x.lock"
    with files.FileLock(path):
        with files.FileLock(path), files.FileLock(path, shared=True):
            assert files.held_by_this_process(path)
        assert files.held_by_this_process(path)  # still held by the outer one
        errors = []

        def other_thread():
            try:
                files.FileLock(path).acquire()
            except files.LockedError as error:
                errors.append(str(error))

        thread = threading.Thread(target=other_thread)
        thread.start()
        thread.join()
        assert errors and "another thread of this process" in errors[0]
    assert not files.held_by_this_process(path) and not path.exists()


def test_record_without_flock_decides_by_pid_and_host(tmp_path, monkeypatch):
    """Where flock is unavailable: a live pid on this host refuses, a dead one is stale, another host
    refuses with how to clear it."""
    import json
    import socket

    monkeypatch.setattr(files, "fcntl", None)
    path = tmp_path / "x.lock"
    sleeper = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"])
    try:
        path.write_text(json.dumps({"pid": sleeper.pid, "host": socket.gethostname(), "started": "then"}))
        with pytest.raises(files.LockedError, match=f"pid {sleeper.pid}"):
            files.FileLock(path).acquire()
    finally:
        sleeper.kill()
        sleeper.wait()
    with files.FileLock(path) as lock:
        assert "stale lock" in lock.note
    path.write_text(json.dumps({"pid": os.getpid() + 1, "host": "elsewhere", "started": "then"}))
    with pytest.raises(files.LockedError, match=f"another host.*delete {path}"):
        files.FileLock(path).acquire()


def test_only_regular_files_are_replaced(tmp_path):
    fifo = tmp_path / "fifo"
    os.mkfifo(fifo)
    assert files.not_regular_problem(fifo) == "is a FIFO, not a regular file; give a file name"
    assert files.not_regular_problem("/dev/null").startswith("is a character device")
    assert files.not_regular_problem(tmp_path / "none") is None
    assert files.output_file_problem(fifo) == "is a FIFO, not a regular file; give a file name"
    with pytest.raises(files.NotARegularFile, match="is a FIFO"):
        files.write_text_atomic(fifo, "x")
    assert fifo.is_fifo() and sorted(p.name for p in tmp_path.iterdir()) == ["fifo"]


def test_write_error_message_names_the_file_the_cause_and_what_to_do():
    full = OSError(28, "No space left on device", "/data/study.zarr")
    assert files.write_error_message(full, "finished realizations are kept in /data/study.zarr") == (
        "cannot write /data/study.zarr: No space left on device; finished realizations are kept in "
        "/data/study.zarr; free some space and run the same command again to resume")
    assert files.write_error_message(OSError(30, "Read-only file system", "/r/x.nc")) == (
        "cannot write /r/x.nc: Read-only file system; use a writable location (read-only filesystem) and run "
        "the command again")


def test_lock_in_use_reads_the_record_without_locking(tmp_path):
    lock = tmp_path / "x.lock"
    assert not files.lock_in_use(lock)
    lock.write_text("")
    assert not files.lock_in_use(lock)  # released cleanly
    proc = _holder(lock)
    try:
        assert files.lock_in_use(lock)
    finally:
        proc.kill()
        proc.wait()
    assert not files.lock_in_use(lock)  # its holder died: stale
