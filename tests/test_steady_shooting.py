"""Shooting on the Poincaré map (rotordiag.simulator.steady, issue 16 item 1)."""
from __future__ import annotations

import numpy as np
import pytest

from rotordiag.simulator import Plant, modal, simulate
from rotordiag.simulator.analysis import classify_motion
from rotordiag.simulator.steady import RotorMap, find_fixed_point, stability_verdict, steady_state
from rotordiag.simulator.system import RotorSystem

PLANT = Plant.default()


def _closest(a: np.ndarray, b: np.ndarray) -> float:
    """Largest distance from a point of ``a`` to the nearest point of ``b`` (both ways)."""
    return max(max(np.min(np.abs(b - v)) for v in a), max(np.min(np.abs(a - v)) for v in b))


@pytest.mark.parametrize("mechanism", ["pin", "rigid", "aligned", "offset", "flexible"])
def test_shooting_equals_brute_force_steady_state(mechanism):
    """Every mechanism: the fixed point equals the state after 400 brute-force revolutions to 1e-6."""
    delta = 0.0 if mechanism == "aligned" else 0.1
    orbit = steady_state(PLANT, 1950.0, delta, 0.05, mechanism=mechanism)
    assert orbit.converged, orbit.message
    assert orbit.period == 1 and orbit.stability == "stable"
    brute = simulate(PLANT, 1950.0, delta, 0.05, mechanism=mechanism, transient_revs=400, record_revs=1)
    pmap = RotorMap(RotorSystem(PLANT, 1950.0, delta, 0.05, mechanism=mechanism))
    # brute force has converged here: the slowest multiplier ≈ 0.93, 0.93**400 ≈ 1e-13
    assert orbit.max_multiplier ** 400 < 1e-10
    diff = pmap.difference(pmap.reduce(brute.final_state), pmap.reduce(orbit.state))
    assert np.max(np.abs(diff)) < 1e-6
    # the returned orbit is the brute-force record of one revolution
    assert orbit.orbit.shape == (64, orbit.state.size)
    np.testing.assert_allclose(orbit.orbit[0], orbit.state)


def test_multipliers_agree_with_finite_difference_monodromy():
    """Central differences of Pⁿ at tight tolerance (independent steps) reproduce the variational M."""
    system = RotorSystem(PLANT, 1950.0, 0.1, 0.05, mechanism="pin", rtol=1e-10, atol=1e-12)
    orbit = steady_state(PLANT, 1950.0, 0.1, 0.05, mechanism="pin", rtol=1e-10, atol=1e-12)
    pmap = RotorMap(system)
    x = pmap.reduce(orbit.state)
    h = 1e-5
    fd = np.empty((pmap.dim, pmap.dim))
    for j in range(pmap.dim):
        xp, xm = x.copy(), x.copy()
        xp[j] += h
        xm[j] -= h
        fd[:, j] = pmap.difference(pmap.evaluate(xp).value, pmap.evaluate(xm).value) / (2 * h)
    var = pmap.evaluate(x, 1, monodromy=True).monodromy
    assert np.max(np.abs(fd - var)) < 1e-6 * np.max(np.abs(var))
    assert _closest(np.linalg.eigvals(fd), orbit.multipliers) < 1e-6


@pytest.mark.parametrize("unbalance", [0.0, 1e-4])
def test_low_amplitude_multipliers_are_exp_of_modal_eigenvalues(unbalance):
    """Aligned, ρ = 0: μ = exp(λT) with λ the linear modal analysis's eigenvalues, T = 60/rpm."""
    plant = PLANT.replace(asymmetry=0.0)
    speed = 1950.0
    orbit = steady_state(plant, speed, 0.0, unbalance, mechanism="aligned")
    assert orbit.converged
    expected = np.exp(modal(plant, speed).eigenvalues_per_s * 60.0 / speed)
    assert len(orbit.multipliers) == len(expected) == 20
    # A = 0: the equilibrium itself; A = 1e-4: an orbit of ~1e-4 clearances, O(A) away from linear
    assert _closest(orbit.multipliers, expected) < (1e-6 if unbalance == 0 else 1e-4)


def test_unstable_orbit_above_the_whirl_threshold_is_found_and_reported_unstable():
    """Above ≈ 2325 r/min the period-1 orbit still exists but is unstable; brute force shows whirl."""
    prev = steady_state(PLANT, 2250.0, 0.0, 0.05, mechanism="aligned")
    assert prev.stability == "stable"
    for speed in (2350.0, 2450.0):  # natural continuation from the stable orbit
        orbit = steady_state(PLANT, speed, 0.0, 0.05, mechanism="aligned", initial_state=prev.state,
                             warmup_revs=0, period=1)
        assert orbit.converged, orbit.message
        prev = orbit
    assert orbit.stability == "unstable"
    unstable = orbit.multipliers[np.abs(orbit.multipliers) > 1]
    assert len(unstable) == 2 and abs(unstable[0].imag) > 0  # a complex pair: Neimark–Sacker (whirl)
    # brute force from MODEL.md's start never shows it: non-periodic motion
    brute = simulate(PLANT, 2450.0, 0.0, 0.05, mechanism="aligned", transient_revs=400, record_revs=64)
    assert not classify_motion(brute.poincare_m / PLANT.clearance_m).label.startswith("period-")
    # and a run started on it leaves it at the rate the largest multiplier says
    pmap = RotorMap(RotorSystem(PLANT, 2450.0, 0.0, 0.05, mechanism="aligned"))
    x = pmap.reduce(orbit.state)
    x_pert = x + 1e-7 * np.linspace(1, 2, x.size)
    d0 = np.max(np.abs(x_pert - x))
    d = np.max(np.abs(pmap.difference(pmap.evaluate(x_pert, 300).value, x)))
    assert d > 10 * d0


def test_period_n_orbit_and_its_least_period():
    """A period-2 fixed point of P² of a period-1 orbit reduces to period 1; asking n=2 keeps n=2."""
    orbit = steady_state(PLANT, 1950.0, 0.1, 0.05, mechanism="rigid", period=2)
    assert orbit.converged and orbit.period == 2 and len(orbit.multipliers) == 20
    one = steady_state(PLANT, 1950.0, 0.1, 0.05, mechanism="rigid")
    # multipliers of P² are the squares of those of P
    assert _closest(orbit.multipliers, one.multipliers ** 2) < 1e-6


def test_stability_verdict_and_bad_inputs():
    assert stability_verdict(np.array([0.5, -0.9])) == "stable"
    assert stability_verdict(np.array([0.5, -1.01])) == "unstable"
    assert stability_verdict(np.array([1.0 + 1e-7j])) == "marginal"
    with pytest.raises(ValueError, match="period"):
        steady_state(PLANT, 1950.0, 0.1, 0.05, period=17)
    with pytest.raises(ValueError, match="speed_rpm"):
        steady_state(PLANT, 50.0, 0.1, 0.05)


def test_newton_reports_failure_instead_of_a_wrong_answer():
    """A map with no fixed point (x ↦ x + 1) fails with a message."""
    class Shift:
        dim = 2

        def evaluate(self, x, n, monodromy=False):
            from rotordiag.simulator.steady import MapEval

            return MapEval(x + n, np.eye(2) if monodromy else None, np.array([x + k + 1 for k in range(n)]),
                           "ok", 1)

        def difference(self, a, b):
            return a - b

    fp = find_fixed_point(Shift(), np.zeros(2))
    assert not fp.converged and fp.message
