"""The lumped limit (issue 42, item 4): the finite-element train reduced to the paper's point masses against
the 11-DOF model (``rotordiag.simulator.simulate``, MODEL.md sections 1–3).

The limit train (:func:`lumped_train`): one massless Timoshenko beam of two elements per rotor, the journals
and the disks point masses (``Disk`` with no inertia), each beam's mid-span stiffness on pinned ends
48EI/L³ (with its shear term) = 2k̄ (generator, with the paper's ρ on both elements) or 2k2 (exciter), the
disks' dampers c1, c2 as zero-stiffness linear "bearings" to ground, the Capone short bearings of the plant
at the journals, the coupling at the coupling-end bearings (no overhang) as a flexible coupling of lateral
stiffness ``K_TIE`` and no angular stiffness (the tie r3 = r4 with no moment: MODEL.md 3c), and
misalignment 3e as the exciter's bearings moved by δ.

What the beam cannot be (docs/train.md, "The lumped limit"). The paper's two half-span springs store
½k̄|r2 − r1|² + ½k̄|r2 − r3|² = k̄|r2 − m|² + ¼k̄|r3 − r1|² (m the journals' mean): the bending of a beam with
mid-span stiffness 2k̄, **plus** a chord spring k̄/2 on r3 − r1 that resists a rigid tilt of the rotor (the
exciter's k2/2 on r6 − r4). A beam tilts freely, so the train reproduces the 11-DOF model exactly only with
that chord spring added to its matrices (:func:`with_chord_springs`); without it the difference is the chord
spring's: exact at the outboard bearings, where the beam's loads are statically determinate, and, for the
1X, the chord springs' linear effect within a tolerance derived from what linear theory leaves out.
"""
from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
import pytest
from scipy import optimize

from rotordiag.simulator import Plant, RotorSystem, simulate
from rotordiag.simulator.bearings import LinearBearing, PlainBearing
from rotordiag.simulator.modal import modal
from rotordiag.simulator.train import (
    Assembly,
    Coupling,
    Disk,
    Material,
    Rotor,
    ShaftElement,
    Support,
    Train,
    Unbalance,
    assemble,
    misaligned,
    modes,
    static_state,
    unbalance_response,
)
from rotordiag.simulator.train.dynamics import simulate_train
from rotordiag.simulator.train.fe import cowper_shear_coefficient, section

#: lateral stiffness of the coupling that stands for the tie r3 = r4, N/m: the coupling's static force (the
#: exciter's share of its weight that bearing 3 does not carry, plus an offset's preload: ≤ 21 kN in these
#: cases) separates the two journals by ≤ 2 nm = 6·10⁻⁶ c
K_TIE = 1e13
#: the beams' density, kg/m³: a 6 m beam weighs 5·10⁻⁶ kg against 500–32 000 kg point masses
DENSITY = 1e-6
POISSON = 0.3
#: the train's bearing indices of the paper's bearings 1..4 (indices 1 and 4 are the disks' dampers c1, c2)
PAPER_BEARINGS = [0, 2, 3, 5]
#: static journal positions: the train with its chord springs against the paper model, in clearances: three
#: times what the coupling's compliance (above) allows; the massless beams (10⁻⁹ of the masses) and both
#: Newton solutions (≤ 10⁻⁹ c) add nothing visible
STATIC_TOL_C = 2e-5
#: 1X/2X at the probes, relative to each line's amplitude: the ETD (64 samples per revolution) agrees with
#: adaptive Dormand–Prince to 2·10⁻³ of 1X on plain films (docs/train.md); the paper runs at rtol 10⁻⁶
LINE_RTOL = 2e-3
SPEED_RPM = 1950.0


class Offset(NamedTuple):
    """A stationary shaft-line offset of the exciter (MODEL.md 3e, docs/model.md): parallel Δ = δ/c and
    angular α (mrad, bearing 4 moved by α·L more) along ``direction_rad`` (from +x toward +y)."""

    delta: float
    tilt_mrad: float
    direction_rad: float


ALIGNED = Offset(0.0, 0.0, 0.0)
#: none; Δ = 0.3 down; Δ = 0.3 sideways (+x); α = 0.09 mrad down (bearing 4 0.31 mm = 0.87 c lower)
OFFSETS = [ALIGNED, Offset(0.3, 0.0, -math.pi / 2), Offset(0.3, 0.0, 0.0), Offset(0.0, 0.09, -math.pi / 2)]
OFFSET_IDS = ["aligned", "down", "sideways", "tilted down"]


def _beam_material(mid_span_stiffness_n_m: float, length_m: float, diameter_m: float) -> Material:
    """The material that gives a pinned–pinned beam of this length and diameter the mid-span stiffness
    asked for, shear included: 1/k = L³/(48EI) + L/(4κGA), G = E/(2(1 + ν)); nearly massless."""
    area, inertia = section(diameter_m, 0.0)
    kappa = cowper_shear_coefficient(diameter_m, 0.0, POISSON)
    young = mid_span_stiffness_n_m * (length_m**3 / (48 * inertia)
                                      + 2 * (1 + POISSON) * length_m / (4 * kappa * area))
    return Material(young_pa=young, shear_pa=young / (2 * (1 + POISSON)), density_kg_m3=DENSITY)


def _damper(damping_n_s_m: float) -> LinearBearing:
    """A viscous damper to ground (the paper's c1, c2 on the disks): a linear bearing with no stiffness."""
    return LinearBearing(diameter_m=1.0, length_m=0.5, clearance_m=0.04, stiffness_n_m=[[0.0, 0.0], [0.0, 0.0]],
                         damping_n_s_m=[[damping_n_s_m, 0.0], [0.0, damping_n_s_m]])


def lumped_train(plant: Plant, unbalance: float = 0.0, *, overhang_m: float = 0.0, asymmetry: float | None = None,
                 generator_span_m: float = 6.0, exciter_span_m: float = 3.4) -> Train:
    """The paper's plant as a train of point masses on massless beams (module docstring). ``unbalance`` is
    the paper's A = a/c; ``overhang_m`` puts the coupling that far beyond the coupling-end bearings (the
    limit broken); ``asymmetry`` overrides the generator's ρ (default the plant's)."""
    p = plant
    brg = [PlainBearing(diameter_m=2 * p.bearing_radius_m[i], length_m=p.bearing_length_m[i],
                        clearance_m=p.clearance_m, viscosity_pa_s=p.viscosity_pa_s) for i in range(4)]
    rho = p.asymmetry if asymmetry is None else asymmetry
    gen_el = (ShaftElement(generator_span_m / 2, 1.0, asymmetry=rho),) * 2
    exc_el = (ShaftElement(exciter_span_m / 2, 0.4),) * 2
    e0 = 0
    if overhang_m:
        gen_el += (ShaftElement(overhang_m, 1.0),)
        exc_el = (ShaftElement(overhang_m, 0.4),) + exc_el
        e0 = 1
    unb = (Unbalance(1, p.generator_mass_kg * unbalance * p.clearance_m, 0.0),) if unbalance else ()
    gen = Rotor("generator", gen_el,
                disks=(Disk(0, p.journal1_mass_kg), Disk(1, p.generator_mass_kg), Disk(2, p.journal3_mass_kg)),
                supports=(Support(0, brg[0], name="B1"), Support(1, _damper(p.generator_damping_n_s_m), name="c1"),
                          Support(2, brg[1], name="B2")),
                unbalances=unb, material=_beam_material(2 * p.generator_stiffness_n_m, generator_span_m, 1.0),
                stiff_axis_rad=p.stiff_axis_angle_rad)
    exc = Rotor("exciter", exc_el,
                disks=(Disk(e0, p.journal4_mass_kg), Disk(e0 + 1, p.exciter_mass_kg),
                       Disk(e0 + 2, p.journal6_mass_kg)),
                supports=(Support(e0, brg[2], name="B3"), Support(e0 + 1, _damper(p.exciter_damping_n_s_m), name="c2"),
                          Support(e0 + 2, brg[3], name="B4")),
                material=_beam_material(2 * p.exciter_stiffness_n_m, exciter_span_m, 0.4))
    return Train((gen, exc), (Coupling("flexible", lateral_stiffness_n_m=K_TIE),), gravity_m_s2=p.gravity_m_s2)


def with_chord_springs(asm: Assembly, plant: Plant) -> Assembly:
    """The assembly with the paper's chord springs added: (k̄/2)(I + ρR(t)) on r3 − r1 (R(t) the two-pole
    rotation, MODEL.md's K1(t)/k̄) and (k2/2) on r6 − r4 — what the half-span springs store beyond a beam's
    bending (module docstring)."""
    j1, j3, j4, j6 = asm.support_nodes[PAPER_BEARINGS]
    chord = np.array([[1.0, -1.0], [-1.0, 1.0]])
    rho = plant.asymmetry
    c2, s2 = math.cos(2 * plant.stiff_axis_angle_rad), math.sin(2 * plant.stiff_axis_angle_rad)
    parts = [((j1, j3), plant.generator_stiffness_n_m, rho), ((j4, j6), plant.exciter_stiffness_n_m, 0.0)]
    for (a, b), k, r in parts:
        idx = np.array([4 * a, 4 * a + 1, 4 * b, 4 * b + 1])
        ix = np.ix_(idx, idx)
        asm.K[ix] += 0.5 * k * np.kron(chord, np.eye(2))
        # K(t) = K + cos 2Ωt·K_cos + sin 2Ωt·K_sin with the stiff axis θ0 inside (fe.py's convention)
        asm.K_cos[ix] += 0.5 * k * r * np.kron(chord, np.array([[c2, s2], [s2, -c2]]))
        asm.K_sin[ix] += 0.5 * k * r * np.kron(chord, np.array([[-s2, c2], [c2, s2]]))
    return asm


# ---------------------------------------------------------------- the paper model's side
def _mechanism(offset: Offset) -> str:
    return "aligned" if offset == ALIGNED else "offset"


def _paper_system(plant: Plant, speed_rpm: float, offset: Offset = ALIGNED) -> RotorSystem:
    return RotorSystem(plant, speed_rpm, offset.delta, 0.0, mechanism=_mechanism(offset),
                       offset_angle_rad=offset.direction_rad, angular_misalignment_mrad=offset.tilt_mrad)


def _paper_static(plant: Plant, speed_rpm: float, offset: Offset) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The paper model's static state with its asymmetry at the mean (as the train's): node positions
    (6, 2) m, the bearing forces on the journals (4, 2) N and the bearing centres (4, 2) m, by a root of its
    accelerations, the offset raised from 0 in five steps (each starting from the last)."""
    mean = plant.replace(asymmetry=0.0)
    q = _paper_system(mean, speed_rpm).initial_state()[:10]
    for f in np.linspace(0.0, 1.0, 1 if offset == ALIGNED else 6):
        step = Offset(f * offset.delta, f * offset.tilt_mrad, offset.direction_rad)
        system = _paper_system(mean, speed_rpm, step if f else ALIGNED)
        y = system.initial_state()

        def acc(x: np.ndarray, y: np.ndarray = y, system: RotorSystem = system) -> np.ndarray:
            y[:10] = x
            return system.rhs(0.0, y)[11:21]

        q = optimize.root(acc, q, method="hybr", options={"xtol": 1e-14}).x
        assert np.abs(acc(q)).max() < 1e-12  # accelerations in clearances per rad²: ~10⁻⁶ N on the journals
    return (system.node_positions(np.zeros(1), y)[0], system.bearing_forces_n(np.zeros(1), y)[0],
            system.bearing_centres_m)


def _paper_stiffness(plant: Plant, tau: float) -> np.ndarray:
    """∂(force)/∂(position) of the paper model's aligned equations at shaft angle τ (10×10, N/m; rows and
    columns x1 y1 x2 y2 x4 y4 x5 y5 x6 y6, node 3 = node 4), from its compiled right-hand side (linear in the
    positions with linear bearings, so one unit difference is exact)."""
    system = _paper_system(plant, 1950.0)
    w = system.speed_rad_s
    p = plant
    mass = np.repeat([p.journal1_mass_kg, p.generator_mass_kg, p.journal3_mass_kg + p.journal4_mass_kg,
                      p.exciter_mass_kg, p.journal6_mass_kg], 2)
    y0 = np.zeros(22)
    f0 = system.rhs(tau, y0)[11:21]
    J = np.empty((10, 10))
    for j in range(10):
        y = y0.copy()
        y[j] = 1.0
        J[:, j] = system.rhs(tau, y)[11:21] - f0
    return -(mass * w**2)[:, None] * J  # the stiffness K: force = −K q


def _translations(asm: Assembly, K: np.ndarray) -> np.ndarray:
    """K condensed onto the nodes' x, y (the rotations are massless: their static condensation)."""
    t = np.array([4 * n + a for n in range(asm.n_nodes) for a in (0, 1)])
    r = np.setdiff1d(np.arange(asm.n_dof), t)
    return K[np.ix_(t, t)] - K[np.ix_(t, r)] @ np.linalg.solve(K[np.ix_(r, r)], K[np.ix_(r, t)])


def _tie() -> np.ndarray:
    """(12 × 10) the train's six nodes' x, y from the paper's five (node 3 = node 4)."""
    T = np.zeros((12, 10))
    for train_node, paper_pair in enumerate([0, 1, 2, 2, 3, 4]):
        T[2 * train_node: 2 * train_node + 2, 2 * paper_pair: 2 * paper_pair + 2] = np.eye(2)
    return T


def _lines(d: np.ndarray, revs: int) -> np.ndarray:
    """Complex amplitudes (3, …) of the mean, 1X and 2X along axis 0 (x(t) = Re Σ X_k e^{ikΩt})."""
    F = np.fft.fft(d, axis=0) / d.shape[0]
    return np.stack([F[0], 2 * F[revs], 2 * F[2 * revs]])


# ---------------------------------------------------------------- the linear limit
def test_the_lumped_train_is_the_paper_models_stiffness_less_its_chord_springs():
    """Linear bearings, ρ = 0.0549, four shaft angles: the train condensed onto its translations and tied at
    the coupling equals the paper model's stiffness less the chord springs k̄/2 (with ρ) and k2/2, exactly;
    its mass is the paper's point masses."""
    kb = 1.0e9
    plant = Plant.default().replace(bearing_model="linear", linear_bearing_stiffness_n_m=kb)
    asm = assemble(lumped_train(plant))
    chorded = with_chord_springs(assemble(lumped_train(plant)), plant)
    T = _tie()
    journals = [0, 1, 4, 5, 4, 5, 8, 9]  # bearings 2 and 3 both hold node 3 = 4
    for tau in (0.0, 0.3, 1.1, 2.0):
        K_paper = _paper_stiffness(plant, tau)
        np.subtract.at(K_paper, (journals, journals), kb)  # the bearings are not the shaft's
        K_beam = T.T @ _translations(asm, asm.stiffness_at(tau)) @ T
        K_chord = T.T @ _translations(chorded, chorded.stiffness_at(tau)) @ T
        scale = plant.generator_stiffness_n_m
        np.testing.assert_allclose(K_chord, K_paper, atol=1e-9 * scale)
        # the beam alone misses exactly a chord spring on x1–x3 of k̄(1 + ρ cos 2τ)/2
        assert K_beam[0, 4] - K_paper[0, 4] == pytest.approx(
            0.5 * scale * (1 + plant.asymmetry * math.cos(2 * tau)), rel=1e-9)
    M = T.T @ _translations(asm, asm.M) @ T
    p = plant
    masses = np.repeat([p.journal1_mass_kg, p.generator_mass_kg, p.journal3_mass_kg + p.journal4_mass_kg,
                        p.exciter_mass_kg, p.journal6_mass_kg], 2)
    np.testing.assert_allclose(M, np.diag(masses), atol=1e-6)


def test_linearised_modes_of_the_lumped_train_are_the_paper_models():
    """Capone films linearised about the static state at 1950 r/min (MODEL.md 7: asymmetry at its mean): with
    the chord springs the train's damped modes are the paper model's (``simulator.modal``); the beam alone
    moves the exciter's horizontal bending mode from 28.3 to 26.9 Hz."""
    plant = Plant.default()
    paper = modal(plant, SPEED_RPM)
    n = len(paper.frequencies_hz)
    chorded = modes(with_chord_springs(assemble(lumped_train(plant)), plant), SPEED_RPM)
    np.testing.assert_allclose(chorded.frequency_hz[:n], paper.frequencies_hz, rtol=1e-5)
    np.testing.assert_allclose(chorded.damping_ratio[:n], paper.damping_ratios, rtol=1e-4)
    beam = modes(assemble(lumped_train(plant)), SPEED_RPM)
    assert np.abs(beam.frequency_hz[:n] / paper.frequencies_hz - 1).max() > 0.04


# ---------------------------------------------------------------- static state
@pytest.mark.parametrize("offset", OFFSETS, ids=OFFSET_IDS)
def test_static_journals_of_the_lumped_train_with_chord_springs_are_the_paper_models(offset):
    """Static journal positions at the four bearings, aligned and with the exciter offset (MODEL.md 3e:
    Δ = 0.3 down and sideways; tilted down by 0.09 mrad), 1950 r/min: within ``STATIC_TOL_C`` of the paper
    model's."""
    plant = Plant.default()
    c = plant.clearance_m
    st = static_state(with_chord_springs(assemble(_misaligned(lumped_train(plant), plant, offset)), plant),
                      SPEED_RPM)
    nodes, _, centres = _paper_static(plant, SPEED_RPM, offset)
    paper_journals = nodes[[0, 2, 3, 5]] - centres
    np.testing.assert_allclose(st.journal_m[PAPER_BEARINGS] / c, paper_journals / c, atol=STATIC_TOL_C)


@pytest.mark.parametrize("offset", OFFSETS, ids=OFFSET_IDS)
def test_the_static_difference_at_the_outboard_bearings_is_the_chord_spring(offset):
    """Without chord springs each rotor is a pinned beam, statically determinate: bearings 1 and 4 carry
    m1 g + M1 g/2 and m6 g + M2 g/2 whatever the offset, so their journals sit at the film's own equilibrium
    under that load (``PlainBearing.equilibrium``, no train code). The paper model's bearings carry that load
    less the chord spring's force, (k̄/2)(r3 − r1) and (k2/2)(r4 − r6): the whole of the difference between the
    two models there. The down offset Δ = 0.3 puts 4.8 kN (a quarter of its load) of chord force on bearing 4,
    the tilt 10.3 kN (over half): in the paper model an angular offset is the chord spring's."""
    plant = Plant.default()
    p = plant
    c, g = p.clearance_m, p.gravity_m_s2
    w = SPEED_RPM * math.pi / 30
    st = static_state(_misaligned(lumped_train(plant), plant, offset), SPEED_RPM)
    weight = {0: (p.journal1_mass_kg + p.generator_mass_kg / 2) * g, 3: (p.journal6_mass_kg + p.exciter_mass_kg / 2) * g}
    brgs = [b for i, b in enumerate(st.assembly.bearings) if i in PAPER_BEARINGS]
    for paper_b, train_b in ((0, 0), (3, 5)):
        load = np.array([0.0, -weight[paper_b]])
        np.testing.assert_allclose(st.bearing_load_n[train_b], load, atol=1e-6 * weight[paper_b])
        film = np.array(brgs[paper_b].equilibrium(load[0], load[1], w))
        np.testing.assert_allclose(st.journal_m[train_b] / c, film / c, atol=1e-9)
    nodes, forces, _ = _paper_static(plant, SPEED_RPM, offset)
    chord_1 = 0.5 * p.generator_stiffness_n_m * (nodes[2] - nodes[0])
    chord_4 = 0.5 * p.exciter_stiffness_n_m * (nodes[3] - nodes[5])
    # the force of bearing b on its journal balances the journal's weight share and the chord spring
    np.testing.assert_allclose(-forces[0], [0.0, -weight[0]] + chord_1, atol=1e-6 * weight[0])
    np.testing.assert_allclose(-forces[3], [0.0, -weight[3]] + chord_4, atol=1e-6 * weight[3])
    if offset.direction_rad < 0:  # the exciter tilts down to its moved far bearing: the chord spring lifts
        assert chord_4[1] > 0.2 * weight[3]  # a quarter (Δ = 0.3) or half (α = 0.09 mrad) of bearing 4's load


def test_a_tilt_about_the_coupling_changes_nothing_in_the_beam_limit():
    """The exciter pinned to the generator at bearing 3 (no moment across the tie) and tilted about it by
    moving bearing 4 (α = 0.09 mrad down): a pinned beam turns rigidly about the pin, so every journal keeps its
    place in its bearing and every load its value. In the paper model the same tilt takes bearing 4 from 17.7
    to 9.3 kN: all of it the chord spring's."""
    plant = Plant.default()
    tilt = OFFSETS[3]
    aligned = static_state(lumped_train(plant), SPEED_RPM)
    tilted = static_state(_misaligned(lumped_train(plant), plant, tilt), SPEED_RPM)
    np.testing.assert_allclose(tilted.journal_m / plant.clearance_m, aligned.journal_m / plant.clearance_m, atol=1e-9)
    np.testing.assert_allclose(tilted.bearing_load_n, aligned.bearing_load_n, atol=1e-3)
    _, f_aligned, _ = _paper_static(plant, SPEED_RPM, ALIGNED)
    _, f_tilted, _ = _paper_static(plant, SPEED_RPM, tilt)
    assert f_tilted[3, 1] < 0.6 * f_aligned[3, 1]


# ---------------------------------------------------------------- steady state: 1X and 2X at the probes
def _compare_steady(train: Train, plant: Plant, speed_rpm: float, offset: Offset = ALIGNED, *,
                    chord: bool = True, revs: int = 32) -> tuple[np.ndarray, np.ndarray]:
    """(mean, 1X, 2X) of x and y at the four probes, (3, 4, 2) complex, of the train and of the paper model,
    A = 0.05, 400 revolutions of transient in both."""
    asm = assemble(train)
    if chord:
        with_chord_springs(asm, plant)
    run = simulate_train(asm, speed_rpm, transient_revs=400, record_revs=revs, samples_per_rev=64, n_modes=0)
    assert run.ok, run.message
    res = simulate(plant, speed_rpm, offset.delta, 0.05, mechanism=_mechanism(offset),
                   offset_angle_rad=offset.direction_rad, angular_misalignment_mrad=offset.tilt_mrad,
                   transient_revs=400, record_revs=revs, samples_per_rev=64)
    assert res.ok, res.message
    return _lines(run.journal_m[:, PAPER_BEARINGS], revs), _lines(res.journal_displacements_m, revs)


def _misaligned(train: Train, plant: Plant, offset: Offset) -> Train:
    """The train with its exciter's bearings moved as ``offset`` says (the coupling is at bearing 3, so the
    tilt moves bearing 4 by α·L, L the exciter's span = the paper's ``exciter_bearing_span_m``)."""
    if offset == ALIGNED:
        return train
    return misaligned(train, offset_m=offset.delta * plant.clearance_m, angle_rad=1e-3 * offset.tilt_mrad,
                      direction_rad=offset.direction_rad)


def _worst(train_lines: np.ndarray, paper_lines: np.ndarray, c: float) -> tuple[float, float]:
    """Largest static difference in clearances, and largest 1X/2X difference relative to each line's amplitude."""
    static = float(np.abs(train_lines[0] - paper_lines[0]).max() / c)
    lines = float((np.abs(train_lines[1:] - paper_lines[1:]) / np.abs(paper_lines[1:])).max())
    return static, lines


@pytest.mark.parametrize("speed_rpm", [SPEED_RPM, 1500.0])
@pytest.mark.parametrize("offset", OFFSETS, ids=OFFSET_IDS)
def test_steady_1x_2x_of_the_lumped_train_are_the_paper_models(speed_rpm, offset):
    """The default plant, A = 0.05, 1950 and 1500 r/min (period-1): mean, 1X and 2X (amplitude and phase, x
    and y) at the four probes, aligned and with the exciter offset (MODEL.md 3e) down, sideways and tilted."""
    plant = Plant.default()
    ours, paper = _compare_steady(_misaligned(lumped_train(plant, 0.05), plant, offset), plant, speed_rpm, offset)
    static, lines = _worst(ours, paper, plant.clearance_m)
    assert static < STATIC_TOL_C
    assert lines < LINE_RTOL


@pytest.mark.parametrize("broken", ["no chord springs", "overhang 0.3 m", "rho 0", "rigid coupling"])
def test_the_comparison_fails_when_the_limit_is_broken(broken):
    """The same comparison (aligned, 1950 r/min) with one part of the limit broken exceeds its tolerances:
    the beam alone (no chord springs), the coupling 0.3 m beyond the bearings, a symmetric generator, or a
    rigid coupling (moment carried across: slope continuity the paper's tie does not have)."""
    plant = Plant.default()
    train = lumped_train(plant, 0.05, overhang_m=0.3 if broken == "overhang 0.3 m" else 0.0,
                         asymmetry=0.0 if broken == "rho 0" else None)
    if broken == "rigid coupling":
        train = Train(train.rotors, (Coupling("rigid"),), gravity_m_s2=train.gravity_m_s2)
    ours, paper = _compare_steady(train, plant, SPEED_RPM, chord=broken != "no chord springs")
    static, lines = _worst(ours, paper, plant.clearance_m)
    assert static > 3 * STATIC_TOL_C or lines > 3 * LINE_RTOL


def test_the_1x_difference_of_the_beam_is_the_linear_effect_of_the_chord_springs():
    """Without chord springs the train's 1X differs from the paper model's by up to 10 % at 1950 r/min (the
    exciter's bending mode moves, above). Linear theory predicts it: the paper's 1X times the ratio of the
    linearised unbalance responses (films' coefficients at the static state) of the beam and of the chorded
    train. What linear theory leaves out is the films' nonlinearity acting on the chord springs' effect: of
    the order ε_lin·ε_chord (ε_lin the linear response's error against the nonlinear 1X, ε_chord the chord
    springs' relative effect); the tolerance is twice that, plus the integrators' ``LINE_RTOL``."""
    plant = Plant.default()
    train = lumped_train(plant, 0.05)
    beam = assemble(train)
    chorded = with_chord_springs(assemble(train), plant)
    nodes = beam.support_nodes[PAPER_BEARINGS]
    lin_beam = unbalance_response(beam, [SPEED_RPM], about_static=True)[0, nodes]
    lin_chord = unbalance_response(chorded, [SPEED_RPM], about_static=True)[0, nodes]
    ours, paper = _compare_steady(train, plant, SPEED_RPM, chord=False)
    eps_lin = float(np.abs(lin_chord / paper[1] - 1).max())
    eps_chord = float(np.abs(lin_beam / lin_chord - 1).max())
    assert eps_chord > 0.05  # the chord springs matter: the check below is not empty
    predicted = paper[1] * lin_beam / lin_chord
    assert float(np.abs(ours[1] / predicted - 1).max()) < 2 * eps_lin * eps_chord + LINE_RTOL


def test_an_undamped_mode_is_no_whirl():
    """The coupling 0.3 m beyond the bearings at 1950 r/min has undamped modes (the chord springs' and the overhang's,
    18.8 MHz and 1.9 GHz, Re λ ~ 1e-6 of 1e10): their log decrement is 0 up to round-off, whose sign is the
    machine's, so the stability check must not read them as a whirl growing (this machine read −1e-15)."""
    from rotordiag.simulator.train import dynamics

    plant = Plant.default()
    asm = assemble(lumped_train(plant, 0.05, overhang_m=0.3))
    with_chord_springs(asm, plant)
    kern = dynamics.build_kernel(asm, SPEED_RPM, 0)
    logdec, f_hz = dynamics.linear_stability(kern, SPEED_RPM)
    lam = np.linalg.eigvals(dynamics._linear_operator(kern))
    osc = lam[lam.imag > 1e-6]
    undamped = np.abs(-2 * np.pi * osc.real / osc.imag) <= dynamics.UNDAMPED_LOGDEC
    assert undamped.any()                                   # the case has them
    assert logdec > dynamics.UNDAMPED_LOGDEC and f_hz < 1e3  # the least-damped mode reported is a physical one
