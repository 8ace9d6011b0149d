"""A real `dask scheduler` and `dask worker` as separate processes on loopback, driven via --scheduler."""
from __future__ import annotations

import os
import signal
import socket
import subprocess
import sys
from pathlib import Path

import pytest

from rotordiag.simulator.dataset.generate import generate

from .dataset_support import differing_datasets, write_spec
from .service_util import wait_until

BIN = Path(sys.executable).parent


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _wait_for_port(port: int, proc: subprocess.Popen) -> None:
    def open_port() -> bool:
        if proc.poll() is not None:
            raise AssertionError(f"dask scheduler exited: {proc.stderr.read().decode()[-2000:]}")
        with socket.socket() as s:
            return s.connect_ex(("127.0.0.1", port)) == 0

    wait_until(open_port, "the dask scheduler's port")


@pytest.fixture
def cluster(tmp_path):
    port = _free_port()
    address = f"tcp://127.0.0.1:{port}"
    procs = []
    sched = subprocess.Popen([str(BIN / "dask"), "scheduler", "--host", "127.0.0.1", "--port", str(port),
                              "--no-dashboard"], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                             start_new_session=True)
    procs.append(sched)
    try:
        _wait_for_port(port, sched)
        worker = subprocess.Popen([str(BIN / "dask"), "worker", address, "--nthreads", "1", "--nworkers", "1",
                                   "--no-dashboard", "--local-directory", str(tmp_path / "dask-worker")],
                                  stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True)
        procs.append(worker)
        from distributed import Client

        with Client(address, timeout=30, set_as_default=False) as client:
            client.wait_for_workers(1, timeout=60)
        yield address
    finally:
        for p in reversed(procs):  # only the processes this fixture started
            if p.poll() is None:
                os.killpg(p.pid, signal.SIGTERM)
                try:
                    p.wait(timeout=20)
                except subprocess.TimeoutExpired:
                    os.killpg(p.pid, signal.SIGKILL)
                    p.wait()


def test_generate_through_an_external_scheduler(cluster, tmp_path):
    spec = write_spec(tmp_path / "spec.toml", n_samples=6)
    serial = generate(spec, tmp_path / "serial.h5", n_workers=0, progress=False)
    out = tmp_path / "remote.h5"
    run = subprocess.run([str(BIN / "rotordiag"), "dataset", "generate", str(spec), "--out", str(out),
                          "--scheduler", cluster, "--no-progress"], capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stderr[-3000:]
    assert "6 samples computed, 6/6 done" in run.stdout
    assert differing_datasets(serial.path, out) == []


def test_unreachable_scheduler_is_a_clean_error(tmp_path):
    from typer.testing import CliRunner

    from rotordiag.cli import app

    spec = write_spec(tmp_path / "spec.toml", n_samples=2)
    r = CliRunner().invoke(app, ["dataset", "generate", str(spec), "--out", str(tmp_path / "o.h5"), "--scheduler",
                                 f"tcp://127.0.0.1:{_free_port()}", "--connect-timeout", "2", "--no-progress"])
    assert r.exit_code == 2, r.output
    assert "cannot reach the Dask scheduler" in r.output and "Traceback" not in r.output
    assert not (tmp_path / "o.h5").exists()
