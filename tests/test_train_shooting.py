"""Shooting on the train through the steady-state flow-map interface: the period-1 orbit equals the long
time response's last revolution; its Floquet multipliers carry the linear stability margin."""
from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np

from rotordiag.simulator.train.dynamics import build_kernel, simulate_train
from rotordiag.simulator.train.linear import modes
from rotordiag.simulator.train.shooting import train_fixed_point

BENCH = Path(__file__).resolve().parents[1] / "benchmarks"


def _machine():
    spec = importlib.util.spec_from_file_location("bench_train", BENCH / "bench_train.py")
    bench = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(bench)
    return bench.plain_train(bench._ref())


def test_period_one_orbit_by_shooting_equals_the_long_time_response():
    """Bench machine (plain films, gravity, two-pole body) at 3000 r/min: the shooting solution from the
    static state against 448 revolutions of the time response (at the same 64 steps per revolution)."""
    train = _machine()
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
