"""The shaft-train finite elements against closed forms and an independent beam solution."""
from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.linalg import eig

from rotordiag.simulator.train import (
    STEEL,
    Coupling,
    Disk,
    Material,
    Rotor,
    ShaftElement,
    Support,
    Train,
    TrainError,
    Unbalance,
    aligned_offsets,
    assemble,
    bearing_moved,
    misaligned,
    modes,
    static_state,
    unbalance_response,
    uniform_elements,
    with_moves,
)
from rotordiag.simulator.train.fe import cowper_shear_coefficient, section

from .train_support import KCBearing, iso, two_rotor_train


def _pinned_beam_frequencies_hz(L, D, n_el, speed_rad_s, n_modes=6, mat: Material = STEEL):
    """FE: a uniform shaft, x and y held at both ends (pinned), forward/backward whirl frequencies
    (at rest the two planes' equal frequencies, each once)."""
    r = Rotor("beam", uniform_elements(L, D, n_el), supports=(Support(0, iso(1.0)), Support(n_el, iso(1.0))),
              material=mat)
    asm = assemble(Train((r,), gravity_m_s2=0.0))
    keep = np.ones(asm.n_dof, dtype=bool)
    for node in (0, n_el):
        keep[4 * node: 4 * node + 2] = False
    M = asm.M[np.ix_(keep, keep)]
    K = asm.K[np.ix_(keep, keep)]
    G = asm.G[np.ix_(keep, keep)] * speed_rad_s
    n = M.shape[0]
    A = np.block([[np.zeros((n, n)), np.eye(n)], [-np.linalg.solve(M, K), -np.linalg.solve(M, G)]])
    lam, vec = eig(A)
    pos = lam.imag > 1e-6
    lam, vec = lam[pos], vec[:n, pos]
    f = np.sort(lam.imag / (2 * math.pi))
    if speed_rad_s == 0.0:
        return f[0::2][:n_modes], f[1::2][:n_modes]
    full = np.zeros((asm.n_dof, vec.shape[1]), dtype=complex)
    full[keep] = vec
    xs, ys = full[0::4], full[1::4]
    fwd = np.sum(np.abs(xs + 1j * ys) ** 2, axis=0) > np.sum(np.abs(xs - 1j * ys) ** 2, axis=0)
    f = lam.imag / (2 * math.pi)
    return np.sort(f[fwd])[:n_modes], np.sort(f[~fwd])[:n_modes]


def _closed_form_hz(L, D, n, speed_rad_s, mat: Material = STEEL):
    """Pinned-pinned rotating Timoshenko shaft, mode sin(nπz/L): roots ω of the 2×2 determinant of
    κGA(w'' − ψ') + ρAω²w = 0, EIψ'' + κGA(w' − ψ) + (ρIω² − ρJΩω)ψ = 0 (J = 2I). Positive roots are
    forward whirl, negative ones backward."""
    A, I = section(D, 0.0)
    E, G, rho = mat.young_pa, mat.shear_pa, mat.density_kg_m3
    kap = cowper_shear_coefficient(D, 0.0, mat.poisson)
    k = n * math.pi / L
    s = kap * G * A
    # (ρA ω² − s k²)(ρI ω² − 2ρI Ω ω − EI k² − s) − (s k)² = 0, a quartic in ω
    p1 = np.poly1d([rho * A, 0.0, -s * k**2])
    p2 = np.poly1d([rho * I, -2 * rho * I * speed_rad_s, -E * I * k**2 - s])
    roots = (p1 * p2 - (s * k) ** 2).r
    roots = roots[np.abs(roots.imag) < 1e-6 * np.abs(roots)].real
    # the lower branch (bending); the upper is the shear-thickness branch
    fwd = min(r for r in roots if r > 0)
    bwd = min(-r for r in roots if r < 0)
    return fwd / (2 * math.pi), bwd / (2 * math.pi)


@pytest.mark.parametrize("D", [0.1, 0.4])  # slender and stubby (shear and rotary inertia matter)
@pytest.mark.parametrize("speed_rpm", [0.0, 6000.0])
def test_pinned_rotating_timoshenko_shaft_matches_its_closed_form(D, speed_rpm):
    L, w = 1.5, speed_rpm * math.pi / 30
    fwd, bwd = _pinned_beam_frequencies_hz(L, D, 60, w, n_modes=3)
    for n in (1, 2, 3):
        f_ref, b_ref = _closed_form_hz(L, D, n, w)
        assert fwd[n - 1] == pytest.approx(f_ref, rel=6e-4)
        assert bwd[n - 1] == pytest.approx(b_ref, rel=6e-4)
    if speed_rpm and D == 0.4:  # gyroscopic split is visible on the stubby shaft
        assert fwd[0] > bwd[0] * 1.01


@pytest.mark.parametrize("D, order", [(0.4, 2), (0.004, 4)])
def test_mesh_convergence_of_the_third_mode(D, order):
    """Halving the element length divides the error by 2^order: 4 where shear is negligible (the cubic
    Hermite limit), 2 on a stubby shaft (the interdependent-interpolation Timoshenko element's mass)."""
    L = 1.5
    ref, _ = _closed_form_hz(L, D, 3, 0.0)
    errs = np.array([abs(_pinned_beam_frequencies_hz(L, D, n, 0.0, 3)[0][2] / ref - 1) for n in (4, 8, 16)])
    ratios = errs[:-1] / errs[1:]
    np.testing.assert_allclose(ratios, 2.0**order, rtol=0.15)


def _ss_reference_reactions(L, supports_z, settlements_m, w_n_m, EI, kGA):
    """Continuous Timoshenko beam (bending and shear flexibility) on rigid supports at ``supports_z`` (the first at 0, the last at L),
    uniform load ``w_n_m`` (down), supports displaced upward by ``settlements_m``: reactions (up) by the
    flexibility method with the simply supported beam between the end supports as primary structure."""
    inner = supports_z[1:-1]

    def defl_point(x, a):  # deflection (down) at x from a unit downward load at a, simply supported
        b = L - a
        if x > a:
            x, a, b = L - x, L - a, a
        return b * x * (L**2 - b**2 - x**2) / (6 * L * EI) + b * x / (L * kGA)

    def defl_udl(x):
        return w_n_m * x * (L**3 - 2 * L * x**2 + x**3) / (24 * EI) + w_n_m * x * (L - x) / (2 * kGA)

    # imposed upward position of each interior support relative to the chord of the end supports
    s = np.asarray(settlements_m, dtype=float)
    chord = s[0] + (s[-1] - s[0]) * np.asarray(inner) / L
    rel = s[1:-1] - chord
    F = np.array([[defl_point(xi, aj) for aj in inner] for xi in inner])
    d0 = np.array([defl_udl(x) for x in inner])
    # downward deflection at interior supports: d0 − F R = −rel  → R = F⁻¹(d0 + rel)
    R_in = np.linalg.solve(F, d0 + rel)
    W = w_n_m * L
    # end reactions by statics (sum of forces, moments about z = 0)
    m_in = np.sum(R_in * np.asarray(inner))
    R_end = (W * L / 2 - m_in) / L
    R_0 = W - np.sum(R_in) - R_end
    return np.concatenate([[R_0], R_in, [R_end]])


def test_static_bearing_loads_under_bearing_offsets_match_the_three_support_beam_solution():
    """Two uniform rotors rigidly coupled = one continuous beam on four supports; bearings moved up and
    down by 0.1–0.3 mm. Stiff linear bearings stand in for rigid supports."""
    mat = STEEL
    D, L1, L2 = 0.2, 4.0, 3.0
    stiff = iso(1e14)
    r1 = Rotor("a", uniform_elements(L1, D, 20), supports=(Support(0, stiff), Support(12, stiff)), material=mat)
    r2 = Rotor("b", uniform_elements(L2, D, 15), supports=(Support(5, stiff), Support(15, stiff)), material=mat)
    t = Train((r1, r2), (Coupling("rigid"),))
    moves = np.array([0.0, 2e-4, -1e-4, 3e-4])
    for k, dy in enumerate(moves):
        t = bearing_moved(t, 0 if k < 2 else 1, k % 2, dy_m=dy)
    st = static_state(t, 3000.0)
    A, I = section(D, 0.0)
    zs = np.array([0.0, 12 * L1 / 20, L1 + 5 * L2 / 15, L1 + L2])
    kGA = cowper_shear_coefficient(D, 0.0, mat.poisson) * mat.shear_pa * A
    ref = _ss_reference_reactions(L1 + L2, zs, moves, mat.density_kg_m3 * A * 9.81, mat.young_pa * I, kGA)
    got = -st.bearing_load_n[:, 1]  # reaction on the shaft, up
    np.testing.assert_allclose(got, ref, rtol=1e-3)
    assert np.ptp(ref) > 0.5 * np.abs(ref).max()  # the offsets shift the load substantially


def test_misalignment_moves_the_exciter_bearings_as_a_line():
    t = two_rotor_train()
    m = misaligned(t, offset_m=1e-4, angle_rad=2e-4, direction_rad=-math.pi / 2)
    z = t.support_z_m()
    zc = t.rotor_start_z_m()[1]
    for k, ((_, s0), (_, s1)) in enumerate(zip(t.supports(), m.supports(), strict=True)):
        expect = 0.0 if k < 2 else -(1e-4 + 2e-4 * (z[k] - zc))
        assert s1.centre_y_m - s0.centre_y_m == pytest.approx(expect, abs=1e-15)
        assert s1.centre_x_m == pytest.approx(s0.centre_x_m, abs=1e-15)


def test_aligned_reference_leaves_the_coupling_without_shear_or_moment():
    """Anisotropic, cross-coupled bearings: the journals move sideways too; the catenary moves then make
    the coupled train's state the uncoupled rotors' own."""
    bg = KCBearing(1.5e9, 2.5e9, kxy=6e8, kyx=-4e8, clearance_m=5e-4)
    be = KCBearing(4e8, 7e8, kxy=2e8, kyx=-1e8, clearance_m=3e-4)
    t = two_rotor_train(bg, be)
    straight = static_state(t, 3000.0)
    moves = aligned_offsets(t, 3000.0)
    aligned = static_state(with_moves(t, moves), 3000.0)
    shear0 = np.abs(straight.coupling_load[0][:2]).max()
    assert shear0 > 1e3
    assert np.abs(aligned.coupling_load[0][:2]).max() < 1e-6 * shear0
    assert np.abs(aligned.coupling_load[0][2:]).max() < 1e-6 * np.abs(straight.coupling_load[0][2:]).max()
    assert np.abs(moves[2:, 0]).max() > 1e-6  # a horizontal move too (the cross-coupled films)
    # each rotor then carries its own weight
    asm = assemble(t)
    w_exc = -(asm.gravity_n[4 * asm.rotor_nodes[1][1]:]).sum()  # not exact per rotor: check via total
    assert aligned.bearing_load_n[:, 1].sum() == pytest.approx(straight.bearing_load_n[:, 1].sum(), rel=1e-9)
    assert w_exc != 0


def test_isotropic_train_whirls_in_circles_and_reversed_rotation_mirrors_the_orbits():
    t = two_rotor_train(iso(2e9, 3e5), iso(5e8, 6e4), unbalance_kg_m=0.05)
    r = unbalance_response(t, [1500.0, 2900.0])
    X, Y = r[..., 0], r[..., 1]
    # circular forward orbits: y lags x by 90° with the same amplitude
    np.testing.assert_allclose(Y, -1j * X, atol=1e-9 * np.abs(X).max())
    # anisotropic bearings (no cross-coupling): elliptical orbits; the reversed rotation with the
    # unbalance mirrored (angle π − a) gives the orbits mirrored about the vertical plane
    t2 = two_rotor_train(KCBearing(1e9, 3e9, cxx=2e5, cyy=4e5), KCBearing(3e8, 8e8, cxx=5e4, cyy=7e4))
    gen = t2.rotors[0]
    a = 0.7
    tf = Train((gen.__class__(**{**gen.__dict__, "unbalances": (Unbalance(5, 0.05, a),)}), t2.rotors[1]),
               t2.couplings)
    tb = Train((gen.__class__(**{**gen.__dict__, "unbalances": (Unbalance(5, 0.05, math.pi - a),)}), t2.rotors[1]),
               t2.couplings)
    f = unbalance_response(tf, [2200.0])
    b = unbalance_response(tb, [-2200.0])
    assert np.abs(f[..., 0] + 1j * f[..., 1]).max() > 2 * np.abs(f[..., 0] - 1j * f[..., 1]).min()  # elliptical
    np.testing.assert_allclose(b[..., 0], -np.conj(f[..., 0]), atol=1e-9 * np.abs(f).max())
    np.testing.assert_allclose(b[..., 1], np.conj(f[..., 1]), atol=1e-9 * np.abs(f).max())


def test_campbell_forward_modes_stiffen_with_speed_on_a_disk_heavy_train():
    t = two_rotor_train()
    m0 = modes(t, 10.0, n_modes=8, about_static=False)
    m1 = modes(t, 4000.0, n_modes=8, about_static=False)
    f0, f1 = m0.frequency_hz, m1.frequency_hz
    assert np.all(np.isfinite(f1))
    assert f1[m1.forward].min() >= f0.min() - 1e-9


@pytest.mark.parametrize("make, needle", [
    (lambda t: Train((t.rotors[0].__class__(**{**t.rotors[0].__dict__, "supports": ()}), t.rotors[1]),
                     t.couplings), "no bearing"),
    (lambda t: Train((t.rotors[0].__class__(**{**t.rotors[0].__dict__,
                                               "unbalances": (Unbalance(99, 0.1),)}), t.rotors[1]),
                     t.couplings), "beyond the shaft"),
    (lambda t: Train(t.rotors, ()), "coupling"),
    (lambda t: Train((t.rotors[0].__class__(**{**t.rotors[0].__dict__,
                                               "elements": uniform_elements(1.0, 0.3, 2)[:1]
                                               + (t.rotors[0].elements[0].__class__(-0.5, 0.3),)}),
                      t.rotors[1]), t.couplings), "length_m"),
])
def test_bad_trains_say_what_to_fix(make, needle):
    with pytest.raises(TrainError, match=needle):
        make(two_rotor_train())


_B = iso(1e9)
_NAN = float("nan")


@pytest.mark.parametrize("make, field, value", [
    (lambda: Material(young_pa=-2e11), "Material young_pa", "-200000000000.0"),
    (lambda: Material(density_kg_m3="7810"), "Material density_kg_m3", "'7810'"),
    (lambda: ShaftElement(0.0, 0.3), "ShaftElement length_m", "0.0"),
    (lambda: ShaftElement(0.5, _NAN), "ShaftElement outer_diameter_m", "nan"),
    (lambda: ShaftElement(0.5, 0.3, -0.1), "ShaftElement inner_diameter_m", "-0.1"),
    (lambda: ShaftElement(0.5, 0.3, 0.3), "ShaftElement inner_diameter_m", "0.3"),
    (lambda: ShaftElement(0.5, 0.3, 0.0, 0.5), "ShaftElement asymmetry", "0.5"),
    (lambda: ShaftElement(0.5, 0.3, 0.0, True), "ShaftElement asymmetry", "True"),
    (lambda: Disk(2, -500.0), "Disk at station 2 mass_kg", "-500.0"),
    (lambda: Disk(2, 500.0, float("inf")), "Disk at station 2 polar_kg_m2", "inf"),
    (lambda: Disk(2, 500.0, 1.0, None), "Disk at station 2 transverse_kg_m2", "None"),
    (lambda: Disk(-1, 500.0), "Disk station", "-1"),
    (lambda: Disk(1.5, 500.0), "Disk station", "1.5"),
    (lambda: Support(True, _B), "Support station", "True"),
    (lambda: Support(1, _B, centre_x_m=_NAN, name="B1"), "Support 'B1' at station 1 centre_x_m", "nan"),
    (lambda: Support(1, _B, centre_y_m="0"), "Support at station 1 centre_y_m", "'0'"),
    (lambda: Support(1, object()), "Support at station 1 bearing clearance_m", "None"),
    (lambda: Support(1, _B, name=3), "Support name", "3"),
    (lambda: Unbalance(4, -0.1), "Unbalance at station 4 amount_kg_m", "-0.1"),
    (lambda: Unbalance(4, 0.1, _NAN), "Unbalance at station 4 angle_rad", "nan"),
    (lambda: Coupling("gear"), "Coupling kind", "'gear'"),
    (lambda: Coupling("rigid", lateral_damping_n_s_m=-1.0), "Coupling lateral_damping_n_s_m", "-1.0"),
    (lambda: Coupling("rigid", kinematic_phase_rad=_NAN), "Coupling kinematic_phase_rad", "nan"),
    (lambda: Coupling("flexible"), "Coupling (flexible) lateral_stiffness_n_m", "0.0"),
    (lambda: Rotor("r", uniform_elements(1.0, 0.3, 2), supports=(Support(0, _B),), stiff_axis_rad=_NAN),
     "rotor 'r' stiff_axis_rad", "nan"),
    (lambda: Rotor("r", ((1.0, 0.3),), supports=(Support(0, _B),)), "rotor 'r' elements", "(1.0, 0.3)"),
    (lambda: Rotor("r", uniform_elements(1.0, 0.3, 2), disks=[(1, 500.0)], supports=(Support(0, _B),)),
     "rotor 'r' disks", "(1, 500.0)"),
    (lambda: Rotor("r", uniform_elements(1.0, 0.3, 2), supports=(Support(0, _B),), material="steel"),
     "rotor 'r' material", "'steel'"),
    (lambda: Rotor(None, uniform_elements(1.0, 0.3, 2), supports=(Support(0, _B),)), "Rotor name", "None"),
    (lambda: Train((two_rotor_train().rotors[0],), gravity_m_s2=-9.81), "Train gravity_m_s2", "-9.81"),
    (lambda: Train((two_rotor_train().rotors[0],), internal_damping_s="1e-4"), "Train internal_damping_s", "'1e-4'"),
    (lambda: Train(two_rotor_train().rotors, ("rigid",)), "Train couplings", "'rigid'"),
    (lambda: uniform_elements(1.0, 0.3, 2.0), "a segment", "n=2.0"),
])
def test_every_part_of_a_train_refuses_a_bad_field_naming_the_part_the_field_and_the_value(make, field, value):
    """One way of validating: each part refuses a wrong value — out of range, not finite, not a number at all,
    a bool — when it is built, always a TrainError (a ValueError) whose message names the field and the value."""
    with pytest.raises(TrainError) as err:
        make()
    msg = str(err.value)
    assert msg.startswith(field) and value in msg, msg


def test_good_parts_build_and_keep_their_values():
    """The checks refuse nothing a valid train holds: numpy scalars and ints are numbers, a zero bore and
    asymmetry, a station at 0 and a negative angle are all fine."""
    d = Disk(np.int64(0), np.float64(500.0), 0, 0.0)
    u = Unbalance(3, 0.0, -math.pi)
    assert (d.station, d.mass_kg, u.angle_rad) == (0, 500.0, -math.pi)
    r = Rotor("r", uniform_elements(1.0, 0.3, 4, asymmetry=0.49), disks=(d,), supports=(Support(0, _B), Support(4, _B)),
              unbalances=(u,), stiff_axis_rad=-1.0)
    t = Train((r,))
    assert t.rotors[0] is r and t.gravity_m_s2 == 9.81


def test_a_journal_pushed_outside_its_clearance_is_refused_with_the_bearing_named():
    t = two_rotor_train(iso(2e9, clearance_m=3e-4), iso(5e8, clearance_m=2e-4))
    bad = misaligned(t, offset_m=5e-3)
    with pytest.raises(TrainError, match="clearance.*B3"):
        static_state(bad, 3000.0)


def test_internal_damping_destabilises_the_forward_mode_above_its_critical_speed():
    """Rotating (internal) damping alone on stiff undamped supports: the forward whirl is stable below the
    first forward critical speed and unstable above it (Kimball–Newkirk; e.g. Friswell et al. §3.6)."""
    from dataclasses import replace

    from rotordiag.simulator.train import critical_speeds

    r = Rotor("s", uniform_elements(2.0, 0.1, 16), disks=(Disk(8, 50.0, 0.3, 0.15),),
              supports=(Support(0, iso(1e12)), Support(16, iso(1e12))))
    t = Train((r,), gravity_m_s2=0.0, internal_damping_s=2e-4)
    wc = critical_speeds(replace(t, internal_damping_s=0.0), 1, 20000.0, n_grid=60)[0]

    def first_forward_logdec(speed_rpm):
        m = modes(t, speed_rpm, about_static=False)
        # the forward bending mode near the critical (heavily overdamped high modes have tiny frequencies)
        k = np.argmin(np.where(m.forward, np.abs(m.frequency_hz - wc / 60), np.inf))
        return m.log_decrement[k]

    assert first_forward_logdec(0.97 * wc) > 0
    assert first_forward_logdec(1.03 * wc) < 0
