"""Benettin LLE on systems with independently known exponents (tests/reference/analysis_systems.py)."""
from __future__ import annotations

import numpy as np
import pytest

from rotordiag.simulator.analysis import FlowMapError, largest_lyapunov
from tests.reference import analysis_systems as ref


def test_lorenz_neighbour_matches_literature():
    res = largest_lyapunov(ref.lorenz_flow(0.5), [1.0, 1.0, 1.0], n_intervals=4000, interval_s=0.5,
                           transient_intervals=100)
    assert res.lle_per_s == pytest.approx(ref.LORENZ_LLE, abs=0.02)
    assert res.lle_per_interval == pytest.approx(0.5 * res.lle_per_s)
    # convergence history ends at the estimate and has settled over the last half
    assert res.history_per_interval.shape == (4000,)
    assert res.history_per_interval[-1] == res.lle_per_interval
    assert np.ptp(res.history_per_interval[2000:]) < 0.05
    assert 0 < res.stderr_per_interval < 0.01


def test_lorenz_variational_equals_neighbour():
    kw = dict(n_intervals=1000, interval_s=0.5, transient_intervals=100)
    var = largest_lyapunov(None, [1.0, 1.0, 1.0], method="variational",
                           tangent_map=ref.lorenz_tangent(0.5), **kw)
    nb = largest_lyapunov(ref.lorenz_flow(0.5), [1.0, 1.0, 1.0], **kw)
    assert var.method == "variational"
    assert var.lle_per_s == pytest.approx(nb.lle_per_s, abs=1e-4)
    assert var.lle_per_s == pytest.approx(ref.LORENZ_LLE, abs=0.05)


@pytest.mark.parametrize("omega_n, zeta", [(2.0, 0.05), (5.0, 0.3)])
def test_damped_oscillator_exact_flow(omega_n, zeta):
    res = largest_lyapunov(ref.damped_oscillator_flow_exact(omega_n, zeta, 0.7), [1.0, 0.0],
                           n_intervals=2000, interval_s=0.7)
    # bounded oscillation of the per-interval growth around -ζω: error O(1/N)
    assert res.lle_per_s == pytest.approx(-zeta * omega_n, abs=0.01 * zeta * omega_n + 1e-3)
    assert res.lle_per_s < 0


def test_damped_oscillator_adaptive_integrator():
    """Same answer when the flow map is an adaptive RK integrator, as for the rotor."""
    res = largest_lyapunov(ref.damped_oscillator_flow_adaptive(2.0, 0.05, 1.0), [1.0, 0.0],
                           n_intervals=300, interval_s=1.0, separation=1e-6)
    assert res.lle_per_s == pytest.approx(-0.1, abs=0.003)


def test_torus_exponent_is_zero():
    res = largest_lyapunov(ref.torus_flow(), [0.5, 0.0, 0.5, 0.2], n_intervals=300, interval_s=2 * np.pi,
                           transient_intervals=50, separation=1e-7)
    assert abs(res.lle_per_interval) < 2e-3
    # the second exponent is -2 per time unit; a wrong (e.g. non-renormalised) scheme would not give ~0
    assert abs(res.lle_per_s) < 1e-3


def test_maps_logistic_and_henon():
    lg = largest_lyapunov(ref.logistic_map(4.0), [0.3], n_intervals=20000, transient_intervals=10)
    assert lg.lle_per_interval == pytest.approx(ref.LOGISTIC_LLE, abs=0.01)
    kw = dict(n_intervals=20000, transient_intervals=10)
    hn = largest_lyapunov(ref.henon_map(), [0.1, 0.1], **kw)
    hv = largest_lyapunov(None, [0.1, 0.1], method="variational", tangent_map=ref.henon_tangent(), **kw)
    assert hn.lle_per_interval == pytest.approx(ref.HENON_LLE, abs=0.015)
    assert hv.lle_per_interval == pytest.approx(hn.lle_per_interval, abs=1e-4)


def test_periodic_window_of_logistic_map_is_negative():
    # r = 3.83: stable period-3 orbit; λ = log|f'(x1) f'(x2) f'(x3)| / 3 computed independently
    r = 3.83
    f = ref.logistic_map(r)
    x = 0.5
    for _ in range(5000):
        x = f(x)
    cycle = [x, f(x), f(f(x))]
    expected = np.mean([np.log(abs(r * (1 - 2 * c))) for c in cycle])
    res = largest_lyapunov(f, [x], n_intervals=3000, separation=1e-9)
    assert expected < 0
    assert res.lle_per_interval == pytest.approx(expected, abs=0.01)


def test_deterministic_for_a_seed():
    kw = dict(n_intervals=200, interval_s=0.5, transient_intervals=10, seed=3)
    a = largest_lyapunov(ref.lorenz_flow(0.5), [1.0, 1.0, 1.0], **kw)
    b = largest_lyapunov(ref.lorenz_flow(0.5), [1.0, 1.0, 1.0], **kw)
    np.testing.assert_array_equal(a.log_growth, b.log_growth)


def test_norm_weights_do_not_change_the_exponent():
    kw = dict(n_intervals=2000, interval_s=0.5, transient_intervals=100)
    a = largest_lyapunov(ref.lorenz_flow(0.5), [1.0, 1.0, 1.0], **kw)
    b = largest_lyapunov(ref.lorenz_flow(0.5), [1.0, 1.0, 1.0], norm_weights=[1.0, 10.0, 0.1], **kw)
    assert b.lle_per_s == pytest.approx(a.lle_per_s, abs=0.03)


@pytest.mark.parametrize("kwargs, word", [
    (dict(n_intervals=0), "n_intervals"),
    (dict(n_intervals=10, interval_s=0.0), "interval_s"),
    (dict(n_intervals=10, separation=-1.0), "separation"),
    (dict(n_intervals=10, method="qr"), "method"),
    (dict(n_intervals=10, transient_intervals=-1), "transient_intervals"),
    (dict(n_intervals=10, norm_weights=[1.0]), "norm_weights"),
    (dict(n_intervals=10, method="variational"), "tangent_map"),
])
def test_bad_arguments_name_the_parameter(kwargs, word):
    with pytest.raises(ValueError, match=word):
        largest_lyapunov(ref.henon_map(), [0.1, 0.1], **kwargs)


def test_flow_map_failure_propagates():
    def bad(state):
        return state * np.nan

    with pytest.raises(FlowMapError, match="non-finite"):
        largest_lyapunov(bad, [0.1, 0.1], n_intervals=5)


def test_separation_below_resolution_is_reported():
    # a map that rounds to a coarse grid: the neighbour collapses onto the reference
    with pytest.raises(FlowMapError, match="separation"):
        largest_lyapunov(lambda s: np.round(0.5 * s, 3), [0.1, 0.2], n_intervals=5, separation=1e-9)
