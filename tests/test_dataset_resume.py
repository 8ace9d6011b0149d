"""Crash safety: SIGKILL a real `rotordiag dataset generate`, read the file, resume, compare."""
from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import h5py
import numpy as np
import pytest

from rotordiag.simulator.dataset.generate import generate
from rotordiag.simulator.dataset.store import open_dataset, repair_file

from .dataset_support import differing_datasets, write_spec

ROTORDIAG = str(Path(sys.executable).with_name("rotordiag"))


def _start(spec: Path, out: Path, workers: int) -> subprocess.Popen:
    cmd = [ROTORDIAG, "dataset", "generate", str(spec), "--out", str(out), "--workers", str(workers), "--no-progress"]
    # own session: the kill takes the CLI and the Dask workers it started, nothing else
    return subprocess.Popen(cmd, start_new_session=True, stdout=subprocess.PIPE, stderr=subprocess.PIPE)


def _n_done(out: Path) -> int:
    try:
        with h5py.File(out, "r", swmr=True) as f:
            return int(f["done"][...].sum())
    except (OSError, KeyError):
        return -1


def _kill_when(proc: subprocess.Popen, out: Path, at_least: int, timeout_s: float = 120.0) -> None:
    deadline = time.monotonic() + timeout_s
    while _n_done(out) < at_least:
        if proc.poll() is not None:
            raise AssertionError(f"generate exited early: {proc.stderr.read().decode()[-2000:]}")
        if time.monotonic() > deadline:
            os.killpg(proc.pid, signal.SIGKILL)
            raise AssertionError("generate made no progress")
        time.sleep(0.01)
    os.killpg(proc.pid, signal.SIGKILL)
    proc.wait()


def _check_finished_rows_match(out: Path, reference: Path) -> int:
    """Every finished sample of a killed file equals the uninterrupted run's; returns how many."""
    with open_dataset(out) as f, h5py.File(reference, "r") as ref:
        done = f["done"][...].astype(bool)
        idx = np.flatnonzero(done)
        for i in idx:
            assert np.array_equal(f["waveforms"][i], ref["waveforms"][i]), f"sample {i}"
            assert f["parameters/speed_rpm"][i] == ref["parameters/speed_rpm"][i]
            assert f["labels/status"][i] == ref["labels/status"][i]
        return int(idx.size)


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    d = tmp_path_factory.mktemp("resume")
    spec = write_spec(d / "spec.toml", n_samples=24)
    ref = d / "reference.h5"
    assert generate(spec, ref, n_workers=0, progress=False).complete
    return spec, ref


def test_sigkill_during_dask_and_serial_runs_then_resume_gives_identical_values(reference, tmp_path):
    spec, ref = reference
    out = tmp_path / "killed.h5"
    # 1) kill the CLI (and its LocalCluster worker) once samples have started landing
    _kill_when(_start(spec, out, workers=1), out, at_least=2)
    with pytest.raises(OSError):  # HDF5's writing flag is still set ...
        h5py.File(out, "r").close()
    n1 = _check_finished_rows_match(out, ref)  # ... but the file reads, with every finished sample
    assert 2 <= n1 < 24
    # 2) resume serially and kill again further on
    _kill_when(_start(spec, out, workers=0), out, at_least=n1 + 6)
    n2 = _check_finished_rows_match(out, ref)
    assert n2 >= n1 + 6
    # 3) resume to the end: only the missing samples are computed
    done = subprocess.run([ROTORDIAG, "dataset", "generate", str(spec), "--out", str(out), "--workers", "0",
                           "--no-progress"], capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    assert f"{24 - n2} samples computed, 24/24 done" in done.stdout
    assert "repaired after a crash" in done.stdout
    with h5py.File(out, "r") as f:  # plain h5py again
        assert f["done"][...].all()
        log = [json.loads(x) for x in f["resume_log"][...] if x]
    assert [e["n_done"] for e in log] == [n1, n2] and all(e["repaired"] for e in log)
    assert differing_datasets(ref, out) == []


def test_sigkill_at_arbitrary_moments_never_leaves_an_unreadable_file(reference, tmp_path):
    spec, ref = reference
    out = tmp_path / "arbitrary.h5"
    rng = np.random.default_rng(12345)
    for delay in rng.uniform(0.3, 4.0, size=3):
        proc = _start(spec, out, workers=0)
        time.sleep(delay)
        os.killpg(proc.pid, signal.SIGKILL)
        proc.wait()
        if out.exists():  # killed before the file was created is fine too
            _check_finished_rows_match(out, ref)
    generate(spec, out, n_workers=0, progress=False)
    assert differing_datasets(ref, out) == []


def test_repair_makes_a_killed_file_plain_readable(reference, tmp_path):
    spec, ref = reference
    out = tmp_path / "repair.h5"
    _kill_when(_start(spec, out, workers=0), out, at_least=4)
    n = _check_finished_rows_match(out, ref)
    crashed, n_done = repair_file(out)
    assert crashed and n_done == n
    with h5py.File(out, "r") as f:
        assert int(f["done"][...].sum()) == n
    assert repair_file(out) == (False, n)
    _check_finished_rows_match(out, ref)


def test_writer_waits_for_a_reader_holding_the_file_lock(reference, tmp_path):
    """A reader (another process) opening the file just before the writer re-opens it
    must not crash the run: the writer waits for HDF5's file lock to clear."""
    import shutil
    import sys

    from rotordiag.simulator.dataset import store

    _, ref = reference
    path = tmp_path / "locked.h5"
    shutil.copy(ref, path)
    store.repair_file(path)  # plain-readable copy
    code = ("import h5py, sys, time; f = h5py.File(sys.argv[1], 'r'); print('open', flush=True); "
            "time.sleep(1.0); f.close()")
    reader = subprocess.Popen([sys.executable, "-c", code, str(path)], stdout=subprocess.PIPE, text=True)
    try:
        assert reader.stdout.readline().strip() == "open"
        t0 = time.monotonic()
        f = store._open_swmr_write(path)  # raised BlockingIOError at once before the wait was added
        try:
            assert int(f["done"][...].sum()) > 0
        finally:
            f.close()
        assert time.monotonic() - t0 > 0.3  # it did have to wait for the reader
    finally:
        reader.wait(timeout=30)
