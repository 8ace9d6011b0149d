"""The stiff hand-over (simulator/_stiff.py): Dormand–Prince hands a run that became stiff to LSODA.

The stiff case is a sample of the shipped aligned spec (a ×½…2 plant with light exciter journals
at 3376 r/min): its journals whirl towards the bushing wall (ε ≈ 0.97–0.98 after 40–80
revolutions), where the film gives eigenvalues of about −4.6e4 per radian and Dormand–Prince
needs 10⁵–2·10⁵ steps per revolution.
"""
from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from rotordiag.simulator import Plant, simulate
from rotordiag.simulator import _kernels as K
from rotordiag.simulator._stiff import _jacobian, continue_stiff
from rotordiag.simulator.system import RotorSystem

TWO_PI = 2.0 * math.pi

STIFF_PLANT = {
    "journal1_mass_kg": 3946.5733674065937, "generator_mass_kg": 21628.106242022557,
    "journal3_mass_kg": 3668.3590366681615, "journal4_mass_kg": 524.5724640619125,
    "exciter_mass_kg": 3236.994704390463, "journal6_mass_kg": 253.43559211978277,
    "generator_stiffness_n_m": 385743982.0387482, "asymmetry": 0.026021473489701744, "stiff_axis_angle_rad": 0.0,
    "generator_damping_n_s_m": 46354.808755046324, "exciter_stiffness_n_m": 122567355.4372859,
    "exciter_damping_n_s_m": 28877.450682226397, "clearance_m": 0.0006233942467261331,
    "viscosity_pa_s": 0.032520946352253055,
    "bearing_radius_m": [0.1848302385074463, 0.1848302385074463, 0.10268346583747015, 0.10268346583747015],
    "bearing_length_m": [0.5215392134638978, 0.5215392134638978, 0.22351680577024188, 0.22351680577024188],
}
STIFF_KW = dict(mechanism="aligned", unbalance_phase_rad=1.5248349341926957, exciter_unbalance=0.017965964414179327,
                exciter_unbalance_phase_rad=2.47300426221107)
STIFF_OP = (3376.062785089016, 0.0, 0.02366241842508316)  # speed_rpm, Δ, A


def stiff_system(stiff_solver: bool = True) -> RotorSystem:
    return RotorSystem(Plant.from_dict(STIFF_PLANT), *STIFF_OP, stiff_solver=stiff_solver, **STIFF_KW)


@pytest.fixture(scope="module")
def state_rev50() -> np.ndarray:
    """The state after 50 revolutions (reached through the hand-over: fast)."""
    system = stiff_system()
    y, _, _, stats, _, _ = system.integrate(system.initial_state(), 0.0, TWO_PI * 50)
    assert stats.status == "ok"
    assert math.isfinite(stats.stiff_from_tau), "the run never became stiff: the test case lost its point"
    assert stats.max_eccentricity > 0.95
    return y


def test_hand_over_matches_a_tight_reference(state_rev50):
    """Three revolutions from revolution 50: the hand-over and Dormand–Prince throughout both agree
    with Radau IIA at rtol 1e-10 to ≤ 1e-5 (measured 1.2e-6 and 0.8e-6), the explicit one at ~40× the cost."""
    p = stiff_system().params
    t0, t1 = TWO_PI * 50, TWO_PI * 53
    ref = solve_ivp(lambda t, s: K.rhs_alloc(t, s, p), (t0, t1), state_rev50, method="Radau", rtol=1e-10,
                    atol=1e-12, jac=lambda t, s: _jacobian(t, s, p))
    assert ref.status == 0
    y_ref = ref.y[:, -1]
    auto = stiff_system()
    y_auto, _, _, st_auto, _, _ = auto.integrate(state_rev50, t0, t1)
    explicit = stiff_system(stiff_solver=False)
    y_exp, _, _, st_exp, _, _ = explicit.integrate(state_rev50, t0, t1)
    assert st_auto.status == st_exp.status == "ok"
    assert math.isfinite(st_auto.stiff_from_tau) and math.isnan(st_exp.stiff_from_tau)
    assert np.max(np.abs(y_auto - y_ref)) < 1e-5
    assert np.max(np.abs(y_exp - y_ref)) < 1e-5
    assert st_auto.nfev * 10 < st_exp.nfev  # the point of it (counts, not time)


def test_grid_and_poincare_points_across_the_hand_over(state_rev50):
    """Record samples and Poincaré points are filled on both sides of the hand-over and agree with
    Dormand–Prince throughout (dense output of either integrator)."""
    t0, t1 = TWO_PI * 50, TWO_PI * 53
    out = {}
    for flag in (True, False):
        system = stiff_system(stiff_solver=flag)
        y, grid, pcs, stats, ng, npc = system.integrate(state_rev50, t0, t1, grid_t0=t0, grid_dt=TWO_PI / 64,
                                                        n_grid=3 * 64, pc_t0=t0, n_poincare=3)
        assert (ng, npc) == (3 * 64, 3)
        assert np.all(np.isfinite(grid)) and np.all(np.isfinite(pcs))
        out[flag] = (grid, pcs, stats)
    assert out[True][2].stiff_from_tau < t1  # handed over inside the window
    np.testing.assert_allclose(out[True][0], out[False][0], atol=2e-5, rtol=0)
    np.testing.assert_allclose(out[True][1], out[False][1], atol=2e-5, rtol=0)


def test_non_stiff_runs_are_unchanged_to_the_bit():
    """A period-1 run never meets the stiffness test: identical with and without the stiff solver."""
    plant = Plant()
    a = simulate(plant, 1950.0, 0.1, 0.05, transient_revs=40, record_revs=8)
    b = simulate(plant, 1950.0, 0.1, 0.05, transient_revs=40, record_revs=8, stiff_solver=False)
    assert a.inputs["stiff_from_rev"] is None and b.inputs["stiff_from_rev"] is None
    np.testing.assert_array_equal(a.positions_m, b.positions_m)
    assert a.nfev == b.nfev


def test_whole_run_completes_where_the_explicit_step_budget_was_spent():
    """The sample that took 163 s and ended 'diverged' (Dormand–Prince's step budget spent at ε ≈ 0.98)
    now runs its 400 + 64 revolutions through; the record is finite and stays inside the bushing."""
    res = simulate(Plant.from_dict(STIFF_PLANT), *STIFF_OP, transient_revs=400, record_revs=64, **STIFF_KW)
    assert res.status == "ok", res.message
    assert res.inputs["stiff_from_rev"] is not None and res.inputs["stiff_from_rev"] < 100
    assert np.all(np.isfinite(res.positions_m))
    ecc = np.hypot(*np.moveaxis(res.positions_m[:, [0, 2, 3, 5]], -1, 0)) / res.clearance_m
    assert 0.9 < ecc.max() < K.CONTACT_ECCENTRICITY


def test_stiff_leg_reports_contact_and_a_spent_budget(state_rev50):
    """The LSODA leg keeps the explicit leg's contract: contact at ε ≥ 0.999, diverged on the step budget."""
    p = stiff_system().params
    g, pc = np.empty((0, 22)), np.empty((0, 22))
    status, tau, *_ = continue_stiff(p, state_rev50, TWO_PI * 50, TWO_PI * 60, 1e-6, 1e-8, 5, 0.0, 1.0, g, 0,
                                     0.0, TWO_PI, pc, 0)
    assert status == K.STATUS_DIVERGED and tau < TWO_PI * 60
    y = state_rev50.copy()
    y[0], y[1] = 0.9995, 0.0  # journal 1 past the contact eccentricity, moving outward
    y[11], y[12] = 0.05, 0.0
    status, tau, _, _, _, _, _, emax = continue_stiff(p, y, TWO_PI * 50, TWO_PI * 51, 1e-6, 1e-8, 10**6, 0.0, 1.0,
                                                      g, 0, 0.0, TWO_PI, pc, 0)
    assert status == K.STATUS_CONTACT and emax >= K.CONTACT_ECCENTRICITY


def test_spec_integrator_setting():
    """``[simulation] integrator``: "auto" (the default) keeps the spec hash; "explicit" is another
    spec and reaches the sample runner; anything else is refused with the field named."""
    from pathlib import Path

    from rotordiag.simulator.dataset.spec import SpecError, parse_spec
    from rotordiag.simulator.dataset.worker import SimulationSettings

    path = Path(__file__).resolve().parent.parent / "models" / "default" / "dataset_aligned.toml"
    text = path.read_text()

    def with_line(line: str):
        return parse_spec(text.replace("[simulation]", f"[simulation]\n{line}", 1), base_dir=path.parent)

    base = parse_spec(text, base_dir=path.parent)
    auto, explicit = with_line('integrator = "auto"'), with_line('integrator = "explicit"')
    assert base.spec_hash == auto.spec_hash != explicit.spec_hash
    assert SimulationSettings.from_spec(base.spec).integrator == "auto"
    assert SimulationSettings.from_spec(explicit.spec).integrator == "explicit"
    with pytest.raises(SpecError, match="integrator"):
        with_line('integrator = "rk4"')
