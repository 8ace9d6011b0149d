"""Long-horizon physics checks (``make test-slow``)."""
import numpy as np
import pytest
from scipy.integrate import solve_ivp

from rotordiag.simulator import Plant, build_system, simulate
from tests.reference.rotor_numpy import ReferenceRotor
from tests.test_simulator_physics import W1950, _total_energy

pytestmark = pytest.mark.slow


def _subsynchronous_fraction(res):
    """Share of journal-2 vibration energy below 0.9X (record of whole revolutions)."""
    d = res.journal_displacements_m[:, 1, 0]
    spec = np.abs(np.fft.rfft(d - d.mean())) ** 2
    revs = res.inputs["record_revs"]
    orders = np.arange(len(spec)) / revs
    return spec[(orders > 0.05) & (orders < 0.9)].sum() / spec[orders > 0.05].sum()


def test_oil_whip_onset_between_2200_and_2400_rpm():
    """MODEL.md: period-1 up to ≈ 2200 r/min, oil whip above ≈ 2350 (orbits to ε ≈ 0.93)."""
    below = simulate(Plant.default(), 2200.0, 0.0, 0.05, record_revs=64, samples_per_rev=32)
    above = simulate(Plant.default(), 2400.0, 0.0, 0.05, record_revs=64, samples_per_rev=32)
    assert _subsynchronous_fraction(below) < 1e-3
    assert _subsynchronous_fraction(above) > 0.5
    ecc = np.hypot(*above.journal_displacements_m[:, 1].T) / Plant.default().clearance_m
    assert ecc.max() > 0.8


def test_energy_drift_over_500_revolutions():
    plant = Plant.default().replace(bearing_model="linear", linear_bearing_stiffness_n_m=1e10,
                                    generator_damping_n_s_m=0.0, exciter_damping_n_s_m=0.0, asymmetry=0.0)
    res = simulate(plant, 1950.0, 0.1, 0.0, transient_revs=0, record_revs=500, samples_per_rev=4,
                   rtol=1e-11, atol=1e-13, record_state=True)
    E, _ = _total_energy(res, plant, W1950, 0.1)
    assert np.abs(E - E[0]).max() / abs(E[0]) < 1e-6


def test_agreement_with_solve_ivp_over_30_revolutions():
    plant = Plant.default()
    res = simulate(plant, 1950.0, 0.1, 0.05, transient_revs=0, record_revs=30, samples_per_rev=8,
                   rtol=1e-10, atol=1e-12)
    ref = ReferenceRotor(plant.to_dict(), 1950.0, 0.1, 0.05, "pin")
    y0 = build_system(plant, 1950.0, 0.1, 0.05).initial_state()
    sol = solve_ivp(ref, (0.0, res.time_s[-1]), ref.to_si(y0), method="DOP853", rtol=1e-10, atol=1e-14,
                    t_eval=res.time_s)
    x_sim = res.positions_m[:, [0, 1, 3, 4, 5], :].reshape(len(res.time_s), 10)
    assert np.abs(x_sim - sol.y[:10].T).max() / np.abs(sol.y[:10]).max() < 1e-6
