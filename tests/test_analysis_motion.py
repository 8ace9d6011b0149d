"""Motion-type classification on constructed Poincaré sets and on systems with known motion."""
from __future__ import annotations

import numpy as np
import pytest

from rotordiag.simulator.analysis import classify_motion, detect_period, largest_lyapunov, poincare_divergence_rate
from rotordiag.simulator.analysis.motion import LLE_NOISE_PER_INTERVAL
from tests.reference import analysis_systems as ref


def _cycle(period: int, n: int = 128, dim: int = 2, noise: float = 1e-5, seed: int = 0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    base = rng.uniform(-0.5, 0.5, size=(period, dim))
    pts = base[np.arange(n) % period]
    return pts + noise * rng.standard_normal(pts.shape)


@pytest.mark.parametrize("period", [1, 2, 3, 7, 16])
def test_period_n_with_small_noise(period):
    m = classify_motion(_cycle(period), orbit_size=1.0)
    assert (m.kind, m.period, m.label) == ("period-n", period, f"period-{period}")


def test_period_is_smallest_and_noise_above_tolerance_is_not_periodic():
    pts = _cycle(7, noise=0.0)
    assert detect_period(pts, orbit_size=1.0)[0] == 7          # not 14
    noisy = _cycle(3, noise=0.05)                               # 5 % of the orbit: not a clean cycle
    assert classify_motion(noisy, orbit_size=1.0).kind != "period-n"


def test_period_tolerance_is_relative_to_orbit_size():
    pts = _cycle(3, noise=1e-5) * 1e-4 + 0.3                   # small orbit far from the origin
    # with the true orbit size the cycle is resolved; with a too-large scale it merges to period-1
    assert classify_motion(pts, orbit_size=1e-4).period == 3
    assert classify_motion(pts, orbit_size=1.0).period == 1


def test_rotor_shaped_points_are_accepted():
    pts = _cycle(3, dim=12).reshape(128, 6, 2)
    assert classify_motion(pts, orbit_size=1.0).period == 3


def test_period_longer_than_max_is_unresolved_with_negative_lle():
    pts = _cycle(20)
    m = classify_motion(pts, lle=-0.2, orbit_size=1.0)
    assert m.kind == "unresolved" and m.period is None


def test_quasi_periodic_circle_map():
    pts = ref.circle_map_points(256)
    m = classify_motion(pts)
    assert m.kind == "quasi-periodic", m.evidence
    assert abs(poincare_divergence_rate(pts)) < 0.02


def test_circle_map_locked_is_periodic():
    # K = 0.95: Ω = 1/2 is the centre of the 1/2 Arnold tongue (by symmetry); Ω = 0.345 lies
    # inside the 1/3 tongue, which for θ' = θ + Ω - K/2π sin 2πθ bends to Ω > 1/3
    assert classify_motion(ref.circle_map_points(128, omega=0.5, k=0.95, transient=2000)).period == 2
    assert classify_motion(ref.circle_map_points(128, omega=0.345, k=0.95, transient=2000)).period == 3


def test_logistic_chaos():
    pts = ref.iterate(ref.logistic_map(4.0), [0.3], 128, transient=100)
    m = classify_motion(pts)
    assert m.kind == "chaotic", m.evidence
    assert poincare_divergence_rate(pts) == pytest.approx(np.log(2), abs=0.15)


def test_logistic_period_doubling_windows():
    for r, period in [(3.2, 2), (3.5, 4), (3.83, 3)]:
        pts = ref.iterate(ref.logistic_map(r), [0.3], 128, transient=3000)
        assert classify_motion(pts).period == period


def test_henon_chaos_from_one_coordinate_with_delay_embedding():
    pts = ref.iterate(ref.henon_map(), [0.1, 0.1], 256, transient=100)
    assert classify_motion(pts).kind == "chaotic"
    assert classify_motion(pts[:, 0], delay_embedding=2).kind == "chaotic"


def test_lle_decides_between_chaos_and_torus():
    pts = ref.circle_map_points(128)
    assert classify_motion(pts, lle=0.3).kind == "chaotic"
    assert classify_motion(pts, lle=0.5 * LLE_NOISE_PER_INTERVAL).kind == "quasi-periodic"


def test_known_flows_lorenz_torus_forced_oscillator():
    # Lorenz sampled every 0.5 time units + its Benettin LLE
    flow = ref.lorenz_flow(0.5)
    lz = ref.iterate(flow, [1.0, 1.0, 1.0], 128, transient=100)
    lle = largest_lyapunov(flow, lz[-1], n_intervals=400, interval_s=0.5)
    assert classify_motion(lz, lle).kind == "chaotic"
    assert classify_motion(lz).kind == "chaotic"
    # attracting torus of two Stuart-Landau oscillators, stroboscopic section
    tflow = ref.torus_flow()
    tor = ref.iterate(tflow, [0.5, 0.0, 0.5, 0.2], 128, transient=50)
    tlle = largest_lyapunov(tflow, tor[-1], n_intervals=200, interval_s=2 * np.pi, separation=1e-7)
    assert classify_motion(tor, tlle).kind == "quasi-periodic"
    assert classify_motion(tor).kind == "quasi-periodic"
    # harmonically forced damped oscillator, section once per forcing period: period-1, LLE = -ζω per period
    omega_n, zeta, period = 2.0, 0.1, 2 * np.pi
    fflow = ref.forced_oscillator_flow(omega_n, zeta, period)
    pts = ref.iterate(fflow, [1.0, 0.0], 64, transient=20)
    flle = largest_lyapunov(fflow, pts[-1], n_intervals=50, interval_s=period, separation=1e-6)
    assert flle.lle_per_s == pytest.approx(-zeta * omega_n, abs=0.01)
    m = classify_motion(pts, flle)
    assert (m.kind, m.period) == ("period-n", 1)


@pytest.mark.parametrize("bad, word", [
    (np.array([[0.0, np.nan]] * 10), "NaN"),
    (np.zeros((0, 2)), "n_sections"),
    (np.zeros((2, 2)), "min_repeats"),
])
def test_bad_points(bad, word):
    with pytest.raises(ValueError, match=word):
        classify_motion(bad)


def test_bad_thresholds():
    with pytest.raises(ValueError, match="period_rtol"):
        classify_motion(_cycle(1), period_rtol=0)
    with pytest.raises(ValueError, match="orbit_size"):
        classify_motion(_cycle(1), orbit_size=-1)
    with pytest.raises(ValueError, match="lle_noise"):
        classify_motion(_cycle(1), lle_noise=-1)
