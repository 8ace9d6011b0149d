"""Time response of the reduced train: against the full model's frequency response, energy conservation,
the two-pole asymmetry's gravity 2X against quasi-static solutions, the reduction's error."""
from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from rotordiag.simulator.train import (
    Material,
    Rotor,
    Support,
    Train,
    assemble,
    critical_speeds,
    reduced_critical_speeds,
    unbalance_response,
    uniform_elements,
)
from rotordiag.simulator.train.dynamics import build_kernel, simulate_train
from rotordiag.simulator.train.linear import linear_matrices
from rotordiag.simulator.train.reduced import reduce

from .bench_util import bench_machine, ross_reference
from .train_support import iso, two_rotor_train


def _line(sig: np.ndarray, revs: int, order: int) -> np.ndarray:
    """Complex amplitude X of order ``order`` along axis 0 (x(t) = Re(X e^{i·order·Ωt}))."""
    return 2 * np.fft.fft(sig, axis=0)[order * revs] / sig.shape[0]


def test_time_response_of_the_reduced_train_matches_the_full_models_unbalance_response():
    asm = assemble(ross_reference().reference_train(True))
    run = simulate_train(asm, 3000.0, transient_revs=60, record_revs=16, samples_per_rev=64, n_modes=16)
    assert run.ok
    X = _line(run.journal_m, 16, 1)
    R = unbalance_response(asm, [3000.0])[0, asm.support_nodes, :]
    np.testing.assert_allclose(np.abs(X), np.abs(R), rtol=2e-3)
    assert np.abs(np.angle(X / R)).max() < 2e-3


def test_reduction_keeps_the_first_six_critical_speeds_within_a_tenth_of_a_percent():
    asm = assemble(ross_reference().reference_train(False))
    red = reduce(asm, 16)
    full = critical_speeds(asm, 6, 9000.0, n_grid=90)
    np.testing.assert_allclose(reduced_critical_speeds(red, 6, 9000.0, n_grid=90), full, rtol=1e-3)


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
    kern = build_kernel(bench_machine(), 3000.0, 12)
    a = simulate_train(kern, 3000.0, transient_revs=24, record_revs=8, samples_per_rev=32)
    b = simulate_train(kern, 3000.0, transient_revs=24, record_revs=8, samples_per_rev=32, method="dopri")
    assert a.ok and b.ok and a.inputs["method"] == "etd" and b.n_accepted > 20 * a.n_accepted / 32
    scale = np.abs(b.journal_m).max()
    np.testing.assert_allclose(a.journal_m.mean(0), b.journal_m.mean(0), atol=1e-4 * scale)
    for order in (1, 2):
        np.testing.assert_allclose(_line(a.journal_m, 8, order), _line(b.journal_m, 8, order),
                                   atol=2e-3 * np.abs(_line(b.journal_m, 8, 1)).max())
    assert np.abs(_line(b.journal_m, 8, 2)).max() > 0.002 * np.abs(_line(b.journal_m, 8, 1)).max()


def test_flexible_couplings_kinematic_2x_matches_the_frequency_response_to_its_forcing():
    """A flexible coupling under parallel offset δ: the double-engagement 2X force ±(k u + c u̇),
    u = (δ/2)(cos(2Ωt + ψ + γ), sin(2Ωt + ψ + γ)), on the two hubs; the journals' 2X from the time response
    against the full model's harmonic response to that forcing at 2Ω (no asymmetry, no unbalance)."""
    from rotordiag.simulator.train import Coupling

    delta, psi, gam, kc, cc = 2e-4, 0.3, -math.pi / 2, 5e7, 2e3
    cpl = Coupling("flexible", lateral_stiffness_n_m=kc, angular_stiffness_n_m_rad=1e6, lateral_damping_n_s_m=cc,
                   kinematic_offset_m=delta, kinematic_phase_rad=psi, kinematic_direction_rad=gam)
    t = replace(two_rotor_train(iso(2e9, 3e5), iso(5e8, 8e4), coupling=cpl), gravity_m_s2=0.0)
    speed = 1800.0
    run = simulate_train(t, speed, transient_revs=300, record_revs=8, samples_per_rev=32, n_modes=12)
    assert run.ok
    X2 = _line(run.journal_m, 8, 2)
    asm = assemble(t)
    w = speed * math.pi / 30
    M, C, K = linear_matrices(asm, w)
    a, b = asm.coupling_nodes[0]
    # u = Re(U e^{2iΩt}) with U = (δ/2) e^{i(ψ+γ)} (1, −i); force on b: +(k + 2iΩ c) U, on a: the opposite
    U = 0.5 * delta * np.exp(1j * (psi + gam)) * np.array([1.0, -1j])
    F = np.zeros(asm.n_dof, dtype=complex)
    F[4 * b: 4 * b + 2] += (kc + 2j * w * cc) * U
    F[4 * a: 4 * a + 2] -= (kc + 2j * w * cc) * U
    Q = np.linalg.solve(K - (2 * w) ** 2 * M + 2j * w * C, F)
    R = np.stack([Q[4 * asm.support_nodes], Q[4 * asm.support_nodes + 1]], axis=1)
    np.testing.assert_allclose(np.abs(X2), np.abs(R), rtol=0.01, atol=1e-3 * np.abs(R).max())
    big = np.abs(R) > 0.1 * np.abs(R).max()
    assert np.abs(np.angle(X2[big] / R[big])).max() < 0.01
    assert np.abs(_line(run.journal_m, 8, 1)).max() < 1e-3 * np.abs(R).max()  # nothing at 1X


def test_three_bearing_train_with_the_exciter_overhung_on_one_bearing():
    """Exciter on a single outboard bearing, rigidly coupled: the static state carries the exciter on the
    generator's coupling-end bearing; the loads sum to the weight and the aligned reference is refused with
    a message that says why."""
    from rotordiag.simulator.train import TrainError, aligned_offsets, static_state

    t = two_rotor_train(iso(2e9, 2e5), iso(5e8, 5e4))
    exc = t.rotors[1]
    exc1 = replace(exc, supports=exc.supports[1:])
    t3 = Train((t.rotors[0], exc1), t.couplings)
    st = static_state(t3, 3000.0)
    asm = assemble(t3)
    weight = -asm.gravity_n[1::4].sum()
    assert -st.bearing_load_n[:, 1].sum() == pytest.approx(weight, rel=1e-9)
    assert len(st.bearing_load_n) == 3
    # the coupling hands the generator what the exciter's own bearing does not carry of its weight
    from rotordiag.simulator.train.fe import section

    w_exc = 9.81 * (sum(exc.material.density_kg_m3 * section(e.outer_diameter_m, e.inner_diameter_m)[0] * e.length_m
                        for e in exc.elements) + sum(d.mass_kg for d in exc.disks))
    r_b4 = -st.bearing_load_n[2, 1]
    assert st.coupling_load[0][1] == pytest.approx(-(w_exc - r_b4), rel=1e-6)
    assert w_exc - r_b4 > 0.2 * w_exc
    with pytest.raises(TrainError, match="one bearing"):
        aligned_offsets(t3, 3000.0)
    with pytest.raises(TrainError, match="one bearing and no coupling"):
        Train((t.rotors[0], exc1), (replace(t.couplings[0], kind="flexible", lateral_stiffness_n_m=1e7),))


@pytest.mark.parametrize("kind", ["elliptical", "tilting_pad"])
def test_trains_on_two_lobe_and_tilting_pad_films_settle_and_run(kind):
    """The static Newton solution and the time response with the other film types: loads carry the weight,
    the run stays period-1 near its static state at a moderate speed."""
    from rotordiag.simulator.bearings import EllipticalBearing, TiltingPadBearing
    from rotordiag.simulator.train import static_state

    t = bench_machine()
    cls = EllipticalBearing if kind == "elliptical" else TiltingPadBearing
    bg = cls(diameter_m=0.25, length_m=0.2, clearance_m=190e-6, viscosity_pa_s=0.02)
    be = cls(diameter_m=0.15, length_m=0.1, clearance_m=120e-6, viscosity_pa_s=0.02)
    t = replace(t, rotors=tuple(replace(r, supports=tuple(replace(s, bearing=b) for s in r.supports))
                                for r, b in zip(t.rotors, (bg, be), strict=True)))
    st = static_state(t, 3000.0)
    asm = assemble(t)
    assert -st.bearing_load_n[:, 1].sum() == pytest.approx(-asm.gravity_n[1::4].sum(), rel=1e-8)
    run = simulate_train(t, 3000.0, transient_revs=40, record_revs=4, samples_per_rev=32)
    assert run.ok
    np.testing.assert_allclose(run.journal_m.mean(0), st.journal_m, atol=0.05 * 120e-6)


def test_aligned_reference_on_oil_films_and_the_load_transfer_of_a_downward_offset():
    """Plain bearings: the catenary moves (here half a millimetre at the exciter's far bearing) leave the
    coupling without shear or moment; an exciter line moved down from there unloads the exciter's
    coupling-end bearing and loads the generator's (the field's and the paper model's direction)."""
    from rotordiag.simulator.train import aligned_offsets, misaligned, static_state, with_moves

    t = bench_machine()
    moves = aligned_offsets(t, 3000.0)
    assert np.abs(moves).max() > 4 * 120e-6  # far beyond the clearance: the continuation must carry it
    al = static_state(with_moves(t, moves), 3000.0)
    straight = static_state(t, 3000.0)
    assert np.abs(al.coupling_load[0]).max() < 1e-6 * np.abs(straight.coupling_load[0]).max()
    down = static_state(misaligned(with_moves(t, moves), offset_m=50e-6), 3000.0)
    load = -down.bearing_load_n[:, 1]
    load0 = -al.bearing_load_n[:, 1]
    assert load[2] < load0[2] - 2e3 and load[1] > load0[1] + 2e3
