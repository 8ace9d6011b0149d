"""``rotordiag continue`` (issue 16 item 3) and the rotor branches behind it."""
from __future__ import annotations

import numpy as np
from typer.testing import CliRunner

from rotordiag.cli import app
from rotordiag.simulator.steady.report import read_branches


def test_continue_over_speed_finds_the_whirl_threshold_as_a_torus_bifurcation(tmp_path):
    """Aligned default plant: the period-1 branch loses stability through a complex pair (NS) at the
    linear whirl threshold (MODEL.md: ≈ 2325 r/min; modal analysis's stability margin changes sign there)."""
    out, png = tmp_path / "b.h5", tmp_path / "b.png"
    res = CliRunner().invoke(app, ["continue", "--over", "speed", "--from", "2200", "--to", "2450",
                                   "--misalignment", "0", "--mechanism", "aligned", "--brute-points", "3",
                                   "--out", str(out), "--plot", str(png)])
    assert res.exit_code == 0, res.output
    data = read_branches(out)
    br = data["branches"][0]
    kinds = list(br["bifurcations"]["kind"])
    assert kinds == ["neimark_sacker"]
    ns = br["bifurcations"]["parameter"][0]
    assert 2300 < ns < 2350
    assert br["stability"][0] == "stable" and br["stability"][-1] == "unstable"
    assert data["brute_force"]["poincare"].shape == (3, 32)
    assert png.stat().st_size > 10_000
    assert "NS at" in res.output


def test_continue_bad_input_is_a_clear_usage_error(tmp_path):
    res = CliRunner().invoke(app, ["continue", "--over", "speed", "--from", "2200", "--to", "2450",
                                   "--out", str(tmp_path / "b.h5")])
    assert res.exit_code == 2 and "--misalignment" in res.output
    res = CliRunner().invoke(app, ["continue", "--over", "torque", "--from", "1", "--to", "2",
                                   "--out", str(tmp_path / "b.h5")])
    assert res.exit_code == 2


def test_modal_margin_changes_sign_at_the_located_torus_bifurcation(tmp_path):
    """Independent check of the NS location: the linear modal stability margin (A = 0, ρ = 0) changes sign
    within 15 r/min of it (A = 0.05 and ρ = 0.0549 shift it only slightly)."""
    from rotordiag.simulator import Plant, modal

    out = tmp_path / "b.h5"
    CliRunner().invoke(app, ["continue", "--over", "speed", "--from", "2250", "--to", "2400", "--misalignment", "0",
                             "--mechanism", "aligned", "--brute-points", "0", "--out", str(out)])
    ns = read_branches(out)["branches"][0]["bifurcations"]["parameter"][0]
    margins = [modal(Plant.default(), s).stability_margin_per_s for s in (ns - 15, ns + 15)]
    assert margins[0] < 0 < margins[1]
    assert np.isfinite(ns)


def test_continue_writes_a_branch_without_bifurcations(tmp_path):
    """A short period-1 branch with no fold/PD/NS is written and read back (an empty bifurcation list
    once crashed the HDF5 writer); the light-exciter plant file is accepted."""
    out = tmp_path / "b.h5"
    res = CliRunner().invoke(app, ["continue", "--over", "speed", "--from", "1800", "--to", "1900",
                                   "--misalignment", "0.02", "--plant", "docs/figures/light-exciter-plant.toml",
                                   "--brute-points", "0", "--ds-max", "0.1", "--out", str(out)])
    assert res.exit_code == 0, res.output
    br = read_branches(out)["branches"][0]
    assert len(br["bifurcations"]["kind"]) == 0
    assert br["bifurcations"]["section_x"].shape == (0, 1)
    assert br["parameter"].min() <= 1800 + 1e-9 and br["parameter"].max() >= 1900 - 1e-9
    assert set(br["stability"]) == {"stable"}


def test_continue_bounds_must_contain_the_start_and_a_non_periodic_start_is_a_clear_error(tmp_path):
    out = str(tmp_path / "b.h5")
    res = CliRunner().invoke(app, ["continue", "--over", "misalignment", "--from", "0.3", "--to", "0.4",
                                   "--lo", "0.35", "--speed-rpm", "1843", "--out", out])
    assert res.exit_code == 2 and "--lo" in res.output
    res = CliRunner().invoke(app, ["continue", "--over", "misalignment", "--from", "0.3", "--to", "0.4",
                                   "--period", "17", "--speed-rpm", "1843", "--out", out])
    assert res.exit_code == 2
    # light-exciter plant at Δ = 0.3: quasi-periodic (racing φ), no period ≤ 16 to shoot for
    res = CliRunner().invoke(app, ["continue", "--over", "misalignment", "--from", "0.3", "--to", "0.4",
                                   "--speed-rpm", "1843", "--plant", "docs/figures/light-exciter-plant.toml",
                                   "--start-revs", "100", "--brute-points", "0", "--out", out])
    assert res.exit_code == 2 and "no period <= 16" in res.output
