"""``rotordiag continue --train/--shaftline``: a shaft train's period-1 orbit by shooting, its Floquet
multipliers and its branch over speed."""
from __future__ import annotations

import json

import numpy as np
import pytest
from typer.testing import CliRunner

from rotordiag.cli import app
from rotordiag.simulator.train import modes
from rotordiag.simulator.train.shaftline import shaftline_of, train_from_shaftline


@pytest.mark.slow
def test_continue_on_a_preset_train_reports_its_floquet_multipliers(tmp_path):
    """gen200_2pole at 3000 r/min: the shooting orbit is stable and its largest multiplier equals
    max exp(Re λ·T) of the damped modes of the full FE model linearised about the static state (the orbit is
    a small motion about it), the reduced model's 12 modes against the full model, to 0.5 %."""
    out, png = tmp_path / "b.json", tmp_path / "b.png"
    r = CliRunner().invoke(app, ["continue", "--train", "gen200_2pole", "--over", "speed", "--from", "3000",
                                 "--to", "3100", "--max-points", "3", "--out", str(out), "--plot", str(png)])
    assert r.exit_code == 0, r.output
    assert "Floquet multipliers" in r.output and "|μ| =" in r.output
    data = json.loads(out.read_text())
    assert data["start"]["stability"] == "stable" and data["start"]["residual"] < 1e-10
    mu = max(abs(complex(*z)) for z in data["start"]["multipliers"])
    full = modes(train_from_shaftline(shaftline_of("gen200_2pole")[0]), 3000.0)
    low = full.frequency_hz < 500.0
    mu_lin = float(np.exp(full.eigenvalues[low].real * 60.0 / 3000.0).max())
    assert mu == pytest.approx(mu_lin, rel=5e-3)
    assert len(data["points"]) == 3 and all(p["max_multiplier"] < 1 for p in data["points"])
    assert png.stat().st_size > 5_000


def test_continue_on_a_train_refuses_what_it_cannot_do(tmp_path):
    run = CliRunner().invoke
    r = run(app, ["continue", "--train", "gen200_2pole", "--over", "misalignment", "--from", "0", "--to", "0.2",
                  "--speed-rpm", "3000", "--out", str(tmp_path / "b.json")])
    assert r.exit_code == 2 and "over speed only" in r.output
    r = run(app, ["continue", "--train", "gen200_2pole", "--over", "speed", "--from", "3000", "--to", "3100",
                  "--out", str(tmp_path / "b.h5")])
    assert r.exit_code == 2 and "JSON" in r.output
    r = run(app, ["continue", "--train", "nope", "--over", "speed", "--from", "3000", "--to", "3100",
                  "--out", str(tmp_path / "b.json")])
    assert r.exit_code == 2 and "unknown shaft-line preset" in r.output
    assert not (tmp_path / "b.json").exists()
