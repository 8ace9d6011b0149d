"""Shooting and continuation on the train through the steady-state flow-map interface: the period-1 orbit
equals the long time response; its Floquet multipliers and the branch's whirl onset agree with the
linearisation about the static state."""
from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import brentq

from rotordiag.simulator.steady.continuation import continue_branch
from rotordiag.simulator.train.dynamics import build_kernel, linear_stability, simulate_train
from rotordiag.simulator.train.linear import modes
from rotordiag.simulator.train.shooting import TrainSpeedFamily, train_fixed_point

from .bench_util import bench_machine


def test_period_one_orbit_by_shooting_equals_the_long_time_response():
    """Bench machine (plain films, gravity, two-pole body) at 3000 r/min: the shooting solution from the
    static state against 448 revolutions of the time response (at the same 64 steps per revolution)."""
    train = bench_machine()
    speed = 3000.0
    kern = build_kernel(train, speed, 12)
    fp = train_fixed_point(kern, speed, 1, steps_per_rev=64)
    assert fp.converged, fp.message
    run = simulate_train(kern, speed, transient_revs=447, record_revs=1, samples_per_rev=32, steps_per_sample=2,
                         record_state=True)
    long_x = run.states[0]  # the state at the start of revolution 448 (t ≡ 0 mod T)
    n = kern.red.n
    pos = kern.red.T @ fp.x[:n]
    pos_long = kern.red.T @ long_x[:n]
    sup = kern.red.assembly.support_nodes
    rows = np.concatenate([4 * np.asarray(sup), 4 * np.asarray(sup) + 1])
    # journals: the orbit's point in the section against the long run's, to 1e-6 of the whirl amplitude
    amp = np.ptp(run.journal_m, axis=0).max()
    assert np.abs(pos[rows] - pos_long[rows]).max() < 1e-6 * amp
    # stable orbit: every multiplier inside the unit circle, the largest |μ| = max exp(Re λ·T) over the damped
    # modes of the full FE model about the static state (the orbit is a small motion about it)
    full = modes(train, speed)
    low = full.frequency_hz < 500.0
    mu_lin = np.exp(full.eigenvalues[low].real * 60.0 / speed).max()
    mu = np.abs(fp.multipliers).max()
    assert fp.stability == "stable" and mu < 1
    np.testing.assert_allclose(mu, mu_lin, rtol=1e-3)


@pytest.mark.slow
def test_continuation_over_speed_finds_the_whirl_onset_at_the_linear_stability_threshold():
    """The period-1 branch of the bench machine from 3200 r/min upward loses stability by a Neimark–Sacker
    bifurcation (a pair of multipliers leaving the unit circle: the whirl onset) where the least log
    decrement of the static linearisation crosses zero (found here by root-finding on the eigenvalues)."""
    train = bench_machine()
    fam = TrainSpeedFamily(train)
    start = 3200.0
    fp = train_fixed_point(fam.at(start).kernel, start)
    assert fp.converged
    br = continue_branch(fam, fp.x, start, p_min=3000.0, p_max=4000.0, ds=0.05, ds_max=0.1, tol=1e-10,
                         max_points=12)
    ns = [b for b in br.bifurcations if b.kind == "neimark_sacker"]
    assert len(ns) == 1 and ns[0].located
    threshold = brentq(lambda s: linear_stability(build_kernel(train, s, 12), s)[0], 3000.0, 4000.0, xtol=0.01)
    assert ns[0].parameter == pytest.approx(threshold, rel=5e-3)
    assert (br.max_multiplier[br.values < threshold - 50] < 1).all()
    assert (br.max_multiplier[br.values > threshold + 50] > 1).all()
