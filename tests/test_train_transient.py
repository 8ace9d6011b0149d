"""Run-ups of finite-element shaft trains (simulator.train.transient through simulator.transient and the CLI)."""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from rotordiag.simulator.transient import SpeedProfile, simulate_transient
from tests.test_simulator_transient import _rev_1x


@pytest.fixture(scope="module")
def gen200():
    from rotordiag.simulator import shaftline as sl
    from rotordiag.simulator.train.shaftline import train_from_shaftline
    from rotordiag.simulator.train.transient import unbalanced

    return unbalanced(train_from_shaftline(sl.preset("gen200_2pole")), 0.2, replace_own=True)


def _lightly_damped_crossings(train, grid_rpm: np.ndarray, max_zeta: float = 0.15) -> list[tuple[float, float]]:
    """(speed, ζ) where a lightly damped mode of the full finite-element train, linearised about its static state
    at each speed (``simulator.train.modes``: independent of the reduced model and of the time integration),
    meets 1X: the sign change of f − n/60 on ``grid_rpm``, interpolated linearly."""
    from rotordiag.simulator.train import assemble, modes

    asm = assemble(train)
    rows = []
    for s in grid_rpm:
        m = modes(asm, float(s), about_static=True)
        keep = (m.damping_ratio < max_zeta) & (m.frequency_hz > 1.0)
        rows.append((m.frequency_hz[keep][:4], m.damping_ratio[keep][:4]))
    n = min(len(f) for f, _ in rows)
    out = []
    for j in range(n):
        g = np.array([f[j] - s / 60.0 for (f, _), s in zip(rows, grid_rpm, strict=True)])
        for i in np.flatnonzero((g[:-1] > 0) & (g[1:] <= 0)):
            a = g[i] / (g[i] - g[i + 1])
            out.append((float(grid_rpm[i] + a * (grid_rpm[i + 1] - grid_rpm[i])), float(rows[i][1][j])))
    return out


@pytest.mark.slow
def test_train_run_up_1x_peaks_at_its_damped_criticals(gen200):
    """A 50 r/min/s run-up of the 200 MW train through its first criticals: every journal's 1X (horizontal and
    vertical) peaks within the half-power half-width ζ·n_c of a 1X crossing of a lightly damped mode of the
    linearised train."""
    from rotordiag.simulator.train.transient import TrainTransientModel

    res = simulate_transient(TrainTransientModel(gen200), SpeedProfile.linear(1050, 1400, 7), sample_rate_hz=2560,
                             settle_revs=60)
    assert res.ok and res.journal_displacements_m.shape[1:] == (4, 2)
    crit = _lightly_damped_crossings(gen200, np.arange(1050.0, 1401.0, 25.0))
    assert crit, "no lightly damped critical between 1050 and 1400 r/min"
    kp = res.keyphasor_times_s
    rpm = 60.0 / np.diff(kp)
    for b in range(4):
        amp = np.array([np.abs(_rev_1x(res.journal_displacements_m[:, b] * 1e6, kp[k], kp[k + 1], 2560.0))
                        for k in range(kp.size - 1)])
        for axis in (0, 1):
            peak = float(rpm[np.argmax(amp[:, axis])])
            assert 1100 < peak < 1350, (b, axis, peak)                  # a peak inside the run, not at its ends
            n_c, zeta = min(crit, key=lambda c: abs(c[0] - peak))
            assert abs(peak - n_c) <= zeta * n_c, (b, axis, peak, crit)


@pytest.mark.slow
def test_train_slow_ramp_agrees_with_the_steady_solution(gen200):
    """A 5 r/min/s ramp through 1500 r/min: every journal's 1X over the revolution at 1500 r/min within 2 % and 2° of
    the steady simulation (simulate_train) at that speed, same keyphasor reference (t·Ω ≡ 0)."""
    from rotordiag.simulator.train.dynamics import simulate_train
    from rotordiag.simulator.train.transient import TrainTransientModel

    res = simulate_transient(TrainTransientModel(gen200), SpeedProfile.linear(1490, 1510, 4), sample_rate_hz=5120,
                             settle_revs=150)
    assert res.ok
    kp = res.keyphasor_times_s
    rpm = 60.0 / np.diff(kp)
    k = int(np.argmin(np.abs(rpm - 1500.0)))
    got = _rev_1x(res.journal_displacements_m.reshape(res.time_s.size, -1) * 1e6, kp[k], kp[k + 1], 5120.0)
    st = simulate_train(gen200, float(rpm[k]), transient_revs=300, record_revs=2, samples_per_rev=256,
                        method="dopri")
    spr = 256
    d = st.journal_m[-spr:] * 1e6
    th = 2 * np.pi * np.arange(spr) / spr
    ref = (2.0 / spr) * (d.reshape(spr, -1) * np.exp(-1j * th)[:, None]).sum(axis=0)
    assert np.abs(got) == pytest.approx(np.abs(ref), rel=0.02)
    assert np.degrees(np.abs(np.angle(got / ref))).max() < 2.0


def test_runup_cli_runs_a_train_and_refuses_bad_input(tmp_path: Path):
    from typer.testing import CliRunner

    from rotordiag.cli import app

    out = tmp_path / "train.npy"
    r = CliRunner().invoke(app, ["runup", "--train", "gen200_2pole", "--profile", "1450:1500:0.5", "--settle-revs",
                                 "4", "--snr-db", "inf", "--out", str(out)])
    assert r.exit_code == 0, r.output
    a = np.load(out)
    assert a.shape[0] == 9 and a.shape[1] > 1000        # 4 bearings × x/y, then the keyphasor
    assert np.all(np.isfinite(a)) and np.ptp(a[:8], axis=1).min() > 0
    pulses = int(np.sum(np.diff((a[8] < -0.5).astype(int)) == 1)) + int(a[8, 0] < -0.5)
    assert abs(pulses - 1475 / 60.0 * 0.5) <= 1.5         # one mark per revolution of the ramp
    for args, message in [
        (["--train", "gen200_2pole", "--profile", "0@1500,1@1600,2@1400"], "reverses"),
        (["--train", "gen200_2pole", "--profile", "50:1500:2"], "100"),
        (["--train", "no_such_machine", "--profile", "1000:1500:2"], "unknown shaft-line preset"),
        (["--train", "gen200_2pole", "--misalignment", "0.3", "--profile", "1000:1500:2"], "--offset-um"),
    ]:
        bad = tmp_path / "bad.npy"
        r = CliRunner().invoke(app, ["runup", *args, "--out", str(bad)])
        assert r.exit_code == 2, (args, r.output)
        assert message in r.output, (args, r.output)
        assert not bad.exists() and not list(tmp_path.glob(".bad*"))


def test_unbalanced_puts_the_unbalance_where_asked(gen200):
    from rotordiag.simulator.train import TrainError
    from rotordiag.simulator.train.transient import unbalanced

    r0 = gen200.rotors[0]
    assert r0.unbalances[-1].station == r0.n_stations // 2 and r0.unbalances[-1].amount_kg_m == 0.2
    with pytest.raises(TrainError, match="amount_kg_m"):
        unbalanced(gen200, -1.0)
    with pytest.raises(TrainError, match="station"):
        unbalanced(gen200, 0.1, station=10**6)
    assert math.isclose(unbalanced(gen200, 0.1, rotor=1).rotors[1].unbalances[-1].amount_kg_m, 0.1)


def test_a_train_run_records_the_train_not_the_paper_models_inputs(gen200):
    from rotordiag.simulator.train.transient import TrainTransientModel, train_channels

    res = simulate_transient(TrainTransientModel(gen200), SpeedProfile.linear(1450, 1500, 0.3), settle_revs=2)
    assert res.ok and res.inputs["misalignment"] is None and res.inputs["unbalance"] is None
    m = res.inputs["model"]
    assert m["kind"] == "shaft train" and len(m["bearings"]) == 4
    assert {"station": gen200.rotors[0].n_stations // 2, "amount_kg_m": 0.2}.items() <= m["unbalances"][-1].items()
    w = res.probe_waveforms_um(train_channels(4))
    assert w.shape == (8, res.time_s.size)
    with pytest.raises(ValueError, match="bearing must be 1–4"):
        res.probe_waveforms_um(((5, 45.0),))
