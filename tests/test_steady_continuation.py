"""Continuation and bifurcation detection checked on the forced Duffing oscillator (issue 16 item 2).

The Duffing map (tests/steady_duffing.py) is integrated by SciPy with its analytic
variational equations, so these tests check the continuation code on its own.
"""
from __future__ import annotations

import numpy as np
import pytest

from rotordiag.simulator.analysis import detect_period
from rotordiag.simulator.steady import find_fixed_point
from rotordiag.simulator.steady.continuation import continue_branch, switch_period_doubling
from tests.steady_duffing import (
    DuffingFamily,
    DuffingMap,
    IsolaFamily,
    NoisyDuffingFamily,
    harmonic_balance_folds,
)

HARDENING = dict(delta=0.1, alpha=1.0, beta=0.1, gamma=0.3)
# Holmes' double well, x'' + 0.3x' − x + x³ = γ cos 1.2t: period 1 at γ = 0.20, period 2 at 0.28,
# period 4 at 0.29 (the textbook sequence, e.g. the Duffing-equation pages of Wikipedia and
# Kovacic & Brennan, "The Duffing Equation", 2011)
DOUBLE_WELL = dict(delta=0.3, alpha=-1.0, beta=1.0, omega=1.2)


def test_frequency_response_folds_match_harmonic_balance():
    """Hardening Duffing: both folds (the jumps) found, located, and within 0.5 % of harmonic balance."""
    fam = DuffingFamily(DuffingMap(omega=0.8, **HARDENING))
    branch = continue_branch(fam, np.zeros(2), 0.8, p_min=0.8, p_max=2.0, ds=0.05, ds_max=0.1, max_points=300)
    assert branch.values[-1] > 2.0  # passed both folds to the far end
    folds = [b for b in branch.bifurcations if b.kind == "fold"]
    assert [b.located for b in folds] == [True, True]
    down, up = harmonic_balance_folds(**HARDENING)
    # the branch turns back at the jump-down fold first, then forward at the jump-up one
    assert folds[0].parameter == pytest.approx(down, rel=5e-3)
    assert folds[1].parameter == pytest.approx(up, rel=5e-3)
    for b in folds:  # a fold is a multiplier through +1
        assert np.min(np.abs(b.multipliers - 1.0)) < 1e-5
    # stability changes at each fold: stable - unstable (middle branch) - stable
    st = branch.stability
    i, j = folds[0].index, folds[1].index
    assert st[i - 1] == "stable" and set(st[i + 2:j - 1]) == {"unstable"} and st[j + 2] == "stable"
    assert not [b for b in branch.bifurcations if b.kind != "fold"]


def test_period_doubling_located_and_the_doubled_branch_matches_brute_force():
    fam = DuffingFamily(DuffingMap(gamma=0.2, **DOUBLE_WELL), parameter="gamma")
    branch = continue_branch(fam, np.array([1.0, 0.0]), 0.2, p_min=0.1, p_max=0.4, ds=0.02, ds_max=0.05)
    pds = [b for b in branch.bifurcations if b.kind == "period_doubling"]
    assert len(pds) == 1 and pds[0].located
    pd = pds[0]
    assert 0.20 < pd.parameter < 0.28
    assert np.min(np.abs(pd.multipliers + 1.0)) < 1e-6
    # brute force on either side: period 1 just below, period 2 just above
    for gamma, period in ((pd.parameter - 0.005, 1), (pd.parameter + 0.005, 2)):
        m = fam.at(gamma)
        pts = m.evaluate(pd.x, 600).sections[-64:]
        assert detect_period(pts, orbit_size=2.0)[0] == period
    # switching: the period-2 branch starts at the PD point and is stable just past it
    doubled = switch_period_doubling(fam, branch, pd, p_min=0.1, p_max=0.4, max_points=60)
    assert doubled.n_periods == 2 and doubled.values[1] > pd.parameter
    k = int(np.argmin(np.abs(doubled.values - 0.28)))
    p28 = doubled.points[k]
    assert p28.stability == "stable"
    # its two section points are the brute-force attractor at that γ
    m = fam.at(p28.parameter)
    brute = m.evaluate(p28.x, 600).sections[-2:]
    assert min(np.max(np.abs(brute - p28.sections)), np.max(np.abs(brute[::-1] - p28.sections))) < 1e-6
    assert np.max(np.abs(p28.sections[0] - p28.sections[1])) > 1e-2  # a genuine 2-cycle
    # the cascade goes on: the doubled branch period-doubles again before γ = 0.29 (period 4 there)
    pd2 = [b for b in doubled.bifurcations if b.kind == "period_doubling"]
    assert pd2 and 0.28 < pd2[0].parameter < 0.29


def test_fixed_point_of_duffing_and_liouville():
    """det M = exp(−δT) (Liouville): an exact check of the monodromy and of the multipliers."""
    m = DuffingMap(omega=1.2, **HARDENING)
    fp = find_fixed_point(m, np.zeros(2))
    assert fp.converged
    assert np.prod(fp.multipliers).real == pytest.approx(np.exp(-0.1 * 2 * np.pi / 1.2), rel=1e-8)


def test_bad_direction():
    fam = DuffingFamily(DuffingMap(omega=0.8, **HARDENING))
    with pytest.raises(ValueError, match="direction"):
        continue_branch(fam, np.zeros(2), 0.8, direction=0)


def test_continuation_passes_folds_on_a_map_whose_residual_has_a_noise_floor_above_tol():
    """The step-control stall (docs/reproduction.md, light-exciter plant, Δ ≈ 0.0386): with map
    errors of 2e-8 no corrector reaches tol = 1e-9; the corrector must accept its best iterate
    once Newton stagnates (within 100·tol) and the step must grow again, not fall below ds_min."""
    # the integration itself at rtol 1e-9 (its error, ~1e-10, is below the added 2e-8)
    fam = NoisyDuffingFamily(DuffingMap(omega=0.8, rtol=1e-9, atol=1e-10, **HARDENING), noise=2e-8)
    branch = continue_branch(fam, np.zeros(2), 0.8, p_min=0.8, p_max=2.0, ds=0.05, ds_max=0.1, max_points=300,
                             tol=1e-9)
    assert "ds_min" not in branch.message
    assert branch.values[-1] > 2.0
    folds = [b for b in branch.bifurcations if b.kind == "fold"]
    down, up = harmonic_balance_folds(**HARDENING)
    assert [b.parameter for b in folds] == [pytest.approx(down, rel=5e-3), pytest.approx(up, rel=5e-3)]
    assert len(branch.points) < 150  # the step grew back (a crawl at ds_min would take thousands)


def test_a_closed_branch_is_followed_once_around_and_both_folds_located():
    """An isola (a period-n window born and dying in saddle-nodes, as on the light-exciter plant):
    the continuation stops when it is back at its start, with the two folds at p₀ ± r."""
    fam = IsolaFamily()
    branch = continue_branch(fam, np.array([0.5, 0.0]), 1.0, p_min=0.0, p_max=2.0, ds=0.05, ds_max=0.1,
                             max_points=500)
    assert branch.message.startswith("closed")
    folds = sorted(b.parameter for b in branch.bifurcations if b.kind == "fold")
    assert folds == [pytest.approx(0.5, abs=1e-6), pytest.approx(1.5, abs=1e-6)]
    x1 = branch.states[:, 0]
    assert np.all(branch.stability[x1 > 1e-3] == "stable") and np.all(branch.stability[x1 < -1e-3] == "unstable")
    assert 30 < len(branch.points) < 60  # once around (circumference π, steps ≤ 0.1), not twice


def test_period_two_orbit_from_a_brute_force_point_continued_to_its_next_doubling():
    """Period-n shooting from a brute-force point (how a rotor window's orbit is reached): Holmes'
    double-well Duffing at γ = 0.28 is period 2 (brute force says so), shooting finds that 2-cycle
    (stable, least period 2, both points on the attractor) and its branch doubles again to
    period 4 between γ = 0.28 and 0.29 — not via switching from the period-1 branch."""
    m = DuffingMap(gamma=0.28, **DOUBLE_WELL)
    pts = m.evaluate(np.array([1.0, 0.0]), 400).sections[-32:]
    period = detect_period(pts, orbit_size=2.0)[0]
    assert period == 2
    fp = find_fixed_point(m, pts[-1], period)
    assert fp.converged and fp.stability == "stable"
    assert np.max(np.abs(fp.sections[0] - fp.x)) > 1e-2  # not a period-1 orbit counted twice
    assert min(np.max(np.abs(fp.x - p)) for p in pts[-2:]) < 1e-6
    fam = DuffingFamily(m, parameter="gamma")
    branch = continue_branch(fam, fp.x, 0.28, n_periods=2, p_min=0.25, p_max=0.3, ds=0.01, ds_max=0.02,
                             max_points=40)
    pds = [b for b in branch.bifurcations if b.kind == "period_doubling"]
    assert pds and 0.28 < pds[0].parameter < 0.29
    assert np.min(np.abs(pds[0].multipliers + 1.0)) < 1e-6
