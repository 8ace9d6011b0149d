"""`rotordiag bifurcate`, `lyapunov`, `figures`: clean errors, real outputs."""
from __future__ import annotations

import json

import pytest
from typer.testing import CliRunner

from rotordiag.cli import app
from rotordiag.simulator.analysis.sweeps import SweepResult

runner = CliRunner()


def test_bifurcate_speed_writes_plot_and_data(tmp_path):
    png, h5 = tmp_path / "b.png", tmp_path / "b.h5"
    r = runner.invoke(app, ["bifurcate", "--over", "speed", "--from", "1200", "--to", "1600", "--points", "3",
                            "--misalignment", "0.1", "--transient-revs", "150", "--record-revs", "24",
                            "--workers", "0", "--no-progress", "--plot", str(png), "--out", str(h5)])
    assert r.exit_code == 0, r.output
    assert "period-1" in r.output
    assert png.stat().st_size > 5000
    sw = SweepResult.from_hdf5(h5)
    assert sw.poincare.shape == (3, 24)
    assert list(sw.values) == [1200.0, 1400.0, 1600.0]


@pytest.mark.parametrize("args, word", [
    (["--over", "temperature", "--from", "1", "--to", "2"], "speed"),
    (["--over", "speed", "--from", "1200", "--to", "1600"], "--misalignment"),
    (["--over", "misalignment", "--from", "0.1", "--to", "0.3"], "--speed-rpm"),
    (["--over", "speed", "--from", "1600", "--to", "1200", "--misalignment", "0.1"], "--to"),
    (["--over", "speed", "--from", "50", "--to", "1200", "--misalignment", "0.1", "--workers", "0"], "speeds_rpm"),
    (["--over", "speed", "--from", "1200", "--to", "1600", "--misalignment", "0.1", "--node", "9",
      "--workers", "0"], "node"),
])
def test_bifurcate_bad_input_is_a_clean_error(args, word):
    r = runner.invoke(app, ["bifurcate", *args, "--points", "2", "--no-progress"])
    assert r.exit_code == 2
    assert word in r.output
    assert "Traceback" not in r.output


def test_lyapunov_json(tmp_path):
    r = runner.invoke(app, ["lyapunov", "--speed-rpm", "1500", "--misalignment", "0.02", "--revs", "30",
                            "--transient-revs", "150", "--json", "--plot", str(tmp_path / "h.png")])
    assert r.exit_code == 0, r.output
    data = json.loads(r.output[r.output.index("{"):r.output.rindex("}") + 1])
    assert data["lle_per_rev"] < 0
    assert data["motion"] == "period-1"
    assert (tmp_path / "h.png").exists()


def test_lyapunov_bad_input():
    r = runner.invoke(app, ["lyapunov", "--speed-rpm", "99999", "--misalignment", "0.02"])
    assert r.exit_code == 2 and "speed_rpm" in r.output and "Traceback" not in r.output


@pytest.mark.slow
def test_figures_quick(tmp_path):
    r = runner.invoke(app, ["figures", "--out", str(tmp_path), "--quick", "--workers", "2"])
    assert r.exit_code == 0, r.output
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert len(summary["files"]) == 9
    for name in summary["files"]:
        assert (tmp_path / name).stat().st_size > 10_000
    assert summary["windows"]["speed_d0"][0]["motion"] == "period-1"
