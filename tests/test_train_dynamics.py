"""Time response of the reduced train: against the full model's frequency response, energy conservation,
the two-pole asymmetry's gravity 2X against quasi-static solutions, the reduction's error."""
from __future__ import annotations

import importlib.util
import math
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np

from rotordiag.simulator.train import (
    Material,
    Rotor,
    Support,
    Train,
    assemble,
    critical_speeds,
    unbalance_response,
    uniform_elements,
)
from rotordiag.simulator.train.dynamics import build_kernel, simulate_train
from rotordiag.simulator.train.linear import linear_matrices
from rotordiag.simulator.train.reduced import reduce

from .train_support import iso, two_rotor_train

BENCH = Path(__file__).resolve().parents[1] / "benchmarks"


def _ref():
    name = "train_ross_reference"
    if name not in sys.modules:
        spec = importlib.util.spec_from_file_location(name, BENCH / f"{name}.py")
        mod = importlib.util.module_from_spec(spec)
        sys.modules[name] = mod
        spec.loader.exec_module(mod)
    return sys.modules[name]


def _line(sig: np.ndarray, revs: int, order: int) -> np.ndarray:
    """Complex amplitude X of order ``order`` along axis 0 (x(t) = Re(X e^{i·order·Ωt}))."""
    return 2 * np.fft.fft(sig, axis=0)[order * revs] / sig.shape[0]


def test_time_response_of_the_reduced_train_matches_the_full_models_unbalance_response():
    asm = assemble(_ref().reference_train(True))
    run = simulate_train(asm, 3000.0, transient_revs=60, record_revs=16, samples_per_rev=64, n_modes=16)
    assert run.ok
    X = _line(run.journal_m, 16, 1)
    R = unbalance_response(asm, [3000.0])[0, asm.support_nodes, :]
    np.testing.assert_allclose(np.abs(X), np.abs(R), rtol=2e-3)
    assert np.abs(np.angle(X / R)).max() < 2e-3


def test_reduction_keeps_the_first_six_critical_speeds_within_a_tenth_of_a_percent():
    asm = assemble(_ref().reference_train(False))
    red = reduce(asm, 16)
    full = critical_speeds(asm, 6, 9000.0, n_grid=90)
    # critical speeds of the reduced model: Campbell crossings of its linear eigenvalues
    from scipy.optimize import brentq

    def freqs(speed_rpm):
        w = speed_rpm * math.pi / 30
        M, C, K = linear_matrices(asm, w)
        Mr, Cr, Kr = (red.T.T @ A @ red.T for A in (M, C, K))
        n = red.n
        A = np.block([[np.zeros((n, n)), np.eye(n)], [-np.linalg.solve(Mr, Kr), -np.linalg.solve(Mr, Cr)]])
        lam = np.linalg.eigvals(A)
        return np.sort(lam.imag[lam.imag > 1e-6]) / (2 * math.pi)

    grid = np.linspace(50.0, 9000.0, 90)
    f = np.array([freqs(s)[:16] for s in grid])
    crit = []
    for k in range(16):
        g = f[:, k] - grid / 60
        for j in range(len(grid) - 1):
            if g[j] > 0 >= g[j + 1]:
                crit.append(brentq(lambda s, k=k: freqs(s)[k] - s / 60, grid[j], grid[j + 1], xtol=1e-6))
    np.testing.assert_allclose(np.sort(crit)[:6], full, rtol=1e-3)


def test_undamped_train_conserves_energy():
    """Linear undamped bearings, no gravity or unbalance, symmetric shaft: the gyroscopic forces do no work."""
    t = two_rotor_train(iso(2e9), iso(5e8))
    t = replace(t, gravity_m_s2=0.0)
    kern = build_kernel(t, 3000.0, 10)
    red = kern.red
    rng = np.random.default_rng(4)
    s0 = np.concatenate([rng.normal(0, 1e-5, red.n), np.zeros(red.n)])
    run = simulate_train(kern, 3000.0, transient_revs=0, record_revs=20, samples_per_rev=16, initial=s0,
                         rtol=1e-10, atol_m=1e-16, record_state=True)
    assert run.ok
    w = 3000.0 * math.pi / 30
    M, _, K = linear_matrices(red.assembly, w)
    Mr, Kr = red.T.T @ M @ red.T, red.T.T @ K @ red.T
    p, v = run.states[:, :red.n], run.states[:, red.n:]
    E = 0.5 * np.einsum("ij,jk,ik->i", v, Mr, v) + 0.5 * np.einsum("ij,jk,ik->i", p, Kr, p)
    assert np.ptp(E) / E[0] < 1e-6
    assert np.ptp(0.5 * np.einsum("ij,jk,ik->i", v, Mr, v)) > 0.1 * E[0]  # energy does move between forms


def test_two_pole_asymmetry_gives_the_quasi_static_gravity_2x_of_a_turning_shaft():
    """Generator body with ρ = 0.1 on stiff isotropic supports at 60 r/min (2X far below the first mode):
    the midspan deflection follows the static deflections of the shaft turned through one revolution,
    computed here from two symmetric shafts of stiffness EI(1 ± ρ) (no asymmetric matrix used)."""
    mat = Material()
    rho = 0.1
    L, D, n = 6.0, 0.5, 16
    brg = iso(5e9, 2e6)
    rot = Rotor("g", uniform_elements(L, D, n, asymmetry=rho), supports=(Support(0, brg), Support(n, brg)))
    train = Train((rot,))
    speed = 60.0
    run = simulate_train(train, speed, transient_revs=3, record_revs=2, samples_per_rev=32, n_modes=8,
                         record_state=True)
    assert run.ok
    mid = run.node_m(n // 2)
    X2 = _line(mid, 2, 2)

    def deflection(E_scale):
        r = Rotor("g", uniform_elements(L, D, n), supports=(Support(0, brg), Support(n, brg)),
                  material=replace(mat, young_pa=mat.young_pa * E_scale))
        a = assemble(Train((r,)))
        Kb = a.K.copy()
        for node in (0, n):
            Kb[4 * node, 4 * node] += 5e9
            Kb[4 * node + 1, 4 * node + 1] += 5e9
        return np.linalg.solve(Kb, a.gravity_n)[4 * (n // 2) + 1]  # vertical midspan deflection

    d_stiff, d_soft = deflection(1 + rho), deflection(1 - rho)
    # shaft turned by θ: the load (vertical) has components along the stiff axis (at θ) and the soft one;
    # deflection = R diag(d_stiff, d_soft) Rᵀ ĝ with the gravity deflections of each principal stiffness
    theta = np.arange(64) * 2 * math.pi / 64
    ref = np.empty((64, 2))
    for k, th in enumerate(theta):
        e1 = np.array([math.cos(th), math.sin(th)])
        e2 = np.array([-math.sin(th), math.cos(th)])
        ref[k] = (e1 * d_stiff * e1[1] + e2 * d_soft * e2[1])
    R2 = _line(ref, 1, 2)
    np.testing.assert_allclose(np.abs(X2), np.abs(R2), rtol=0.03)
    assert abs(X2[1]) > 0.03 * abs(np.mean(mid[:, 1]))  # a visible 2X: a few % of the sag


def test_exponential_integrator_agrees_with_adaptive_dormand_prince_on_oil_films():
    """Plain bearings, gravity, a two-pole body: the fixed-step ETDRK4 (32 steps per revolution) against the
    adaptive explicit integrator at the paper model's tolerances, DC, 1X and 2X at every probe."""
    ref = _ref()
    bench = importlib.util.spec_from_file_location("bench_train", BENCH / "bench_train.py")
    mod = importlib.util.module_from_spec(bench)
    bench.loader.exec_module(mod)
    kern = build_kernel(mod.plain_train(ref), 3000.0, 12)
    a = simulate_train(kern, 3000.0, transient_revs=24, record_revs=8, samples_per_rev=32)
    b = simulate_train(kern, 3000.0, transient_revs=24, record_revs=8, samples_per_rev=32, method="dopri")
    assert a.ok and b.ok and a.inputs["method"] == "etd" and b.n_accepted > 20 * a.n_accepted / 32
    scale = np.abs(b.journal_m).max()
    np.testing.assert_allclose(a.journal_m.mean(0), b.journal_m.mean(0), atol=1e-4 * scale)
    for order in (1, 2):
        np.testing.assert_allclose(_line(a.journal_m, 8, order), _line(b.journal_m, 8, order),
                                   atol=2e-3 * np.abs(_line(b.journal_m, 8, 1)).max())
    assert np.abs(_line(b.journal_m, 8, 2)).max() > 0.002 * np.abs(_line(b.journal_m, 8, 1)).max()
