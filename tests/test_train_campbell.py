"""The train's Campbell diagram, critical speeds and stability margin (simulator.train.campbell) and the
``rotordiag campbell`` command on trains."""
from __future__ import annotations

import json
import math

import numpy as np
import pytest
from typer.testing import CliRunner

from rotordiag.cli import app
from rotordiag.simulator.train import TrainError, unbalance_response
from rotordiag.simulator.train.campbell import damping_ratio_of_log_decrement, train_campbell

from .train_support import iso, two_rotor_train


def test_damping_ratio_inverts_the_log_decrement_definition():
    zeta = np.array([0.0, 0.01, 0.1, 0.5, -0.02])
    delta = 2 * math.pi * zeta / np.sqrt(1 - zeta**2)
    assert np.allclose(damping_ratio_of_log_decrement(delta), zeta, atol=1e-12)


def test_first_critical_speed_is_where_the_unbalance_response_peaks():
    """The Campbell diagram's first 1X crossing (eigenvalues) against the peak of the forced unbalance
    response (a linear solve per speed, no eigenproblem): within half the half-power width."""
    train = two_rotor_train(iso(2e8, 2e5), iso(1e8, 5e4), unbalance_kg_m=0.5)
    tc = train_campbell(train, np.linspace(1000.0, 2000.0, 9))
    crit = [c for c in tc.critical_speeds((1,))]
    assert crit, "no 1X critical between 1000 and 2000 r/min"
    sp = np.linspace(1100.0, 1900.0, 401)
    amp = np.abs(unbalance_response(train, sp)).max(axis=2)
    node = int(np.argmax(amp.max(axis=0)))
    peak = sp[np.argmax(amp[:, node])]
    near = min(crit, key=lambda c: abs(c.speed_rpm - peak))
    assert abs(near.speed_rpm - peak) < 0.5 * near.half_power_width_rpm, (near, peak)
    # the 2X line: a crossing's frequency is twice its running frequency
    for c in tc.critical_speeds((2,)):
        assert c.frequency_hz == pytest.approx(2 * c.speed_rpm / 60.0, rel=1e-9)
    # margins are the least-damped mode of the band: positive for this damped, symmetric train
    assert all(m.stable for m in tc.margin)


def test_bad_speed_grids_say_what_to_fix():
    train = two_rotor_train()
    with pytest.raises(TrainError, match="2 to"):
        train_campbell(train, [1000.0])
    with pytest.raises(TrainError, match="increasing"):
        train_campbell(train, [1000.0, 900.0])
    with pytest.raises(TrainError, match="n_modes"):
        train_campbell(train, [1000.0, 2000.0], n_modes=0)


def test_campbell_command_on_a_preset_train(tmp_path):
    """``rotordiag campbell --train gen200_2pole``: table, JSON, PNG, and the margin at its rated speed
    positive (issue 42: every preset stable at rated speed)."""
    png = tmp_path / "c.png"
    res = CliRunner().invoke(app, ["campbell", "--train", "gen200_2pole", "--points", "5", "--json",
                                   "--plot", str(png)])
    assert res.exit_code == 0, res.output
    out = json.loads(res.stdout[: res.stdout.rindex("}") + 1])
    assert out["stability_margin"]["speed_rpm"] == 3000.0
    assert out["stability_margin"]["log_decrement"] > 0 and out["stability_margin"]["stable"]
    assert len(out["speeds_rpm"]) == 5 and len(out["log_decrements"]) == 5
    assert png.stat().st_size > 10_000


def test_campbell_command_rejects_bad_trains(tmp_path):
    r = CliRunner().invoke(app, ["campbell", "--train", "gen999"])
    assert r.exit_code == 2 and "unknown shaft-line preset" in r.output and "gen200_2pole" in r.output
    r = CliRunner().invoke(app, ["campbell", "--shaftline", str(tmp_path / "none.toml")])
    assert r.exit_code == 2 and "does not exist" in r.output
    r = CliRunner().invoke(app, ["campbell", "--train", "gen200_2pole", "--plant", str(tmp_path / "p.toml")])
    assert r.exit_code == 2 and "not both" in r.output
    bad = tmp_path / "bad.toml"
    bad.write_text("[generator]\nsegments = [[-1.0, 0.5]]\n")
    r = CliRunner().invoke(app, ["campbell", "--shaftline", str(bad)])
    assert r.exit_code == 2 and "error" in r.output.lower()
