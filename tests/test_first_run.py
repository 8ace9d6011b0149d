"""A newcomer's first run (issue 45): `make run PORT=…`, `rotordiag examples`, and Ctrl-C during the warm-up."""
from __future__ import annotations

import os
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest
from typer.testing import CliRunner

from rotordiag.cli import app as cli_app
from rotordiag.features.examples import example_path, list_examples
from tests.service_util import API_KEY, shipped_or_tiny_registry

ROOT = Path(__file__).resolve().parent.parent


def test_make_run_takes_a_port_and_a_host():
    out = subprocess.run(["make", "-n", "-W", "pyproject.toml", "-o", ".venv/.installed", "run", "PORT=8080",
                          "HOST=0.0.0.0"], cwd=ROOT, capture_output=True, text=True, check=True).stdout
    assert "rotordiag serve --host 0.0.0.0 --port 8080" in out, out
    out = subprocess.run(["make", "-n", "-o", ".venv/.installed", "run"], cwd=ROOT, capture_output=True, text=True,
                         check=True).stdout
    assert "rotordiag serve --host 127.0.0.1 --port 8000" in out, out


def test_examples_lists_every_shipped_recording_where_it_is():
    res = CliRunner().invoke(cli_app, ["examples"])
    assert res.exit_code == 0, res.output
    assert str(example_path(list_examples()[0]).parent) in res.stdout
    for name in list_examples():
        assert f"  {name} " in res.stdout
    assert "sample_rate_hz=2560" in res.stdout            # the NPY's sidecar says what it needs


def test_examples_copy_to_a_folder_then_diagnose_reads_them(tmp_path):
    res = CliRunner().invoke(cli_app, ["examples", "--copy-to", str(tmp_path / "ex"), "whirl_2560hz.npy"])
    assert res.exit_code == 0, res.output
    assert sorted(p.name for p in (tmp_path / "ex").iterdir()) == ["whirl_2560hz.json", "whirl_2560hz.npy"]
    assert (tmp_path / "ex" / "whirl_2560hz.npy").read_bytes() == example_path("whirl_2560hz.npy").read_bytes()
    again = CliRunner().invoke(cli_app, ["examples", "--copy-to", str(tmp_path / "ex"), "whirl_2560hz.npy"])
    assert again.exit_code == 2 and "already there" in again.output
    bad = CliRunner().invoke(cli_app, ["examples", "--copy-to", str(tmp_path / "ex2"), "nope.csv"])
    assert bad.exit_code == 2 and "no example recording 'nope.csv'; the examples are" in bad.output
    assert not (tmp_path / "ex2").exists()


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def test_ctrl_c_during_the_workers_warm_up_is_clean(tmp_path):
    """Ctrl-C reaches the whole process group (the server and its diagnosis workers) as a terminal sends it;
    in the seconds after the server says it started, the workers are still importing and loading the model
    (before the fix: a KeyboardInterrupt traceback per worker, or a BrokenPipeError when one finished loading
    after the server had closed its socket)."""
    env = dict(os.environ, ROTORDIAG_DATA_DIR=str(tmp_path / "data"), ROTORDIAG_API_KEY=API_KEY,
               ROTORDIAG_DIAGNOSIS_WORKERS="2", ROTORDIAG_SHIPPED_REGISTRY_DIR=str(shipped_or_tiny_registry()))
    exe = Path(sys.executable).parent / "rotordiag"
    proc = subprocess.Popen([str(exe), "serve", "--port", str(_free_port())], cwd=tmp_path, env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, start_new_session=True)
    lines = []
    try:
        t0 = time.monotonic()
        assert proc.stdout is not None
        for line in proc.stdout:
            lines.append(line)
            if "Application startup complete" in line:
                break
            if time.monotonic() - t0 > 120:
                pytest.fail("the server did not start within 120 s:\n" + "".join(lines))
        time.sleep(2.0)          # the workers' interpreters are up (a SIGINT before that kills them silently)
        os.killpg(proc.pid, signal.SIGINT)
        out, _ = proc.communicate(timeout=30)
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        pytest.fail("the server did not stop within 30 s of Ctrl-C:\n" + "".join(lines))
    out = "".join(lines) + out
    assert proc.returncode == 0, out
    for word in ("Traceback", "KeyboardInterrupt", "BrokenPipeError"):
        assert word not in out, out
    assert "Finished server process" in out
