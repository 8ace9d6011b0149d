"""Lyapunov exponent and amplitude–speed curves of a shaft train (simulator.analysis.train) and the
``lyapunov`` / ``bifurcate`` commands with --train."""
from __future__ import annotations

import json

import numpy as np
import pytest
from typer.testing import CliRunner

from rotordiag.cli import app
from rotordiag.simulator.analysis.train import (
    half_power_band,
    order_amplitude_pp,
    train_lyapunov,
    train_speed_sweep,
    with_unbalance,
)
from rotordiag.simulator.train import modes
from rotordiag.simulator.train.campbell import train_campbell
from rotordiag.simulator.train.shaftline import shaftline_of, train_from_shaftline

from .train_support import iso, two_rotor_train


def test_order_amplitude_of_a_known_signal():
    n_rev, spr = 8, 64
    t = np.arange(n_rev * spr) / spr  # revolutions
    x = 3.0 + 5.0 * np.cos(2 * np.pi * t + 0.3) + 2.0 * np.sin(4 * np.pi * t)
    assert order_amplitude_pp(x, spr, 1) == pytest.approx(10.0, rel=1e-12)
    assert order_amplitude_pp(x, spr, 2) == pytest.approx(4.0, rel=1e-12)
    with pytest.raises(ValueError, match="whole revolutions"):
        order_amplitude_pp(x[:-3], spr, 1)


def test_stable_period_one_train_has_the_negative_exponent_of_its_least_damped_mode():
    """gen200_2pole at 3000 r/min with an unbalance: the Benettin estimate on the time response against
    ln max exp(Re λ·T) of the full FE model linearised about its static state (eigenvalues, no integration)."""
    train = with_unbalance(train_from_shaftline(shaftline_of("gen200_2pole")[0]), 0.5)
    lle, _ = train_lyapunov(train, 3000.0, n_revs=100, transient_revs=100)
    full = modes(train, 3000.0)
    expect = float(np.max(full.eigenvalues[full.frequency_hz < 500.0].real)) * 60.0 / 3000.0
    assert lle.lle_per_interval < 0
    assert abs(lle.lle_per_interval - expect) < 3 * lle.stderr_per_interval + 0.05 * abs(expect), (lle, expect)


def test_amplitude_speed_peak_is_at_the_damped_critical_within_its_half_power_width():
    """The time response's 1X over speed (integration) against the Campbell diagram's first critical
    (eigenvalues): the peak within half the half-power width 2ζ·n_c, the measured band's width within 25 %."""
    train = two_rotor_train(iso(2e8, 2e5), iso(1e8, 5e4), unbalance_kg_m=0.5)
    crit = train_campbell(train, np.linspace(1000.0, 2000.0, 9)).critical_speeds((1,))[0]
    sw = train_speed_sweep(train, np.linspace(1300.0, 1650.0, 15), transient_revs=150, record_revs=16)
    assert all(s == "ok" for s in sw.status)
    b = int(np.argmax(sw.amp_1x_um_pp.max(axis=0)))
    peak, lo, hi = half_power_band(sw.speeds_rpm, sw.amp_1x_um_pp[:, b])
    assert abs(peak - crit.speed_rpm) < 0.5 * crit.half_power_width_rpm
    assert hi - lo == pytest.approx(crit.half_power_width_rpm, rel=0.25)
    # the symmetric, aligned train: 2X far below 1X at the peak
    assert sw.amp_2x_um_pp[np.argmax(sw.amp_1x_um_pp[:, b]), b] < 0.05 * sw.amp_1x_um_pp[:, b].max()


def test_unbalance_goes_on_the_heaviest_body_mass():
    train = train_from_shaftline(shaftline_of("gen200_2pole")[0])
    t2 = with_unbalance(train, 0.5, 90.0)
    u = t2.rotors[0].unbalances[-1]
    assert u.amount_kg_m == 0.5 and u.angle_rad == pytest.approx(np.pi / 2)
    assert u.station == max(train.rotors[0].disks, key=lambda d: d.mass_kg).station
    with pytest.raises(ValueError, match="0..100"):
        with_unbalance(train, -1.0)


def test_lyapunov_and_bifurcate_commands_take_a_train(tmp_path):
    run = CliRunner().invoke
    r = run(app, ["lyapunov", "--train", "gen200_2pole", "--speed-rpm", "3000", "--revs", "30",
                  "--transient-revs", "50", "--unbalance-kg-m", "0.5", "--json"])
    assert r.exit_code == 0, r.output
    out = json.loads(r.stdout[: r.stdout.rindex("}") + 1])
    assert out["lle_per_rev"] < 0 and out["source"] == "gen200_2pole"
    js, png = tmp_path / "s.json", tmp_path / "s.png"
    r = run(app, ["bifurcate", "--train", "gen200_2pole", "--over", "speed", "--from", "1100", "--to", "1300",
                  "--points", "3", "--unbalance-kg-m", "0.5", "--transient-revs", "50", "--record-revs", "8",
                  "--out", str(js), "--plot", str(png)])
    assert r.exit_code == 0, r.output
    data = json.loads(js.read_text())
    assert data["bearings"] == ["B1", "B2", "B3", "B4"] and len(data["amp_1x_um_pp"]) == 3
    assert png.stat().st_size > 10_000


def test_train_commands_refuse_what_they_cannot_do(tmp_path):
    run = CliRunner().invoke
    r = run(app, ["bifurcate", "--train", "gen200_2pole", "--over", "misalignment", "--from", "0", "--to", "0.2"])
    assert r.exit_code == 2 and "speed only" in r.output
    r = run(app, ["bifurcate", "--train", "gen200_2pole", "--over", "speed", "--from", "1000", "--to", "1200",
                  "--out", str(tmp_path / "s.h5")])
    assert r.exit_code == 2 and "JSON" in r.output
    r = run(app, ["lyapunov", "--train", "gen999", "--speed-rpm", "3000"])
    assert r.exit_code == 2 and "unknown shaft-line preset" in r.output
    r = run(app, ["lyapunov", "--speed-rpm", "3000"])
    assert r.exit_code == 2 and "--misalignment" in r.output


@pytest.mark.slow
def test_whirling_train_has_a_near_zero_exponent():
    """The bench machine (plain films) at 4300 r/min, beyond its stability threshold (3842 r/min, the
    continuation test's Neimark–Sacker point): after 300 revolutions it whips (orbit ≈ 1.8 c pk-pk) and its
    largest exponent is near zero (a limit cycle / torus: neutral along the flow), an order of magnitude
    smaller than the stable train's (−0.064 per revolution above). Measured: −0.0070 ± 0.0039 per rev."""
    from .bench_util import bench_machine

    train = bench_machine()
    lle, state = train_lyapunov(train, 4300.0, n_revs=60, transient_revs=300)
    assert abs(lle.lle_per_interval) < 0.02, lle


@pytest.mark.slow
def test_train_figures_show_what_the_static_state_and_the_two_pole_rotor_predict(tmp_path):
    """``rotordiag figures --train``: four PNGs and a summary; the centreline's mean journal positions at a
    speed against the Newton static state there (time integration vs. the static solution, within 5 % of the
    clearance), every orbit inside its clearance, and the two-pole generator's gravity 2X present."""
    from rotordiag.simulator.train import static_state

    r = CliRunner().invoke(app, ["figures", "--train", "gen200_2pole", "--quick", "--out", str(tmp_path)])
    assert r.exit_code == 0, r.output
    names = {"train_orbits.png", "train_spectra.png", "train_centreline.png", "train_amplitude_speed.png"}
    assert names <= {p.name for p in tmp_path.iterdir()}
    assert all((tmp_path / n).stat().st_size > 10_000 for n in names)
    s = json.loads((tmp_path / "train_summary.json").read_text())
    assert s["status"] == "ok" and s["speed_rpm"] == 3000.0
    assert min(s["amp_2x_um_pp"][:2]) > 1.0  # gravity 2X of the asymmetric body at the generator bearings

    from rotordiag.simulator.analysis.train import train_speed_sweep

    train = with_unbalance(train_from_shaftline(shaftline_of("gen200_2pole")[0]), 0.5)
    sw = train_speed_sweep(train, [2000.0], transient_revs=120, record_revs=8)
    st = static_state(train, 2000.0)
    c_um = sw.clearance_um
    assert np.all(np.abs(sw.centre_um[0] - st.journal_m * 1e6).max(axis=-1) < 0.05 * c_um)
    assert np.all(np.hypot(sw.poincare_um[0, :, :, 0], sw.poincare_um[0, :, :, 1]) < c_um)
