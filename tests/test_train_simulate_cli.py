"""``rotordiag simulate --train``: a shaft train's steady recording through the CLI, in the layout the features read
(probes at every bearing, DC included, a keyphasor), and bad input refused with what to fix, nothing written."""
from __future__ import annotations

import numpy as np
from typer.testing import CliRunner

from rotordiag.cli import app
from rotordiag.features.reader import ReadOptions, read_recording

runner = CliRunner()


def test_simulate_a_train_writes_probes_and_a_keyphasor_the_reader_takes(tmp_path):
    out = tmp_path / "train.csv"
    r = runner.invoke(app, ["simulate", "--train", "gen200_2pole", "--speed-rpm", "3000", "--offset-um", "150",
                            "--transient-revs", "80", "--record-revs", "8", "--snr-db", "inf",
                            "--probes-out", str(out)])
    assert r.exit_code == 0, r.output
    rec = read_recording(out, options=ReadOptions(keyphasor_channel="kp")).recording
    assert sorted({c.bearing for c in rec.channels}) == [1, 2, 3, 4] and len(rec.channels) == 8
    assert rec.keyphasor_times_s is not None
    periods = np.diff(np.asarray(rec.keyphasor_times_s))
    assert np.allclose(periods, 60.0 / 3000.0, rtol=1e-3)              # one mark per revolution at 3000 r/min
    # the DC part is the journal's static position (bearing 1, generator far end: the journal sits low)
    b1 = [c for c in rec.channels if c.bearing == 1]
    y = (b1[0].data_um.mean() + b1[1].data_um.mean()) / np.sqrt(2)  # x cos45 + y sin45 and −x cos45 + y sin45
    assert -350 < y < -50


def test_simulate_a_train_refuses_paper_model_options_and_bad_input(tmp_path):
    out = tmp_path / "x.csv"
    r = runner.invoke(app, ["simulate", "--train", "gen200_2pole", "--speed-rpm", "3000", "--misalignment", "0.2",
                            "--probes-out", str(out)])
    assert r.exit_code == 2 and "a train takes --offset-um" in r.output
    r = runner.invoke(app, ["simulate", "--train", "gen999", "--speed-rpm", "3000", "--probes-out", str(out)])
    assert r.exit_code == 2 and "gen200_2pole" in r.output
    r = runner.invoke(app, ["simulate", "--train", "gen200_2pole", "--speed-rpm", "-5", "--probes-out", str(out)])
    assert r.exit_code == 2 and "speed" in r.output
    r = runner.invoke(app, ["simulate", "--speed-rpm", "3000"])
    assert r.exit_code == 2 and "--misalignment" in r.output
    assert list(tmp_path.iterdir()) == []
