"""Physics checks of the simulator (MODEL.md verification 3, 4, 6, 7, 8 and the
reference figures of MODEL.md section 6)."""
import math

import numpy as np
import pytest

from rotordiag.simulator import Plant, modal, simulate, static_equilibrium
from rotordiag.simulator.simulate import order_amplitudes

W1950 = 1950 * math.pi / 30


def _total_energy(res, plant, speed_rad_s, delta):
    """Kinetic + potential energy (J) written from MODEL.md section 2, linear bearings."""
    c = plant.clearance_m
    S = res.states
    pos = res.positions_m
    V = S[:, 11:21] * c * speed_rad_s
    phi, phid = S[:, 10], S[:, 21] * speed_rad_s
    v3 = V[:, 4:6] + delta * c * phid[:, None] * np.stack([-np.sin(phi), np.cos(phi)], 1)
    masses = [plant.journal1_mass_kg, plant.generator_mass_kg, plant.journal4_mass_kg,
              plant.exciter_mass_kg, plant.journal6_mass_kg]
    T = sum(0.5 * m * (V[:, 2 * i] ** 2 + V[:, 2 * i + 1] ** 2) for i, m in enumerate(masses))
    T += 0.5 * plant.journal3_mass_kg * (v3**2).sum(1)
    r = [pos[:, i] for i in range(6)]
    sq = lambda v: (v**2).sum(1)  # noqa: E731
    U = 0.5 * plant.generator_stiffness_n_m * (sq(r[1] - r[0]) + sq(r[1] - r[2]))
    U += 0.5 * plant.exciter_stiffness_n_m * (sq(r[4] - r[3]) + sq(r[4] - r[5]))
    U += 0.5 * plant.linear_bearing_stiffness_n_m * sum(sq(r[i]) for i in (0, 2, 3, 5))
    all_m = [plant.journal1_mass_kg, plant.generator_mass_kg, plant.journal3_mass_kg,
             plant.journal4_mass_kg, plant.exciter_mass_kg, plant.journal6_mass_kg]
    U += plant.gravity_m_s2 * sum(m * pos[:, i, 1] for i, m in enumerate(all_m))
    return T + U, T


def test_energy_conserved_with_linear_springs_and_no_damping():
    plant = Plant.default().replace(bearing_model="linear", linear_bearing_stiffness_n_m=1e10,
                                    generator_damping_n_s_m=0.0, exciter_damping_n_s_m=0.0, asymmetry=0.0)
    res = simulate(plant, 1950.0, 0.1, 0.0, mechanism="pin", transient_revs=0, record_revs=50,
                   samples_per_rev=8, rtol=1e-10, atol=1e-12, record_state=True)
    assert res.status == "ok"
    E, T = _total_energy(res, plant, W1950, 0.1)
    assert T.max() > 1.0  # something moves
    drift = np.abs(E - E[0]).max() / abs(E[0])
    assert drift < 1e-6, drift
    # and the check can fail: with damping the energy falls
    damped = simulate(plant.replace(generator_damping_n_s_m=7e4), 1950.0, 0.1, 0.0, transient_revs=0,
                      record_revs=5, samples_per_rev=8, rtol=1e-10, atol=1e-12, record_state=True)
    E2, _ = _total_energy(damped, plant, W1950, 0.1)
    assert E2[-1] < E2[0] - 1e-3 * abs(E2[0] - E2.min() + 1)


def test_convergence_under_tolerance_refinement():
    kw = dict(transient_revs=400, record_revs=16, samples_per_rev=64)
    a = simulate(Plant.default(), 1950.0, 0.1, 0.05, rtol=1e-6, **kw)
    b = simulate(Plant.default(), 1950.0, 0.1, 0.05, rtol=1e-8, atol=1e-10, **kw)
    a1, b1 = order_amplitudes(a)[..., 0], order_amplitudes(b)[..., 0]
    rel = np.abs(a1 - b1).max() / np.abs(b1).max()
    assert rel < 1e-4, rel


def test_static_eccentricities_match_model_md():
    plant = Plant.default()
    y = static_equilibrium(plant, 1950.0)
    ecc = [math.hypot(y[i], y[i + 1]) for i in (0, 4, 8)]  # bearings 1, 2/3 (aligned), 4
    np.testing.assert_allclose(ecc, [0.48, 0.49, 0.62], atol=0.01)


def test_modal_frequencies_match_model_md_and_stability_threshold():
    m = modal(Plant.default(), 1950.0)
    light = m.frequencies_hz[m.damping_ratios < 0.2]
    np.testing.assert_allclose(light[:4], [18.4, 20.7, 28.3, 33.2], atol=0.15)
    assert m.stable
    # linear stability lost at ≈ 2325 r/min with whirl ≈ 0.48X
    assert modal(Plant.default(), 2300.0).stable
    unstable = modal(Plant.default(), 2350.0)
    assert not unstable.stable
    f_whirl = unstable.frequencies_hz[np.argmin(unstable.damping_ratios)]
    assert f_whirl / (2350 / 60) == pytest.approx(0.48, abs=0.02)


def test_modal_frequencies_agree_with_fft_of_free_response():
    """The nonlinear model, released near its equilibrium, rings at the modal frequencies."""
    plant = Plant.default().replace(asymmetry=0.0)
    speed = 1950.0
    m = modal(plant, speed)
    y0 = static_equilibrium(plant, speed)
    rng = np.random.default_rng(3)
    y0[:10] += rng.normal(scale=2e-3, size=10)
    revs, spr = 96, 32
    res = simulate(plant, speed, 0.0, 0.0, transient_revs=0, record_revs=revs, samples_per_rev=spr,
                   initial_state=y0, rtol=1e-9, atol=1e-12)
    d = res.positions_m.reshape(len(res.time_s), 12)
    d = d - d.mean(0)
    n = len(d)
    nfft = 64 * n
    freqs = np.fft.rfftfreq(nfft, res.time_s[1] - res.time_s[0])
    spec = np.abs(np.fft.rfft(d * np.hanning(n)[:, None], nfft, axis=0))
    light = np.flatnonzero(m.damping_ratios < 0.1)
    assert len(light) == 4
    for i in light:
        f = m.frequencies_hz[i]
        others = np.delete(m.frequencies_hz, i)
        half = 0.5 * np.abs(others - f).min()
        dof = np.argmax(np.abs(m.mode_shapes[i]).ravel())  # where this mode shows most
        band = (freqs > f - half) & (freqs < f + half)
        f_peak = freqs[band][np.argmax(spec[band, dof])]
        assert f_peak == pytest.approx(f, abs=0.2), (f, f_peak)


@pytest.mark.parametrize("mechanism, delta", [("aligned", 0.0), ("rigid", 0.2)])
def test_isotropic_rotor_has_circular_synchronous_orbits(mechanism, delta):
    plant = Plant.default().replace(asymmetry=0.0, gravity_m_s2=0.0, bearing_model="linear",
                                    linear_bearing_stiffness_n_m=2e9, linear_bearing_damping_n_s_m=2e6,
                                    generator_damping_n_s_m=1e6, exciter_damping_n_s_m=2e5)
    res = simulate(plant, 1950.0, delta, 0.05, mechanism=mechanism, transient_revs=150, record_revs=4,
                   samples_per_rev=64, rtol=1e-10, atol=1e-12)
    d = res.journal_displacements_m
    radius = np.hypot(d[..., 0], d[..., 1])  # (n, 4)
    assert radius.mean() > 1e-7
    assert (radius.std(0) / radius.mean(0)).max() < 1e-5
    # and forward whirl at 1X: backward component of x + jy negligible
    z = d[..., 0] + 1j * d[..., 1]
    spec = np.fft.fft(z, axis=0)
    fwd, bwd = np.abs(spec[4]), np.abs(spec[-4])
    assert (bwd / fwd).max() < 1e-5


def test_asymmetry_and_gravity_make_2x_when_aligned():
    """MODEL.md: the two-pole generator shows 2X even when aligned (ρ × gravity sag)."""
    res = simulate(Plant.default(), 1950.0, 0.0, 0.05, transient_revs=300, record_revs=16, samples_per_rev=64)
    ratio = order_amplitudes(res)[1, 0, 1] / order_amplitudes(res)[1, 0, 0]
    assert 0.3 < ratio < 1.0
    sym = simulate(Plant.default().replace(asymmetry=0.0), 1950.0, 0.0, 0.05, transient_revs=300, record_revs=16,
                   samples_per_rev=64)
    amp = order_amplitudes(sym)
    assert amp[1, 0, 1] / amp[1, 0, 0] < 0.1 * ratio


def test_pin_approaches_aligned_as_misalignment_vanishes():
    kw = dict(transient_revs=400, record_revs=8, samples_per_rev=32)
    base = simulate(Plant.default(), 1950.0, 0.0, 0.05, **kw).journal_displacements_m
    diffs = []
    for delta in (1e-2, 1e-3):
        d = simulate(Plant.default(), 1950.0, delta, 0.05, mechanism="pin", **kw).journal_displacements_m
        diffs.append(np.abs(d - base).max() / Plant.default().clearance_m)
    assert diffs[0] < 0.05
    assert diffs[1] < 0.2 * diffs[0]  # first order in Δ


def test_rigid_with_zero_misalignment_equals_aligned():
    kw = dict(transient_revs=50, record_revs=4, samples_per_rev=32)
    a = simulate(Plant.default(), 1950.0, 0.0, 0.05, mechanism="aligned", **kw)
    r = simulate(Plant.default(), 1950.0, 0.0, 0.05, mechanism="rigid", **kw)
    np.testing.assert_array_equal(a.positions_m, r.positions_m)
    assert np.isnan(r.phi_rad).all()
    tiny = simulate(Plant.default(), 1950.0, 1e-9, 0.05, mechanism="rigid", **kw)
    assert np.abs(tiny.positions_m - a.positions_m).max() < 1e-6 * Plant.default().clearance_m


def test_rigid_offset_drives_exciter_journal_round_at_1x():
    """The rigid coupling carries the offset round: 1X across the coupling grows with Δ."""
    kw = dict(transient_revs=300, record_revs=16, samples_per_rev=64)
    a0 = order_amplitudes(simulate(Plant.default(), 1950.0, 0.0, 0.0, **kw))
    a2 = order_amplitudes(simulate(Plant.default(), 1950.0, 0.2, 0.0, mechanism="rigid", **kw))
    assert a2[2, :, 0].max() > 5 * a0[2, :, 0].max() + 1e-6


@pytest.mark.parametrize("speed, delta, mechanism", [(1950.0, 0.1, "pin"), (1500.0, 0.2, "rigid"), (1200.0, 0.0, "pin")])
def test_early_transient_end_gives_the_same_steady_state(speed, delta, mechanism):
    kw = dict(record_revs=16, samples_per_rev=64, mechanism=mechanism)
    full = simulate(Plant.default(), speed, delta, 0.05, **kw)
    early = simulate(Plant.default(), speed, delta, 0.05, settle_tol=1e-6, **kw)
    assert early.inputs["transient_revs_used"] < 400  # it did end early
    a, b = order_amplitudes(full), order_amplitudes(early)
    assert np.abs(a - b).max() / np.abs(a).max() < 1e-4
    # the same phase too: compare the Poincaré points (same τ mod 2π)
    assert np.abs(full.poincare_m - early.poincare_m).max() < 1e-4 * Plant.default().clearance_m


def test_early_transient_end_does_not_fire_on_whirl():
    res = simulate(Plant.default(), 2600.0, 0.1, 0.05, transient_revs=120, record_revs=2, settle_tol=1e-6)
    assert res.inputs["transient_revs_used"] == 120
